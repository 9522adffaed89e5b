"""A servo run saved, loaded and reversed (Barker: "recording and reversing a motion")."""

from __future__ import annotations

import collections
import math
import os
import re
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

import pinrate
from pinrate.kinematics.targets import nearby_target
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


@pytest.fixture(scope="module")
def run() -> tuple[pinrate.Robot, pinrate.Trajectory]:
    robot = pinrate.load("kinova")  # continuous joints: q holds (cos, sin) pairs
    _, target = nearby_target(robot, pinrate.Partition.auto(robot), 3)
    return robot, pinrate.servo(robot, robot.home(), target, algorithm="exact")


def test_the_reversed_rates_lead_back_to_the_start(run) -> None:
    robot, trajectory = run
    backwards = trajectory.reversed()
    assert backwards.q.shape == trajectory.q.shape and backwards.steps == trajectory.steps
    np.testing.assert_array_equal(backwards.q[0], trajectory.q[-1])
    q = backwards.q[0]
    for rates in backwards.joint_rates:  # integrated here with Pinocchio, step by step
        q = pin.integrate(robot.model, q, rates * backwards.dt)
    np.testing.assert_allclose(q, trajectory.q[0], atol=1e-6)
    assert backwards.status[-1] == "reversed" and len(backwards.status) == len(trajectory.status)
    assert backwards.reason.startswith("reversed: ") and not backwards.converged
    assert len(backwards.detail) == len(trajectory.detail) and backwards.detail[-1].startswith("reversed: ")


def test_a_trajectory_saves_and_loads(run, tmp_path: Path) -> None:
    _, trajectory = run
    path = trajectory.save(tmp_path / "run.npz")
    loaded = pinrate.Trajectory.load(path)
    for name in ("q", "position_error", "orientation_error", "spectral_radius", "joint_rates"):
        np.testing.assert_array_equal(getattr(loaded, name), getattr(trajectory, name))
    assert loaded.status == trajectory.status and loaded.reason == trajectory.reason
    assert loaded.detail == trajectory.detail and len(loaded.detail) == loaded.q.shape[0]
    assert loaded.converged == trajectory.converged and loaded.dt == trajectory.dt
    assert loaded.algorithm == trajectory.algorithm and loaded.partition == trajectory.partition
    # A name without the suffix is written as given.
    assert trajectory.save(tmp_path / "plain").name == "plain"


def test_bad_trajectory_files_are_input_errors(run, tmp_path: Path) -> None:
    _, trajectory = run
    with pytest.raises(pinrate.InputError, match="does not exist"):
        pinrate.Trajectory.load(tmp_path / "missing.npz")
    (tmp_path / "text.npz").write_text("not an archive", encoding="utf-8")
    with pytest.raises(pinrate.InputError, match=r"not an \.npz archive"):
        pinrate.Trajectory.load(tmp_path / "text.npz")
    np.savez(tmp_path / "other.npz", q=np.zeros(3))
    with pytest.raises(pinrate.InputError, match="not a pinrate trajectory"):
        pinrate.Trajectory.load(tmp_path / "other.npz")
    with pytest.raises(pinrate.InputError, match="folder"):
        trajectory.save(tmp_path)


def test_every_step_leaves_its_detail_in_words() -> None:
    robot = pinrate.load("ur5")
    q0 = robot.home()
    q0[2] = 0.3  # near the elbow singularity: the run decelerates and says so
    far = robot.pose(q0)
    far[:3, 3] *= 1.4  # out of reach: the arm extends toward full extension
    trajectory = pinrate.servo(robot, q0, far, algorithm="exact", max_steps=300)
    assert len(trajectory.detail) == trajectory.q.shape[0] and trajectory.detail[-1] == trajectory.reason
    words = [detail for status, detail in zip(trajectory.status, trajectory.detail, strict=True) if status != "moving"]
    assert words and all(words)  # every step that met a condition says which
    assert any("block J" in detail for detail in trajectory.detail)


def test_a_trajectory_of_the_first_format_loads_with_todays_words(run, tmp_path: Path) -> None:
    """Release 0.1.0 wrote ``pinrate-trajectory-1`` with its own step words; they are read as
    today's (the words written here by hand, as 0.1.0's servo_loop spelt them)."""
    _, trajectory = run
    path = trajectory.save(tmp_path / "run.npz")
    with np.load(path, allow_pickle=False) as data:
        entries = {name: data[name] for name in data.files}
    old_words = ["saturated", "joint limit", "decelerating", "frozen", "moving", "converged"]
    entries["format"] = np.array("pinrate-trajectory-1")
    entries["status"] = np.array([*old_words, *["moving"] * (len(trajectory.status) - len(old_words))])
    np.savez(tmp_path / "old.npz", **entries)
    loaded = pinrate.Trajectory.load(tmp_path / "old.npz")
    statuses = [pinrate.Status.TWIST_SATURATED, pinrate.Status.JOINT_LIMIT, pinrate.Status.DECELERATE_FOR_SINGULARITY]
    assert loaded.status[:4] == [*(status.word for status in statuses), pinrate.Status.FROZEN.word]
    assert loaded.status[4:6] == ["moving", "converged"]


# Saved files that are damaged or hostile (issue 23, item 6): every load either gives a
# valid trajectory or an InputError naming the file; nothing hangs, nothing allocates what a
# header declares; a failed save leaves the old file.


def entries_of(path: Path) -> dict[str, np.ndarray]:
    with np.load(path, allow_pickle=False) as data:
        return {name: data[name] for name in data.files}


def assert_valid(trajectory: pinrate.Trajectory, label: str) -> None:
    """What a loaded trajectory must be, whatever its file held."""
    rows = trajectory.q.shape[0]
    assert trajectory.q.ndim == 2 and rows >= 1 and trajectory.q.shape[1] >= 1, label
    assert trajectory.joint_rates.ndim == 2 and trajectory.joint_rates.shape[0] == rows - 1, label
    for name in ("position_error", "orientation_error", "spectral_radius"):
        values = getattr(trajectory, name)
        assert values.shape == (rows,) and not np.isnan(values).any() and (values >= 0).all(), (label, name)
    for name in ("q", "joint_rates", "position_error", "orientation_error"):
        assert np.isfinite(getattr(trajectory, name)).all(), (label, name)
    assert all(getattr(trajectory, name).dtype == float for name in ("q", "joint_rates", "spectral_radius")), label
    assert isinstance(trajectory.converged, bool) and math.isfinite(trajectory.dt) and trajectory.dt > 0, label
    assert len(trajectory.status) == rows and len(trajectory.detail) in (0, rows), label
    assert all(isinstance(word, str) for word in (*trajectory.status, *trajectory.detail)), label
    assert isinstance(trajectory.reason, str) and isinstance(trajectory.partition, pinrate.Partition), label


def must_refuse(kind: str, name: str, entries: dict[str, np.ndarray]) -> bool:
    """Whether a trajectory file with field ``name`` changed the ``kind`` way of
    support.MUTATIONS can only be refused (otherwise it may load, and must then be valid)."""
    value = entries[name]
    numeric = value.dtype.kind in "fb"
    if kind in ("drop", "extra", "rename", "object", "bytes", "complex", "add a dimension", "scalar as a list"):
        return True
    if kind == "as text":
        return numeric
    if kind == "as number":
        return name != "dt"
    if kind == "nan" or (kind in ("inf", "huge") and name != "spectral_radius") or kind == "-inf":
        return True
    if kind == "negate":
        return name == "dt" or (name in ("position_error", "orientation_error", "spectral_radius") and value.any())
    if kind == "zero":
        return name == "dt"
    if kind == "drop a row":
        return name not in ("arm", "wrist")
    if kind == "empty name":
        return name in ("arm", "wrist", "format")
    if kind == "transpose":
        return value.shape[0] != value.shape[1]
    return False


def test_a_fuzz_of_damaged_trajectory_files(run, tmp_path: Path) -> None:
    """Bytes damaged at random (truncated, bits flipped, runs overwritten, cut or repeated)
    and fields changed at random (missing, extra, renamed, objects, other dtypes and shapes,
    NaN, inf, huge, negative, zero dt, empty names): a valid trajectory or an InputError
    naming the file, never another exception; a change that breaks the format is refused."""
    _, trajectory = run
    original = trajectory.save(tmp_path / "original.npz")
    data, entries = original.read_bytes(), entries_of(original)
    rng = np.random.default_rng(23)
    path = tmp_path / "case.npz"
    tally: collections.Counter[str] = collections.Counter()
    for _ in range(fuzz_count(300)):
        label, damaged = corrupt_bytes(data, rng)
        path.write_bytes(damaged)
        verdict = outcome(pinrate.Trajectory.load, path, label)
        if verdict == "loaded":
            assert_valid(pinrate.Trajectory.load(path), label)
        tally["bytes " + verdict] += 1
    for _ in range(fuzz_count(300)):
        kind, name, changed = mutate(entries, rng)
        path.unlink(missing_ok=True)
        with path.open("wb") as stream:
            np.savez(stream, **changed)  # an object array is pickled: the loader must not unpickle it
        label = f"{kind} {name}"
        verdict = outcome(pinrate.Trajectory.load, path, label)
        assert verdict == "refused" or not must_refuse(kind, name, entries), f"{label} loaded"
        if verdict == "loaded":
            assert_valid(pinrate.Trajectory.load(path), label)
        tally["fields " + verdict] += 1
    print(f"trajectory file fuzz: {dict(sorted(tally.items()))}")
    assert tally["bytes refused"] and tally["fields refused"] and tally["fields loaded"]


@pytest.mark.parametrize("version", ["pinrate-trajectory-2", "pinrate-trajectory-1"])
def test_a_field_that_holds_the_wrong_thing_is_refused_by_name(run, tmp_path: Path, version: str) -> None:
    _, trajectory = run
    entries = {**entries_of(trajectory.save(tmp_path / "run.npz")), "format": np.array(version)}
    rows = len(trajectory.status)
    cases = {
        "converged": np.array("yes"),
        "dt": np.array(-0.01),
        "q": np.where(np.arange(trajectory.q.size).reshape(trajectory.q.shape) == 3, np.nan, trajectory.q),
        "status": np.array(["moving"] * (rows - 1)),
        "detail": np.array(["x"] * (rows + 1)),
        "spectral_radius": np.full(rows, -1.0),
        "joint_rates": trajectory.joint_rates[:, :2].T,
        "arm": np.array(["", "joint_2"]),
        "wrist": np.array([trajectory.partition.arm[0]]),  # in both arm and wrist
    }
    for name, value in cases.items():
        path = tmp_path / f"{name}.npz"
        np.savez(path, **{**entries, name: value})
        with pytest.raises(pinrate.InputError) as refused:
            pinrate.Trajectory.load(path)
        assert str(path) in str(refused.value) and repr(name) in str(refused.value), refused.value
    del entries["detail"]  # the first format may lack it; the second may not
    np.savez(tmp_path / "without.npz", **entries)
    if version == "pinrate-trajectory-1":
        assert pinrate.Trajectory.load(tmp_path / "without.npz").detail == []
    else:
        with pytest.raises(pinrate.InputError, match=r"lacks the field.* detail"):
            pinrate.Trajectory.load(tmp_path / "without.npz")


def test_what_is_not_a_regular_file_is_refused_at_once(tmp_path: Path) -> None:
    """A FIFO (which would block a reader until a writer comes), a folder, a device and a
    file that cannot be read: InputError naming the file and saying what it is."""
    for label, path, said in special_files(tmp_path):
        error = load_with_timeout(pinrate.Trajectory.load, path)
        assert isinstance(error, pinrate.InputError), f"{label}: {error!r}"
        assert str(path) in str(error) and re.search(said, str(error)), f"{label}: {error}"


def test_a_header_declaring_terabytes_is_refused_before_any_allocation(run, tmp_path: Path) -> None:
    """A 14 KB file whose q declares 4 TiB (shape (2**36, 8)): refused from the header, the
    process's peak memory growing by less than 64 MB (it would be a MemoryError or more)."""
    _, trajectory = run
    members = npz_members(trajectory.save(tmp_path / "run.npz"))
    members = [
        (name, npy((2**36, 8), "<f8", data[128:]), 0, 0, len(npy((2**36, 8), "<f8", data[128:])))
        if name == "q.npy"
        else (name, data, method, crc, size)
        for name, data, method, crc, size in members
    ]
    path = tmp_path / "huge.npz"
    path.write_bytes(raw_zip(members))
    growth, what = peak_memory_of_load("pinrate.Trajectory", path)
    assert growth < 64 << 20, f"the peak memory grew by {growth / 2**20:.0f} MiB ({what})"
    assert what.startswith("InputError") and str(path) in what and "'q'" in what, what


def test_zip_bombs_are_refused_before_they_are_inflated(run, tmp_path: Path) -> None:
    """q as 256 MiB of deflated zeros (256 KB in the file): refused from its header, which
    declares a shape that does not fit the other fields, with the peak memory growing by
    less than 64 MB; a member declaring more than deflate can hold is refused unread, and
    one whose stream holds more than it declares is read as far as it declares, its checksum
    refusing it."""
    _, trajectory = run
    members = npz_members(trajectory.save(tmp_path / "run.npz"))
    header = npy((2**22, 8))
    stream, crc, size = deflated_zeros(header, 256)

    def with_q(data: bytes, crc: int, size: int, method: int = 8) -> list[tuple[str, bytes, int, int, int]]:
        return [(m[0], data, method, crc, size) if m[0] == "q.npy" else m for m in members]

    path = tmp_path / "bomb.npz"
    path.write_bytes(raw_zip(with_q(stream, crc, size)))
    growth, what = peak_memory_of_load("pinrate.Trajectory", path)
    assert growth < 64 << 20, f"the peak memory grew by {growth / 2**20:.0f} MiB ({what})"
    assert what.startswith("InputError") and str(path) in what and "(4194304,)" in what, what
    small = npy(trajectory.q.shape)  # the right shape; its stream inflates to 256 MiB, its checksum wrong
    liar = tmp_path / "liar.npz"
    liar.write_bytes(raw_zip(with_q(deflated_zeros(small, 256)[0], 0, len(small) + trajectory.q.nbytes)))
    over = tmp_path / "over.npz"  # declares 1 GiB in a stream of 1 MB
    over.write_bytes(raw_zip(with_q(deflated_zeros(header, 1)[0], crc, len(header) + (1 << 30))))
    for path in (liar, over):
        with pytest.raises(pinrate.InputError) as refused:
            pinrate.Trajectory.load(path)
        assert str(path) in str(refused.value) and "'q'" in str(refused.value)


def test_a_save_that_fails_part_way_leaves_the_old_file(run, tmp_path: Path) -> None:
    """A save over a file that fails part-way (here a file-size limit: EFBIG, as a full
    disk's ENOSPC) is an InputError naming the file; the old file is as it was, byte for
    byte, and no temporary file is left."""
    _, trajectory = run
    path = trajectory.save(tmp_path / "run.npz")
    old = path.read_bytes()
    setup = """
        import numpy as np
        import pinrate
        rows = 20_000  # 2.9 MB: well past the limit
        saved = pinrate.Trajectory(
            q=np.zeros((rows, 6)), position_error=np.zeros(rows), orientation_error=np.zeros(rows),
            spectral_radius=np.zeros(rows), status=["moving"] * rows, joint_rates=np.zeros((rows - 1, 6)),
            converged=False, reason="max steps", algorithm="exact", dt=0.01,
            partition=pinrate.Partition(["a", "b", "c"], ["d", "e", "f"]), detail=[""] * rows,
        )
    """
    what = save_under_a_file_size_limit(setup, path, 256 << 10)
    assert what.startswith("InputError") and str(path) in what, what
    assert path.read_bytes() == old
    assert sorted(os.listdir(tmp_path)) == ["run.npz"]
    assert_valid(pinrate.Trajectory.load(path), "the old file")


def test_a_plant_record_is_saved_whole_and_a_partial_one_refused(tmp_path: Path) -> None:
    from pinrate.plants import KinematicPlant

    robot = pinrate.load("ur5")
    target = robot.pose(robot.home())
    target[:3, 3] += 0.05
    trajectory = pinrate.servo(robot, robot.home(), target, plant=KinematicPlant(robot), max_steps=20)
    path = trajectory.save(tmp_path / "run.npz")
    loaded = pinrate.Trajectory.load(path)
    assert loaded.plant is not None and loaded.plant.name == "kinematic"
    np.testing.assert_array_equal(loaded.plant.measured_rates, trajectory.joint_rates)
    with np.load(path) as npz:
        members = {name: npz[name] for name in npz.files}
    partial = dict(members)
    del partial["saturated"]
    np.savez(tmp_path / "partial.npz", **partial)
    with pytest.raises(pinrate.InputError, match="without saturated: a plant record has all four"):
        pinrate.Trajectory.load(tmp_path / "partial.npz")
    wrong = dict(members, tracking_error=-np.ones(trajectory.steps))
    np.savez(tmp_path / "negative.npz", **wrong)
    with pytest.raises(pinrate.InputError, match="tracking_error"):
        pinrate.Trajectory.load(tmp_path / "negative.npz")
