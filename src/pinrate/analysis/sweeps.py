"""Design sweeps: the converging share of the work volume against one robot parameter, and
the parameter's limit for convergence everywhere (the paper's Fig. 10, the Hirata rule)."""

from __future__ import annotations

import math
import numbers
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from tqdm.auto import tqdm

from ..checks import check_count, check_name, check_positive
from ..errors import InputError
from ..kinematics.manipulator import Robot
from ..theorem.sampling import sample_convergence, wilson_interval
from . import design


@dataclass(frozen=True)
class Sweep:
    """The converging share of the work volume against one robot parameter."""

    parameter: str
    values: np.ndarray
    fraction: np.ndarray
    low: np.ndarray  # 95 % interval
    high: np.ndarray
    worst: np.ndarray  # worst ρ on the dense grid at each value
    limit: float | None  # the parameter bound for ρ < 1 everywhere (None if none in range)
    limit_kind: str  # "largest", "smallest" or "none"


def sweep(
    factory: Callable[[float], Robot],
    parameter: str,
    low: float,
    high: float,
    *,
    steps: int = 12,
    samples: int = 4000,
    points: int = 61,
    rng: int = 0,
    tolerance: float = 1e-5,
    progress: bool | None = None,
) -> Sweep:
    """Fraction with ρ < 1 at ``steps`` values in [low, high], and the convergence limit.

    The limit is the largest (ρ grows with the parameter) or smallest (ρ shrinks with it)
    value whose worst ρ on a dense grid of the joints J depends on stays below 1, found by
    bisection (:func:`pinrate.analysis.design.largest_parameter`).
    """
    for bound in (low, high):
        if isinstance(bound, bool) or not isinstance(bound, numbers.Real):
            raise InputError(f"sweep range {parameter}={low}:{high} must be two numbers")
    if not (math.isfinite(low) and math.isfinite(high)) or low >= high:
        raise InputError(f"sweep range {parameter}={low}:{high} must have low < high, both finite")
    steps = check_count(steps, "steps", minimum=2, maximum=10_000)
    check_positive(tolerance, "tolerance")
    values = np.linspace(low, high, steps)
    fractions, lows, highs, worst = [], [], [], []
    for value in tqdm(
        values, desc=f"sweep {parameter}", disable=None if progress is None else not progress, leave=False
    ):
        robot = factory(float(value))
        sample = sample_convergence(robot, samples, rng=rng)
        count = int(np.sum(sample.spectral_radius < 1))
        fractions.append(sample.fraction)
        interval = wilson_interval(count, samples)
        lows.append(interval[0])
        highs.append(interval[1])
        worst.append(design.worst_spectral_radius(robot, points=points))
    worst_array = np.array(worst)
    converges_low, converges_high = worst_array[0] < 1, worst_array[-1] < 1
    limit: float | None
    if converges_low and not converges_high:
        limit, kind = design.largest_parameter(factory, low, high, points=points, tolerance=tolerance), "largest"
    elif converges_high and not converges_low:
        limit, kind = design.smallest_parameter(factory, low, high, points=points, tolerance=tolerance), "smallest"
    else:
        limit, kind = None, "none"
    return Sweep(parameter, values, np.array(fractions), np.array(lows), np.array(highs), worst_array, limit, kind)


def parse_sweep(text: str) -> tuple[str, float, float]:
    """'PARAM=LO:HI' -> (PARAM, LO, HI)."""
    try:
        name, bounds = check_name(text, "sweep").split("=", 1)
        low, high = (float(v) for v in bounds.split(":", 1))
    except ValueError:
        raise InputError(f"--sweep takes PARAM=LO:HI (for example l3=0.01:0.2), got {text!r}") from None
    if not (math.isfinite(low) and math.isfinite(high)):
        raise InputError(f"--sweep bounds must be finite numbers, got {text!r}")
    return name.strip(), low, high
