"""A plant's measurement as the controller takes it (pinrate.control.measured)."""

from __future__ import annotations

import numpy as np

from pinrate import Controller
from pinrate.control.measured import onto_limits


def test_a_joint_past_its_limit_within_the_tolerance_is_put_on_it(panda):
    controller = Controller(panda)
    limit = next(limit for limit in controller.joint_limits if limit.joint == "panda_joint4")
    tolerance = np.full(panda.nv, 0.01)
    q = panda.home()
    assert onto_limits(controller, q, tolerance) == (q, "")  # inside: q itself, nothing said
    q[limit.q_index] = limit.upper + 0.004
    view, beyond = onto_limits(controller, q, tolerance)
    assert view[limit.q_index] == limit.upper and not beyond
    assert q[limit.q_index] == limit.upper + 0.004  # the measurement itself is kept
    assert np.array_equal(np.delete(view, limit.q_index), np.delete(q, limit.q_index))


def test_a_joint_past_it_by_more_is_named_and_clipped_only_when_asked(panda):
    controller = Controller(panda)
    limit = next(limit for limit in controller.joint_limits if limit.joint == "panda_joint4")
    q = panda.home()
    q[limit.q_index] = limit.lower - 0.05
    view, beyond = onto_limits(controller, q, np.full(panda.nv, 0.01))
    assert view[limit.q_index] == q[limit.q_index]
    assert beyond.startswith("panda_joint4 at") and "0.05 past its limit" in beyond and "tolerance 0.01" in beyond
    clipped, said = onto_limits(controller, q, np.full(panda.nv, 0.01), clip=True)
    assert clipped[limit.q_index] == limit.lower and said == beyond
    free = Controller(panda, position_limits=False)  # limits not kept: nothing to put it on
    assert onto_limits(free, q, np.zeros(panda.nv)) == (q, "")
