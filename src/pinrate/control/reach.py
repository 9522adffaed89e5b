"""What the partition's joints can make of a twist (contract v2.1, the honest step).

With fewer joints than controlled twist components, or a J whose rank is below their number
at almost every configuration (:attr:`.context.StepContext.ranks`), some twists are out of
reach at every q. The step then moves by (the algorithm's version of) the part of the command the
joints can make, and says what it misses:

    x = J_r^+ twist    (the exact algorithm's solution, eq. 4 with the pseudo-inverse),
    residual r = twist - J_r x = (I - J_r J_r^+) twist,

J_r the partition's rows and columns of J in the sensor frame's axes (m/s then rad/s per unit
rate). With a square A and a tall W (a 5-DOF arm:
:func:`~pinrate.kinematics.partition.position_first_applies`) position comes first: x is
:func:`~pinrate.solvers.reference.position_first`'s, r has no linear part, and its angular
part is the rotation the arm cannot make at q while it makes the velocity, about one axis
for a 3x2 W (the left null vector of W - U A^-1 B), said as a unit vector in the sensor
frame. ``Status.UNACHIEVABLE_TWIST`` with r in words where ‖r‖ exceeds
:data:`REACH_TOLERANCE` of ‖twist‖. So a pure +x jog of a 5-DOF arm says which rotation
comes with it: the twist asked for none. A partition whose generic
rank equals its row count can make every twist away from singular configurations, which the
singularity strategies judge; it is not checked here (nothing to pay per step).
"""

from __future__ import annotations

import numpy as np

from ..errors import SingularBlockError
from ..kinematics.partition import split_blocks
from ..solvers.reference import position_first
from ..solvers.registry import REGISTRY
from .context import StepContext
from .observation import Observation

REACH_TOLERANCE = 1e-6
"""Relative residual, ‖r‖ / ‖twist‖ (m/s and rad/s in one norm, as the exact algorithm's
least squares weighs them), above which a twist counts as out of reach: a twist the
joints can make leaves a least-squares residual of rounding, about κ(J) × 1e-16, far below
it even near the singular region (κ ≤ 1 / 1e-4); a twist they cannot make misses by its
component outside J's range, which no rounding produces."""


def shortfall(context: StepContext, observation: Observation, twist: np.ndarray) -> tuple[np.ndarray, bool]:
    """(r, position_first): the residual r (m + k,; m/s then rad/s, sensor axes, partition
    order) of ``twist`` that the partition's joints cannot make at the observation's q, and
    whether position came first (r's linear part is then rounding): it does where the
    algorithm puts it first on this partition (exact, schur, dls; ``Algorithm.position_first``),
    least squares over the whole J elsewhere and where A is singular."""
    reduced = context.reduced(observation.jacobian)
    index = context.index
    if index.position_first and REGISTRY[context.algorithm].position_first is not None:
        m = index.m
        try:
            arm, wrist = position_first(*split_blocks(reduced, m, index.arm_columns.size), twist[:m], twist[m:])
            return twist - reduced @ np.concatenate([arm, wrist]), True
        except SingularBlockError:
            pass  # at an arm singularity no rates make the velocity: the whole twist in least squares
    return twist - reduced @ np.linalg.lstsq(reduced, twist, rcond=None)[0], False


def about(direction: np.ndarray, axes: str) -> str:
    """A unit vector over the sensor frame's ``axes`` in words, e.g. "+0.12 x -0.99 y +0.05 z"."""
    return " ".join(f"{value:+.3f} {axis}" for value, axis in zip(direction, axes, strict=True))


def out_of_reach(context: StepContext, observation: Observation, twist: np.ndarray) -> str:
    """The residual of ``twist`` (m + k,; m/s then rad/s, sensor axes) in words when the
    partition's joints cannot make it at the observation's q, else "". With position first,
    the words name the axis (a unit vector, sensor frame) of the rotation given up."""
    if context.ranks["J"] >= context.index.rows.size:
        return ""
    size = float(np.linalg.norm(twist))
    if size == 0.0:
        return ""
    residual, first = shortfall(context, observation, twist)
    share = float(np.linalg.norm(residual)) / size
    if share <= REACH_TOLERANCE:
        return ""
    m = context.index.m
    angular = float(np.linalg.norm(residual[m:]))
    if first and angular > 0.0:
        return (
            f"position first: the commanded velocity is made, the rotation about "
            f"{about(residual[m:] / angular, context.partition.angular)} (unit, sensor frame) is not "
            f"controllable here: it misses by {angular:.3g} rad/s ({share:.0%} of the twist; "
            f"rank {context.ranks['J']} for {context.index.rows.size} components)"
        )
    return (
        f"the joints cannot make {share:.0%} of the commanded twist (rank {context.ranks['J']} for "
        f"{context.index.rows.size} components): it misses by {np.linalg.norm(residual[:m]):.3g} m/s and "
        f"{angular:.3g} rad/s"
    )


__all__ = ["REACH_TOLERANCE", "about", "out_of_reach", "shortfall"]
