"""A servo run saved, loaded and reversed (Barker: "recording and reversing a motion")."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

import pinrate
from pinrate.kinematics.targets import nearby_target


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
