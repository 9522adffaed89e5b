"""Design rules: independent joints, dense grid checks, parameter limits by bisection."""

from __future__ import annotations

import math

import pytest

import pinrate
from pinrate import robots
from pinrate.analysis import design


def test_independent_joints() -> None:
    assert design.independent_joints(robots.scara()) == ("theta1", "d")
    assert design.independent_joints(pinrate.load("ur5")) == ("shoulder_pan_joint",)
    # In base axes the dual holds: the TCP lies on the last axis, so its velocity ignores wrist_3.
    assert design.independent_joints(pinrate.load("ur5", sensor="base_link")) == ("wrist_3_joint",)


def test_grid_check_worst_is_the_polar_closed_form() -> None:
    # d2 in [d2_min, 1], theta3 over [-pi, pi]: the worst ρ is l / (d2_min - l) at C3 = -1.
    robot = robots.planar_polar(l=0.2, d2_min=0.5)
    check = design.grid_check(robot, points=41)
    assert check.joints == ("d2", "theta3")
    assert check.worst == pytest.approx(0.2 / (0.5 - 0.2), rel=1e-9)
    assert check.worst_q[1] == pytest.approx(0.5)


def test_largest_tool_length_is_the_hirata_rule() -> None:
    limit = design.largest_parameter(lambda l3: robots.hirata_arh300(l3=l3), 0.01, 0.3, points=61, tolerance=1e-5)
    assert limit == pytest.approx(0.275 * math.sin(math.radians(25)) / 2, abs=3e-4)


def test_smallest_stroke_is_the_polar_rule() -> None:
    limit = design.smallest_parameter(lambda d: robots.planar_polar(l=0.2, d2_min=d), 0.1, 0.9, points=41)
    assert limit == pytest.approx(0.4, abs=1e-3)


def test_grid_too_large_is_refused() -> None:
    with pytest.raises(pinrate.InputError, match="max_configurations"):
        design.grid_check(pinrate.load("ur5"), points=61)


def test_largest_parameter_needs_convergence_at_the_low_end() -> None:
    with pytest.raises(pinrate.InputError, match="low end"):
        design.largest_parameter(lambda l3: robots.hirata_arh300(l3=l3), 0.1, 0.3, points=21)
