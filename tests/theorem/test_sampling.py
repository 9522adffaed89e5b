"""The ρ map over many configurations (pinrate.theorem.sampling) on the compiled core's
threads: the split over threads changes which thread takes a configuration, never the
operations made on it, so every thread count gives the single-threaded map bit for bit."""

from __future__ import annotations

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
    a few roundings (ur5), or Eigen's SVD against LAPACK's (panda's 3x4 A), so ρ within
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
