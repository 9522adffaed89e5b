"""A teleoperated run kept tick by tick (pinrate.teleop.Recording): the times as the ticks were
given, zero ticks a valid run, frames at a frame rate, and save/load giving every column back
bit for bit."""

from __future__ import annotations

import collections
import math
import os
import re
import time
import zlib
from pathlib import Path

import numpy as np
import pytest

from pinrate import InputError, PinrateError, Status, Teleop
from pinrate.teleop import Recording
from pinrate.teleop.recording import FORMAT
from support import (
    corrupt_bytes,
    deflated_zeros,
    fuzz_count,
    load_with_timeout,
    mutate,
    npy,
    npz_members,
    outcome,
    peak_memory_of_load,
    raw_zip,
    save_under_a_file_size_limit,
    special_files,
)

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


# Saved files that are damaged or hostile (issue 23, item 6): every load either gives a
# valid recording or an InputError naming the file; nothing hangs, nothing allocates what a
# header declares; a failed save leaves the old file.


@pytest.fixture
def saved(ur5, tmp_path) -> tuple[Recording, Path]:
    """A recording of 40 ticks with statuses and details, saved (compressed, as ever)."""
    wrist_3 = ur5.model.joints[ur5.joint_id("wrist_3_joint")].idx_q
    q0 = ur5.home()
    q0[wrist_3] = ur5.model.upperPositionLimit[wrist_3] - 0.02
    teleop = Teleop(ur5, q0, dt=DT)
    teleop.start_recording()
    run(teleop, [k * DT for k in range(40)], linear=(0.3, -0.7, 0.2), angular=(0, 0, 1))
    recording = teleop.stop_recording()
    return recording, recording.save(tmp_path / "original.npz")


def entries_of(path: Path) -> dict[str, np.ndarray]:
    with np.load(path, allow_pickle=False) as data:
        return {name: data[name] for name in data.files}


def assert_valid(recording: Recording, label: str) -> None:
    """What a loaded recording must be, whatever its file held."""
    count = len(recording)
    times, q, rates = recording.times, recording.q, recording.joint_rates
    assert times.shape == (count,) and np.isfinite(times).all() and (np.diff(times) >= 0).all(), label
    assert q.shape == (count, recording.nq) and rates.shape == (count, recording.nv), label
    assert np.isfinite(q).all() and np.isfinite(rates).all(), label
    assert recording.status.shape == recording.detail.shape == (count,), label
    assert math.isfinite(recording.dt) and recording.dt > 0, label
    assert recording.start is None or (recording.start.shape == (recording.nq,) and np.isfinite(recording.start).all())
    assert all(name and isinstance(name, str) for name in recording.joint_names), label


def must_refuse(kind: str, name: str, entries: dict[str, np.ndarray]) -> bool:
    """Whether a recording file with field ``name`` changed the ``kind`` way of
    support.MUTATIONS can only be refused (otherwise it may load, and must then be valid)."""
    value = entries[name]
    if kind in ("drop", "extra", "rename", "object", "bytes", "complex", "add a dimension", "scalar as a list"):
        return True
    if kind == "as text":
        return value.dtype.kind == "f"
    if kind == "as number":
        return name != "dt"
    if kind in ("nan", "inf", "-inf"):
        return True
    if kind == "huge":
        return name != "times"
    if kind in ("negate", "zero"):
        return name == "dt"
    if kind == "drop a row":
        return name != "joint_names"
    if kind == "empty name":
        return name in ("joint_names", "format")
    if kind == "transpose":
        return value.shape[0] != value.shape[1]
    return False


def test_a_fuzz_of_damaged_recording_files(saved, tmp_path):
    """Bytes damaged at random (truncated, bits flipped, runs overwritten, cut or repeated:
    the deflated streams, the zip's headers) and fields changed at random (missing, extra,
    renamed, objects, other dtypes and shapes, NaN, inf, huge, negative, zero dt, empty
    names): a valid recording or an InputError naming the file, never another exception; a
    change that breaks the format is refused."""
    _, original = saved
    data, entries = original.read_bytes(), entries_of(original)
    rng = np.random.default_rng(6)
    path = tmp_path / "case.npz"
    tally: collections.Counter[str] = collections.Counter()
    for _ in range(fuzz_count(300)):
        label, damaged = corrupt_bytes(data, rng)
        path.write_bytes(damaged)
        verdict = outcome(Recording.load, path, label)
        if verdict == "loaded":
            assert_valid(Recording.load(path), label)
        tally["bytes " + verdict] += 1
    for _ in range(fuzz_count(300)):
        kind, name, changed = mutate(entries, rng)
        path.unlink(missing_ok=True)
        with path.open("wb") as stream:
            np.savez_compressed(stream, **changed)  # an object array is pickled: never unpickled
        label = f"{kind} {name}"
        verdict = outcome(Recording.load, path, label)
        assert verdict == "refused" or not must_refuse(kind, name, entries), f"{label} loaded"
        if verdict == "loaded":
            assert_valid(Recording.load(path), label)
        tally["fields " + verdict] += 1
    print(f"recording file fuzz: {dict(sorted(tally.items()))}")
    assert tally["bytes refused"] and tally["fields refused"] and tally["fields loaded"]


def test_a_field_that_holds_the_wrong_thing_is_refused_by_name(saved, tmp_path):
    recording, original = saved
    entries = entries_of(original)
    count = len(recording)
    cases = {
        "dt": np.array(np.nan),
        "times": np.where(np.arange(count) == 5, np.inf, recording.times),
        "q": np.where(np.arange(recording.q.size).reshape(recording.q.shape) == 7, np.nan, recording.q),
        "joint_rates": recording.joint_rates.astype(complex),
        "status": np.arange(count, dtype=float),
        "detail": np.array([""] * (count + 1)),
        "joint_names": np.array(["shoulder", ""]),
        "robot": np.array(["ur5", "ur10"]),
        "start": np.array(recording.start, dtype=object),
    }
    for name, value in cases.items():
        path = tmp_path / f"{name}.npz"
        np.savez_compressed(path, **{**entries, name: value})
        with pytest.raises(InputError) as refused:
            Recording.load(path)
        assert str(path) in str(refused.value) and repr(name) in str(refused.value), refused.value


def test_what_is_not_a_regular_file_is_refused_at_once(tmp_path):
    """A FIFO (Recording.load blocked on one for ever), a folder, a device and a file that
    cannot be read: InputError naming the file and saying what it is."""
    for label, path, said in special_files(tmp_path):
        error = load_with_timeout(Recording.load, path)
        assert isinstance(error, InputError), f"{label}: {error!r}"
        assert str(path) in str(error) and re.search(said, str(error)), f"{label}: {error}"


def test_a_header_declaring_terabytes_is_refused_before_any_allocation(saved, tmp_path):
    """A file of a few KB whose q declares 4 TiB (shape (2**36, 8)): refused from the
    header, the process's peak memory growing by less than 64 MB."""
    _, original = saved
    header = npy((2**36, 8), "<f8", bytes(64))
    members = [
        ("q.npy", zlib.compress(header)[2:-4], 8, zlib.crc32(header), len(header)) if member[0] == "q.npy" else member
        for member in npz_members(original)
    ]
    path = tmp_path / "huge.npz"
    path.write_bytes(raw_zip(members))
    growth, what = peak_memory_of_load("pinrate.teleop.Recording", path)
    assert growth < 64 << 20, f"the peak memory grew by {growth / 2**20:.0f} MiB ({what})"
    assert what.startswith("InputError") and str(path) in what and "'q'" in what, what


def test_zip_bombs_are_refused_before_they_are_inflated(saved, tmp_path):
    """q as 256 MiB of deflated zeros (256 KB in the file, declared honestly): refused from
    its header, its shape not fitting the times', the peak memory growing by less than 64
    MB (the old loader inflated it first); a member declaring more than deflate can hold is
    refused unread, one whose stream holds more than it declares by its checksum."""
    recording, original = saved
    members = npz_members(original)
    header = npy((2**22, 8))
    stream, crc, size = deflated_zeros(header, 256)

    def with_q(data: bytes, crc: int, size: int) -> list[tuple[str, bytes, int, int, int]]:
        return [("q.npy", data, 8, crc, size) if member[0] == "q.npy" else member for member in members]

    path = tmp_path / "bomb.npz"
    path.write_bytes(raw_zip(with_q(stream, crc, size)))
    assert path.stat().st_size < 1 << 20
    growth, what = peak_memory_of_load("pinrate.teleop.Recording", path)
    assert growth < 64 << 20, f"the peak memory grew by {growth / 2**20:.0f} MiB ({what})"
    assert what.startswith("InputError") and str(path) in what and "'q'" in what, what
    small = npy(recording.q.shape)
    liar = tmp_path / "liar.npz"
    liar.write_bytes(raw_zip(with_q(deflated_zeros(small, 256)[0], 0, len(small) + recording.q.nbytes)))
    over = tmp_path / "over.npz"
    over.write_bytes(raw_zip(with_q(deflated_zeros(header, 1)[0], crc, len(header) + (1 << 30))))
    for path in (liar, over):
        with pytest.raises(InputError) as refused:
            Recording.load(path)
        assert str(path) in str(refused.value) and "'q'" in str(refused.value)


def test_a_save_that_fails_part_way_leaves_the_old_file(saved, tmp_path):
    """A save over a file that fails part-way (a file-size limit: EFBIG, as a full disk's
    ENOSPC) is an InputError naming the file; the old file is as it was, byte for byte,
    and no temporary file is left."""
    recording, original = saved
    old = original.read_bytes()
    setup = """
        import types
        import numpy as np
        from pinrate import Status
        from pinrate.teleop import Recording
        saved = Recording(None, 0.01)
        rng = np.random.default_rng(1)
        for k in range(20_000):  # random numbers: about 2 MB deflated, well past the limit
            step = types.SimpleNamespace(q=rng.random(6), joint_rates=rng.random(6), status=Status.OK, detail="")
            saved.add(k * 0.01, step)
    """
    what = save_under_a_file_size_limit(setup, original, 256 << 10)
    assert what.startswith("InputError") and str(original) in what, what
    assert original.read_bytes() == old
    assert sorted(os.listdir(tmp_path)) == ["original.npz"]
    assert_same_bits(Recording.load(original), recording)
