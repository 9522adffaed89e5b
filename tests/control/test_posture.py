"""The null-space secondary task (issue 11): the twist unchanged to 1e-9 (by the robot's own
Jacobian) while the posture objective improves; its gradient against finite differences."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

import pinrate
from pinrate import Controller, InputError, PoseGoal, Status
from pinrate.control import posture

UNLIMITED = {"velocity_limits": np.inf, "position_limits": False}


@pytest.mark.parametrize("name", ["panda", "xarm7"])
def test_the_twist_is_unchanged_and_the_objective_improves(name: str) -> None:
    robot = pinrate.load(name)
    with_posture = Controller(robot, posture="home", **UNLIMITED)
    without = Controller(robot, **UNLIMITED)
    rng = np.random.default_rng(4)
    checked = 0
    for q in robot.sample_configurations(20, 5):
        twist = rng.normal(size=6) * 0.05
        step, plain = with_posture.step(q, twist), without.step(q, twist)
        if plain.status is not Status.OK:
            continue  # near a singular block: the task is off, or the step decelerates
        checked += 1
        np.testing.assert_allclose(robot.jacobian(q) @ step.joint_rates, twist, atol=1e-9)
        before = posture.objective(with_posture.posture.joints, q)
        gradient = posture.gradient(with_posture.posture.joints, q)
        columns = with_posture.posture.joints.q_indices  # 1-DOF joints: q index = v index here
        # to first order, the step changes H by ∇H · q̇ dt: less than without the task
        assert gradient @ step.joint_rates[columns] < gradient @ plain.joint_rates[columns]
        joints = with_posture.posture.joints
        assert posture.objective(joints, step.q) < posture.objective(joints, plain.q)
        assert before > 0.0
    assert checked >= 10


def test_the_gradient_is_the_objectives_derivative() -> None:
    robot = pinrate.load("panda")
    controller = Controller(robot, posture="home")
    joints = controller.posture.joints
    lower, upper = robot.position_limits()
    for q in robot.sample_configurations(10, 6):
        q[0] = lower[0] + 0.02 * (upper[0] - lower[0])  # inside the limit margin
        h = 1e-7
        numeric = []
        for index in joints.q_indices:
            ahead, behind = q.copy(), q.copy()
            ahead[index] += h
            behind[index] -= h
            numeric.append((posture.objective(joints, ahead) - posture.objective(joints, behind)) / (2 * h))
        np.testing.assert_allclose(posture.gradient(joints, q), numeric, rtol=1e-6, atol=1e-8)


def test_holding_the_hand_still_moves_a_joint_off_its_limit() -> None:
    robot = pinrate.load("panda")
    controller = Controller(robot, posture="home", posture_gain=2.0)
    _, upper = robot.joint_limits("panda_joint7")
    q = robot.home()
    q[6] = upper - 0.01
    start = robot.pose(q)
    hold = PoseGoal.of(start, gain=5.0)  # closed loop: Euler steps of the null motion drift the hand
    objective = [posture.objective(controller.posture.joints, q)]
    for _ in range(200):
        q = controller.step(q, hold).q
        objective.append(posture.objective(controller.posture.joints, q))
    assert upper - q[6] > 0.3  # well off the limit
    assert all(after <= before + 1e-12 for before, after in itertools.pairwise(objective))
    np.testing.assert_allclose(robot.pose(q), start, atol=1e-4)  # the hand held


def test_bad_posture_options_are_input_errors() -> None:
    robot = pinrate.load("panda")
    with pytest.raises(InputError, match="posture must be"):
        Controller(robot, posture="upright")
    with pytest.raises(InputError):
        Controller(robot, posture=np.zeros(3))
    with pytest.raises(InputError, match="posture_gain"):
        Controller(robot, posture="home", posture_gain=0.0)


def test_the_posture_task_gives_way_before_a_velocity_limit_slows_the_twist() -> None:
    robot = pinrate.load("panda")
    q = robot.home()
    q[0] = 2.88  # near its limit: the limit term pushes hard
    twist = np.array([0.2, 0.0, 0.0, 0.0, 0.0, 0.0])
    with_posture = Controller(robot, posture="home", posture_gain=5.0).step(q, twist)
    plain = Controller(robot).step(q, twist)
    np.testing.assert_allclose(
        robot.jacobian(q) @ with_posture.joint_rates, robot.jacobian(q) @ plain.joint_rates, atol=1e-9
    )
    assert np.all(np.abs(with_posture.joint_rates) <= Controller(robot).velocity_limits + 1e-12)
