"""Shoham & Koren §5.1-5.2: where MCA2 converges on the planar polar robot and on the SCARA.

Rows: G in closed form (eq. 56 polar, l = 0.2 m; eq. 60 SCARA, l1 = l2 = l3 = 0.4 m), the
boundaries ρ < 1 ⇔ eq. 58 (Fig. 5) and eq. 63 (Fig. 8) over random samples, and the design
rules they give: §5.1's d2 / l > 2, and §5.2's tool length for the Hirata ARH-300 (Fig. 10),
l3 < l2 sin 25° / 2 (the worst case S2 = sin 25°, S23 = -1 of eq. 63).
"""

from __future__ import annotations

import math

import numpy as np

from .. import robots
from ..analysis import design
from ..theorem import convergence, sample_convergence
from .table import Result, deviation_text, row


# ---------------------------------------------------------------------- §5.1 polar
def _polar_G_deviation(count: int = 500) -> float:
    """max ``|G - l C3 / (d2 + l C3)|`` (eq. 56), l = 0.2."""
    robot = robots.planar_polar()

    def deviation(q: np.ndarray) -> float:
        closed_form = 0.2 * math.cos(q[2]) / (q[1] + 0.2 * math.cos(q[2]))
        return abs(float(convergence(robot, q).G[0, 0]) - closed_form)

    return max(deviation(q) for q in robot.sample_configurations(count, 0))


@row
def _polar_G_row() -> Result:
    """S&K eq. 56: the polar robot's G."""
    return Result(
        "S&K eq. 56",
        "polar: G = l C3 / (d2 + l C3)",
        f"max deviation {deviation_text(_polar_G_deviation())}",
        "theorem/test_convergence.py::test_planar_polar_G_is_eq_56",
    )


def polar_boundary_agreement(count: int = 5000) -> float:
    """Share of samples where ρ < 1 agrees with eq. 58, C3 > -d2 / (2 l)."""
    sample = sample_convergence(robots.planar_polar(), count, rng=4)
    analytic = np.cos(sample.q[:, 2]) > -sample.q[:, 1] / (2 * 0.2)
    return float(np.mean((sample.spectral_radius < 1) == analytic))


@row
def _polar_boundary_row() -> Result:
    """S&K eq. 58, Fig. 5: the polar robot's boundary."""
    return Result(
        "S&K eq. 58, Fig. 5",
        "polar converges iff C3 > -d2 / (2 l)",
        f"ρ < 1 agrees with eq. 58 on {100 * polar_boundary_agreement():.2f} % of 5000 samples",
        "papers/test_worked_examples.py::test_polar_boundary",
    )


def polar_rule(points: int = 61) -> float:
    """The smallest lower stroke d2_min whose worst ρ < 1 (the rule says 2 l = 0.4)."""
    return design.smallest_parameter(
        lambda d2_min: robots.planar_polar(l=0.2, d2_min=d2_min), 0.1, 0.9, points=points, tolerance=1e-5
    )


@row
def _polar_rule_row() -> Result:
    """S&K §5.1's rule: d2 / l > 2 converges in the whole work volume."""
    smallest = polar_rule()
    return Result(
        "S&K §5.1 rule",
        "d2 / l > 2 ⇒ converges in the whole work volume",
        f"smallest d2_min with worst ρ < 1: {smallest:.4f} m = {smallest / 0.2:.3f} l",
        "papers/test_worked_examples.py::test_polar_rule",
    )


# ---------------------------------------------------------------------- §5.2 SCARA
def _scara_G_deviation(count: int = 500) -> float:
    """max ``|G - l3 S23 / (l2 S2 + l3 S23)|`` (eq. 60), relative, l1 = l2 = l3 = 0.4."""
    robot = robots.scara()

    def deviation(q: np.ndarray) -> float:
        s2, s23 = math.sin(q[1]), math.sin(q[1] + q[3])
        closed_form = 0.4 * s23 / (0.4 * s2 + 0.4 * s23)
        return abs(float(convergence(robot, q).G[0, 0]) - closed_form) / max(1.0, abs(closed_form))

    return max(deviation(q) for q in robot.sample_configurations(count, 0))


@row
def _scara_G_row() -> Result:
    """S&K eq. 60: the SCARA's G."""
    return Result(
        "S&K eq. 60",
        "SCARA: G = l3 S23 / (l2 S2 + l3 S23)",
        f"max relative deviation {deviation_text(_scara_G_deviation())}",
        "theorem/test_convergence.py::test_scara_G_is_eq_60",
    )


def scara_boundary_agreement(count: int = 5000) -> float:
    """Share of samples where ρ < 1 agrees with eq. 63, S23 / S2 > -l2 / (2 l3)."""
    sample = sample_convergence(robots.scara(), count, rng=5)
    s2, s23 = np.sin(sample.q[:, 1]), np.sin(sample.q[:, 1] + sample.q[:, 3])
    return float(np.mean((sample.spectral_radius < 1) == (s23 / s2 > -0.5)))


@row
def _scara_boundary_row() -> Result:
    """S&K eq. 63, Fig. 8: the SCARA's boundary."""
    return Result(
        "S&K eq. 63, Fig. 8",
        "SCARA converges iff S23 / S2 > -l2 / (2 l3)",
        f"ρ < 1 agrees with eq. 63 on {100 * scara_boundary_agreement():.2f} % of 5000 samples",
        "papers/test_worked_examples.py::test_scara_boundary",
    )


def hirata_rule(points: int = 121) -> float:
    """The largest tool length l3 (m) with worst ρ < 1 on the Hirata ARH-300."""
    return design.largest_parameter(lambda l3: robots.hirata_arh300(l3=l3), 0.01, 0.3, points=points, tolerance=1e-6)


HIRATA_CLOSED_FORM = 0.275 * math.sin(math.radians(25)) / 2
"""l2 sin(25°) / 2: the worst case S2 = sin 25°, S23 = -1 of eq. 63."""


@row
def _hirata_row() -> Result:
    """S&K §5.2, Fig. 10: the Hirata ARH-300's largest tool length."""
    return Result(
        "S&K §5.2, Fig. 10",
        "Hirata ARH-300 (l2 = 275 mm, 25° < theta2 < 145°): l3 < 60 mm "
        f"(exactly l2 sin 25° / 2 = {1000 * HIRATA_CLOSED_FORM:.2f} mm)",
        f"largest l3 with worst ρ < 1 (bisection, 121² grid): {1000 * hirata_rule():.2f} mm",
        "papers/test_worked_examples.py::test_hirata_rule",
    )
