"""Every worked result of both papers, against the closed forms (see docs/paper-results.md)."""

from __future__ import annotations

import math

import numpy as np
import pytest

import pinrate
from pinrate import robots
from pinrate.analysis import design
from pinrate.papers import worked_examples as paper_results
from support import ROOT

DOC = ROOT / "docs" / "paper-results.md"


def test_two_link_eq_10() -> None:
    assert paper_results.two_link_deviation() < 1e-12


def test_cylindrical_eq_13() -> None:
    assert paper_results.cylindrical_deviation() < 1e-12


def test_spherical_eq_16() -> None:
    assert paper_results.spherical_deviation() < 1e-12


def test_first_joint_independent() -> None:
    assert all(paper_results.first_joint_independent().values())
    # The detector is not vacuous: with the sensor on the base, J depends on the first joint.
    base_view = pinrate.load("ur5", sensor="base_link")
    assert "shoulder_pan_joint" not in design.independent_joints(base_view)


def test_diagonal_arms() -> None:
    assert paper_results.diagonal_arms() == {
        "cartesian": True,
        "cylindrical": True,
        "spherical": True,
        "scara": False,
        "articulated (ur5)": False,
    }


def test_eq_22_B_zero_iff_wrist_meets_tcp() -> None:
    centre = robots.barker_arm()
    assert paper_results.max_abs_B(centre) < 1e-12
    assert paper_results.max_abs_B(robots.cartesian()) < 1e-12
    assert paper_results.max_abs_B(robots.barker_arm(tip="hand")) > 1e-2  # HW away from the axes
    assert paper_results.max_abs_B(robots.spherical_6dof()) > 1e-2  # tool length l beyond P
    assert paper_results.max_abs_B(robots.spherical_6dof(tip="wrist_centre")) < 1e-12  # TCP at P
    assert paper_results.mca2_minus_exact(centre) < 1e-9


def test_polar_boundary() -> None:
    assert paper_results.polar_boundary_agreement() == 1.0


def test_polar_rule() -> None:
    # Eq. 58 at C3 = -1: rho = l / (d2 - l) < 1 iff d2 > 2 l.
    assert paper_results.polar_rule(points=61) == pytest.approx(2 * 0.2, abs=1e-3)


def test_scara_boundary() -> None:
    assert paper_results.scara_boundary_agreement() == 1.0


def test_hirata_rule() -> None:
    # Eq. 63 for every theta3 (S23 = -1) and theta2 >= 25°: l3 < l2 sin 25° / 2.
    closed_form = 0.275 * math.sin(math.radians(25)) / 2
    limit = paper_results.hirata_rule()
    assert limit == pytest.approx(closed_form, abs=2e-4)
    assert limit < 0.060  # the paper's rounded rule


def test_spherical_6dof_jacobian_and_eigenvalues() -> None:
    jacobian_deviation, eigen_deviation = paper_results.spherical_6dof_deviations(count=100)
    assert jacobian_deviation < 1e-12
    assert eigen_deviation < 1e-8


def test_spherical_6dof_jacobian_matches_finite_differences() -> None:
    # The corrected eq. 70 is checked against pose differences, not only against pinrate.
    from support import finite_difference_jacobian

    robot = robots.spherical_6dof()
    for q in robot.sample_configurations(5, 1):
        np.testing.assert_allclose(
            paper_results.spherical_6dof_jacobian(q, 0.1), finite_difference_jacobian(robot, q), atol=1e-6
        )


def test_spherical_6dof_work_volume() -> None:
    fraction, k_fraction, sufficient = paper_results.spherical_6dof_fractions(count=5000)
    assert k_fraction >= 0.5 - 0.02  # Fig. 12: "at least within 50 percent"
    assert fraction >= k_fraction and sufficient


def test_barker_determinant() -> None:
    assert paper_results.barker_det_deviation() < 1e-12
    assert paper_results.barker_det_deviation(alpha3=1.4, a3=0.05, r3=0.03) < 1e-12


def test_barker_singularities() -> None:
    extended, folded = paper_results.barker_singular_configurations()
    assert paper_results.barker_singular(extended) and paper_results.barker_singular(folded)
    assert not paper_results.barker_singular(np.array([0.3, 0.4, 0.8, 0.1, 0.6, 0.0]))


def test_barker_wrist_rates() -> None:
    assert paper_results.barker_wrist_deviation(count=50) < 1e-9
    assert paper_results.barker_wrist_deviation(count=20, alpha3=1.4, a3=0.05, r3=0.03) < 1e-9


def test_fig_6() -> None:
    converging, diverging = paper_results.fig6()
    assert converging.start_lambda == pytest.approx(0.50) and converging.target_lambda == pytest.approx(0.45)
    assert diverging.start_lambda == pytest.approx(-1.5) and diverging.target_lambda == pytest.approx(-0.9)
    assert converging.converged
    assert not diverging.converged and diverging.reason.startswith("diverging")


def test_fig_9() -> None:
    converging, diverging = paper_results.fig9()
    assert converging.start_lambda == pytest.approx(0.695, abs=1e-3)
    assert converging.target_lambda == pytest.approx(0.718, abs=2e-3)
    assert converging.converged and converging.error_growth <= 1.0 + 1e-9
    assert diverging.start_lambda > 1
    assert diverging.error_growth > 1.1  # moving away from the target while λ > 1
    assert diverging.final_q[1] < 0  # it only settles after crossing to the other elbow branch


def test_docs_are_current() -> None:
    expected = paper_results.markdown(paper_results.results())
    assert DOC.is_file(), "docs/paper-results.md missing: run `pinrate paper > docs/paper-results.md`"
    assert DOC.read_text(encoding="utf-8") == expected, "docs/paper-results.md is stale: run `make docs`"
