"""The convergence Theorem (eq. 32, 50) and its work-volume statistics."""

from __future__ import annotations

import math

import numpy as np
import pytest

import pinrate
from pinrate import Partition
from pinrate.theorem import wilson_interval


@pytest.mark.parametrize("name", ["ur5", "panda", "scara", "planar_polar", "so100"])
def test_nonzero_eigenvalues_of_G_and_H_coincide(name: str) -> None:
    robot = pinrate.load(name)
    for seed in range(5):
        result = pinrate.convergence(robot, robot.random_configuration(seed))
        g = np.linalg.eigvals(result.G)
        h = np.linalg.eigvals(result.H)
        g_nonzero = np.sort_complex(g[np.abs(g) > 1e-9])
        h_nonzero = np.sort_complex(h[np.abs(h) > 1e-9])
        np.testing.assert_allclose(g_nonzero, h_nonzero, atol=1e-8)
        assert result.spectral_radius == pytest.approx(max(np.abs(g).max(), np.abs(h).max()), abs=1e-8)


def test_G_and_H_definitions(ur5: pinrate.Robot) -> None:
    q = ur5.random_configuration(9)
    A, B, U, W = Partition.auto(ur5).blocks(ur5, ur5.jacobian(q))
    result = pinrate.convergence(ur5, q)
    np.testing.assert_allclose(result.G, U @ np.linalg.solve(A, B) @ np.linalg.inv(W), atol=1e-10)
    np.testing.assert_allclose(result.H, B @ np.linalg.solve(W, U) @ np.linalg.inv(A), atol=1e-10)
    assert result.converges == (result.spectral_radius < 1)


@pytest.mark.parametrize("seed", range(10))
def test_planar_polar_G_is_eq_56(seed: int) -> None:
    robot = pinrate.robots.planar_polar(l=0.2)
    q = robot.random_configuration(seed)
    d2, theta3 = q[1], q[2]
    closed_form = 0.2 * math.cos(theta3) / (d2 + 0.2 * math.cos(theta3))
    result = pinrate.convergence(robot, q)
    assert result.G.shape == (1, 1)
    assert result.G[0, 0] == pytest.approx(closed_form, rel=1e-9)
    assert result.spectral_radius == pytest.approx(abs(closed_form), rel=1e-9)
    assert result.converges == (math.cos(theta3) > -d2 / (2 * 0.2))  # eq. 58


@pytest.mark.parametrize("seed", range(10))
def test_scara_G_is_eq_60(seed: int) -> None:
    l2, l3 = 0.4, 0.3
    robot = pinrate.robots.scara(l1=0.4, l2=l2, l3=l3)
    q = robot.random_configuration(seed)
    theta2, theta3 = q[1], q[3]
    s2, s23 = math.sin(theta2), math.sin(theta2 + theta3)
    closed_form = l3 * s23 / (l2 * s2 + l3 * s23)
    assert pinrate.convergence(robot, q).G[0, 0] == pytest.approx(closed_form, rel=1e-9)


def test_empty_wrist_has_spectral_radius_zero(ur5: pinrate.Robot) -> None:
    partition = Partition(list(ur5.joint_names[:3]), [], linear="xyz", angular="")
    result = pinrate.convergence(ur5, ur5.home(), partition=partition)
    assert result.eigenvalues.size == 0
    assert result.spectral_radius == 0.0 and result.converges


def test_singular_A_has_no_G() -> None:
    robot = pinrate.robots.two_link_planar()
    partition = Partition(["theta1"], ["theta2"], linear="x", angular="z")
    # v_x from theta1 is l1 S2 (eq. 10): A = [l1 S2] vanishes at theta2 = 0.
    with pytest.raises(pinrate.SingularBlockError, match="block A"):
        pinrate.convergence(robot, np.array([0.2, 0.0]), partition=partition)


def polar_fraction(l: float, d2_low: float, d2_high: float) -> float:  # noqa: E741
    """Share of (d2, theta3) uniform in the limits with C3 > -d2 / (2 l) (eq. 58), by quadrature."""
    d2 = np.linspace(d2_low, d2_high, 200001)
    share = np.where(d2 >= 2 * l, 1.0, np.arccos(-np.clip(d2 / (2 * l), 0, 1)) / math.pi)
    return float(np.trapezoid(share, d2) / (d2_high - d2_low))


def test_sample_convergence_matches_eq_58_by_quadrature() -> None:
    robot = pinrate.robots.planar_polar()
    lower, upper = robot.position_limits()
    sample = pinrate.sample_convergence(robot, 20000, rng=3)
    expected = polar_fraction(0.2, lower[1], upper[1])
    low, high = sample.interval
    assert low <= expected <= high
    assert abs(sample.fraction - expected) < 0.015
    assert sample.q.shape == (20000, 3) and sample.spectral_radius.shape == (20000,)


def test_sample_convergence_agrees_with_the_single_test(ur5: pinrate.Robot) -> None:
    sample = pinrate.sample_convergence(ur5, 50, rng=np.random.default_rng(1))
    for q, radius in zip(sample.q[:10], sample.spectral_radius[:10], strict=True):
        assert radius == pytest.approx(pinrate.convergence(ur5, q).spectral_radius, rel=1e-9)


def test_sample_convergence_only_draws_partition_joints(panda: pinrate.Robot) -> None:
    sample = pinrate.sample_convergence(panda, 30, rng=2)
    np.testing.assert_array_equal(sample.q[:, 7:], np.tile(panda.neutral()[7:], (30, 1)))


def test_wilson_interval_known_values() -> None:
    # 50 of 100: the textbook Wilson interval is 0.4038 .. 0.5962.
    low, high = wilson_interval(50, 100)
    assert low == pytest.approx(0.4038, abs=1e-4) and high == pytest.approx(0.5962, abs=1e-4)
    assert wilson_interval(0, 10)[0] == 0.0 and wilson_interval(10, 10)[1] == pytest.approx(1.0)


@pytest.mark.parametrize("bad", [0, -5, 2.5, True])
def test_sample_count_must_be_a_positive_integer(ur5: pinrate.Robot, bad: object) -> None:
    with pytest.raises(pinrate.InputError, match="samples"):
        pinrate.sample_convergence(ur5, bad)
