"""What the partition's joints can make of a twist (contract v2.1, the honest step).

With fewer joints than controlled twist components, or a J whose rank is below their number
at almost every configuration (:attr:`.context.StepContext.ranks`), some twists are out of
reach at every q. The step then moves by (the algorithm's version of) the least-squares
part of the command, and says so:

    x = J_r^+ twist    (the exact algorithm's solution, eq. 4 with the pseudo-inverse),
    residual r = twist - J_r x = (I - J_r J_r^+) twist,

J_r the partition's rows and columns of J in the sensor frame's axes (m/s then rad/s per unit
rate); ``Status.UNACHIEVABLE_TWIST`` with r in words where ‖r‖ exceeds
:data:`REACH_TOLERANCE` of ‖twist‖. A partition whose generic
rank equals its row count can make every twist away from singular configurations, which the
singularity strategies judge; it is not checked here (nothing to pay per step).
"""

from __future__ import annotations

import numpy as np

from .context import StepContext
from .observation import Observation

REACH_TOLERANCE = 1e-6
"""Relative residual, ‖r‖ / ‖twist‖ (m/s and rad/s in one norm, as the exact algorithm's
least squares weighs them), above which a twist counts as out of reach: a twist the
joints can make leaves a least-squares residual of rounding, about κ(J) × 1e-16, far below
it even near the singular region (κ ≤ 1 / 1e-4); a twist they cannot make misses by its
component outside J's range, which no rounding produces."""


def out_of_reach(context: StepContext, observation: Observation, twist: np.ndarray) -> str:
    """The residual of ``twist`` (m + k,; m/s then rad/s, sensor axes) in words when the
    partition's joints cannot make it at the observation's q, else ""."""
    if context.ranks["J"] >= context.index.rows.size:
        return ""
    size = float(np.linalg.norm(twist))
    if size == 0.0:
        return ""
    reduced = context.reduced(observation.jacobian)
    residual = twist - reduced @ np.linalg.lstsq(reduced, twist, rcond=None)[0]
    share = float(np.linalg.norm(residual)) / size
    if share <= REACH_TOLERANCE:
        return ""
    m = context.index.m
    return (
        f"the joints cannot make {share:.0%} of the commanded twist (rank {context.ranks['J']} for "
        f"{context.index.rows.size} components): it misses by {np.linalg.norm(residual[:m]):.3g} m/s and "
        f"{np.linalg.norm(residual[m:]):.3g} rad/s"
    )


__all__ = ["REACH_TOLERANCE", "out_of_reach"]
