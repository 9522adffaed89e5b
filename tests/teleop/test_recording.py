"""A teleoperated run kept tick by tick (pinrate.teleop.Recording): the times as the ticks were
given, zero ticks a valid run, frames at a frame rate, and save/load giving every column back
bit for bit."""

from __future__ import annotations

import time

import numpy as np
import pytest

from pinrate import InputError, PinrateError, Status, Teleop
from pinrate.teleop import Recording
from pinrate.teleop.recording import FORMAT

DT = 0.01
COLUMNS = ("times", "q", "joint_rates", "status", "detail")


def assert_same_bits(loaded: Recording, recording: Recording) -> None:
    """Every column and every field of the two recordings equal bit for bit (dtype too)."""
    for column in COLUMNS:
        a, b = getattr(loaded, column), getattr(recording, column)
        assert (a.dtype, a.shape) == (b.dtype, b.shape), column
        assert a.tobytes() == b.tobytes(), column
    assert (loaded.robot_name, loaded.joint_names, loaded.nq, loaded.nv) == (
        recording.robot_name,
        recording.joint_names,
        recording.nq,
        recording.nv,
    )
    assert np.float64(loaded.dt).tobytes() == np.float64(recording.dt).tobytes()
    assert (loaded.start is None) == (recording.start is None)
    if recording.start is not None:
        assert loaded.start.tobytes() == recording.start.tobytes()


def run(teleop: Teleop, times: list[float], linear=(1, 0, 0), angular=(0, 0, 0)) -> None:
    """A fresh command and a tick at each of ``times``."""
    for now in times:
        teleop.command(linear, angular, now=now)
        teleop.tick(now)


def test_zero_ticks_is_a_valid_recording_that_round_trips(ur5, tmp_path):
    teleop = Teleop(ur5, dt=DT)
    teleop.start_recording()
    recording = teleop.stop_recording()
    assert len(recording) == 0
    assert recording.times.shape == (0,)
    assert recording.q.shape == (0, ur5.nq) and recording.joint_rates.shape == (0, ur5.nv)
    assert recording.status.shape == recording.detail.shape == (0,)
    np.testing.assert_array_equal(recording.frames(), ur5.home()[None, :])  # the start alone
    loaded = Recording.load(recording.save(tmp_path / "empty.npz"))
    assert len(loaded) == 0
    assert_same_bits(loaded, recording)
    np.testing.assert_array_equal(loaded.frames(fps=5), ur5.home()[None, :])
    assert Recording(None, DT).frames().shape == (0, 0)  # no robot, no start: no frame


@pytest.mark.parametrize("fps", [0.5, 30.0, 1000.0])
def test_one_tick_gives_the_start_and_that_tick(ur5, fps):
    teleop = Teleop(ur5, dt=DT)
    teleop.start_recording()
    run(teleop, [3.0])
    recording = teleop.stop_recording()
    frames = recording.frames(fps)
    assert frames.shape == (2, ur5.nq)
    np.testing.assert_array_equal(frames[0], ur5.home())
    np.testing.assert_array_equal(frames[1], teleop.q)


def test_times_are_the_ticks_times_as_given(ur5):
    teleop = Teleop(ur5, dt=DT)
    rng = np.random.default_rng(7)
    given = list(np.cumsum(rng.choice([0.0, 0.001, DT, 0.3], size=80)) + 1e5)  # repeats, jumps, a big clock
    teleop.start_recording()
    run(teleop, given)
    recording = teleop.stop_recording()
    assert recording.times.tobytes() == np.array(given, dtype=float).tobytes()
    assert np.all(np.diff(recording.times) >= 0)


def test_a_tick_dated_before_the_previous_is_kept_at_its_time(ur5):
    teleop = Teleop(ur5, dt=DT)
    teleop.start_recording()
    run(teleop, [2.0, 2.5, 2.25, 3.0])
    recording = teleop.stop_recording()
    np.testing.assert_array_equal(recording.times, [2.0, 2.5, 2.5, 3.0])  # never decreasing
    assert len(recording) == 4


def test_ticks_without_a_time_are_on_the_monotonic_clock(ur5):
    teleop = Teleop(ur5, dt=DT)
    teleop.start_recording()
    before = time.monotonic()
    for _ in range(20):
        teleop.tick()
    after = time.monotonic()
    times = teleop.stop_recording().times
    assert np.all(np.diff(times) >= 0) and before <= times[0] and times[-1] <= after


def test_the_recording_keeps_copies(ur5):
    teleop = Teleop(ur5, dt=DT)
    teleop.start_recording()
    run(teleop, [0.0, DT])
    kept = teleop.q.copy()
    teleop.q[0] += 1.0  # the caller's array changed in place
    teleop.last.joint_rates[:] = 7.0
    recording = teleop.stop_recording()
    np.testing.assert_array_equal(recording.q[-1], kept)
    assert not np.any(recording.joint_rates == 7.0)


def test_every_column_round_trips_bit_for_bit(ur5, tmp_path):
    wrist_3 = ur5.model.joints[ur5.joint_id("wrist_3_joint")].idx_q
    q0 = ur5.home()
    q0[wrist_3] = ur5.model.upperPositionLimit[wrist_3] - 0.02  # a limit on the way: statuses with details
    teleop = Teleop(ur5, q0, dt=DT)
    teleop.start_recording(max_samples=50)
    run(teleop, [k * DT / 3 for k in range(70)], linear=(0.3, -0.7, 0.2), angular=(0, 0, 1))
    recording = teleop.stop_recording()
    assert len(recording) == 50  # the oldest went first
    assert Status.JOINT_LIMIT.word in set(recording.status) and any(recording.detail)
    loaded = Recording.load(recording.save(tmp_path / "run.npz"))
    assert_same_bits(loaded, recording)
    np.testing.assert_array_equal(loaded.frames(24), recording.frames(24))


def test_frames_show_the_last_tick_at_or_before_each_frame(ur5):
    teleop = Teleop(ur5, dt=DT)
    teleop.start_recording()
    times = [1.0 + k * 0.013 for k in range(60)]
    run(teleop, times)
    recording = teleop.stop_recording()
    fps = 20.0
    frames = recording.frames(fps)
    np.testing.assert_array_equal(frames[0], ur5.home())
    shown = frames[1:]
    assert abs((len(shown) - 1) / fps - (times[-1] - times[0])) <= 0.5 / fps + 1e-12  # the whole span
    for k, q in enumerate(shown):
        moment = times[0] + k / fps
        last = max(i for i, t in enumerate(times) if t <= moment + 1e-12)
        np.testing.assert_array_equal(q, recording.q[last])


def test_bad_frame_rates_are_input_errors(ur5):
    teleop = Teleop(ur5, dt=DT)
    teleop.start_recording()
    run(teleop, [0.0, 1e5])
    recording = teleop.stop_recording()
    for fps in (0, -1.0, float("nan")):
        with pytest.raises(InputError, match="fps"):
            recording.frames(fps)
    with pytest.raises(InputError, match="lower fps"):
        recording.frames(1000.0)  # 1e8 frames


def test_files_that_are_not_recordings_are_refused(ur5, tmp_path):
    text = tmp_path / "notes.npz"
    text.write_text("not a zip")
    with pytest.raises(InputError, match=r"notes\.npz"):
        Recording.load(text)
    other = tmp_path / "other.npz"
    np.savez(other, format=np.array("something-else"))
    with pytest.raises(PinrateError, match="not a pinrate teleop recording"):
        Recording.load(other)

    def written(name: str, **changes: np.ndarray):
        fields = {
            "format": np.array(FORMAT),
            "robot": np.array("ur5"),
            "joint_names": np.array(ur5.joint_names, dtype=str),
            "dt": np.array(DT),
            "start": ur5.home(),
            "times": np.array([0.0, 0.1]),
            "q": np.zeros((2, ur5.nq)),
            "joint_rates": np.zeros((2, ur5.nv)),
            "status": np.array(["ok", "ok"]),
            "detail": np.array(["", ""]),
        }
        np.savez(tmp_path / name, **{**fields, **changes})
        return tmp_path / name

    assert len(Recording.load(written("fine.npz"))) == 2
    with pytest.raises(InputError, match="length"):
        Recording.load(written("short.npz", q=np.zeros((1, ur5.nq))))
    with pytest.raises(InputError, match="dimensions"):
        Recording.load(written("flat.npz", q=np.zeros(2)))
    with pytest.raises(InputError, match="non-decreasing"):
        Recording.load(written("backwards.npz", times=np.array([0.1, 0.0])))
    with pytest.raises(InputError, match="start"):
        Recording.load(written("start.npz", start=np.zeros(3)))
    with pytest.raises(InputError, match="dt"):
        Recording.load(written("dt.npz", dt=np.array(-1.0)))
    # The first format kept Status values: read as their words; a value no Status has is refused.
    first = np.array("pinrate-teleop-1")
    old = Recording.load(written("old.npz", format=first, status=np.array(["ok", "joint_limit"])))
    assert list(old.status) == ["moving", "at a joint limit"]
    with pytest.raises(InputError, match="stuck"):
        Recording.load(written("odd.npz", format=first, status=np.array(["ok", "stuck"])))
