"""The honest step (contract v2.1): a twist the partition's joints cannot make is never
reported OK; the step moves by its least-squares part and says the residual."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

import pinrate
from pinrate import Controller, Status
from pinrate.control.reach import REACH_TOLERANCE

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


FIVE_DOF = Path(__file__).parent.parent / "data" / "five_dof_arm.urdf"


def given_up(J: np.ndarray, twist: np.ndarray) -> np.ndarray:
    """The rotation (3,) a 6x5 J cannot make while its linear rows make twist[:3]: Ω minus the
    best J_o x over x = x0 + N z (x0 = J_p^+ v, N a basis of J_p's null space), numpy's lstsq."""
    x0 = np.linalg.lstsq(J[:3], twist[:3], rcond=None)[0]
    null = np.linalg.svd(J[:3])[2][3:].T
    z = np.linalg.lstsq(J[3:] @ null, twist[3:] - J[3:] @ x0, rcond=None)[0]
    return twist[3:] - J[3:] @ (x0 + null @ z)


@pytest.mark.parametrize("algorithm", ["exact", "schur", "dls"])
@pytest.mark.parametrize("axis", [0, 1, 2])
def test_a_five_dof_jog_goes_along_its_tool_axis_and_says_what_it_gives_up(algorithm: str, axis: int) -> None:
    """A teleop jog of a yaw-pitch-pitch-pitch-roll arm along one tool axis (the sensor is the
    tool): the hand moves along it, off by at most the angle the tool turned on the way
    (each step's velocity lies along the tool's axis as it is then) plus the explicit Euler
    steps' bend, dt |v| / ρ = 0.01 s x 0.05 m/s / 0.05 m = 0.01 rad (ρ: the arm's shortest
    lever). Least squares over all six rows went 52° off on this arm. A step whose rotation
    the arm cannot hold says so, with the axis given up (unit, sensor frame) and its rate."""
    robot = pinrate.load(FIVE_DOF)
    controller = Controller(robot, algorithm=algorithm)
    assert controller.index.position_first
    rng = np.random.default_rng(7)
    for _ in range(3):
        q = robot.home() + rng.uniform(-0.6, 0.6, robot.nq)
        _, start, sensor = robot.kinematics(q)
        command = np.zeros(6)
        command[axis] = 0.05
        for _ in range(20):
            J = robot.jacobian(q)
            step = controller.step(q, command)
            if algorithm != "dls":  # rates ~0.5 rad/s on J entries <= 0.5 m: rounding ~1e-16 m/s
                np.testing.assert_allclose(J[:3] @ step.joint_rates, command[:3], atol=1e-12)
            missed = given_up(J, command)
            share = np.linalg.norm(missed) / np.linalg.norm(command)
            # Near the tolerance two computations may disagree on the side: judged away from it.
            if share > 2 * REACH_TOLERANCE:
                assert step.status is Status.UNACHIEVABLE_TWIST
                said = re.findall(r"rotation about (\S+) x (\S+) y (\S+) z .* misses by (\S+) rad/s", step.detail)[0]
                # 3 decimals of a unit vector; 3 digits of the rate
                np.testing.assert_allclose([float(v) for v in said[:3]], missed / np.linalg.norm(missed), atol=6e-4)
                assert float(said[3]) == pytest.approx(np.linalg.norm(missed), rel=5e-3)
            elif share < 0.5 * REACH_TOLERANCE:
                assert step.status is Status.OK
            q = step.q
        _, end, turned = robot.kinematics(q)
        moved = sensor.rotation.T @ (end.translation - start.translation)
        off = np.arccos(moved[axis] / np.linalg.norm(moved))
        tool_turn = np.linalg.norm(pin.log3(sensor.rotation.T @ turned.rotation))
        assert off <= tool_turn + 0.01, (np.degrees(off), np.degrees(tool_turn))
        assert np.linalg.norm(moved) == pytest.approx(0.01, rel=0.02)  # 20 x 0.01 s x 0.05 m/s, dls damped
