"""``singularity="freeze"`` (Barker's "variables held constant"): the joints that carry the
lost direction (those with at least :data:`~pinrate.control.singular_region.FREEZE_SHARE` of
the largest entry of the weakest block's smallest right singular vector) hold still and the
others serve the command, until a step of all the joints would raise c: that step is then
executed, nothing frozen (``Status.NEAR_SINGULARITY``), so the arm can always leave the
region.

Which joints: Barker's example holds θ2 and θ3 as they "approach the singular condition in
equations (32) and (33)", the variables det M is written in (it does not depend on θ1).
pinrate holds the joints that carry the lost motion instead, for two reasons. Barker's
choice does not generalise: c of a 6R arm depends on every joint but the first and last, and
holding those leaves almost nothing. And it gives up feasible commands: near the
minimum-radius singularity alone (eq. 32, S2 ES + F5 = 0) the lost motion is M's null
vector, θ1 with θ2 at F2/F3 of it (about 0.17, under
:data:`~pinrate.control.singular_region.FREEZE_SHARE`), and the lost
direction is only the radial one; holding θ2 and θ3 leaves the wrist centre θ1's circle, and
a "down" command (in M's range) is lost entirely, while holding θ1 (with the wrist joint
that cancels its turn of the hand) leaves a well-conditioned system that makes every
commanded component but the radial one. Tested in
tests/control/test_singularity.py::test_freeze_near_barkers_minimum_radius_holds_theta1_not_theta2_theta3."""

from __future__ import annotations

import numpy as np

from ..context import StepContext
from ..observation import Observation
from ..singular_region import ColumnMap, Conditioning, carrying_joints
from ..status import Status
from .plan import Plan, lookahead, solve_planned, where

decelerates = False


def near(context: StepContext, observation: Observation, twist: np.ndarray, weakest: Conditioning, plan: Plan) -> Plan:
    """The plan with the carrying joints dropped (``Status.FROZEN``), unless the free step
    raises c without crossing a singularity."""
    said = where(weakest, context.slow_threshold)
    free = solve_planned(context, observation, twist, plan, frozenset())
    ahead, crossed = lookahead(context, observation, free, plan.columns)
    if not crossed and ahead > weakest.value:
        return plan._replace(
            statuses=(*plan.statuses, Status.NEAR_SINGULARITY),
            details=(*plan.details, f"{said}: the step of all joints raises c, none frozen"),
        )
    carrying = {
        position
        for variable in carrying_joints(weakest)
        for position in np.flatnonzero(plan.columns.matrix[:, variable]).tolist()
    }
    dropped = plan.dropped | frozenset(carrying)
    frozen = tuple(context.names[position] for position in sorted(carrying))
    index = context.index
    return plan._replace(
        columns=ColumnMap.of(index.arm_columns.size, index.wrist_columns.size, dropped, plan.merged),
        dropped=dropped,
        frozen=frozen,
        statuses=(*plan.statuses, Status.FROZEN),
        details=(*plan.details, f"{said}: {', '.join(frozen)} held still"),
    )


__all__ = ["decelerates", "near"]
