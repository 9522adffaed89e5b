"""The one table of resolved-rate algorithms: each name with its numpy reference form and,
where it has one, its closed-form kernel on Python floats."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from ..errors import InputError, choices_hint
from . import closed_form, reference

WholeSolver = Callable[[np.ndarray, np.ndarray], np.ndarray]
"""(J restricted to the partition, twist) -> rates of the partition's joints."""

BlockSolver = Callable[..., tuple[np.ndarray, np.ndarray]]
"""(A, B, U, W, v, Ω) -> (arm rates, wrist rates), numpy."""


@dataclass(frozen=True)
class Algorithm:
    """One resolved-rate algorithm.

    Exactly one of ``whole`` (acts on the partition's J at once) and ``blocks`` (acts on
    A, B, U, W of eq. 19) is set; ``closed_form`` is the float kernel that replaces
    ``blocks`` when A and W are square of size at most 3. ``position_first``: on a
    partition with A square and W tall (no rates make every twist,
    :func:`~pinrate.kinematics.partition.position_first_applies`) the algorithm solves by
    :func:`~pinrate.solvers.reference.position_first` instead, its blocks inverted by this
    inverter: position exact (up to the damping, for dls), orientation in least squares over
    what is left. The MCAs keep their own equations there (with W^+), as the papers state
    them: MCA1 makes the velocity exactly (eq. 28), MCA2 and MCA3 do not.
    """

    name: str
    summary: str
    whole: WholeSolver | None = None
    blocks: BlockSolver | None = None
    closed_form: closed_form.Kernel | None = None
    position_first: reference.Inverter | None = None


REGISTRY: dict[str, Algorithm] = {
    algorithm.name: algorithm
    for algorithm in (
        Algorithm(
            "exact",
            "J^-1 s, least squares where J is singular or not square (eq. 4, 18); position first with a tall W",
            whole=reference.exact,
            position_first=reference.inverse,
        ),
        Algorithm(
            "schur",
            "exact inverse by blocks, Schur complement of W (eq. 20)",
            blocks=reference.schur,
            closed_form=closed_form.schur,
            position_first=reference.inverse,
        ),
        Algorithm(
            "mca1",
            "U taken as 0: two small inversions (eq. 24-25)",
            blocks=reference.mca1,
            closed_form=closed_form.mca1,
        ),
        Algorithm(
            "mca2",
            "B taken as 0: two small inversions (eq. 44-45)",
            blocks=reference.mca2,
            closed_form=closed_form.mca2,
        ),
        Algorithm("mca3", "K ~ A^-1, N ~ W^-1 (eq. 51-52)", blocks=reference.mca3, closed_form=closed_form.mca3),
        Algorithm(
            "dls",
            "damped least squares, finite everywhere; position first with a tall W",
            whole=reference.dls,
            position_first=reference.damped,
        ),
    )
}
"""Every algorithm by name: its summary and its solvers (numpy, and closed form where it has one)."""

ALGORITHMS: tuple[str, ...] = tuple(REGISTRY)
"""Every algorithm name, in the order the papers introduce them (``exact`` first)."""


def check_algorithm(algorithm: object) -> str:
    """The algorithm name, or an InputError listing the valid ones."""
    if not isinstance(algorithm, str) or algorithm not in REGISTRY:
        raise InputError(f"unknown algorithm {algorithm!r}." + choices_hint(str(algorithm), ALGORITHMS))
    return algorithm
