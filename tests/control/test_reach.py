"""The honest step (contract v2.1): a twist the partition's joints cannot make is never
reported OK; the step moves by its least-squares part and says the residual."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

import pinrate
from pinrate import Controller, Status

AL5D = Path(__file__).parent.parent / "data" / "third_party" / "rtb_al5d_robot.urdf"


def test_a_two_link_arm_cannot_turn_its_hand_at_will() -> None:
    """Fig. 1's arm: rows vx, vy, ωz and two joints. A twist J q̇ is made exactly (OK); adding
    n, normal to both of J's columns (their cross product: the one direction out of reach),
    makes it unachievable. Position comes first (A square, W 1x0): the two joints make the
    commanded velocity, the only rates that do (A invertible), and the step says the rotation
    about z it misses."""
    robot = pinrate.robots.two_link_planar()
    controller = Controller(robot, algorithm="exact", max_linear_speed=np.inf, max_angular_speed=np.inf)
    assert (controller.partition.linear, controller.partition.angular) == ("xy", "z")
    q = np.array([0.4, 0.9])
    jacobian = controller.context.reduced(robot.jacobian(q))
    reachable = jacobian @ np.array([0.2, -0.3])
    step = controller.step(q, reachable)
    assert step.status is Status.OK
    normal = np.cross(jacobian[:, 0], jacobian[:, 1])
    normal *= 0.05 / np.linalg.norm(normal)
    commanded = reachable + normal
    step = controller.step(q, commanded)
    assert step.status is Status.UNACHIEVABLE_TWIST
    made = jacobian @ step.joint_rates
    np.testing.assert_allclose(made[:2], commanded[:2], atol=1e-12)  # rates ~0.5 rad/s: rounding ~1e-16
    missed = commanded[2] - made[2]
    said = re.findall(r"rotation about ([+-]1\.000) z .* misses by (\S+) rad/s", step.detail)[0]
    assert float(said[0]) == np.sign(missed)
    assert float(said[1]) == pytest.approx(abs(missed), rel=5e-3)  # 3 digits: half a unit in 100


@pytest.mark.parametrize("name", ["two_link_planar", "cylindrical", "spherical", "al5d"])
def test_no_step_reports_ok_for_a_twist_it_does_not_make(name: str) -> None:
    """Random commands on partitions with fewer joints than rows: a step said OK or
    TWIST_SATURATED makes its (saturated) twist; the others say why they do not."""
    robot = pinrate.load(AL5D) if name == "al5d" else getattr(pinrate.robots, name)()
    controller = Controller(robot, algorithm="exact", singularity="generalized_inverse")
    rng = np.random.default_rng(5)
    q = robot.home()
    said = set()
    for _ in range(300):
        step = controller.step(q, rng.normal(size=controller.index.rows.size) * 0.2)
        said.add(step.status)
        made = robot.jacobian(q)[controller.index.rows] @ step.joint_rates
        if step.status in (Status.OK, Status.TWIST_SATURATED):
            np.testing.assert_allclose(made, step.twist, atol=1e-9 * max(1.0, np.linalg.norm(step.twist)))
        else:
            assert step.detail
        q = step.q
    assert Status.UNACHIEVABLE_TWIST in said
