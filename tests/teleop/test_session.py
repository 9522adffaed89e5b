"""Barker's operator loop (pinrate.Teleop, contract v2): deflections scaled by the max speeds
in the hand or base axes, one controller step per tick, the dead man, reverse."""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin
import pytest

import pinrate
from pinrate import InputError, Status, Teleop
from pinrate.control.singularity import STRATEGIES, WRIST_STRATEGIES
from support import EPS, fuzz_count

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


def test_a_command_over_the_linear_speed_keeps_its_screw(ur5):
    """Contract v2.1: two linear axes fully deflected (|v| = sqrt(2) x 0.05 m/s) and one angular
    (0.25 rad/s, within its limit) are scaled by one factor, 1/sqrt(2): the hand moves along
    the commanded screw, slower (scaling the linear part alone would turn it less per metre)."""
    teleop = Teleop(ur5, dt=DT, max_linear_speed=0.05, max_angular_speed=0.25)
    teleop.command([1, 1, 0], [0, 0, 1], now=0.0)
    step = teleop.tick(0.0)
    np.testing.assert_allclose(step.twist, np.array([0.05, 0.05, 0, 0, 0, 0.25]) / np.sqrt(2), rtol=1e-12)
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


def test_reverse_while_halted_is_refused_and_the_robot_stays(ur5):
    teleop = Teleop(ur5, dt=DT)
    now = drive(teleop, [1, 0, 0], [0, 0, 0], 30)
    teleop.halt()
    held = teleop.q.copy()
    with pytest.raises(InputError, match="halted: resume first"):
        teleop.reverse(now)
    assert not teleop.reversing and teleop.halted
    for _ in range(30):
        now += DT
        teleop.tick(now)
    np.testing.assert_array_equal(teleop.q, held)  # a halted robot does not move
    teleop.resume()
    assert teleop.reverse(now)  # resumed: the way back is still there
    now, _ = retrace(teleop, now)
    np.testing.assert_allclose(teleop.q, ur5.home(), atol=1e-9)


def test_the_dead_man_says_why_it_stopped_until_the_operator_drives_again(ur5):
    teleop = Teleop(ur5, dt=DT, timeout=0.25)
    now = drive(teleop, [1, 0, 0], [0, 0, 0], 10)
    assert teleop.dead_man == ""
    while now < 10 * DT + 0.25 + 2 * DT:  # the page goes silent with the stick held
        now += DT
        step = teleop.tick(now)
    assert not step.joint_rates.any()
    assert teleop.dead_man == "no input for 0.25 s"
    teleop.command([0, 0, 0], [0, 0, 0], now=now)  # the page speaks again, stick released
    teleop.tick(now + DT)
    assert teleop.dead_man == "no input for 0.25 s"  # latched: the page can still see why
    teleop.command([0, 1, 0], [0, 0, 0], now=now + DT)
    assert teleop.dead_man == ""
    assert teleop.tick(now + 2 * DT).joint_rates.any()
    # stopped by the console for a reason of its own; a still robot says nothing
    assert teleop.dead_man_stop("the controlling page is gone")
    assert teleop.dead_man == "the controlling page is gone"
    assert not teleop.dead_man_stop("the page froze")  # nothing moved since: the first reason stays
    assert teleop.dead_man == "the controlling page is gone"
    teleop.resume()
    assert teleop.dead_man == ""
    assert not teleop.dead_man_stop("the controlling page is gone")
    assert teleop.dead_man == ""


def test_a_jog_moves_the_named_joint_alone_and_the_dead_man_stops_it(ur5):
    teleop = Teleop(ur5, dt=DT, timeout=0.25)
    start = teleop.q.copy()
    elbow = ur5.model.joints[ur5.joint_id("elbow_joint")].idx_q
    now = 0.0
    for _ in range(50):  # the button held: the page's heartbeat refreshes the jog
        teleop.jog({"elbow_joint": -0.3}, now=now)
        now += DT
        teleop.tick(now)
    others = np.delete(np.arange(ur5.nq), elbow)
    np.testing.assert_array_equal(teleop.q[others], start[others])  # exactly still
    assert teleop.q[elbow] - start[elbow] == pytest.approx(-0.3 * 50 * DT, rel=1e-12)
    held = teleop.q.copy()
    for _ in range(40):  # silent: the jog expires
        now += DT
        teleop.tick(now)
    assert teleop.q[elbow] - held[elbow] == pytest.approx(-0.3 * (0.25 - DT), abs=0.3 * DT * 1.01)
    assert teleop.dead_man == "no input for 0.25 s"
    assert teleop.reverse(now)  # a jog is motion: the way back retraces it
    retrace(teleop, now)
    np.testing.assert_allclose(teleop.q, start, atol=1e-9)
    with pytest.raises(InputError, match="elbow_joint"):
        teleop.jog({"elbow": 0.1})
    with pytest.raises(InputError, match="finite"):
        teleop.jog({"elbow_joint": math.nan})


def wrist_centre(robot: pinrate.Robot, q: np.ndarray, first: str, second: str) -> np.ndarray:
    """The midpoint of the common perpendicular of two joints' axes (world, m), from
    Pinocchio's joint placements and each joint's own axis (RX/RY/RZ)."""
    data = robot.model.createData()
    pin.forwardKinematics(robot.model, data, q)
    lines = []
    for name in (first, second):
        joint = robot.joint_id(name)
        local = np.eye(3)["XYZ".index(robot.model.joints[joint].shortname()[-1])]
        lines.append((np.array(data.oMi[joint].translation), data.oMi[joint].rotation @ local))
    (p, a), (r, b) = lines
    # p + s a and r + t b closest: solve [a -b] [s t] = r - p in the least-squares sense
    s, t = np.linalg.lstsq(np.column_stack([a, -b]), r - p, rcond=None)[0]
    return 0.5 * (p + s * a + r + t * b)


def test_uncoupled_translation_moves_the_wrist_centre_and_keeps_the_wrist_still(ur5):
    # the world's axes: the hand's turn with the forearm, since the wrist does not move
    teleop = Teleop(ur5, dt=DT, max_linear_speed=0.08, frame="base")
    wrist = [ur5.model.joints[ur5.joint_id(name)].idx_q for name in teleop.controller.partition.wrist]
    start = teleop.q.copy()
    centre = wrist_centre(ur5, start, "wrist_1_joint", "wrist_2_joint")
    now = 0.0
    for _ in range(50):
        teleop.command([1, 0, 0], [0, 0, 0], now=now, mode="uncoupled")
        now += DT
        teleop.tick(now)
    np.testing.assert_array_equal(teleop.q[wrist], start[wrist])  # the wrist joints exactly still
    travel = wrist_centre(ur5, teleop.q, "wrist_1_joint", "wrist_2_joint") - centre
    assert travel[0] == pytest.approx(0.08 * 50 * DT, rel=1e-3)  # the wrist centre along the world's x
    assert np.linalg.norm(travel[1:]) < 5e-3 * travel[0]  # Euler steps on a curved path: O(dt)
    moved = teleop.q.copy()
    for _ in range(20):  # a rotation key pair: one wrist joint each
        teleop.command([0, 0, 0], [0, 1, 0], now=now, mode="uncoupled")
        now += DT
        teleop.tick(now)
    changed = np.flatnonzero(teleop.q != moved)
    assert changed.tolist() == [wrist[1]]
    assert teleop.q[wrist[1]] - moved[wrist[1]] == pytest.approx(0.5 * 20 * DT, rel=1e-12)
    with pytest.raises(InputError, match="uncoupled"):
        teleop.command([1, 0, 0], [0, 0, 0], mode="coupled")


def test_an_uncoupled_diagonal_is_no_faster_than_one_axis(ur5):
    """Two axes fully deflected move the wrist centre at max_linear_speed, not sqrt(2) x it."""
    teleop = Teleop(ur5, dt=DT, max_linear_speed=0.08, frame="base")
    centre = wrist_centre(ur5, teleop.q, "wrist_1_joint", "wrist_2_joint")
    now = 0.0
    for _ in range(50):
        teleop.command([1, 1, 0], [0, 0, 0], now=now, mode="uncoupled")
        now += DT
        teleop.tick(now)
    travel = wrist_centre(ur5, teleop.q, "wrist_1_joint", "wrist_2_joint") - centre
    assert np.linalg.norm(travel) == pytest.approx(0.08 * 50 * DT, rel=5e-3)  # Euler steps on a curve: O(dt)
    assert travel[0] == pytest.approx(travel[1], rel=1e-2)  # still the diagonal


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


def retrace(teleop: Teleop, now: float, limit: int = 10_000) -> tuple[float, int]:
    """Tick until the reversal ends (at most ``limit`` ticks); (now, ticks)."""
    ticks = 0
    while teleop.reversing and ticks < limit:
        now += DT
        teleop.tick(now)
        ticks += 1
    assert not teleop.reversing
    return now, ticks


def half_reversed(teleop: Teleop) -> tuple[np.ndarray, float]:
    """From the start, 60 ticks along x, then half of that retraced; (start, now)."""
    start = teleop.q.copy()
    now = drive(teleop, [1, 0, 0], [0, 0, 0], 60)
    assert teleop.reverse(now)
    for _ in range(30):
        now += DT
        teleop.tick(now)
    assert teleop.reversing
    return start, now


def test_a_mark_during_a_reversal_waits_for_its_end(ur5):
    teleop = Teleop(ur5, dt=DT)
    start, now = half_reversed(teleop)
    teleop.mark()  # the operator marks while the robot retraces: it keeps retracing
    assert teleop.reversing
    now, ticks = retrace(teleop, now)
    assert ticks == pytest.approx(30, abs=2)  # the rest of the way, at the recorded pace
    np.testing.assert_allclose(teleop.q, start, atol=1e-9)
    assert not teleop.reverse(now)  # the new segment starts here: nothing to retrace yet
    now = drive(teleop, [0, 1, 0], [0, 0, 0], 20, now)
    assert teleop.reverse(now)
    retrace(teleop, now)
    np.testing.assert_allclose(teleop.q, start, atol=1e-9)


@pytest.mark.parametrize("end", ["command", "stop", "halt"])
def test_a_mark_during_a_reversal_starts_the_segment_where_it_was_ended(ur5, end):
    teleop = Teleop(ur5, dt=DT)
    _, now = half_reversed(teleop)
    teleop.mark()
    if end == "command":
        teleop.command([0, 0, 1], [0, 0, 0], now=now + DT)
        there = teleop.q.copy()
        now = drive(teleop, [0, 0, 1], [0, 0, 0], 20, now + DT)
    else:
        getattr(teleop, end)()
        there = teleop.q.copy()
        teleop.resume()
        now = drive(teleop, [0, 0, 1], [0, 0, 0], 20, now)
    assert not teleop.reversing
    assert teleop.reverse(now)
    retrace(teleop, now)
    np.testing.assert_allclose(teleop.q, there, atol=1e-9)  # not back to the old start


def test_recording_during_a_reversal_keeps_its_ticks_and_marks_at_its_end(ur5):
    teleop = Teleop(ur5, dt=DT)
    start, now = half_reversed(teleop)
    there = teleop.q.copy()
    teleop.start_recording()  # R pressed while B runs
    assert teleop.reversing and teleop.recording
    now, ticks = retrace(teleop, now)
    np.testing.assert_allclose(teleop.q, start, atol=1e-9)
    now = drive(teleop, [0, 1, 0], [0, 0, 0], 10, now)
    recording = teleop.stop_recording()
    assert len(recording) == ticks + 10
    np.testing.assert_array_equal(recording.start, there)
    np.testing.assert_allclose(recording.q[ticks - 1], start, atol=1e-9)  # the reversal is in the run
    assert teleop.reverse(now)
    retrace(teleop, now)
    np.testing.assert_allclose(teleop.q, start, atol=1e-9)  # the segment began where the reversal ended


def test_reverse_and_configure_during_a_reversal_let_it_go_on(ur5):
    teleop = Teleop(ur5, dt=DT)
    start, now = half_reversed(teleop)
    distance = float(np.linalg.norm(teleop.q - start))
    assert teleop.reverse(now)  # pressed again: it goes on, not back to where it began
    teleop.configure(singularity="freeze")
    assert teleop.reversing
    now += DT
    teleop.tick(now)
    assert np.linalg.norm(teleop.q - start) < distance
    retrace(teleop, now)
    np.testing.assert_allclose(teleop.q, start, atol=1e-9)


def test_a_recording_is_not_restarted_unsaved(ur5):
    teleop = Teleop(ur5, dt=DT)
    teleop.start_recording()
    drive(teleop, [1, 0, 0], [0, 0, 0], 5)
    with pytest.raises(InputError, match="already recording"):
        teleop.start_recording()
    assert len(teleop.stop_recording()) == 5


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


# ---------------------------------------------------------------------- the operator, at random
FUZZ_OPERATIONS = 500
"""Random public calls per sequence (``fuzz_count`` sequences per robot)."""

LIMIT_SLACK_ULPS = 4.0
"""A joint stopped on its limit lands there up to rounding: q + ((limit - q) / dt) * dt is
within a few ulps of the limit (two roundings, each half an ulp of a number at most as big)."""

PLAYBACK_DONE = 1e-12
"""A playback ends when its last step achieved at least 1 - this share of the step to the
oldest configuration (recorder.Playback.step): what the reversal may leave of that step."""


def return_tolerance(q: np.ndarray, last_step: np.ndarray) -> float:
    """How far a reversal that ran to completion may end from its segment's start: the share
    of the last step the playback may leave undone, plus the rounding of pinocchio's
    difference and integrate in that step (a few ulps of the largest coordinate) and of the
    interpolated target (an ulp of the motion clock over a sample's span, far below that)."""
    return PLAYBACK_DONE * float(np.abs(last_step).max()) + 64 * EPS * max(1.0, float(np.abs(q).max()))


class Operator:
    """Random public calls on a Teleop with a model of what the documentation promises,
    checked after every call; ``log`` keeps the calls for the failure message."""

    def __init__(self, robot: pinrate.Robot, seed: int, tmp_path) -> None:
        self.robot = robot
        self.rng = np.random.default_rng(seed)
        self.tmp_path = tmp_path
        self.teleop = Teleop(robot, dt=DT, timeout=0.25)
        self.lower, self.upper = robot.position_limits()
        self.slack = LIMIT_SLACK_ULPS * EPS * np.maximum(1.0, np.maximum(np.abs(self.lower), np.abs(self.upper)))
        self.now = 0.0
        self.held = (False, -math.inf)  # (a non-zero deflection, its time)
        self.reversed_at = -math.inf
        self.halted = False
        self.segment_start = self.teleop.q.copy()
        self.pending_mark = False  # a mark made during a reversal, due when it ends
        self.recording: dict | None = None
        self.saved = 0
        self.log: list[str] = []

    # ------------------------------------------------------------------ the calls
    def run(self, operations: int) -> None:
        names, weights = zip(
            *[
                ("command", 20),
                ("jog", 4),
                ("tick", 40),
                ("reverse", 5),
                ("stop", 2),
                ("halt", 1),
                ("resume", 2),
                ("mark", 3),
                ("reset", 0.5),
                ("configure", 1),
                ("frame", 1),
                ("start_recording", 2),
                ("stop_recording", 2),
                ("invalid", 3),
            ],
            strict=True,
        )
        p = np.array(weights) / sum(weights)
        for _ in range(operations):
            getattr(self, "do_" + names[self.rng.choice(len(names), p=p)])()
            self.check_state()

    def do_command(self) -> None:
        if self.rng.random() < 0.3:
            linear, angular = np.zeros(3), np.zeros(3)
        else:
            linear, angular = self.rng.uniform(-1, 1, 3), self.rng.uniform(-1, 1, 3)
        mode = "uncoupled" if self.rng.random() < 0.25 else "twist"
        self.log.append(f"command({linear.tolist()}, {angular.tolist()}, now={self.now!r}, mode={mode!r})")
        self.teleop.command(linear, angular, now=self.now, mode=mode)
        self.held = (bool(linear.any() or angular.any()), self.now)

    def do_jog(self) -> None:
        names = self.robot.joint_names
        chosen = self.rng.choice(len(names), size=int(self.rng.integers(0, 3)), replace=False)
        rates = {names[i]: float(self.rng.uniform(-1, 1)) for i in chosen}
        self.log.append(f"jog({rates}, now={self.now!r})")
        self.teleop.jog(rates, now=self.now)
        self.held = (any(rates.values()), self.now)

    def do_tick(self) -> None:
        draw = self.rng.random()
        if draw < 0.8:
            self.now += DT
        elif draw < 0.9:
            self.now += self.teleop.timeout * self.rng.uniform(1.0, 4.0)  # past the dead man
        self.log.append(f"tick({self.now!r})")
        teleop = self.teleop
        was_reversing, before = teleop.reversing, teleop.q.copy()
        nonzero, stamp = self.held
        fresh = not self.halted and self.now - stamp <= teleop.timeout
        interrupted = was_reversing and nonzero and fresh and stamp > self.reversed_at
        step = teleop.tick(self.now)
        np.testing.assert_array_equal(teleop.q, step.q)
        if self.halted and not was_reversing:  # zero rates: q itself, up to renormalising a continuous joint
            moved = float(np.abs(pin.difference(self.robot.model, before, teleop.q)).max())
            assert moved <= 4 * EPS, f"a halted Teleop moved by {moved:.3g}"
        if self.recording is not None:
            self.recording["times"].append(self.now)
            self.recording["last_q"] = step.q.copy()
        if was_reversing and not teleop.reversing:
            if not interrupted:  # ran to completion: back at the start of the segment
                error = float(np.abs(teleop.q - self.segment_start).max())
                assert error <= return_tolerance(teleop.q, step.joint_rates * DT), (
                    f"the reversal ended {error:.3g} from the segment's start"
                )
                assert not teleop.reverse(self.now), "a completed reversal left motion to retrace"
                self.segment_start = teleop.q.copy()  # the record is this configuration alone
            elif self.pending_mark:  # the new segment starts where the command ended the reversal
                self.segment_start = before
            self.pending_mark = False
        if was_reversing and teleop.reversing:
            assert not interrupted, "a fresh command did not end the reversal"

    def do_reverse(self) -> None:
        self.log.append(f"reverse({self.now!r})")
        was_reversing = self.teleop.reversing
        if self.halted:  # refused: a halted robot does not move
            with pytest.raises(InputError, match="halted: resume first"):
                self.teleop.reverse(self.now)
            assert not self.teleop.reversing
            return
        started = self.teleop.reverse(self.now)
        assert self.teleop.reversing is (started or was_reversing)
        if was_reversing:
            assert started, "reverse() during a reversal keeps it running"
        if started:
            self.reversed_at = self.now
            self.held = (False, -math.inf)

    def _ended_by_call(self) -> None:
        """A reversal ended by a call (stop, halt): the record ends where the robot is."""
        if self.pending_mark:
            self.segment_start = self.teleop.q.copy()
            self.pending_mark = False

    def do_stop(self) -> None:
        self.log.append("stop()")
        self.teleop.stop()
        assert not self.teleop.reversing
        self.held = (False, -math.inf)
        self._ended_by_call()

    def do_halt(self) -> None:
        self.log.append("halt()")
        self.teleop.halt()
        assert not self.teleop.reversing and self.teleop.halted
        self.held = (False, -math.inf)
        self.halted = True
        self._ended_by_call()

    def do_resume(self) -> None:
        self.log.append("resume()")
        self.teleop.resume()
        assert not self.teleop.halted
        self.halted = False

    def do_mark(self) -> None:
        self.log.append("mark()")
        reversing = self.teleop.reversing
        self.teleop.mark()
        assert self.teleop.reversing is reversing, "mark() does not change the motion"
        self._mark(reversing)

    def _mark(self, reversing: bool) -> None:
        if reversing:
            self.pending_mark = True
        else:
            self.segment_start = self.teleop.q.copy()

    def do_reset(self) -> None:
        q = self.robot.random_configuration(self.rng) if self.rng.random() < 0.5 else None
        self.log.append(f"reset({None if q is None else q.tolist()})")
        self.teleop.reset(q)
        expected = self.robot.home() if q is None else q
        np.testing.assert_array_equal(self.teleop.q, expected)
        assert not self.teleop.reversing
        if not self.halted:
            assert not self.teleop.reverse(self.now), "reset() forgets the record"
        self.held = (False, -math.inf)
        self.segment_start = expected.copy()
        self.pending_mark = False

    def do_configure(self) -> None:
        options = {
            "singularity": str(self.rng.choice(STRATEGIES)),
            "wrist": str(self.rng.choice(WRIST_STRATEGIES)),
        }
        self.log.append(f"configure(**{options})")
        reversing, q = self.teleop.reversing, self.teleop.q.copy()
        self.teleop.configure(**options)
        np.testing.assert_array_equal(self.teleop.q, q)
        assert self.teleop.reversing is reversing, "configure() does not change the motion"

    def do_frame(self) -> None:
        frame = str(self.rng.choice(["hand", "base"]))
        self.log.append(f"frame = {frame!r}")
        self.teleop.frame = frame

    def do_start_recording(self) -> None:
        max_samples = int(self.rng.integers(1, 40)) if self.rng.random() < 0.5 else 2_000_000
        self.log.append(f"start_recording({max_samples})")
        if self.recording is not None:
            with pytest.raises(InputError, match="already recording"):
                self.teleop.start_recording(max_samples)
            return
        reversing = self.teleop.reversing
        self.teleop.start_recording(max_samples)
        assert self.teleop.recording and self.teleop.reversing is reversing
        self.recording = {"max_samples": max_samples, "times": [], "start": self.teleop.q.copy(), "last_q": None}
        self._mark(reversing)

    def do_stop_recording(self) -> None:
        self.log.append("stop_recording()")
        if self.recording is None:
            with pytest.raises(InputError, match="not recording"):
                self.teleop.stop_recording()
            return
        recording, expected = self.teleop.stop_recording(), self.recording
        self.recording = None
        kept = expected["times"][-expected["max_samples"] :]
        assert len(recording) == len(kept)
        assert recording.times.tobytes() == np.array(kept, dtype=float).tobytes()  # as given to tick
        assert np.all(np.diff(recording.times) >= 0)
        np.testing.assert_array_equal(recording.start, expected["start"])
        assert recording.q.shape == (len(kept), self.robot.nq)
        assert recording.joint_rates.shape == (len(kept), self.robot.nv)
        if kept:
            np.testing.assert_array_equal(recording.q[-1], expected["last_q"])
        if self.saved < 3 or not kept:  # every empty one, and a few others
            self.saved += 1
            loaded = pinrate.teleop.Recording.load(recording.save(self.tmp_path / f"run-{self.saved}.npz"))
            for column in ("times", "q", "joint_rates", "status", "detail"):
                assert getattr(loaded, column).tobytes() == getattr(recording, column).tobytes(), column
        frames = recording.frames(fps=float(self.rng.uniform(1, 60)))
        assert frames.shape[1:] == (self.robot.nq,) and len(frames) >= 1 + min(1, len(kept))
        np.testing.assert_array_equal(frames[0], expected["start"])

    def do_invalid(self) -> None:
        teleop = self.teleop
        calls = [
            ("command([1, 0], [0, 0, 0])", lambda: teleop.command([1, 0], [0, 0, 0], now=self.now)),
            ("command([nan, 0, 0], [0, 0, 0])", lambda: teleop.command([math.nan, 0, 0], [0, 0, 0], now=self.now)),
            ("tick(nan)", lambda: teleop.tick(math.nan)),
            ("jog({'nothing': 1})", lambda: teleop.jog({"nothing": 1.0}, now=self.now)),
            ("command(mode='both')", lambda: teleop.command([0, 0, 0], [0, 0, 0], now=self.now, mode="both")),
            ("reverse('soon')", lambda: teleop.reverse("soon")),
            ("reset(q of the wrong size)", lambda: teleop.reset(np.zeros(self.robot.nq + 1))),
            ("configure(singularity='pray')", lambda: teleop.configure(singularity="pray")),
            ("frame = 'world'", lambda: setattr(teleop, "frame", "world")),
        ]
        if not teleop.recording:
            calls.append(("start_recording(0)", lambda: teleop.start_recording(0)))
        text, call = calls[self.rng.integers(len(calls))]
        self.log.append(text + "  # invalid")
        q, reversing, recording, halted = teleop.q.copy(), teleop.reversing, teleop.recording, teleop.halted
        with pytest.raises(InputError):
            call()
        np.testing.assert_array_equal(teleop.q, q)
        assert (teleop.reversing, teleop.recording, teleop.halted) == (reversing, recording, halted)

    # ------------------------------------------------------------------ after every call
    def check_state(self) -> None:
        q = self.teleop.q
        assert np.isfinite(q).all(), "q is not finite"
        outside = (q < self.lower - self.slack) | (q > self.upper + self.slack)
        assert not outside.any(), f"q outside the position limits at {np.flatnonzero(outside)}: {q}"
        assert self.teleop.halted is self.halted


@pytest.mark.parametrize("name", ["ur5", "barker_arm"])
def test_random_operator_calls_keep_every_promise(name, tmp_path):
    """Random public calls in random order (seeded, bounded): no exception but the
    documented InputErrors, q finite and within the limits, a stop ends a reversal, a
    completed reversal is back at its segment's start, a recording holds every tick."""
    robot = pinrate.load(name)
    for seed in range(fuzz_count(20)):
        operator = Operator(robot, seed, tmp_path)
        try:
            operator.run(FUZZ_OPERATIONS)
        except (Exception, pytest.fail.Exception) as error:
            calls = "\n    ".join(operator.log[-25:])
            where = f"{name}, seed {seed}, after {len(operator.log)} calls"
            raise AssertionError(f"{where}; the last:\n    {calls}\n{type(error).__name__}: {error}") from error
