"""Velocity limits (step 6 of :mod:`pinrate.control.controller`, after the look-ahead): when a rate exceeds its
joint's limit, every rate is scaled by the same factor, the largest that meets every limit,
so the direction of motion is kept (``Status.RATE_LIMITED``)."""

from __future__ import annotations

import math

import numpy as np

from ...checks import check_positive
from ...errors import InputError
from ...kinematics.manipulator import Robot
from ..status import Status


def per_joint(limits: object, what: str, robot: Robot) -> np.ndarray:
    """One positive limit per velocity component (nv,) from a number or an (nv,) array
    (inf for none)."""
    if np.ndim(limits) == 0:  # type: ignore[arg-type]  # any object: check_positive names a bad one
        value = check_positive(limits, what, allow_inf=True)
        return np.full(robot.nv, value)
    try:
        values = np.array(limits, dtype=float)
    except (TypeError, ValueError):
        raise InputError(f"{what} must be numbers, not {type(limits).__name__}") from None
    if values.shape != (robot.nv,):
        raise InputError(
            f"{what} must be one number or {robot.nv} (one per velocity component of "
            f"{robot.name!r}), got shape {values.shape}"
        )
    if np.isnan(values).any() or (values <= 0).any():
        raise InputError(f"{what} must be positive (inf for none), got {values}")
    return values


def scaled_detail(scale: float) -> str:
    """A step's detail when the velocity limits scaled its rates by ``scale`` (the one
    wording, whichever path took the step). Three significant digits, more where three would
    round a scale just under 1 to "1" (a limit that bound must never read as no scaling)."""
    digits = 3
    while f"{scale:.{digits}g}" == "1" and digits < 17:
        digits += 1
    return f"rates scaled by {scale:.{digits}g} to meet the velocity limits"


class VelocityLimits:
    """Per velocity component (nv,) limits in rad/s or m/s, inf where there is none."""

    def __init__(self, limits: np.ndarray) -> None:
        self.limits = limits
        self.rows = [(velocity, float(limit)) for velocity, limit in enumerate(limits) if math.isfinite(limit)]
        """(v index, limit) of the finite limits: the per-step test reads Python floats."""

    def scale(self, rates: np.ndarray) -> float:
        """The largest factor <= 1 that brings every rate within its velocity limit."""
        scale = 1.0
        rate_values = rates.tolist()
        for velocity, limit in self.rows:
            magnitude = abs(rate_values[velocity])
            if magnitude * scale > limit:
                scale = limit / magnitude
        return scale

    def apply(self, rates: np.ndarray, statuses: list[Status], details: list[str]) -> np.ndarray:
        """``rates`` scaled by :meth:`scale`, the condition said when it binds."""
        scale = self.scale(rates)
        if scale < 1.0:
            rates = rates * scale
            statuses.append(Status.RATE_LIMITED)
            details.append(scaled_detail(scale))
        return rates

    def room(self, task: np.ndarray, null: np.ndarray) -> float:
        """The largest α in [0, 1] keeping task + α null within the limits (0 when the task
        alone exceeds one): a secondary motion gives way before a velocity limit can scale the
        commanded twist."""
        room = 1.0
        task_values, null_values = task.tolist(), null.tolist()
        for velocity, limit in self.rows:
            rate, extra = task_values[velocity], null_values[velocity]
            if extra == 0.0:
                continue
            if abs(rate) >= limit:
                return 0.0
            room = min(room, (limit - math.copysign(1.0, extra) * rate) / abs(extra))
        return max(room, 0.0)


__all__ = ["VelocityLimits", "per_joint"]
