"""A stalled servo run names the cause its stall window's steps met (pinrate.control.stall):
the wrist singularity with the angle between the aligned axes, the joint held at a limit,
the frozen joints; and the default wrist rule passes the singularity where Barker's rules
stall."""

from __future__ import annotations

import math
import re

import numpy as np
import pytest

import pinrate
from pinrate.control.singular_region import SLOW_THRESHOLD
from pinrate.control.stall import stall_cause


def barker_across_the_wrist_singularity() -> tuple[pinrate.Robot, np.ndarray, np.ndarray]:
    """Barker's arm at θ5 = -0.007 (θ4 and θ6 nearly aligned), and a target whose rotation
    lies along the direction the aligned axes cannot make: θ4 + π/2, θ5 = 0.3, θ6 - π/2 (the
    hand turns 0.3 rad about the axis normal to θ5's and the common one)."""
    robot = pinrate.robots.barker_arm()
    q0 = robot.home()
    q0[4] = -0.007
    q_target = q0.copy()
    q_target[3] += math.pi / 2
    q_target[4] = 0.3
    q_target[5] -= math.pi / 2
    return robot, q0, robot.pose(q_target)


def test_the_default_passes_a_wrist_singularity() -> None:
    robot, q0, target = barker_across_the_wrist_singularity()
    trajectory = pinrate.servo(robot, q0, target)
    assert trajectory.converged, trajectory.reason
    assert "wrist singularity" in trajectory.status  # it did go through the region
    assert abs(trajectory.q[-1, 4]) == pytest.approx(0.3, abs=1e-3)  # either wrist solution of the target


@pytest.mark.parametrize("wrist", ["split", "hold_first"])
def test_a_stall_at_a_wrist_singularity_is_named(wrist: str) -> None:
    robot, q0, target = barker_across_the_wrist_singularity()
    trajectory = pinrate.servo(robot, q0, target, wrist=wrist)
    assert trajectory.status[-1] == "stalled"
    found = re.search(
        r"; wrist singularity on (\d+) of its (\d+) steps: wrist axes of theta4 and theta6 aligned "
        r"\(theta5 = (\S+) rad",
        trajectory.reason,
    )
    assert found, trajectory.reason
    assert found[1] == found[2]  # every step of the window
    theta5 = trajectory.q[-2, 4]  # the last step's q, whose detail the reason quotes
    assert float(found[3]) == pytest.approx(theta5, rel=5e-3, abs=1e-12)  # said to 3 digits
    # Independently: Barker's W = [z4 z5 z6] with z5 normal to z4 and z6 and z4 · z6 = cos θ5
    # has W^T W eigenvalues 1 + cos θ5, 1, 1 - cos θ5, so c(W) = tan(|θ5| / 2): the wrist is in
    # the singular region when |θ5| < 2 atan(slow_threshold).
    J = robot.jacobian(trajectory.q[-2])
    z4, z5, z6 = J[3:, 3], J[3:, 4], J[3:, 5]
    assert abs(z4 @ z5) < 1e-12 and abs(z5 @ z6) < 1e-12 and z4 @ z6 == pytest.approx(math.cos(theta5), abs=1e-12)
    assert abs(theta5) < 2.0 * math.atan(SLOW_THRESHOLD)


def test_a_stall_against_a_limit_names_the_joint() -> None:
    # θ5 from 0.3 to -0.3 with θ4 and θ6 turned: MCA1 heads for the target's other wrist
    # solution, whose θ4 lies past its limit; θ4 is held there and the run stalls.
    robot = pinrate.robots.barker_arm()
    q0 = robot.home()
    q0[4] = 0.3
    q_target = q0.copy()
    q_target[[1, 3, 4, 5]] += [0.1, 0.4, -0.6, -0.3]
    trajectory = pinrate.servo(robot, q0, robot.pose(q_target))
    assert trajectory.status[-1] == "stalled"
    assert re.search(
        r"; at a joint limit on (\d+) of its \1 steps: held at a position limit: theta4$", trajectory.reason
    )
    assert trajectory.q[-1, 3] in robot.joint_limits("theta4")  # really on its limit


def test_a_stall_with_a_frozen_joint_names_it() -> None:
    # A target three times as far as home's tip: the arm stretches to full extension, where
    # freeze holds the elbow still.
    robot = pinrate.load("ur5")
    target = robot.pose(robot.home())
    target[:3, 3] *= 3.0
    trajectory = pinrate.servo(robot, robot.home(), target, singularity="freeze")
    assert trajectory.status[-1] == "stalled"
    assert re.search(
        r"; frozen joints on \d+ of its \d+ steps: block A near singular .*: elbow_joint held still$", trajectory.reason
    ), trajectory.reason


def test_the_cause_is_the_most_frequent_bending_status() -> None:
    words = ["moving", "speed limited", "rate limited", "at a joint limit", "wrist singularity", "wrist singularity"]
    details = ["", "", "scaled", "held at a position limit: a", "wrist 1", "wrist 2"]
    assert stall_cause(words, details) == "wrist singularity on 2 of its 6 steps: wrist 2"
    # a tie goes to the more severe; a speed or rate limit is never a cause
    assert stall_cause(words[:5], details[:5]).startswith("wrist singularity on 1 of its 5 steps")
    assert stall_cause(words[:3], details[:3]).startswith("no step of its 3 was held")
