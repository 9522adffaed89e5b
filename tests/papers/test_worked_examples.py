"""Every worked result of both papers, against the closed forms (see docs/paper-results.md)."""

from __future__ import annotations

import importlib
import math
import pkgutil

import numpy as np
import pytest

import pinrate
from pinrate import robots
from pinrate.analysis import design
from pinrate.papers import (
    barker_jacobian,
    barker_wrist,
    convergence_boundaries,
    polar_simulation,
    scara_simulation,
    sensor_jacobians,
    spherical_6dof,
    table,
    worked_examples,
)
from support import ROOT

DOC = ROOT / "docs" / "paper-results.md"


def test_two_link_eq_10() -> None:
    assert sensor_jacobians.two_link_deviation() < 1e-12


def test_cylindrical_eq_13() -> None:
    assert sensor_jacobians.cylindrical_deviation() < 1e-12


def test_spherical_eq_16() -> None:
    assert sensor_jacobians.spherical_deviation() < 1e-12


def test_first_joint_independent() -> None:
    assert all(sensor_jacobians.first_joint_independent().values())
    # The detector is not vacuous: with the sensor on the base, J depends on the first joint.
    base_view = pinrate.load("ur5", sensor="base_link")
    assert "shoulder_pan_joint" not in design.independent_joints(base_view)


def test_diagonal_arms() -> None:
    assert sensor_jacobians.diagonal_arms() == {
        "cartesian": True,
        "cylindrical": True,
        "spherical": True,
        "scara": False,
        "articulated (ur5)": False,
    }


def test_eq_22_B_zero_iff_wrist_meets_tcp() -> None:
    centre = robots.barker_arm()
    assert sensor_jacobians.max_abs_B(centre) < 1e-12
    assert sensor_jacobians.max_abs_B(robots.cartesian()) < 1e-12
    assert sensor_jacobians.max_abs_B(robots.barker_arm(tip="hand")) > 1e-2  # HW away from the axes
    assert sensor_jacobians.max_abs_B(robots.spherical_6dof()) > 1e-2  # tool length l beyond P
    assert sensor_jacobians.max_abs_B(robots.spherical_6dof(tip="wrist_centre")) < 1e-12  # TCP at P
    assert sensor_jacobians.mca2_minus_exact(centre) < 1e-9


def test_polar_boundary() -> None:
    assert convergence_boundaries.polar_boundary_agreement() == 1.0


def test_polar_rule() -> None:
    # Eq. 58 at C3 = -1: rho = l / (d2 - l) < 1 iff d2 > 2 l.
    assert convergence_boundaries.polar_rule(points=61) == pytest.approx(2 * 0.2, abs=1e-3)


def test_scara_boundary() -> None:
    assert convergence_boundaries.scara_boundary_agreement() == 1.0


def test_hirata_rule() -> None:
    # Eq. 63 for every theta3 (S23 = -1) and theta2 >= 25°: l3 < l2 sin 25° / 2.
    closed_form = 0.275 * math.sin(math.radians(25)) / 2
    limit = convergence_boundaries.hirata_rule()
    assert limit == pytest.approx(closed_form, abs=2e-4)
    assert limit < 0.060  # the paper's rounded rule


def test_spherical_6dof_jacobian_and_eigenvalues() -> None:
    jacobian_deviation, eigen_deviation = spherical_6dof.spherical_6dof_deviations(count=100)
    assert jacobian_deviation < 1e-12
    assert eigen_deviation < 1e-8


def test_spherical_6dof_jacobian_matches_finite_differences() -> None:
    # The corrected eq. 70 is checked against pose differences, not only against pinrate.
    from support import finite_difference_jacobian

    robot = robots.spherical_6dof()
    for q in robot.sample_configurations(5, 1):
        np.testing.assert_allclose(
            spherical_6dof.spherical_6dof_jacobian(q, 0.1), finite_difference_jacobian(robot, q), atol=1e-6
        )


def test_printed_eq_71() -> None:
    # Eq. 71 is U A^-1 B W^-1 of the printed eq. 70 except for the sign of d3 in entry (3, 3).
    others, printed, corrected = spherical_6dof.printed_eq71_errors(count=100)
    assert others < 1e-9 and corrected < 1e-9
    assert printed > 0.1
    # The same from numpy's solve alone, and the derivation's step: row 1 of B W^-1 is
    # (0, l C5, l C4 S5), so G(3, 3) = -S2 l C4 S5 / a11.
    l = 0.1  # noqa: E741
    for q in robots.spherical_6dof().sample_configurations(20, 25):
        J = spherical_6dof.spherical_6dof_printed_jacobian(q, l)
        A, B, U, W = J[:3, :3], J[:3, 3:], J[3:, :3], J[3:, 3:]
        B_W_inverse = np.linalg.solve(W.T, B.T).T
        G = U @ np.linalg.solve(A, B_W_inverse)
        C4, C5, S5 = math.cos(q[3]), math.cos(q[4]), math.sin(q[4])
        np.testing.assert_allclose(B_W_inverse[0], [0.0, l * C5, l * C4 * S5], atol=1e-12)
        corrected_g = spherical_6dof.spherical_6dof_printed_G(q, l, d3_sign_33=-1.0)
        np.testing.assert_allclose(G, corrected_g, atol=1e-9 * max(1.0, np.abs(G).max()))
        assert G[2, 2] == pytest.approx(-math.sin(q[1]) * l * C4 * S5 / A[0, 0], rel=1e-9, abs=1e-12)


def test_spherical_6dof_work_volume() -> None:
    # §5.3: eq. 72 holds for every theta4 (the paper's "always") iff C2 C5 > |S2 S5|, i.e.
    # |theta2| + |theta5| < 90°: exactly half of the (theta2, theta5) square (-90°, 90°)²; at
    # theta4 = 0 (C4 = 1) |theta2 + theta5| < 90°, exactly 3/4. The shares are binomial
    # estimates over n samples: standard error sqrt(p (1 - p) / n), held to 4 of them (a
    # false failure has probability 6e-5; the seed is fixed anyway).
    volume = spherical_6dof.spherical_6dof_work_volume()
    n = volume.samples
    assert n >= 20000
    assert abs(volume.every_theta4 - 0.5) <= 4 * math.sqrt(0.5 * 0.5 / n)
    assert abs(volume.theta4_zero - 0.75) <= 4 * math.sqrt(0.75 * 0.25 / n)
    assert volume.sufficient  # eq. 72 ⇒ ρ < 1 (d3 > 2 l)


def test_spherical_6dof_work_volume_exact_shares() -> None:
    # The exact 1/2 and 3/4 by a midpoint rule on the square, eq. 72's K minimised over a
    # theta4 grid (no use of K being affine in C4): the error of the rule is O(h) on the
    # boundary, under 3 / points.
    points = 600
    h = math.pi / points
    midpoints = -math.pi / 2 + h * (np.arange(points) + 0.5)
    theta2, theta5 = np.meshgrid(midpoints, midpoints)
    theta4 = np.linspace(0.0, math.pi, 181)[:, None, None]
    K = np.cos(theta2) * np.cos(theta5) - np.sin(theta2) * np.cos(theta4) * np.sin(theta5)
    assert abs(float(np.mean(K.min(axis=0) > 0)) - 0.5) < 3 / points
    assert abs(float(np.mean(K[0] > 0)) - 0.75) < 3 / points


def test_barker_determinant() -> None:
    assert barker_jacobian.barker_det_deviation() < 1e-12
    assert barker_jacobian.barker_det_deviation(alpha3=1.4, a3=0.05, r3=0.03) < 1e-12


def test_barker_singularities() -> None:
    extended, folded = barker_jacobian.barker_singular_configurations()
    assert barker_jacobian.barker_singular(extended) and barker_jacobian.barker_singular(folded)
    assert not barker_jacobian.barker_singular(np.array([0.3, 0.4, 0.8, 0.1, 0.6, 0.0]))


def _mca2(robot: pinrate.Robot, q: np.ndarray, twist: np.ndarray) -> np.ndarray:
    return pinrate.joint_rates(robot, q, twist, algorithm="mca2")


def test_barker_wrist_rates() -> None:
    # Eq. 49-51 evaluated with the rates pinrate produced (RVEL~ from the command, eq. 48).
    assert barker_wrist.barker_wrist_deviation(count=50) < 1e-9
    assert barker_wrist.barker_wrist_deviation(count=20, alpha3=1.4, a3=0.05, r3=0.03) < 1e-9


def test_barker_wrist_rates_check_fails_for_wrong_rates() -> None:
    # The check is of the rates, not of the robot's geometry: wrist rates off by 1e-6 rad/s,
    # random wrist rates, or an arm rate off by 1e-6 rad/s leave a residual of their size.
    rng = np.random.default_rng(3)

    def wrist_nudged(robot: pinrate.Robot, q: np.ndarray, twist: np.ndarray) -> np.ndarray:
        return _mca2(robot, q, twist) + np.array([0.0, 0.0, 0.0, 1e-6, 1e-6, 1e-6])

    def wrist_random(robot: pinrate.Robot, q: np.ndarray, twist: np.ndarray) -> np.ndarray:
        rates = _mca2(robot, q, twist)
        rates[3:] = rng.normal(size=3)
        return rates

    def arm_nudged(robot: pinrate.Robot, q: np.ndarray, twist: np.ndarray) -> np.ndarray:
        return _mca2(robot, q, twist) + np.array([1e-6, 0.0, 0.0, 0.0, 0.0, 0.0])

    assert barker_wrist.barker_wrist_deviation(count=20, solver=_mca2) < 1e-9
    assert barker_wrist.barker_wrist_deviation(count=20, solver=wrist_nudged) > 1e-7
    assert barker_wrist.barker_wrist_deviation(count=20, solver=wrist_random) > 1e-2
    assert barker_wrist.barker_wrist_deviation(count=20, solver=arm_nudged) > 1e-7


def test_fig_6() -> None:
    converging, diverging = polar_simulation.fig6()
    assert converging.start_lambda == pytest.approx(0.50) and converging.target_lambda == pytest.approx(0.45)
    assert diverging.start_lambda == pytest.approx(-1.5) and diverging.target_lambda == pytest.approx(-0.9)
    assert converging.converged
    assert not diverging.converged and diverging.reason.startswith("diverging")


POLAR_L = 0.2
"""The planar polar robot's link l (m), eq. 55."""


def polar_pose(q: np.ndarray) -> np.ndarray:
    """(x, y, phi) of the polar robot's TCP (Fig. 4): d2 (C1, S1) + l (C13, S13), phi = theta1 + theta3."""
    t1, d2, t3 = q
    return np.array(
        [d2 * math.cos(t1) + POLAR_L * math.cos(t1 + t3), d2 * math.sin(t1) + POLAR_L * math.sin(t1 + t3), t1 + t3]
    )


def polar_error(q: np.ndarray, target: np.ndarray) -> tuple[np.ndarray, float]:
    """The sensor's command at q for the dead-beat gain: (v in the sensor's axes, x along d2; Ω)."""
    t1 = q[0]
    here = polar_pose(q)
    rotation = np.array([[math.cos(t1), -math.sin(t1)], [math.sin(t1), math.cos(t1)]])
    return rotation.T @ (target[:2] - here[:2]), math.remainder(target[2] - here[2], 2 * math.pi)


def polar_mca2_update(q: np.ndarray, v: np.ndarray, omega: float) -> np.ndarray:
    """MCA2 (eq. 44-45) on eq. 55: arm (theta1, d2) = A^-1 v, theta3 = W^-1 (Ω - U arm), W = 1, U = (1, 0)."""
    s3, c3 = math.sin(q[2]), math.cos(q[2])
    A = np.array([[-POLAR_L * s3, 1.0], [q[1] + POLAR_L * c3, 0.0]])
    theta1, d2 = np.linalg.solve(A, v)
    return np.array([theta1, d2, omega - theta1])


def polar_dead_beat(q0: np.ndarray, target: np.ndarray, steps: int, tol: float = 1e-6) -> tuple[np.ndarray, np.ndarray]:
    """The Theorem's iteration (gain dt = 1): q <- q + MCA2(error), no limits; (q's, total errors)."""
    q, configurations, errors = np.array(q0, dtype=float), [], []
    for _ in range(steps + 1):
        v, omega = polar_error(q, target)
        configurations.append(q)
        errors.append(float(np.linalg.norm(v)) + abs(omega))
        if np.linalg.norm(v) < tol and abs(omega) < tol:
            break
        q = q + polar_mca2_update(q, v, omega)
    return np.array(configurations), np.array(errors)


def test_fig_6b_continued() -> None:
    q0, q_target = polar_simulation.fig6_poses("b")
    for q, lam in ((q0, -1.5), (q_target, -0.9)):  # eq. 56
        assert POLAR_L * math.cos(q[2]) / (q[1] + POLAR_L * math.cos(q[2])) == pytest.approx(lam, rel=1e-12)
    target = polar_pose(q_target)
    reference_q, reference_error = polar_dead_beat(q0, target, 2000)

    # The servo: its steps are the iteration's until its stop rule (e > 3 min e + tol) fires.
    _, servo_run = polar_simulation.fig6()
    best = np.minimum.accumulate(reference_error)
    stop = next(k for k, error in enumerate(reference_error) if error > 3 * best[k] + 1e-6)
    assert stop == 4 and len(servo_run.q) == stop + 1 and servo_run.reason.startswith("diverging")
    np.testing.assert_allclose(servo_run.q, reference_q[: stop + 1], atol=1e-12)
    np.testing.assert_allclose(servo_run.total_error, reference_error[: stop + 1], atol=1e-12)

    # Without joint limits pinrate's step is that iteration to the end: it converges, on d2 < 0.
    free, held = polar_simulation.fig6b_continued()
    assert free.converged and set(free.statuses) == {"OK"}
    assert free.steps == len(reference_q) - 1 == 110
    np.testing.assert_allclose(free.q, reference_q, atol=1e-9)
    np.testing.assert_allclose(free.total_error, reference_error, atol=1e-9)
    assert reference_error.max() / reference_error[0] > 4 and int(np.argmax(reference_error)) == 7
    denominator = reference_q[:, 1] + POLAR_L * np.cos(reference_q[:, 2])  # G's pole, eq. 56
    assert polar_simulation.polar_pole_crossings(free.q) == int(np.sum(denominator[1:] * denominator[:-1] < 0)) == 3
    assert int(np.argmax(reference_q[:, 1] < 0)) == 6 and reference_q[-1, 1] < 0
    np.testing.assert_allclose(polar_pose(reference_q[-1])[:2], target[:2], atol=1e-6)
    np.testing.assert_allclose(reference_q[-1, 1], -q_target[1], atol=1e-6)  # the mirror branch:
    for joint in (0, 2):  # theta1 and theta3 half a turn from the target's
        assert abs(math.remainder(reference_q[-1, joint] - q_target[joint], 2 * math.pi)) == pytest.approx(
            math.pi, abs=1e-5
        )

    # With the URDF's limits held it ends at d2's and theta3's limits, a fixed point of the step,
    # where the plain MCA2 update would drive both further into them.
    lower, _ = robots.planar_polar().joint_limits("d2")
    assert not held.converged and held.steps == 2000
    end = held.q[-1]
    assert end[1] == pytest.approx(lower, abs=1e-12) and end[2] == pytest.approx(math.pi, abs=1e-12)
    assert np.abs(held.q[-100:] - end).max() < 1e-12
    v, omega = polar_error(end, target)
    update = polar_mca2_update(end, v, omega)
    assert update[1] < -0.01 and update[2] > 0.1
    assert held.position_error[-1] == pytest.approx(np.linalg.norm(v), abs=1e-12)
    assert held.orientation_error[-1] == pytest.approx(abs(omega), abs=1e-12)


def test_fig_9() -> None:
    converging, diverging = scara_simulation.fig9()
    assert converging.start_lambda == pytest.approx(0.695, abs=1e-3)
    assert converging.target_lambda == pytest.approx(0.718, abs=2e-3)
    assert converging.converged and converging.error_growth <= 1.0 + 1e-9
    assert diverging.start_lambda > 1
    assert diverging.error_growth > 1.1  # moving away from the target while λ > 1
    assert diverging.final_q[1] < 0  # it only settles after crossing to the other elbow branch


def test_docs_are_current() -> None:
    expected = table.markdown(worked_examples.results())
    assert DOC.is_file(), "docs/paper-results.md missing: run `pinrate paper > docs/paper-results.md`"
    assert DOC.read_text(encoding="utf-8") == expected, "docs/paper-results.md is stale: run `make docs`"


def test_every_row_is_in_the_table() -> None:
    # A module's @row functions reach the table only through worked_examples.SECTIONS.
    for info in pkgutil.iter_modules(pinrate.papers.__path__, "pinrate.papers."):
        importlib.import_module(info.name)
    sections = [section.__name__ for section in worked_examples.SECTIONS]
    assert set(table.ROWS) <= set(sections), set(table.ROWS) - set(sections)
    assert all(table.rows_of(section) for section in worked_examples.SECTIONS)
    assert len(sections) == len(set(sections))
