"""The end of the step drives the mimic joints (issue 24, the fold): rate(mimic) = m
rate(leader) in every step, twist, jog or playback, so q keeps q_mimic = m q_leader + o; a
mimic's position limits hold through its leader; the tip goes where it is told."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

import pinrate
from mimic_urdfs import parallelogram_arm, planar_mimic_on_the_tip_path
from pinrate import Controller, InputError, Partition, Status
from pinrate.compiled import backend
from pinrate.control.commands import JointJog
from pinrate.control.recorder import Recorder

MULTIPLIER, OFFSET = 0.5, 0.1  # joint_2 = 0.5 joint_1 + 0.1 in planar_mimic_on_the_tip_path
PLANAR = Partition(["joint_1", "joint_3"], [], linear="xy", angular="")
RELATION_TOLERANCE = 1e-12  # rad: rounding of q + m r dt against m (q + r dt) + o, ~1e-16 per step


def loaded(tmp_path: Path, text: str, **options: object) -> pinrate.Robot:
    """The robot as pinrate.load gives it (its home searched)."""
    path = tmp_path / "robot.urdf"
    path.write_text(text)
    return pinrate.load(path, **options)


def planar(tmp_path: Path, follower_limits: tuple[float, float] = (-2.5, 2.5)) -> pinrate.Robot:
    return loaded(tmp_path, planar_mimic_on_the_tip_path(follower_limits), sensor="base_link")


def planar_tip(q: np.ndarray) -> np.ndarray:
    """The tip (x, y) in the base, by hand: links 0.5, 0.4, 0.3 m, every axis z."""
    a1, a12, a123 = q[0], q[0] + q[1], q[0] + q[1] + q[2]
    return np.array(
        [
            0.5 * math.cos(a1) + 0.4 * math.cos(a12) + 0.3 * math.cos(a123),
            0.5 * math.sin(a1) + 0.4 * math.sin(a12) + 0.3 * math.sin(a123),
        ]
    )


def assert_on_the_relation(q: np.ndarray) -> None:
    np.testing.assert_allclose(q[..., 1], MULTIPLIER * q[..., 0] + OFFSET, rtol=0, atol=RELATION_TOLERANCE)


def test_the_home_puts_the_mimic_on_its_relation(tmp_path: Path) -> None:
    assert_on_the_relation(planar(tmp_path).home())


def test_servo_converges_to_a_target_reached_through_the_coupled_motion(tmp_path: Path) -> None:
    robot = planar(tmp_path)
    # A pose on the relation (joint_1 = 0.9, joint_2 = 0.55): the joint_1 column must carry
    # joint_2's motion, or the steps miss it (issue 24: 0.34 m/rad off at the load's example).
    goal_q = np.array([0.9, MULTIPLIER * 0.9 + OFFSET, -0.7])
    target = np.eye(4)
    target[:2, 3] = planar_tip(goal_q)
    run = pinrate.servo(robot, robot.home(), target, algorithm="exact", partition=PLANAR, tol=1e-6)
    assert run.converged, run.reason
    # tol 1e-6 m on the controlled position error, checked by hand on the last q
    assert np.linalg.norm(planar_tip(run.q[-1]) - target[:2, 3]) < 1e-6
    assert_on_the_relation(run.q)
    np.testing.assert_allclose(run.joint_rates[:, 1], MULTIPLIER * run.joint_rates[:, 0], rtol=0, atol=1e-15)
    assert np.abs(run.joint_rates[:, 0]).max() > 0.1  # the leader did move


def test_the_compiled_core_leaves_a_robot_with_moving_mimics_to_python(tmp_path: Path) -> None:
    if backend().name != "compiled":
        pytest.skip(f"the compiled core is not in use ({backend().reason})")
    assert "mimic joint 'joint_2'" in (Controller(planar(tmp_path), partition=PLANAR).compiled_reason() or "")
    arm = loaded(tmp_path, parallelogram_arm())
    assert "follows a joint of the partition" in (Controller(arm).compiled_reason() or "")


def test_a_commanded_twist_moves_the_tip_along_it_with_status_ok(tmp_path: Path) -> None:
    robot = planar(tmp_path)
    controller = Controller(robot, partition=PLANAR, dt=0.01)
    q = robot.home()
    start = planar_tip(q)
    command = np.array([-0.06, 0.08])  # m/s in the base's axes (sensor = base_link)
    for _ in range(40):
        step = controller.step(q, command)
        assert step.status is Status.OK, step.detail
        np.testing.assert_allclose(step.joint_rates[1], MULTIPLIER * step.joint_rates[0], rtol=0, atol=1e-15)
        q = step.q
        assert_on_the_relation(q)
    moved = planar_tip(q) - start
    # Resolved rates make the commanded velocity to first order; each 1 mm step bends by
    # ~(|dq| ~ 3e-3 rad)^2 x 1.2 m ~ 1e-5 m, so over 40 mm the direction is off < 1e-2 rad.
    cosine = moved @ command / (np.linalg.norm(moved) * np.linalg.norm(command))
    assert math.acos(min(cosine, 1.0)) < 1e-2
    assert abs(np.linalg.norm(moved) - 0.4 * 0.1) < 1e-3


def test_a_mimics_limits_hold_through_its_leader(tmp_path: Path) -> None:
    # joint_2 within [-0.5, 0.5] rad: joint_1 may go to (0.5 - 0.1) / 0.5 = 0.8 rad at most
    robot = planar(tmp_path, follower_limits=(-0.5, 0.5))
    assert robot.coupled_limits("joint_1") == pytest.approx((-1.2, 0.8), abs=1e-15)
    controller = Controller(robot, partition=PLANAR, dt=0.01)
    q = robot.home()
    statuses = []
    for _ in range(150):  # 1 rad/s for 1.5 s: the leader would reach 1.5 rad unhindered
        step = controller.step(q, JointJog({"joint_1": 1.0}))
        q = step.q
        statuses.append(step.status)
        assert q[1] <= 0.5 and q[0] <= 0.8
        assert_on_the_relation(q)
    assert q[0] == pytest.approx(0.8, abs=1e-12) and q[1] == pytest.approx(0.5, abs=1e-12)
    assert statuses[-1] is Status.JOINT_LIMIT


def test_a_mimic_joint_is_neither_jogged_nor_put_in_a_partition(tmp_path: Path) -> None:
    robot = planar(tmp_path)
    controller = Controller(robot, partition=PLANAR)
    assert "joint_2" not in controller.joggable
    with pytest.raises(InputError, match="not a joint that can be jogged"):
        controller.step(robot.home(), JointJog({"joint_2": 1.0}))
    with pytest.raises(InputError, match=r"'joint_2' of robot 'planar_mimic' mimics 'joint_1'"):
        Controller(robot, partition=Partition(["joint_1", "joint_2"], [], linear="xy", angular=""))


def test_parallelogram_side_links_follow_their_leader_at_home_and_in_every_step(tmp_path: Path) -> None:
    # side_a = joint_2, side_b = -joint_2 (mimic_urdfs.parallelogram_arm); off the tip path
    robot = loaded(tmp_path, parallelogram_arm())
    index = {name: robot.model.joints[robot.joint_id(name)].idx_q for name in robot.joint_names}

    def assert_following(q: np.ndarray) -> None:
        assert q[index["side_a_joint"]] == pytest.approx(q[index["joint_2"]], abs=RELATION_TOLERANCE)
        assert q[index["side_b_joint"]] == pytest.approx(-q[index["joint_2"]], abs=RELATION_TOLERANCE)

    q = robot.home()
    assert_following(q)
    controller = Controller(robot)
    recorder = Recorder(history=10.0)
    recorder.record(0.0, q)
    for tick in range(1, 31):
        command = JointJog({"joint_2": 0.5}) if tick <= 15 else np.array([0.0, 0.0, 0.05, 0.0, 0.0, 0.0])
        step = controller.step(q, command)
        assert step.status is Status.OK, step.detail
        q = step.q
        assert_following(q)
        recorder.record(tick * controller.dt, q)
    assert q[index["side_a_joint"]] > robot.home()[index["side_a_joint"]] + 0.05  # it did move
    playback = recorder.playback(controller)  # the way back drives them too
    while not playback.done:
        q = playback.step(q).q
        assert_following(q)
    np.testing.assert_allclose(q, robot.home(), atol=1e-9)
