"""Barker eq. 34-44: the arm rates (theta1, theta2, theta3) for a base-axes TVEL^, in closed
form, by the generalized inverse and by the 2x2 reduction, and pinrate's step against each
(the frames and units of :mod:`.barker`, M and F1 .. F7 of :mod:`.barker_jacobian`).

* eq. 34-36 (Cramer's rule, det M = F1 (F3 F5 - F1 F4) = F1 ES (F5 C2 - F4 S2), eq. D4):
  theta1 = (TVEL^1 S1 - TVEL^2 C1)(F1 F4 - F3 F5) / det M = (C1 TVEL^2 - S1 TVEL^1) / F1,
  theta2 = +[F5 (TVEL^1 F7 + TVEL^2 F6) + TVEL^3 F1 F4] / det M,
  theta3 = -F1 (TVEL^1 F7 + TVEL^2 F6 + TVEL^3 F3) / det M.
* eq. 38: [theta1 theta2 theta3]' = M* TVEL^, M* the generalized (Moore-Penrose) inverse.
* eq. 39-44, the 2x2 reduction: theta1 = (F3 theta2 + F4 theta3 - C1 TVEL^1 - S1 TVEL^2) / F2
  (C1 x row 1 + S1 x row 2 of eq. 25; F2 != 0 on this arm, SN~ != 0 and CAL3 ~ 0), and from rows 1 and 3
  g1 = M1 [theta2 theta3]', g1 = (F2 TVEL^1 - F6 (C1 TVEL^1 + S1 TVEL^2), TVEL^3),
  M1 = [[(C1 F2 - F6) F3, (C1 F2 - F6) F4], [-F1, -F5]], solved by M1*.

Misprints settled (each derived again and tested in tests/papers/test_barker.py):

* eq. 35 prints theta2 = -{F5 [TVEL^1 F7 + TVEL^2 F6] + TVEL^3 F1 F4} / det M: the overall
  sign is wrong (Cramer's rule gives +).
* eq. 36 prints theta3 = -F1 [TVEL^1 F7 - TVEL^2 F6 + TVEL^3 F3] / det M: the TVEL^2 F6 term
  has the wrong sign (Cramer's rule gives +). Eq. 34 is right and simplifies to
  (C1 TVEL^2 - S1 TVEL^1) / F1, since F1 F4 - F3 F5 = -det M / F1.

What the reduction is, measured against the Moore-Penrose solution of eq. 38:

* det M1 = S1 det M (derived: C1 F2 - F6 = -S1 F1, so M1's first row is -S1 F1 (F3, F4)):
  the reduction is singular at theta1 = 0 or 180° where M is not. Row 1 of eq. 25 is then the
  very combination eq. 39 already uses, M1* drops it, and TVEL^2 reaches no joint.
* theta3 = 0 (full extension): M's null vector is (0, F4, -F3), in the (theta2, theta3) plane,
  and theta1 of eq. 39 is constant along it. For TVEL^ in M's range (no component along the
  arm) M* TVEL^ and the reduction are the same: both are exact, and among the exact solutions
  both take the one with (theta2, theta3) orthogonal to (F4, -F3), the least norm. For a
  TVEL^ with a component along the arm (which no joint rate produces) they differ: M*
  minimises ``|M x - TVEL^|`` in base axes, M1* minimises ``|M1 y - g1|`` in the units of g1, and
  eq. 39 then sets theta1 exactly.
* S2 ES + F5 = 0 (F1 = 0, the wrist centre at its least radius from Z0): M's null vector is
  (F3, F2, 0), which moves theta1. M1 = [[0, 0], [0, -F5]]: M1* gives theta2 = 0 and eq. 39
  puts the whole tangential motion on theta1, while M* shares it between theta1 and theta2;
  both are exact for a feasible TVEL^, so they differ even there.

pinrate's ``singularity="generalized_inverse"`` is eq. 38 (M* with singular values under
``singular_threshold`` x sigma_1 cut): at theta3 = 0 on a feasible command it is the reduction
too, at F1 = 0 it is not.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from .. import robots
from ..control.controller import Step
from .barker import base_axes, hand_twist, relative_deviation, unlimited_controller, well_conditioned
from .barker_jacobian import arm_terms, barker_m, barker_singular_configurations, wrist_centre_from_shoulder
from .table import Result, deviation_text, row

REFERENCE_TVEL = np.array([0.05, -0.03, 0.02])
"""A base-axes TVEL^ (m/s) whose part in M's range is the feasible command at the arm singularities."""

ALONG_THE_ARM = 0.02
"""m/s of TVEL^ along M's left null vector (away from the shoulder) added to make a command infeasible."""


# ---------------------------------------------------------------------- eq. 34-37, the closed form
def arm_rates_closed_form(q: np.ndarray, tvel: np.ndarray, parameters: Mapping[str, float] | None = None) -> np.ndarray:
    """(theta1, theta2, theta3) rates (rad/s) for a base-axes TVEL^ (m/s) where det M != 0:
    eq. 34-37 with the signs of eq. 35 and 36 derived again (module docstring)."""
    f = arm_terms(q, parameters)
    T1, T2, T3 = (float(value) for value in tvel)
    det = f.det_m
    theta1 = (T1 * f.S1 - T2 * f.C1) * (f.F1 * f.F4 - f.F3 * f.F5) / det  # eq. 34
    theta2 = (f.F5 * (T1 * f.F7 + T2 * f.F6) + T3 * f.F1 * f.F4) / det  # eq. 35, sign derived
    theta3 = -f.F1 * (T1 * f.F7 + T2 * f.F6 + T3 * f.F3) / det  # eq. 36, F6's sign derived
    return np.array([theta1, theta2, theta3])


def arm_rates_as_printed(q: np.ndarray, tvel: np.ndarray, parameters: Mapping[str, float] | None = None) -> np.ndarray:
    """Eq. 34-36 exactly as the OCR'd paper prints them (eq. 35 and 36 carry sign errors)."""
    f = arm_terms(q, parameters)
    T1, T2, T3 = (float(value) for value in tvel)
    det = f.det_m
    return np.array(
        [
            (T1 * f.S1 - T2 * f.C1) * (f.F1 * f.F4 - f.F3 * f.F5) / det,
            -(f.F5 * (T1 * f.F7 + T2 * f.F6) + T3 * f.F1 * f.F4) / det,
            -f.F1 * (T1 * f.F7 - T2 * f.F6 + T3 * f.F3) / det,
        ]
    )


def arm_rates_deviation(count: int = 100, **lengths: float) -> float:
    """max relative ``|step's arm rates - eq. 34-37|`` over random q off the singular region
    (c >= 0.05) and random twists, for ``algorithm="mca1"`` and ``"mca2"`` (B = 0 here)."""
    robot = robots.barker_arm(**lengths)  # type: ignore[arg-type]  # lengths holds no tip or sensor
    generator = np.random.default_rng(12)
    worst = 0.0
    for algorithm in ("mca1", "mca2"):
        controller = unlimited_controller(robot, algorithm)
        for q in well_conditioned(controller, count, 13):
            twist = generator.normal(size=6) * 0.1
            tvel, _ = base_axes(robot, q, twist)
            step = controller.step(q, twist)
            worst = max(worst, relative_deviation(step.joint_rates[:3], arm_rates_closed_form(q, tvel, lengths)))
    return worst


def printed_arm_rates_error(count: int = 100) -> float:
    """max relative ``|eq. 34-36 as printed - M^-1 TVEL^|`` over random q and TVEL^ (the misprints' size)."""
    robot = robots.barker_arm()
    generator = np.random.default_rng(14)
    worst = 0.0
    for q in robot.sample_configurations(count, 15):
        tvel = generator.normal(size=3) * 0.1
        worst = max(worst, relative_deviation(arm_rates_as_printed(q, tvel), np.linalg.solve(barker_m(q), tvel)))
    return worst


@row
def _arm_rates_row() -> Result:
    """Barker eq. 34-37: MCA1's and MCA2's steps against the closed form, the signs derived."""
    deviation = max(arm_rates_deviation(), arm_rates_deviation(alpha3=1.4, a3=0.05, r3=0.03))
    return Result(
        "Barker eq. 34-37",
        "closed-form arm rates for det M != 0 (as printed, eq. 35 has the wrong overall sign and "
        "eq. 36 the wrong sign of TVEL(2) F6; eq. 34 is (C1 TVEL(2) - S1 TVEL(1)) / F1)",
        f"MCA1 and MCA2 steps vs eq. 34-37 with the signs derived: max relative deviation "
        f"{deviation_text(deviation)}"
        f" (nominal and alpha3 = 1.4, a3 = 0.05, r3 = 0.03); the printed eq. 35-36 are off by up to "
        f"{printed_arm_rates_error():.1f}× the largest rate",
        "papers/test_barker.py::test_arm_rates_eq_34_37",
    )


# ---------------------------------------------------------------------- eq. 38, the generalized inverse
def _generalized_inverse_rates(
    q: np.ndarray, tvel: np.ndarray, threshold: float, parameters: Mapping[str, float] | None = None
) -> np.ndarray:
    """Eq. 38: M* TVEL^, M* the Moore-Penrose inverse with singular values under
    ``threshold`` x sigma_1 treated as 0 (numpy's pinv, rad/s)."""
    return np.linalg.pinv(barker_m(q, parameters), rcond=threshold) @ np.asarray(tvel, dtype=float)


def along_the_arm(q: np.ndarray, parameters: Mapping[str, float] | None = None) -> np.ndarray:
    """The unit base-axes direction that M produces least (its last left singular vector),
    signed away from the shoulder (positive along :func:`wrist_centre_from_shoulder`): at a
    singularity of M, the wrist-centre velocity no joint rate gives."""
    direction = np.linalg.svd(barker_m(q, parameters))[0][:, -1]
    return -direction if direction @ wrist_centre_from_shoulder(q, parameters) < 0.0 else direction


@dataclass(frozen=True)
class SingularCase:
    """The arm rates (rad/s) at one of M's singularities for one base-axes TVEL^ (m/s)."""

    q: np.ndarray
    tvel: np.ndarray
    step: Step  # the controller's (mca2, generalized_inverse)
    generalized: np.ndarray  # eq. 38, M* TVEL^
    reduction: np.ndarray  # eq. 39-44, M1* then eq. 39

    @property
    def step_rates(self) -> np.ndarray:
        return self.step.joint_rates[:3]

    @property
    def step_error(self) -> float:
        """``|M x - TVEL^|`` of the step's arm rates, m/s."""
        return float(np.linalg.norm(barker_m(self.q) @ self.step_rates - self.tvel))

    @property
    def reduction_error(self) -> float:
        """``|M x - TVEL^|`` of the reduction's rates, m/s."""
        return float(np.linalg.norm(barker_m(self.q) @ self.reduction - self.tvel))


def singular_case(which: int, along: float = 0.0, algorithm: str = "mca2") -> SingularCase:
    """The step (``singularity="generalized_inverse"``), eq. 38 and eq. 39-44 at
    ``barker_singular_configurations()[which]`` (0: theta3 = 0, 1: S2 ES + F5 = 0) for
    TVEL^ = the part of :data:`REFERENCE_TVEL` in M's range plus ``along`` m/s along
    :func:`along_the_arm` (0: a feasible command)."""
    robot = robots.barker_arm()
    q = barker_singular_configurations()[which]
    direction = along_the_arm(q)
    tvel = REFERENCE_TVEL - (direction @ REFERENCE_TVEL) * direction + along * direction
    controller = unlimited_controller(robot, algorithm, singularity="generalized_inverse")
    step = controller.step(q, hand_twist(robot, q, tvel))
    threshold = controller.singular_threshold
    return SingularCase(
        q, tvel, step, _generalized_inverse_rates(q, tvel, threshold), reduction_2x2(q, tvel, threshold)
    )


def generalized_inverse_deviation() -> float:
    """max ``|step's arm rates - M* TVEL^ (eq. 38)|`` (rad/s) at both arm singularities, feasible
    and infeasible commands, ``algorithm="mca1"`` and ``"mca2"``."""
    return max(
        float(np.abs(case.step_rates - case.generalized).max())
        for which in (0, 1)
        for along in (0.0, ALONG_THE_ARM)
        for algorithm in ("mca1", "mca2")
        for case in [singular_case(which, along, algorithm)]
    )


@row
def _generalized_inverse_row() -> Result:
    """Barker eq. 38: the step with ``singularity="generalized_inverse"`` is M* TVEL^."""
    return Result(
        "Barker eq. 38",
        "near det M = 0: the generalized inverse, M* TVEL^",
        f"singularity=generalized_inverse at theta3 = 0 and at S2 ES + F5 = 0, commands with and without "
        f"a component along the arm, MCA1 and MCA2: step vs M* TVEL^ (M* cut at singular_threshold), max "
        f"deviation {deviation_text(generalized_inverse_deviation())} rad/s",
        "papers/test_barker.py::test_generalized_inverse_eq_38",
    )


# ---------------------------------------------------------------------- eq. 39-44, the 2x2 reduction
def reduced_system(
    q: np.ndarray, tvel: np.ndarray, parameters: Mapping[str, float] | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """(M1, g1) of eq. 40-43: g1 = M1 [theta2 theta3]' (M1 in m², g1 in m²/s)."""
    f = arm_terms(q, parameters)
    T1, T2, T3 = (float(value) for value in tvel)
    g1 = np.array([f.F2 * T1 - f.F6 * (f.C1 * T1 + f.S1 * T2), T3])  # eq. 42
    lead = f.C1 * f.F2 - f.F6  # = -S1 F1
    M1 = np.array([[lead * f.F3, lead * f.F4], [-f.F1, -f.F5]])  # eq. 43
    return M1, g1


def reduction_2x2(
    q: np.ndarray, tvel: np.ndarray, threshold: float = 0.0, parameters: Mapping[str, float] | None = None
) -> np.ndarray:
    """(theta1, theta2, theta3) rates (rad/s) by the 2x2 reduction: eq. 44 with M1* the
    Moore-Penrose inverse of M1 (singular values under ``threshold`` x sigma_1 cut; 0 keeps
    every non-zero one, M1^-1 where M1 is invertible), then theta1 by eq. 39."""
    f = arm_terms(q, parameters)
    M1, g1 = reduced_system(q, tvel, parameters)
    theta2, theta3 = np.linalg.pinv(M1, rcond=threshold) @ g1  # eq. 44
    theta1 = (f.F3 * theta2 + f.F4 * theta3 - f.C1 * float(tvel[0]) - f.S1 * float(tvel[1])) / f.F2  # eq. 39
    return np.array([theta1, theta2, theta3])


def reduction_deviation(count: int = 100) -> float:
    """max relative ``|step's arm rates (mca2) - eq. 39-44 with M1^-1|`` over random q off the
    singular region (c >= 0.05) and random twists."""
    robot = robots.barker_arm()
    controller = unlimited_controller(robot, "mca2")
    generator = np.random.default_rng(16)
    worst = 0.0
    for q in well_conditioned(controller, count, 17):
        twist = generator.normal(size=6) * 0.1
        tvel, _ = base_axes(robot, q, twist)
        worst = max(worst, relative_deviation(controller.step(q, twist).joint_rates[:3], reduction_2x2(q, tvel)))
    return worst


THETA1_ZERO_Q = np.array([0.0, 0.4, 0.8, 0.1, 0.6, 0.0])
"""theta1 = 0 with M well conditioned: the reduction's own singularity (det M1 = S1 det M)."""


def reduction_at_theta1_zero() -> tuple[float, float, float]:
    """(c of the controller's measured blocks, ``|det M1|``, reduction's ``|M x - TVEL^|`` in m/s) at
    :data:`THETA1_ZERO_Q` for TVEL^ = :data:`REFERENCE_TVEL`, M1* cutting under the
    controller's ``singular_threshold``: the reduction drops TVEL^2."""
    robot = robots.barker_arm()
    controller = unlimited_controller(robot, "mca2")
    q = THETA1_ZERO_Q
    rates = reduction_2x2(q, REFERENCE_TVEL, controller.singular_threshold)
    M1, _ = reduced_system(q, REFERENCE_TVEL)
    error = float(np.linalg.norm(barker_m(q) @ rates - REFERENCE_TVEL))
    return controller.conditioning(q).value, abs(float(np.linalg.det(M1))), error


@row
def _reduction_row() -> Result:
    """Barker eq. 39-44: the step against the reduction, and the reduction's own singularity."""
    condition, _, reduction_error = reduction_at_theta1_zero()
    reference_tvel = ", ".join(f"{value:g}" for value in REFERENCE_TVEL)
    return Result(
        "Barker eq. 39-44",
        "theta1 by eq. 39 (F2 != 0), (theta2, theta3) = M1* g1: only a 2x2 inverse",
        f"off the singular region, MCA2 step vs reduction: max relative deviation "
        f"{deviation_text(reduction_deviation())}; but det M1 = S1 det M: "
        f"at theta1 = 0 (c = {condition:.2f}) M1 is "
        f"singular, M1* drops TVEL(2) and misses TVEL^ = ({reference_tvel}) m/s by {reduction_error:.2f} m/s",
        "papers/test_barker.py::test_reduction_eq_39_44",
    )


# ---------------------------------------------------------------------- eq. 38 against eq. 39-44 at M's singularities
@row
def _full_extension_row() -> Result:
    """Barker eq. 38 against eq. 39-44 at theta3 = 0 (module docstring)."""
    extended, extended_along = singular_case(0), singular_case(0, ALONG_THE_ARM)
    return Result(
        "Barker eq. 38 vs 39-44, theta3 = 0",
        "M* (eq. 38) and M1* (eq. 44) are both the generalized-inverse solution",
        f"M's null vector (0, F4, -F3) leaves theta1 alone: for TVEL^ in M's range the step and the "
        f"reduction agree within {deviation_text(np.abs(extended.step_rates - extended.reduction).max())} rad/s, "
        f"both exact; with {ALONG_THE_ARM} m/s along the arm added they differ: theta1 "
        f"{extended_along.step_rates[0]:.3f} (step) vs {extended_along.reduction[0]:.3f} rad/s, TVEL^ missed "
        f"by {extended_along.step_error:.3f} (the unreachable part, least) vs "
        f"{extended_along.reduction_error:.3f} m/s",
        "papers/test_barker.py::test_eq_38_and_39_44_at_full_extension",
    )


@row
def _least_radius_row() -> Result:
    """Barker eq. 38 against eq. 39-44 at S2 ES + F5 = 0 (module docstring)."""
    least_radius = singular_case(1)
    return Result(
        "Barker eq. 38 vs 39-44, S2 ES + F5 = 0",
        "M* (eq. 38) and M1* (eq. 44) are both the generalized-inverse solution",
        f"M's null vector (F3, F2, 0) moves theta1: for a feasible TVEL^ both are exact (miss "
        f"{deviation_text(least_radius.step_error)}, {deviation_text(least_radius.reduction_error)} m/s) "
        "yet differ: the step (M*) "
        f"gives theta1, theta2 = {least_radius.step_rates[0]:.4f}, {least_radius.step_rates[1]:.4f} rad/s, "
        f"the reduction {least_radius.reduction[0]:.4f}, {abs(least_radius.reduction[1]):.4f} "
        "(M1 = [[0, 0], [0, -F5]]); pinrate's generalized_inverse is M*",
        "papers/test_barker.py::test_eq_38_and_39_44_at_least_radius",
    )
