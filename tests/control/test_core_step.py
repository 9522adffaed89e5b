"""pinrate.control.core_step: a core step's flags in words (the one mapping), checked against
the statuses and details the Python stages write by hand."""

from __future__ import annotations

import numpy as np
import pytest

from pinrate.compiled.boundary import CLAMPED, RATE_LIMITED, SATURATED
from pinrate.control.core_step import CONDITIONS, STATUSES, core_detail
from pinrate.control.robot_facts import Limit
from pinrate.control.status import Status


@pytest.mark.parametrize(
    ("flags", "conditions"),
    [
        (0, ()),
        (SATURATED, (Status.TWIST_SATURATED,)),
        (RATE_LIMITED, (Status.RATE_LIMITED,)),
        (CLAMPED, (Status.JOINT_LIMIT,)),
        (SATURATED | RATE_LIMITED | CLAMPED, (Status.TWIST_SATURATED, Status.RATE_LIMITED, Status.JOINT_LIMIT)),
    ],
)
def test_the_conditions_and_status_of_a_core_step(flags: int, conditions: tuple[Status, ...]) -> None:
    assert CONDITIONS[flags] == conditions
    assert STATUSES[flags] is (conditions[-1] if conditions else Status.OK)


def test_the_detail_names_the_scale_then_the_limit() -> None:
    limit = Limit(joint="elbow", q_index=1, velocity=1, lower=-1.5, upper=2.0)
    next_q = np.array([0.3, 2.0])
    said = core_detail(RATE_LIMITED | CLAMPED, 0.5, lambda: limit, next_q)
    assert said == "rates scaled by 0.5 to meet the velocity limits; elbow reached its upper limit 2"
    assert core_detail(SATURATED, 1.0, lambda: limit, next_q) == ""
