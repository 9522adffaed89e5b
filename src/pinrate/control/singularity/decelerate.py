"""``singularity="decelerate"`` (the default): in the singular region the generalized
inverse's rates, scaled by s = (c - singular_threshold) / (slow_threshold -
singular_threshold) when the step would lower c, and 0 (a halt) when the unscaled step would
carry c under ``singular_threshold`` plus a margin of
:data:`~pinrate.control.singular_region.HALT_MARGIN` of the band, so that the approach halts
in finitely many steps on every machine. A step that raises c is executed unscaled: the way
out is always open (MoveIt Servo's look-ahead, on the block actually inverted).

A step is judged one step ahead (:func:`watched`) in the region, and also from just outside
it when it is big: a servo's big steps could enter the region or cross a singularity in one.
"""

from __future__ import annotations

import numpy as np

from ..context import StepContext
from ..observation import Observation
from ..singular_region import ColumnMap, Conditioning, c_said, deceleration, halts
from ..status import Status
from .plan import Plan, lookahead

WATCH_FACTOR = 3.0
"""A decelerating controller looks one step ahead from a conditioning bound under this many
times ``slow_threshold`` when the step is big (:data:`WATCHED_STEP`)."""

WATCHED_STEP = 0.02
"""rad (or m): a step moving some joint further than this, near the singular region, is
judged one step ahead."""

decelerates = True


def near(context: StepContext, observation: Observation, twist: np.ndarray, weakest: Conditioning, plan: Plan) -> Plan:
    """The generalized inverse's plan, judged one step ahead (:func:`decelerate`)."""
    return plan._replace(decelerate=True)


def watched(
    context: StepContext, observation: Observation, plan: Plan | None, bound: float, rates: np.ndarray
) -> tuple[ColumnMap, float, str] | None:
    """(columns, c, block) when a decelerating step must be judged one step ahead: every
    step in the singular region, and a step from just outside it (``bound`` under
    :data:`WATCH_FACTOR` x slow) that moves some joint more than :data:`WATCHED_STEP` rad.
    None otherwise."""
    if plan is not None:
        return (plan.columns, plan.value, plan.block) if plan.decelerate else None
    if (
        bound >= WATCH_FACTOR * context.slow_threshold
        or float(np.abs(rates).max(initial=0.0)) * context.dt <= WATCHED_STEP
    ):
        return None
    index = context.index
    columns = ColumnMap.of(index.arm_columns.size, index.wrist_columns.size, frozenset(), None)
    here = context.conditioning(context.reduced(observation.jacobian), index.arm_columns.size)
    return columns, here.value, here.block


def decelerate(
    context: StepContext, observation: Observation, rates: np.ndarray, columns: ColumnMap, value: float, block: str
) -> tuple[float, Status, str]:
    """(scale, status, detail) of a step at c = ``value``, judged one step ahead: unscaled
    when it raises c (without crossing a singularity); a halt when the unscaled step
    would cross a singularity or carry c under singular_threshold (with the margin of
    :func:`~pinrate.control.singular_region.halts`); else scaled by
    (c - singular) / (slow - singular), c the lesser of now and ahead."""
    singular, slow = context.singular_threshold, context.slow_threshold
    ahead, crossed = lookahead(context, observation, rates, columns)
    where = f"block {block} near singular ({c_said(min(value, ahead))})"
    crossed = crossed and value >= singular  # sign(det) next to det = 0 is noise
    if ahead > value and not crossed:
        if value >= slow:
            return 1.0, Status.OK, ""
        return 1.0, Status.NEAR_SINGULARITY, f"{where}: the step raises c, executed unscaled"
    if crossed or halts(ahead, singular, slow):
        return 0.0, Status.HALT_FOR_SINGULARITY, f"{where}: halted, the step would make it singular"
    scale = deceleration(min(value, ahead), singular, slow)
    if scale >= 1.0:
        return 1.0, Status.OK, ""
    return scale, Status.DECELERATE_FOR_SINGULARITY, f"{where}: command scaled by {scale:.2g}"


__all__ = ["WATCHED_STEP", "WATCH_FACTOR", "decelerate", "decelerates", "near", "watched"]
