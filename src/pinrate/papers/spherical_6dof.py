"""Shoham & Koren §5.3: the six-DOF spherical robot (eq. 70-73, Fig. 12), l = 0.1 m.

Rows: J and the eigenvalues of G against the corrected eq. 70, eq. 71 against G computed
from the printed eq. 70, and what eq. 72-73 promise of the work volume.

Misprints found in the OCR'd text (each derived again and tested):

* S&K eq. 70, second column (theta2): printed (0, d3 - l C5, -l C4 - S5); the derivation
  (theta2 turns about the sensor's x axis at the joint centre, the TCP lies at
  d3 z + l (S4 S5, -C4 S5, C5)) gives (0, -(d3 + l C5), -l C4 S5). The printed det(A) and
  eq. 71 follow the misprinted column; with the corrected one G has the eigenvalues
  0, l C5 / (d3 + l C5) and l K / (d3 C2 + l K) with K = C2 C5 - S2 C4 S5, so eq. 72
  (K > 0) is sufficient (the exact condition is K > -d3 C2 / (2 l)) and eq. 73 becomes
  C5 > -d3 / (2 l); both hold throughout when d3 > 2 l and -90° < theta5 < 90°.
* S&K eq. 71, entry (3, 3): printed l (d3 S2 C4 S5 + l S2 C4 S5 C5) / det(A); the printed
  eq. 70 gives l (-d3 S2 C4 S5 + l S2 C4 S5 C5) / det(A). Derivation: with the printed
  column 2 (0, d3 - l C5, -l C4 S5) A is lower triangular, det(A) = a11 (d3 - l C5) (the
  printed det(A)), a11 = d3 C2 + l C2 C5 - l S2 C4 S5; U's third row is (-S2, 0, 0), so row
  3 of G = U A^-1 B W^-1 is -S2 / a11 times row 1 of B W^-1, which is (0, l C5, l C4 S5)
  (solve x W = (l C4 S5, l S4 C5, 0)). Hence G(3, 3) = -l S2 C4 S5 / a11
  = l (-d3 S2 C4 S5 + l S2 C4 S5 C5) / det(A), while G(3, 2) = -l S2 C5 / a11 is printed
  right. Every other entry of eq. 71 is U A^-1 B W^-1 of the printed eq. 70
  (:func:`printed_eq71_errors`); the OCR's "-l C4 - S5" at (3, 2) of eq. 70 does not
  enter G (U's third column is 0 and A is lower triangular: U A^-1 uses A's leading 2x2).

What the paper's statement measures (read from the text, computed as read):

* S&K §5.3's "at least within 50 percent of the work volume convergence always exists"
  is about the (theta2, theta5) square (-90°, 90°)² with theta4 free ("always": for every
  theta4): K = C2 C5 - S2 C4 S5 is affine in C4, so eq. 72 holds for every theta4 iff
  C2 C5 > ``|S2 S5|``, i.e. cos(``|theta2|`` + ``|theta5|``) > 0, ``|theta2|`` + ``|theta5|`` < 90°: exactly
  half the square. At one theta4 with C4 = ±1 it is ``|theta2 ± theta5|`` < 90°, 3/4 of it
  (the paper's "much larger" effective work volume when C4 does not take both values).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .. import robots
from ..errors import SingularBlockError
from ..theorem import convergence, convergence_from_blocks, spectral_radius_at
from .table import Result, deviation_text, row, yes_no


# ---------------------------------------------------------------------- eq. 70, J and the eigenvalues of G
def spherical_6dof_jacobian(q: np.ndarray, l: float) -> np.ndarray:  # noqa: E741
    """Eq. 70 with its second column corrected (see the module docstring)."""
    _, t2, d3, t4, t5, _ = q
    C2, S2, C4, S4, C5, S5 = (
        math.cos(t2),
        math.sin(t2),
        math.cos(t4),
        math.sin(t4),
        math.cos(t5),
        math.sin(t5),
    )
    return np.array(
        [
            [d3 * C2 + l * C2 * C5 - l * S2 * C4 * S5, 0, 0, l * C4 * S5, l * S4 * C5, 0],
            [-l * S2 * S4 * S5, -(d3 + l * C5), 0, l * S4 * S5, -l * C4 * C5, 0],
            [-l * C2 * S4 * S5, -l * C4 * S5, 1, 0, -l * S5, 0],
            [0, 1, 0, 0, C4, S4 * S5],
            [C2, 0, 0, 0, S4, -C4 * S5],
            [-S2, 0, 0, 1, 0, C5],
        ]
    )


def _spherical_6dof_eigenvalues(q: np.ndarray, l: float) -> np.ndarray:  # noqa: E741
    """0, l C5 / (d3 + l C5), l K / (d3 C2 + l K), K = C2 C5 - S2 C4 S5 (from the corrected eq. 70)."""
    _, t2, d3, t4, t5, _ = q
    K = math.cos(t2) * math.cos(t5) - math.sin(t2) * math.cos(t4) * math.sin(t5)
    return np.array([0.0, l * math.cos(t5) / (d3 + l * math.cos(t5)), l * K / (d3 * math.cos(t2) + l * K)])


def spherical_6dof_deviations(count: int = 300) -> tuple[float, float]:
    """(max ``|J - corrected eq. 70|``, max eigenvalue mismatch of G)."""
    robot = robots.spherical_6dof()
    l = 0.1  # noqa: E741
    worst_jacobian = worst_eigen = 0.0
    for q in robot.sample_configurations(count, 6):
        worst_jacobian = max(worst_jacobian, float(np.abs(robot.jacobian(q) - spherical_6dof_jacobian(q, l)).max()))
        try:
            found = np.sort(np.abs(convergence(robot, q).eigenvalues))
        except SingularBlockError:
            continue
        worst_eigen = max(worst_eigen, float(np.abs(found - np.sort(np.abs(_spherical_6dof_eigenvalues(q, l)))).max()))
    return worst_jacobian, worst_eigen


@row
def _jacobian_and_eigenvalues_row() -> Result:
    """S&K eq. 70-71: J against the corrected eq. 70, and G's eigenvalues."""
    jacobian_deviation, eigen_deviation = spherical_6dof_deviations()
    return Result(
        "S&K eq. 70-71",
        "six-DOF spherical J and G (eq. 70 column 2 misprinted)",
        f"J vs corrected eq. 70: {deviation_text(jacobian_deviation)}; eigenvalues of G vs "
        f"0, l C5/(d3 + l C5), l K/(d3 C2 + l K): {deviation_text(eigen_deviation)}",
        "papers/test_worked_examples.py::test_spherical_6dof_jacobian_and_eigenvalues",
    )


# ---------------------------------------------------------------------- eq. 71 as printed
def spherical_6dof_printed_jacobian(q: np.ndarray, l: float) -> np.ndarray:  # noqa: E741
    """Eq. 70 as printed (sensor axes; m, rad): column 2 (0, d3 - l C5, -l C4 S5), the OCR's
    "-l C4 - S5" read as -l C4 S5 (it does not enter G, module docstring)."""
    d3, t4, t5 = (float(value) for value in q[2:5])
    printed = spherical_6dof_jacobian(q, l)
    printed[:3, 1] = [0.0, d3 - l * math.cos(t5), -l * math.cos(t4) * math.sin(t5)]
    return printed


def spherical_6dof_printed_G(q: np.ndarray, l: float, *, d3_sign_33: float = 1.0) -> np.ndarray:  # noqa: E741
    """Eq. 71 as printed: G = (l / det A) [...] with the printed det(A) = d3² C2 - d3 l S2 C4 S5
    - l² C2 C5² + l² S2 C4 S5 C5 (dimensionless). ``d3_sign_33 = -1`` changes the sign of the d3
    term of entry (3, 3), the correction (module docstring)."""
    _, t2, d3, t4, t5, _ = q
    C2, S2, C4, S4, C5, S5 = (math.cos(t2), math.sin(t2), math.cos(t4), math.sin(t4), math.cos(t5), math.sin(t5))
    det = d3 * d3 * C2 - d3 * l * S2 * C4 * S5 - l * l * C2 * C5 * C5 + l * l * S2 * C4 * S5 * C5
    entries = np.array(
        [
            [
                -d3 * C2 * C5 - l * C2 * C5 * C5 + l * S2 * C4 * S5 * C5,
                l * S2 * S4 * S5 * C5,
                d3 * C2 * S4 * S5 + l * C2 * S4 * S5 * C5,
            ],
            [0.0, d3 * C2 * C5 - l * C2 * C5 * C5, d3 * C2 * C4 * S5 - l * C2 * C4 * S5 * C5],
            [0.0, -d3 * S2 * C5 + l * S2 * C5 * C5, d3_sign_33 * d3 * S2 * C4 * S5 + l * S2 * C4 * S5 * C5],
        ]
    )
    return l / det * entries


def printed_eq71_errors(count: int = 300) -> tuple[float, float, float]:
    """Eq. 71 against G = U A^-1 B W^-1 of the printed eq. 70 (pinrate's
    :func:`convergence_from_blocks` on its blocks), over random q of the six-DOF robot, each
    error relative to max(1, ``|G|``): (max over the entries other than (3, 3), max at (3, 3) as
    printed, max at (3, 3) with its d3 term's sign changed)."""
    robot = robots.spherical_6dof()
    l = 0.1  # noqa: E741
    others = printed = corrected = 0.0
    mask = np.ones((3, 3), dtype=bool)
    mask[2, 2] = False
    for q in robot.sample_configurations(count, 24):
        J = spherical_6dof_printed_jacobian(q, l)
        G = convergence_from_blocks(J[:3, :3], J[:3, 3:], J[3:, :3], J[3:, 3:]).G
        scale = max(1.0, float(np.abs(G).max()))
        as_printed = spherical_6dof_printed_G(q, l)
        others = max(others, float(np.abs(G - as_printed)[mask].max()) / scale)
        printed = max(printed, abs(float(G[2, 2] - as_printed[2, 2])) / scale)
        corrected = max(corrected, abs(float(G[2, 2] - spherical_6dof_printed_G(q, l, d3_sign_33=-1.0)[2, 2])) / scale)
    return others, printed, corrected


@row
def _printed_eq71_row() -> Result:
    """S&K eq. 71 against G of the printed eq. 70: entry (3, 3) misprinted."""
    printed_others, printed_33, corrected_33 = printed_eq71_errors()
    return Result(
        "S&K eq. 71",
        "G = (l / det A)[...] from the printed eq. 70; entry (3, 3) printed d3 S2 C4 S5 + l S2 C4 S5 C5",
        f"U A^-1 B W^-1 of the printed eq. 70 (column 2 (0, d3 - l C5, -l C4 S5)) vs eq. 71, 300 random q, "
        f"relative: entries other than (3, 3) {deviation_text(printed_others)}; (3, 3) as printed "
        f"off by up to {printed_33:.2f}, with the d3 term's sign changed (-d3 S2 C4 S5 + l S2 C4 S5 C5) "
        f"{deviation_text(corrected_33)}",
        "papers/test_worked_examples.py::test_printed_eq_71",
    )


# ---------------------------------------------------------------------- eq. 72-73, the work volume
@dataclass(frozen=True)
class WorkVolume:
    """Shares of the six-DOF robot's (theta2, theta5) square where eq. 72 holds (§5.3)."""

    samples: int
    every_theta4: float  # eq. 72 holds for every theta4 (the paper's "always"); exactly 1/2
    theta4_zero: float  # eq. 72 holds at theta4 = 0 (C4 = 1); exactly 3/4
    sufficient: bool  # pinrate's ρ < 1 wherever eq. 72 holds for every theta4 (three theta4 each)


def _eq72_K(theta2: np.ndarray, theta4: np.ndarray, theta5: np.ndarray) -> np.ndarray:
    """K = C2 C5 - S2 C4 S5 of eq. 72 (rad in, dimensionless out)."""
    return np.cos(theta2) * np.cos(theta5) - np.sin(theta2) * np.cos(theta4) * np.sin(theta5)


def spherical_6dof_work_volume(count: int = 20000, seed: int = 12) -> WorkVolume:
    """§5.3's "at least within 50 percent of the work volume convergence always exists".

    ``count`` configurations drawn uniformly in the robot's joint limits (theta2, theta5 in
    (-90°, 90°), the paper's assumptions C2 > 0 and -90° < theta5 < 90°; d3 in [0.3, 0.8] m
    > 2 l). Eq. 72 holds for every theta4 where K > 0 at C4 = +1 and at C4 = -1 (K is affine in
    C4): the share of those samples estimates the area of ``|theta2|`` + ``|theta5|`` < 90° over the
    square, 1/2. ``sufficient``: at each such sample pinrate's ρ (:func:`spectral_radius_at`,
    the corrected eq. 70) is below 1 at the sample's theta4 and at theta4 = 0 and 180°.
    """
    robot = robots.spherical_6dof()
    q = robot.sample_configurations(count, seed)
    theta2, theta5 = q[:, 1], q[:, 4]
    every = (_eq72_K(theta2, np.zeros(count), theta5) > 0) & (_eq72_K(theta2, np.full(count, math.pi), theta5) > 0)
    region = q[every]
    variants = [region]
    for theta4 in (0.0, math.pi):
        turned = region.copy()
        robot.set_joint_values(turned, "theta4", np.full(len(turned), theta4))
        variants.append(turned)
    radii = spectral_radius_at(robot, np.concatenate(variants))
    return WorkVolume(
        samples=count,
        every_theta4=float(np.mean(every)),
        theta4_zero=float(np.mean(_eq72_K(theta2, np.zeros(count), theta5) > 0)),
        sufficient=bool((radii < 1).all()),
    )


@row
def _work_volume_row() -> Result:
    """S&K eq. 72-73, Fig. 12: "at least within 50 percent of the work volume" (module docstring)."""
    volume = spherical_6dof_work_volume()
    return Result(
        "S&K eq. 72-73, Fig. 12",
        "-90° < theta5 < 90°, d3 > 2 l: eq. 72 (C2 C5 - S2 C4 S5 > 0) gives convergence always (any theta4) "
        "within at least 50 % of the work volume; much more when C4 does not take both ±1",
        f"{volume.samples} samples uniform in the joint limits ((theta2, theta5) in (-90°, 90°)²): eq. 72 holds "
        f"for every theta4 (at C4 = ±1) on {100 * volume.every_theta4:.2f} % (exactly 1/2: "
        f"|theta2| + |theta5| < 90°; binomial SE {100 * math.sqrt(0.25 / volume.samples):.2f} %), at theta4 = 0 "
        f"on {100 * volume.theta4_zero:.2f} % (exactly 3/4); pinrate's ρ < 1 wherever it holds for every "
        f"theta4 (at theta4 = 0°, 180° and the sample's): {yes_no(volume.sufficient)}",
        "papers/test_worked_examples.py::test_spherical_6dof_work_volume",
    )
