"""Commands besides a twist (issue 11): a joint jog and Barker's uncoupled mode, checked by
finite differences of the kinematics and by numpy's solve of the arm block."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

import pinrate
from pinrate import Controller, InputError, JointJog, Status, Uncoupled

UNLIMITED = {"velocity_limits": np.inf, "position_limits": False}


def test_a_jog_moves_the_named_joints_at_their_rates_and_holds_the_others() -> None:
    robot = pinrate.load("ur5")
    controller = Controller(robot, **UNLIMITED)
    q = robot.home()
    step = controller.step(q, JointJog({"elbow_joint": 0.5, "wrist_3_joint": -1.0}))
    expected = np.zeros(6)
    expected[[2, 5]] = 0.5, -1.0
    np.testing.assert_array_equal(step.joint_rates, expected)
    np.testing.assert_allclose(step.q, q + expected * controller.dt, atol=1e-15)
    assert step.status is Status.OK
    np.testing.assert_allclose(step.twist, robot.jacobian(q) @ expected, atol=1e-15)  # what the jog does


def test_a_jog_holds_a_joint_at_its_limit_and_scales_all_rates_alike() -> None:
    robot = pinrate.load("panda")
    controller = Controller(robot, velocity_limits=1.0)
    lower, upper = robot.joint_limits("panda_joint4")
    q = robot.home()
    q[3] = upper - 0.001
    step = controller.step(q, JointJog({"panda_joint4": 2.0, "panda_joint1": 0.5}))
    assert step.q[3] == upper  # onto the limit, not past it
    assert step.frozen == ("panda_joint4",) and Status.JOINT_LIMIT in step.conditions
    assert step.joint_rates[0] == pytest.approx(0.5)  # the other joint goes on
    away = controller.step(step.q, JointJog({"panda_joint4": -2.0, "panda_joint1": 0.5}))
    # away from the limit: executed, both rates scaled by the same factor to the 1 rad/s limit
    np.testing.assert_allclose(away.joint_rates[[0, 3]], [0.25, -1.0])
    assert away.status is Status.RATE_LIMITED and lower < away.q[3] < upper


def test_bad_jogs_are_input_errors_that_name_the_problem() -> None:
    controller = Controller(pinrate.load("ur5"))
    q = controller.robot.home()
    with pytest.raises(InputError, match="elbow_joint"):
        controller.step(q, JointJog({"elbow": 1.0}))
    with pytest.raises(InputError, match="must map joint names"):
        JointJog([0.1, 0.2])
    with pytest.raises(InputError, match="finite"):
        JointJog({"elbow_joint": float("nan")})
    with pytest.raises(InputError, match="not a joint that can be jogged"):
        controller.step(q, Uncoupled([0.0, 0.0, 0.1], {"elbow_joint": 1.0}))  # not a wrist joint
    with pytest.raises(InputError, match="3 linear components"):
        controller.step(q, Uncoupled([0.1, 0.0]))


def test_uncoupled_on_barkers_arm_is_the_arm_block_solve_and_the_wrist_jog() -> None:
    robot = pinrate.robots.barker_arm()  # the tip is the wrist centre: B = 0 there
    controller = Controller(robot, **UNLIMITED)
    q = np.array([0.3, 0.4, 0.7, 0.1, 0.5, 0.2])
    linear = np.array([0.05, 0.01, -0.02])
    step = controller.step(q, Uncoupled(linear, {"theta5": 0.3, "theta6": -0.2}))
    A = robot.jacobian(q)[:3, :3]
    np.testing.assert_allclose(step.joint_rates[:3], np.linalg.solve(A, linear), atol=1e-12)
    np.testing.assert_array_equal(step.joint_rates[3:], [0.0, 0.3, -0.2])
    np.testing.assert_allclose(step.twist[:3], linear, atol=1e-12)  # the wrist does not move its centre


def wrist_centre_by_geometry(robot: pinrate.Robot, q: np.ndarray) -> np.ndarray:
    """The point of the wrist_1 axis nearest the wrist_2 axis (UR5: they are perpendicular)."""
    data = robot.model.createData()
    pin.forwardKinematics(robot.model, data, q)
    first, second = data.oMi[robot.joint_id("wrist_1_joint")], data.oMi[robot.joint_id("wrist_2_joint")]
    a, b = first.rotation[:, 1], second.rotation[:, 2]  # UR5's URDF: wrist_1 about y, wrist_2 about z
    offset = second.translation - first.translation
    along = (a @ offset - (a @ b) * (b @ offset)) / (1.0 - (a @ b) ** 2)
    return first.translation + along * a


def test_uncoupled_moves_the_ur5_wrist_centre_with_the_linear_command_whatever_the_wrist_does() -> None:
    robot = pinrate.load("ur5")
    controller = Controller(robot, **UNLIMITED)
    q = robot.home()
    q[[1, 2]] = -1.2, 1.4
    linear = np.array([0.03, -0.02, 0.04])  # in tool0's axes
    tool = robot.frame_pose(q, "tool0")[:3, :3]
    for wrist in ({}, {"wrist_1_joint": 0.4, "wrist_2_joint": -0.3, "wrist_3_joint": 1.0}):
        step = controller.step(q, Uncoupled(linear, wrist))
        h = 1e-7
        moved = wrist_centre_by_geometry(robot, pin.integrate(robot.model, q, step.joint_rates * h))
        velocity = (moved - wrist_centre_by_geometry(robot, q)) / h
        np.testing.assert_allclose(tool.T @ velocity, linear, atol=1e-6)
        for name, rate in wrist.items():
            assert step.joint_rates[robot.joint_names.index(name)] == rate


def test_a_jogged_joint_outside_the_partition_stops_at_its_limit() -> None:
    robot = pinrate.load("panda")  # the fingers are not in the partition
    controller = Controller(robot)
    q = robot.home()
    for _ in range(100):
        step = controller.step(q, JointJog({"panda_finger_joint1": 0.1}))
        q = step.q
    _, upper = robot.joint_limits("panda_finger_joint1")
    assert q[7] == upper and step.status is Status.JOINT_LIMIT and step.frozen == ("panda_finger_joint1",)
