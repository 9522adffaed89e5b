"""`pinrate analyze`: block structure, region maps against the analytic boundaries, PNGs, parallel paths."""

from __future__ import annotations

import math
import subprocess
import sys

import numpy as np
import pytest

import pinrate
from pinrate import analysis, robots


def test_block_structure_flags_exact_algorithms() -> None:
    barker = analysis.block_structure(robots.barker_arm())
    assert barker.B_is_zero and not barker.U_is_zero
    assert any("MCA2 is exact" in line for line in barker.lines())
    cartesian = analysis.block_structure(robots.cartesian())
    assert cartesian.U_is_zero and cartesian.B_is_zero
    assert any("MCA1 is exact" in line for line in cartesian.lines())
    ur5 = analysis.block_structure(pinrate.load("ur5"))
    assert not ur5.B_is_zero and not ur5.U_is_zero
    # SCARA, sensor on link 2: d moves the TCP only along z, so A has zeros in d's column.
    scara = analysis.block_structure(robots.scara())
    assert scara.zero["A"][:, 2].tolist() == [True, True, False]


@pytest.mark.parametrize(
    ("name", "expected"),
    [("scara", ("theta2", "theta3")), ("planar_polar", ("d2", "theta3")), ("spherical_6dof", ("theta2", "theta5"))],
)
def test_default_map_joints_are_the_papers(name: str, expected: tuple[str, str]) -> None:
    # Fig. 8 (SCARA over theta2, theta3), Fig. 5 (polar over d2, theta3), Fig. 12 (eq. 72: theta2, theta5).
    assert analysis.default_map_joints(getattr(robots, name)()) == expected


def crossings(values: np.ndarray, radius: np.ndarray) -> list[float]:
    """Where ρ - 1 changes sign along a line, by linear interpolation."""
    excess = np.log(np.clip(radius, 1e-12, 1e12))
    found = []
    for i in range(len(values) - 1):
        if np.isfinite(excess[i]) and np.isfinite(excess[i + 1]) and excess[i] * excess[i + 1] < 0:
            t = excess[i] / (excess[i] - excess[i + 1])
            found.append(values[i] + t * (values[i + 1] - values[i]))
    return found


def test_polar_contour_is_eq_58() -> None:
    l = 0.2  # noqa: E741
    region = analysis.region_map(robots.planar_polar(l=l), joints=("d2", "theta3"), points=161)
    step = region.x[1] - region.x[0]
    checked = 0
    for row, theta3 in enumerate(region.y):
        boundary = -2 * l * math.cos(theta3)  # eq. 58: C3 = -d2 / (2 l)
        if region.x[0] + 2 * step < boundary < region.x[-1] - 2 * step:
            found = crossings(region.x, region.spectral_radius[row])
            assert any(abs(d2 - boundary) < step for d2 in found), (theta3, boundary, found)
            checked += 1
    assert checked > 40


def test_scara_contour_is_eq_63() -> None:
    region = analysis.region_map(robots.scara(), joints=("theta2", "theta3"), points=181)
    step = region.y[1] - region.y[0]
    checked = 0
    for column, theta2 in enumerate(region.x):
        s2 = math.sin(theta2)
        if abs(s2) < 0.3:
            continue
        # Eq. 63 with l2 = l3: sin(theta2 + theta3) = -S2 / 2 on the boundary.
        base = math.asin(-s2 / 2)
        analytic = [a - theta2 + 2 * math.pi * k for a in (base, math.pi - base) for k in (-1, 0, 1)]
        analytic = [t for t in analytic if region.y[0] + step < t < region.y[-1] - step]
        found = crossings(region.y, region.spectral_radius[:, column])
        for theta3 in analytic:
            assert any(abs(t - theta3) < 1.5 * step for t in found), (theta2, theta3, found)
            checked += 1
    assert checked > 100


def pixel_summary(path) -> tuple[int, float, float, float]:
    """(distinct colours, share of non-white pixels, share greenish, share reddish)."""
    from PIL import Image

    pixels = np.asarray(Image.open(path).convert("RGB")).reshape(-1, 3).astype(int)
    distinct = len(np.unique(pixels, axis=0))
    non_white = np.mean(pixels.sum(axis=1) < 3 * 245)
    red, green, blue = pixels[:, 0], pixels[:, 1], pixels[:, 2]
    greenish = np.mean((green > red + 40) & (green > blue + 20))
    reddish = np.mean((red > green + 60) & (red > blue + 60))
    return distinct, float(non_white), float(greenish), float(reddish)


def test_report_and_pngs_have_content(tmp_path) -> None:
    robot = robots.hirata_arh300(l3=0.1)
    report = analysis.analyze(robot, samples=4000, points=61, tcp_samples=1500)
    report.sweep = analysis.sweep(
        lambda l3: robots.hirata_arh300(l3=l3), "l3", 0.02, 0.2, steps=5, samples=1000, points=61, tolerance=1e-4
    )
    path = analysis.write_report(report, tmp_path)
    text = path.read_text()
    assert "Block structure" in text and "`theta1`" in text and "Largest `l3`" in text
    assert set(report.files) == {"region map", "work volume", "sweep"}
    for name, png in report.files.items():
        distinct, non_white, greenish, _reddish = pixel_summary(png)
        assert png.stat().st_size > 10_000, name
        assert distinct > 30 and non_white > 0.05, name
        assert greenish > 0.001, name  # converging points or regions are drawn
    assert pixel_summary(report.files["region map"])[3] > 0.01  # and diverging regions
    assert report.sweep.limit == pytest.approx(0.275 * math.sin(math.radians(25)) / 2, abs=2e-4)


def test_polar_fraction_and_sweep_rule() -> None:
    result = analysis.sweep(
        lambda d: robots.planar_polar(l=0.2, d2_min=d),
        "d2_min",
        0.1,
        0.9,
        steps=4,
        samples=2000,
        points=41,
        tolerance=1e-4,
    )
    assert result.limit_kind == "smallest"
    assert result.limit == pytest.approx(0.4, abs=1e-3)  # d2 / l > 2
    assert result.fraction[-1] == 1.0 and result.fraction[0] < 1.0


def test_workers_give_the_same_answer() -> None:
    robot = robots.scara()
    sequential = pinrate.sample_convergence(robot, 45_000, rng=3)
    parallel = pinrate.sample_convergence(robot, 45_000, rng=3, workers=2)
    np.testing.assert_array_equal(sequential.spectral_radius, parallel.spectral_radius)


def test_dask_local_cluster_gives_the_same_answer() -> None:
    distributed = pytest.importorskip("distributed")
    robot = pinrate.load("ur5")
    expected = pinrate.sample_convergence(robot, 25_000, rng=4)
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as cluster:
        result = pinrate.sample_convergence(robot, 25_000, rng=4, scheduler=cluster)
        with distributed.Client(cluster) as client:
            assert len(client.scheduler_info()["workers"]) == 2
    np.testing.assert_array_equal(result.spectral_radius, expected.spectral_radius)


def test_bad_sweep_text() -> None:
    with pytest.raises(pinrate.InputError, match="PARAM=LO:HI"):
        analysis.parse_sweep("l3:0.1")


def test_cli_analyze_writes_the_report(tmp_path) -> None:
    result = subprocess.run(
        [
            sys.executable,
            "-m",
            "pinrate.cli",
            "analyze",
            "planar_polar",
            "--samples",
            "3000",
            "--points",
            "41",
            "--out",
            str(tmp_path),
        ],
        capture_output=True,
        text=True,
        timeout=300,
        check=False,
    )
    assert result.returncode == 0, result.stderr[-2000:]
    assert (tmp_path / "report.md").is_file() and (tmp_path / "planar_polar-region-map.png").is_file()
    assert "ρ over `d2` x `theta3`" in result.stdout
    bad = subprocess.run(
        [
            sys.executable,
            "-m",
            "pinrate.cli",
            "analyze",
            "ur5",
            "--sweep",
            "l3=0.1:0.2",
            "--samples",
            "100",
            "--points",
            "5",
            "--out",
            str(tmp_path / "x"),
        ],
        capture_output=True,
        text=True,
        timeout=300,
        check=False,
    )
    assert bad.returncode == 2 and "papers' parametric robots" in bad.stderr
