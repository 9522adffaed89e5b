"""The ρ map over many configurations (pinrate.theorem.sampling) on the compiled core's
threads: the split over threads changes which thread takes a configuration, never the
operations made on it, so every thread count gives the single-threaded map bit for bit."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import pinrate
from compiled_core import ROBOTS, load, needs_core, path
from pinrate.compiled import CoreServo, rho_map
from pinrate.theorem import sampling, spectral_radius_at
from support import spectral_radius_tolerance

pytestmark = needs_core


def core_map(robot: pinrate.Robot) -> CoreServo:
    index = pinrate.Partition.auto(robot).resolve(robot)
    with path("compiled"):
        core = rho_map(
            robot, tuple(index.rows.tolist()), tuple(index.columns.tolist()), index.m, int(index.arm_columns.size)
        )
    assert core is not None, f"{robot.name}: the core maps no rho"
    return core


@pytest.mark.parametrize("name", ROBOTS)
def test_every_thread_count_gives_the_single_threaded_map(name: str) -> None:
    """Thread counts that split 1001 configurations unevenly, more threads than
    configurations, and none at all: the same doubles (inf where a block is singular)."""
    robot = load(name)
    core = core_map(robot)
    configurations = robot.sample_configurations(1001, 11)
    configurations[::97] = robot.neutral()  # singular on most arms: inf rows mixed in
    single = core.spectral_radius_at(configurations, threads=1)
    for threads in (2, 3, 7):
        np.testing.assert_array_equal(core.spectral_radius_at(configurations, threads=threads), single)
    np.testing.assert_array_equal(core.spectral_radius_at(configurations[:2], threads=5), single[:2])
    assert core.spectral_radius_at(configurations[:0], threads=3).shape == (0,)


def test_workers_reach_the_core_and_chunks_do_not_change_the_map(monkeypatch: pytest.MonkeyPatch) -> None:
    """sample_convergence(workers=2) maps on the core's threads; a map cut into many calls
    (CORE_CHUNK made small) is the one made in a single call."""
    robot = pinrate.load("ur5")
    with path("compiled"):
        single = pinrate.sample_convergence(robot, 5000, rng=4)
        threaded = pinrate.sample_convergence(robot, 5000, rng=4, workers=2)
        monkeypatch.setattr(sampling, "CORE_CHUNK", 999)
        chunked = spectral_radius_at(robot, single.q, workers=2, progress=False)
    np.testing.assert_array_equal(threaded.q, single.q)
    np.testing.assert_array_equal(threaded.spectral_radius, single.spectral_radius)
    np.testing.assert_array_equal(chunked, single.spectral_radius)


@pytest.mark.parametrize("name", ["ur5", "panda"])
def test_threaded_map_agrees_with_the_python_path(name: str) -> None:
    """On two threads against the batched numpy path: the same formulas in another order of
    a few roundings (ur5), or a Gram-Schmidt pseudo-inverse against LAPACK's SVD (panda's
    3x4 A), so ρ within
    support.spectral_radius_tolerance (the bound test_rho_maps_agree uses), inf alike."""
    robot = pinrate.load(name)
    configurations = robot.sample_configurations(3000, 8)
    with path("python"):
        python = spectral_radius_at(robot, configurations)
    with path("compiled"):
        compiled = spectral_radius_at(robot, configurations, workers=2)
    np.testing.assert_array_equal(np.isinf(compiled), np.isinf(python))
    finite = np.isfinite(python)
    tolerance = spectral_radius_tolerance(robot, pinrate.Partition.auto(robot), configurations[finite])
    assert np.all(np.abs(compiled[finite] - python[finite]) <= tolerance)


def _joint(index: int, axis: str, parent: str, child: str, z: float) -> str:
    return (
        f'<joint name="j{index}" type="revolute"><parent link="{parent}"/><child link="{child}"/>'
        f'<origin xyz="0 0 {z}"/><axis xyz="{axis}"/><limit lower="-3" upper="3" effort="1" velocity="1"/></joint>'
    )


# Seven joints straight up at q = 0: j1 and j3 turn about the vertical line through the tip,
# j2 and j4 about parallel horizontal axes, so the 3x4 A has rank 1 there; a spherical wrist
# (j5, j6, j7 about z, y, x at one point, the tip 0.1 above it) with a regular W and B != 0.
_LINKS = ["base", *(f"l{i}" for i in range(1, 8))]
_AXES = ["0 0 1", "0 1 0", "0 0 1", "0 1 0", "0 0 1", "0 1 0", "1 0 0"]
_OFFSETS = [0.3, 0.3, 0.3, 0.3, 0.3, 0.0, 0.0]
STRAIGHT_ARM = (
    '<robot name="straight">'
    + "".join(f'<link name="{link}"/>' for link in [*_LINKS, "tip"])
    + "".join(_joint(i + 1, _AXES[i], _LINKS[i], _LINKS[i + 1], _OFFSETS[i]) for i in range(7))
    + '<joint name="tool" type="fixed"><parent link="l7"/><child link="tip"/><origin xyz="0 0 0.1"/></joint>'
    + "</robot>"
)


def test_a_wide_a_near_rank_loss_takes_the_svd_and_agrees(tmp_path: Path) -> None:
    """The core pseudo-inverts a wide A by Gram-Schmidt only where ||R||_F ||R^-1||_F < 1e8
    (numpy's pinv, rcond 1e-10, would then truncate nothing), else by the SVD. An elbow bent
    by 1e-9 to 1e-6 rad from straight gives sigma_min / sigma_max of 2e-10 to 2e-7 (both ways
    taken), straight gives rank 1 (pinv truncates). ρ within support.spectral_radius_tolerance
    of the Python path's where A has full rank, NaN nowhere; at rank 1 both keep sigma_1 alone
    (the others below 1e-15 sigma_1, far from the cutoff), so their G differ by rounding,
    under 100 eps g with g = ||U|| ||A^+|| ||B|| ||W^-1||, and their ρ by at most Elsner's
    (2 g)^(2/3) (100 eps g)^(1/3) (support.spectral_radius_tolerance's bound, n = 3)."""
    urdf = tmp_path / "straight.urdf"
    urdf.write_text(STRAIGHT_ARM, encoding="utf-8")
    robot = pinrate.load(urdf)
    partition = pinrate.Partition.auto(robot)
    assert (len(partition.arm), len(partition.wrist)) == (4, 3)
    configurations = np.zeros((5, robot.nq))
    configurations[:, 3] = [0.0, 1e-9, 1e-8, 1e-7, 1e-6]  # j4, the elbow
    J = np.stack([robot.jacobian(q) for q in configurations])
    A, B, U, W = J[:, :3, :4], J[:, :3, 4:], J[:, 3:, :4], J[:, 3:, 4:]
    singular_values = np.linalg.svd(A, compute_uv=False)
    ratios = singular_values[:, -1] / singular_values[:, 0]
    assert ratios[0] < 1e-15 and np.all((ratios[1:] > 1e-10) & (ratios[1:] < 1e-6))
    with path("python"):
        python = spectral_radius_at(robot, configurations, partition=partition)
    with path("compiled"):
        assert rho_map(robot, (0, 1, 2, 3, 4, 5), tuple(range(7)), 3, 4) is not None
        compiled = spectral_radius_at(robot, configurations, partition=partition)
    assert np.all(np.isfinite(compiled)) and np.all(np.isfinite(python))
    tolerance = spectral_radius_tolerance(robot, partition, configurations[1:])
    assert np.all(np.abs(compiled[1:] - python[1:]) <= tolerance)
    norm = np.linalg.norm
    g = norm(U[0], 2) * norm(np.linalg.pinv(A[0], rcond=1e-10), 2) * norm(B[0], 2) * norm(np.linalg.inv(W[0]), 2)
    eps = np.finfo(float).eps
    assert abs(compiled[0] - python[0]) <= (2 * g) ** (2 / 3) * (100 * eps * g) ** (1 / 3)


def test_the_jacobian_bound_is_timed_and_threads_are_checked() -> None:
    robot = pinrate.load("ur5")
    core = core_map(robot)
    configurations = robot.sample_configurations(2000, 1)
    for threads in (1, 2):
        seconds = core.jacobian_seconds(configurations, threads=threads)
        assert 0.0 < seconds < 10.0  # 2000 kinematics passes: about a millisecond
    with pytest.raises(ValueError, match="threads"):
        core.spectral_radius_at(configurations, threads=0)
    with pytest.raises(ValueError, match=r"\(N, nq\)"):
        core.spectral_radius_at(configurations[:, :3])
