"""Recording and reversing a motion (Barker's evacuation, issue 11): the playback retraces the
recorded configurations backwards, returns to the start within 1e-6, and keeps every limit."""

from __future__ import annotations

import numpy as np
import pytest

import pinrate
from pinrate import Controller, InputError, Status
from pinrate.control.recorder import Recorder


def record_motion(controller: Controller, seconds: float, seed: int = 1) -> tuple[Recorder, np.ndarray]:
    """A wandering motion under random twists, recorded every step; (recorder, first q)."""
    robot = controller.robot
    rng = np.random.default_rng(seed)
    recorder = Recorder(history=60.0)
    q = robot.home()
    start = q.copy()
    twist = rng.normal(size=6) * 0.05
    for index in range(round(seconds / controller.dt)):
        recorder.record(index * controller.dt, q)
        if index % 25 == 0:
            twist = rng.normal(size=6) * 0.05
        q = controller.step(q, twist).q
    return recorder, start


@pytest.mark.parametrize("name", ["ur5", "panda"])
def test_the_playback_retraces_the_recording_and_returns_to_the_start(name: str) -> None:
    controller = Controller(pinrate.load(name))
    recorder, start = record_motion(controller, 2.0)
    recorded = recorder.configurations
    playback = recorder.playback(controller)
    q = recorded[-1]
    visited = []
    while not playback.done:
        q = playback.step(q).q
        visited.append(q)
    # at the recorded pace: one playback step per recorded step, through the same configurations
    assert len(visited) == len(recorded) - 1
    np.testing.assert_allclose(np.array(visited), recorded[-2::-1], atol=1e-9)
    np.testing.assert_allclose(q, start, atol=1e-6)


def test_a_slower_velocity_limit_slows_the_playback_but_keeps_the_path() -> None:
    robot = pinrate.load("ur5")
    recorder, start = record_motion(Controller(robot), 2.0, seed=3)
    recorded_speed = np.abs(np.diff(recorder.configurations, axis=0)).max() / 0.01
    slow = Controller(robot, velocity_limits=0.5 * recorded_speed)
    playback = recorder.playback(slow)
    q = recorder.configurations[-1]
    steps = 0
    while not playback.done and steps < 10_000:
        step = playback.step(q)
        assert np.all(np.abs(step.joint_rates) <= slow.velocity_limits + 1e-12)
        q = step.q
        steps += 1
    assert playback.done and steps > len(recorder)  # slower than recorded
    np.testing.assert_allclose(q, start, atol=1e-6)


def test_the_recorder_keeps_only_its_history_and_its_bound() -> None:
    recorder = Recorder(history=1.0, max_samples=50)
    for index in range(300):
        recorder.record(index * 0.01, np.array([index * 0.01]))
    assert len(recorder) == 50  # the sample bound bites first
    assert recorder.times[0] == pytest.approx(2.5) and recorder.times[-1] == pytest.approx(2.99)
    spaced = Recorder(history=1.0)
    for index in range(300):
        spaced.record(index * 0.01, np.array([0.0]))
    assert spaced.times[-1] - spaced.times[0] <= 1.0 + 1e-12


def test_bad_recordings_are_input_errors() -> None:
    recorder = Recorder()
    recorder.record(1.0, np.zeros(6))
    with pytest.raises(InputError, match="before the newest"):
        recorder.record(0.5, np.zeros(6))
    with pytest.raises(InputError, match="finite"):
        recorder.record(float("nan"), np.zeros(6))
    with pytest.raises(InputError, match="fewer than two"):
        recorder.playback(Controller(pinrate.load("ur5")))
    with pytest.raises(InputError, match="history"):
        Recorder(history=0.0)


def test_a_playback_step_is_a_controller_step_with_its_limits() -> None:
    robot = pinrate.load("ur5")
    recorder = Recorder()
    q = robot.home()
    far = q.copy()
    far[0] += 1.0  # 1 rad in 0.5 s: 2 rad/s, over the 1 rad/s limit
    recorder.record(0.0, far)
    recorder.record(0.5, q)
    step = recorder.playback(Controller(robot, velocity_limits=1.0)).step(q)
    assert step.status is Status.RATE_LIMITED and abs(step.joint_rates[0]) == pytest.approx(1.0)


def test_bad_configurations_are_input_errors_and_a_stuck_playback_ends() -> None:
    recorder = Recorder()
    with pytest.raises(InputError, match="vector of numbers"):
        recorder.record(0.0, "abc")
    recorder.record(0.0, np.zeros(6))
    with pytest.raises(InputError, match="shape"):
        recorder.record(0.1, np.zeros(5))
    robot = pinrate.load("ur5")
    beyond = robot.home()
    beyond[2] = robot.joint_limits("elbow_joint")[1] + 0.5  # recorded past a limit: unreachable
    stuck = Recorder()
    stuck.record(0.0, beyond)
    at_limit = robot.home()
    at_limit[2] = robot.joint_limits("elbow_joint")[1]
    stuck.record(0.01, at_limit)
    playback = stuck.playback(Controller(robot))
    q = at_limit
    for _ in range(10):
        if playback.done:
            break
        q = playback.step(q).q
    assert playback.done and "could not move" in playback.stopped
    with pytest.raises(InputError, match="coordinates"):
        stuck.playback(Controller(pinrate.load("panda")))
