"""Barker's operator loop (pinrate.Teleop, contract v2): deflections scaled by the max speeds
in the hand or base axes, one controller step per tick, the dead man, reverse."""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin
import pytest

import pinrate
from pinrate import InputError, Status, Teleop

DT = 0.01


def tip_and_sensor(robot: pinrate.Robot, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """World position of the tip and rotation of the sensor at q, from Pinocchio directly."""
    data = robot.model.createData()
    pin.framesForwardKinematics(robot.model, data, q)
    return np.array(data.oMf[robot.tip_id].translation), np.array(data.oMf[robot.sensor_id].rotation)


def drive(teleop: Teleop, linear, angular, ticks: int, start: float = 0.0) -> float:
    """Command (refreshed every tick, as a page's heartbeat would) and tick ``ticks`` times."""
    now = start
    for _ in range(ticks):
        teleop.command(linear, angular, now=now)
        now += DT
        teleop.tick(now)
    return now


@pytest.mark.parametrize("axis", [0, 1, 2])
def test_hand_axis_travel_is_speed_times_time(ur5, axis):
    teleop = Teleop(ur5, dt=DT, max_linear_speed=0.08)
    start_tip, start_sensor = tip_and_sensor(ur5, teleop.q)
    linear = np.zeros(3)
    linear[axis] = 1.0
    drive(teleop, linear, np.zeros(3), 100)
    end_tip, _ = tip_and_sensor(ur5, teleop.q)
    travel = start_sensor.T @ (end_tip - start_tip)  # in the starting hand axes
    assert travel[axis] == pytest.approx(0.08 * 100 * DT, rel=1e-3)
    off_axis = np.delete(travel, axis)
    assert np.linalg.norm(off_axis) < 5e-3 * abs(travel[axis])  # Euler steps on a curved path: O(dt)


def test_base_frame_moves_along_world_axes(ur5):
    teleop = Teleop(ur5, dt=DT, frame="base")
    start_tip, _ = tip_and_sensor(ur5, teleop.q)
    drive(teleop, [0, 0, 1], [0, 0, 0], 50)
    end_tip, _ = tip_and_sensor(ur5, teleop.q)
    np.testing.assert_allclose(end_tip - start_tip, [0, 0, 0.1 * 50 * DT], atol=1e-4)  # 0.2 %: Euler steps


def test_angular_deflection_turns_the_hand_about_its_axis(ur5):
    teleop = Teleop(ur5, dt=DT, max_angular_speed=0.4)
    _, start_sensor = tip_and_sensor(ur5, teleop.q)
    drive(teleop, [0, 0, 0], [0, 1, 0], 50)
    _, end_sensor = tip_and_sensor(ur5, teleop.q)
    rotation = pin.log3(start_sensor.T @ end_sensor)  # in the starting hand axes
    np.testing.assert_allclose(rotation, [0, 0.4 * 50 * DT, 0], atol=3e-4)  # 0.15 %: Euler steps


def test_first_tick_is_the_contracts_controller_step(ur5):
    teleop = Teleop(ur5, dt=DT, max_linear_speed=0.2, max_angular_speed=0.3)
    q0 = teleop.q.copy()
    teleop.command([0.5, -0.25, 0], [0, 0, 1], now=0.0)
    step = teleop.tick(0.0)
    twist = np.array([0.1, -0.05, 0, 0, 0, 0.3])
    np.testing.assert_allclose(step.joint_rates, pinrate.joint_rates(ur5, q0, twist, algorithm="exact"), atol=1e-12)
    np.testing.assert_allclose(step.q, pin.integrate(ur5.model, q0, step.joint_rates * DT), atol=1e-15)
    assert step.status is Status.OK


def test_deflections_are_clipped_and_the_hand_never_exceeds_the_max_speed(ur5):
    teleop = Teleop(ur5, dt=DT, max_linear_speed=0.1)
    teleop.command([3, 0, 0], [0, 0, 0], now=0.0)
    assert teleop.tick(0.0).twist[0] == pytest.approx(0.1)
    teleop.command([1, 1, 0], [0, 0, 0], now=0.0)
    step = teleop.tick(0.0)
    assert np.linalg.norm(step.twist[:3]) == pytest.approx(0.1)  # the controller's saturation
    assert step.status is Status.TWIST_SATURATED


def test_dead_man_zeroes_a_stale_command(ur5):
    teleop = Teleop(ur5, dt=DT, timeout=0.25)
    teleop.command([1, 0, 0], [0, 0, 0], now=10.0)
    moving = [bool(teleop.tick(10.0 + k * DT).joint_rates.any()) for k in range(40)]
    # fresh up to 0.25 s after the command (ticks 0..25), stale after
    assert moving[:25] == [True] * 25
    assert not any(moving[27:])


def test_uncontrolled_components_are_ignored():
    scara = pinrate.load("scara")
    teleop = Teleop(scara, dt=DT)
    start = teleop.q.copy()
    drive(teleop, [0, 0, 0], [1, 1, 0], 20)  # the SCARA controls no rotation about x or y
    np.testing.assert_array_equal(teleop.q, start)


def test_reverse_returns_to_the_start_of_the_motion(ur5):
    teleop = Teleop(ur5, dt=DT)
    start = teleop.q.copy()
    now = drive(teleop, [1, 0, 0], [0, 0, 0], 60)
    now = drive(teleop, [0, 1, 0.5], [0.3, 0, 0], 60, now)
    teleop.command([0, 0, 0], [0, 0, 0], now=now)  # the stick released
    for _ in range(50):  # idle ticks are not motion: nothing to retrace there
        now += DT
        teleop.tick(now)
    assert teleop.reverse(now)
    ticks = 0
    while teleop.reversing and ticks < 1000:
        now += DT
        teleop.tick(now)
        ticks += 1
    assert not teleop.reversing
    assert ticks == pytest.approx(120, abs=2)  # at the recorded pace
    np.testing.assert_allclose(teleop.q, start, atol=1e-9)
    assert not teleop.reverse(now)  # all of it retraced


def test_a_new_command_ends_the_reversal_and_the_record_continues(ur5):
    teleop = Teleop(ur5, dt=DT)
    start = teleop.q.copy()
    now = drive(teleop, [1, 0, 0], [0, 0, 0], 100)
    teleop.reverse(now)
    for _ in range(40):
        now += DT
        teleop.tick(now)
    assert teleop.reversing
    teleop.command([0, 0, 1], [0, 0, 0], now=now)
    now += DT
    assert teleop.tick(now).twist[2] > 0
    assert not teleop.reversing
    now = drive(teleop, [0, 0, 1], [0, 0, 0], 20, now)
    teleop.reverse(now)
    while teleop.reversing:
        now += DT
        teleop.tick(now)
    np.testing.assert_allclose(teleop.q, start, atol=1e-9)  # back through both pieces


def test_mark_starts_a_new_segment(ur5):
    teleop = Teleop(ur5, dt=DT)
    now = drive(teleop, [1, 0, 0], [0, 0, 0], 30)
    middle = teleop.q.copy()
    teleop.mark()
    now = drive(teleop, [0, 1, 0], [0, 0, 0], 30, now)
    teleop.reverse(now)
    while teleop.reversing:
        now += DT
        teleop.tick(now)
    np.testing.assert_allclose(teleop.q, middle, atol=1e-9)


def test_halt_ignores_commands_until_resume(ur5):
    teleop = Teleop(ur5, dt=DT)
    teleop.halt()
    start = teleop.q.copy()
    drive(teleop, [1, 0, 0], [0, 0, 0], 10)
    np.testing.assert_array_equal(teleop.q, start)
    teleop.resume()
    drive(teleop, [1, 0, 0], [0, 0, 0], 10)
    assert not np.array_equal(teleop.q, start)


def test_a_joint_driven_into_its_limit_is_held_there_and_named(ur5):
    wrist_3 = ur5.joint_id("wrist_3_joint")
    index = ur5.model.joints[wrist_3].idx_q
    upper = ur5.model.upperPositionLimit[index]
    q0 = ur5.home()
    q0[index] = upper - 0.05
    teleop = Teleop(ur5, q0, dt=DT, max_angular_speed=0.5)
    statuses = []
    now = 0.0
    for _ in range(60):  # tool0's z is wrist_3's axis: rotating about it drives wrist_3 up
        teleop.command([0, 0, 0], [0, 0, 1], now=now)
        now += DT
        step = teleop.tick(now)
        statuses.append(step.status)
        assert teleop.q[index] <= upper
    assert Status.JOINT_LIMIT in statuses
    assert "wrist_3_joint" in step.detail
    assert teleop.q[index] == pytest.approx(upper)


def test_configure_changes_the_strategy_and_keeps_q(ur5):
    teleop = Teleop(ur5, dt=DT)
    drive(teleop, [1, 0, 0], [0, 0, 0], 5)
    q = teleop.q.copy()
    teleop.configure(singularity="freeze", wrist="hold_first")
    assert teleop.controller.singularity == "freeze"
    assert teleop.controller.wrist == "hold_first"
    np.testing.assert_array_equal(teleop.q, q)
    with pytest.raises(InputError, match="decelerate"):
        teleop.configure(singularity="pray")
    assert teleop.controller.singularity == "freeze"


def test_reset_goes_home_and_forgets(ur5):
    teleop = Teleop(ur5, dt=DT)
    drive(teleop, [1, 0, 0], [0, 0, 0], 20)
    teleop.reset()
    np.testing.assert_array_equal(teleop.q, ur5.home())
    assert not teleop.reverse()


def test_recording_keeps_every_tick_and_saves(ur5, tmp_path):
    teleop = Teleop(ur5, dt=DT)
    teleop.start_recording()
    now = drive(teleop, [1, 0, 0], [0, 0, 0], 30)
    recording = teleop.stop_recording()
    assert len(recording) == 30
    np.testing.assert_array_equal(recording.q[-1], teleop.q)
    assert recording.times[-1] == pytest.approx(now)
    path = recording.save(tmp_path / "run.npz")
    loaded = pinrate.teleop.Recording.load(path)
    np.testing.assert_array_equal(loaded.q, recording.q)
    np.testing.assert_array_equal(loaded.joint_rates, recording.joint_rates)
    assert list(loaded.status) == list(recording.status)
    assert loaded.robot_name == "ur5"
    frames = recording.frames(fps=10)
    assert frames.shape == (1 + math.floor((30 * DT - DT) * 10 + 0.5) + 1, ur5.nq) or frames.shape[0] >= 3
    np.testing.assert_array_equal(frames[0], ur5.home())
    with pytest.raises(InputError, match="not recording"):
        teleop.stop_recording()


@pytest.mark.parametrize(
    ("call", "match"),
    [
        (lambda t: t.command([1, 0], [0, 0, 0]), "shape"),
        (lambda t: t.command([math.nan, 0, 0], [0, 0, 0]), "NaN"),
        (lambda t: t.command([1, 0, 0], "up"), "angular"),
        (lambda t: t.tick(now=math.inf), "finite"),
        (lambda t: t.tick(now="soon"), "seconds"),
        (lambda t: setattr(t, "frame", "world"), "hand, base"),
    ],
)
def test_bad_input_is_an_input_error(ur5, call, match):
    teleop = Teleop(ur5, dt=DT)
    with pytest.raises(InputError, match=match):
        call(teleop)


def test_bad_construction_is_an_input_error(ur5):
    with pytest.raises(InputError, match="timeout"):
        Teleop(ur5, timeout=0)
    with pytest.raises(InputError, match="max_linear_speed"):
        Teleop(ur5, max_linear_speed=-1)
    with pytest.raises(InputError, match="algorithm"):
        Teleop(ur5, algorithm="magic")
    with pytest.raises(InputError, match="robot"):
        Teleop("ur5")
