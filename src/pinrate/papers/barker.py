"""Barker 1983's closed forms for his arm, and pinrate's control step measured against them.

L. K. Barker, "Kinematic Equations for Resolved-Rate Control of an Industrial Robot Arm",
NASA TM-85685 (1983). The closed forms here are written from the paper (derived again where
the OCR'd text is garbled, see below); the row functions at the end measure how far
:class:`pinrate.Controller`'s step is from them, for ``docs/paper-results.md``.

Frames and units. The base axes X0 Y0 Z0 are the world of :func:`pinrate.robots.barker_arm`;
its tip is the wrist centre (frames 4, 5 and 6 of Barker's eq. 22 coincide there) and its
sensor the hand frame 6, so the robot's twist (TVEL, RVEL) is in the hand's axes and the
paper's base-axes ("caret") quantities are TVEL^ = R_hand TVEL, RVEL^ = R_hand RVEL
(eq. 20, R_hand = ``robot.frame_pose(q, "hand")[:3, :3]``). Every function here takes and
returns base-axes quantities: TVEL^ in m/s, RVEL^ in rad/s, joint rates in rad/s, lengths
(ES, WE, SN, A3, R3) in m. q is the paper's (theta1 .. theta6) in rad; ``parameters`` is the
robot's generator keywords (:func:`pinrate.robots.parameters`), the nominal arm when None.

The equations (C = cos, S = sin, C23 = cos(theta2 + theta3), SAL3 = sin alpha3, ...):

* eq. 25-31: TVEL^ = M [theta1 theta2 theta3]' with
  M = [[-S1 F1 - C1 F2, C1 F3, C1 F4], [C1 F1 - S1 F2, S1 F3, S1 F4], [0, -F1, -F5]],
  F1 = S2 ES + F5, F2 = SN~ + CAL3 WE, F3 = C2 ES + F4, F4 = C23 SAL3 WE - S23 A3,
  F5 = S23 SAL3 WE + C23 A3; also F6 = S1 F1 + C1 F2 (eq. 41), F7 = C1 F1 - S1 F2 (eq. 37).
  (F7, F6, F3) is the wrist centre relative to the shoulder (eq. C23: p_06 - p_01).
* eq. 34-36 (Cramer's rule, det M = F1 (F3 F5 - F1 F4) = F1 ES (F5 C2 - F4 S2), eq. D4):
  theta1 = (TVEL^1 S1 - TVEL^2 C1)(F1 F4 - F3 F5) / det M = (C1 TVEL^2 - S1 TVEL^1) / F1,
  theta2 = +[F5 (TVEL^1 F7 + TVEL^2 F6) + TVEL^3 F1 F4] / det M,
  theta3 = -F1 (TVEL^1 F7 + TVEL^2 F6 + TVEL^3 F3) / det M.
* eq. 38: [theta1 theta2 theta3]' = M* TVEL^, M* the generalized (Moore-Penrose) inverse.
* eq. 39-44, the 2x2 reduction: theta1 = (F3 theta2 + F4 theta3 - C1 TVEL^1 - S1 TVEL^2) / F2
  (C1 x row 1 + S1 x row 2 of eq. 25; F2 != 0 on this arm, SN~ != 0 and CAL3 ~ 0), and from rows 1 and 3
  g1 = M1 [theta2 theta3]', g1 = (F2 TVEL^1 - F6 (C1 TVEL^1 + S1 TVEL^2), TVEL^3),
  M1 = [[(C1 F2 - F6) F3, (C1 F2 - F6) F4], [-F1, -F5]], solved by M1*.
* eq. 48: RVEL~ = RVEL^ - z0 theta1 - z1 theta2 - z2 theta3 with z0 = (0, 0, 1) and
  z1 = z2 = (-S1, C1, 0) (eq. C7, C8, C10); eq. 52-56: D1 = C1 RVEL~1 + S1 RVEL~2,
  D2 = S1 RVEL~1 - C1 RVEL~2, D3 = S23 D1 + C23 RVEL~3, D4 = C23 D1 - S23 RVEL~3,
  D5 = CAL3 D3 + SAL3 D2.
* eq. 49: theta5 = -C4 D5 - S4 D4; eq. 57-60: g2 = M2 [theta4 theta6]',
  M2 = [[0, S5], [1, C5]], g2 = (-S4 D5 + C4 D4, SAL3 D3 - CAL3 D2), solved by M2*.
* eq. 61-63 at theta5 = 0 (D = SAL3 D3 - CAL3 D2): theta4 + theta6 = D; M2* splits it
  equally (eq. 60-61, pinrate's ``wrist="split"``); theta4 = 0, theta6 = D (eq. 62,
  ``"hold_first"``); theta6 held at its limit, theta4 = D (eq. 63, ``"last_then_first"``).

OCR garbles and misprints settled (each derived again and tested in tests/papers/test_barker.py):

* eq. 28 prints F2 = SN + CAL3 WE: it is SN~ = SN + R3 (eq. C19, and eq. 39's text "SN~ != 0
  so that, from equation (28), F2 != 0"); with r3 = 0.03 m plain SN is off by r3.
* eq. 35 prints theta2 = -{F5 [TVEL^1 F7 + TVEL^2 F6] + TVEL^3 F1 F4} / det M: the overall
  sign is wrong (Cramer's rule gives +).
* eq. 36 prints theta3 = -F1 [TVEL^1 F7 - TVEL^2 F6 + TVEL^3 F3] / det M: the TVEL^2 F6 term
  has the wrong sign (Cramer's rule gives +). Eq. 34 is right and simplifies to
  (C1 TVEL^2 - S1 TVEL^1) / F1, since F1 F4 - F3 F5 = -det M / F1.
* eq. 47 prints "z3 theta1 + z1 theta5": it is RVEL~ = z3 theta4 + z4 theta5 + z5 theta6
  (eq. C2); eq. 59 prints "-S4 D6": it is -S4 D5 (eq. 50); "theta14" (eq. 60), "theta_l4"
  (eq. 63) and the double dots of eq. 61-62 are theta4 and single dots.
* eq. B11 prints P2 = -S23 CAL3: it is P2 = -S23. Derivation: with R_1^2, R_2^3 the rotations
  of eq. A2, A3, the first column of R_1^2 R_2^3 is (S2 S3 - C2 C3, -(C2 S3 + S2 C3), 0) =
  (-C23, -S23, 0) = (P1, P2, 0) of eq. B4, whose other columns (-P2 CAL3, P1 CAL3, SAL3) and
  (P2 SAL3, -P1 SAL3, CAL3) need the same P2 = -S23. With the printed P2 (0 on the nominal
  arm, CAL3 = 0) the hand-to-base rotation L of eq. B16-B24 is not a rotation of the arm.
* eq. B28-B29 print (TVEL)_X2 = S2 [C1 TVEL(1) - S1 TVEL(2) + C2 TVEL(3)] and (TVEL)_Y2 =
  C2 [C1 TVEL(1) - S1 TVEL(2) - S2 TVEL(3)]. Rows 1 and 2 of R_2^1 R_1^0 (eq. B25-B27) are
  -S2 (-C1, -S1, 0) + C2 (0, 0, 1) = (S2 C1, S2 S1, C2) and -C2 (-C1, -S1, 0) - S2 (0, 0, 1) =
  (C2 C1, C2 S1, -S2): (TVEL)_X2 = S2 (C1 TVEL(1) + S1 TVEL(2)) + C2 TVEL(3) and (TVEL)_Y2 =
  C2 (C1 TVEL(1) + S1 TVEL(2)) - S2 TVEL(3). The bracket closes after the TVEL(2) term, and
  that term's sign is + (the printed - is a second misprint, not a consequence of the
  bracket: mending the bracket alone still gives S2 (C1 TVEL(1) - S1 TVEL(2)) + C2 TVEL(3)).

What the reduction is, measured against the Moore-Penrose solution of eq. 38:

* det M1 = S1 det M (derived: C1 F2 - F6 = -S1 F1, so M1's first row is -S1 F1 (F3, F4)):
  the reduction is singular at theta1 = 0 or 180° where M is not. Row 1 of eq. 25 is then the
  very combination eq. 39 already uses, M1* drops it, and TVEL^2 reaches no joint.
* theta3 = 0 (full extension): M's null vector is (0, F4, -F3), in the (theta2, theta3) plane,
  and theta1 of eq. 39 is constant along it. For TVEL^ in M's range (no component along the
  arm) M* TVEL^ and the reduction are the same: both are exact, and among the exact solutions
  both take the one with (theta2, theta3) orthogonal to (F4, -F3), the least norm. For a
  TVEL^ with a component along the arm (which no joint rate produces) they differ: M*
  minimises |M x - TVEL^| in base axes, M1* minimises |M1 y - g1| in the units of g1, and
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

import math
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from .. import robots
from ..control.controller import Controller, Step
from ..errors import InputError
from ..kinematics.manipulator import Robot

WRIST_SINGULAR_Q = np.array([0.3, 0.4, 0.7, 0.1, 0.0, 0.2])
"""A configuration at the wrist singularity theta5 = 0 with the arm well conditioned (rad)."""

WRIST_TWIST = np.array([0.02, 0.01, -0.03, 0.2, -0.1, 0.3])
"""The hand-axes twist (m/s, rad/s) commanded at :data:`WRIST_SINGULAR_Q`."""

REFERENCE_TVEL = np.array([0.05, -0.03, 0.02])
"""A base-axes TVEL^ (m/s) whose part in M's range is the feasible command at the arm singularities."""

ALONG_THE_ARM = 0.02
"""m/s of TVEL^ along M's left null vector (away from the shoulder) added to make a command infeasible."""

WRIST_RULES = ("split", "hold_first", "last_then_first")
"""pinrate's names of Barker's wrist rules eq. 61, 62 and 63."""


def barker_singular_configurations() -> tuple[np.ndarray, np.ndarray]:
    """q on each singular surface of the nominal arm: theta3 = 0 (eq. 33) and S2 ES + S23 WE = 0 (eq. 32)."""
    theta2 = 0.5
    theta3 = (
        math.asin(-math.sin(theta2) * robots.parameters("barker_arm")["es"] / robots.parameters("barker_arm")["we"])
        - theta2
    )
    return np.array([0.3, 0.4, 0.0, 0.1, 0.6, 0.0]), np.array([0.3, theta2, theta3, 0.1, 0.6, 0.0])


def unlimited_controller(
    robot: Robot, algorithm: str, singularity: str = "decelerate", wrist: str = "split"
) -> Controller:
    """A controller whose step is the algorithm's (or strategy's) rates: no velocity or position limits."""
    return Controller(
        robot,
        algorithm=algorithm,
        singularity=singularity,
        wrist=wrist,
        velocity_limits=np.inf,
        position_limits=False,
    )


def _parameters(parameters: Mapping[str, float] | None) -> dict[str, float]:
    return robots.parameters("barker_arm") | dict(parameters or {})


# ---------------------------------------------------------------------- eq. 25-37, the arm
@dataclass(frozen=True)
class ArmTerms:
    """C1, S1 and Barker's F1 .. F7 at q (eq. 27-31, 37, 41; F in m)."""

    C1: float
    S1: float
    F1: float
    F2: float
    F3: float
    F4: float
    F5: float
    F6: float
    F7: float

    @property
    def det_m(self) -> float:
        """det M = F1 (F3 F5 - F1 F4) = F1 ES (F5 C2 - F4 S2) (eq. D2-D4), m³."""
        return self.F1 * (self.F3 * self.F5 - self.F1 * self.F4)


def arm_terms(q: np.ndarray, parameters: Mapping[str, float] | None = None) -> ArmTerms:
    """F1 .. F7 at q (eq. 27-31, 37, 41), F2 with SN~ = SN + R3 (eq. C19)."""
    values = _parameters(parameters)
    es, we, a3, alpha3 = values["es"], values["we"], values["a3"], values["alpha3"]
    sn_tilde = values["sn"] + values["r3"]
    t1, t2, t3 = (float(angle) for angle in q[:3])
    C1, S1, C2, S2 = math.cos(t1), math.sin(t1), math.cos(t2), math.sin(t2)
    C23, S23 = math.cos(t2 + t3), math.sin(t2 + t3)
    SAL3, CAL3 = math.sin(alpha3), math.cos(alpha3)
    F4 = C23 * SAL3 * we - S23 * a3  # eq. 30
    F5 = S23 * SAL3 * we + C23 * a3  # eq. 31
    F1 = S2 * es + F5  # eq. 27
    F2 = sn_tilde + CAL3 * we  # eq. 28 (SN~)
    F3 = C2 * es + F4  # eq. 29
    F6 = S1 * F1 + C1 * F2  # eq. 41
    F7 = C1 * F1 - S1 * F2  # eq. 37
    return ArmTerms(C1, S1, F1, F2, F3, F4, F5, F6, F7)


def barker_m(q: np.ndarray, parameters: Mapping[str, float] | None = None) -> np.ndarray:
    """Barker's M (eq. 26): TVEL^ (base axes, m/s) = M [theta1 theta2 theta3]' (rad/s); M in m."""
    f = arm_terms(q, parameters)
    C1, S1 = f.C1, f.S1
    return np.array(
        [
            [-S1 * f.F1 - C1 * f.F2, C1 * f.F3, C1 * f.F4],
            [C1 * f.F1 - S1 * f.F2, S1 * f.F3, S1 * f.F4],
            [0.0, -f.F1, -f.F5],
        ]
    )


def wrist_centre_from_shoulder(q: np.ndarray, parameters: Mapping[str, float] | None = None) -> np.ndarray:
    """p_06 - p_01 = (F7, F6, F3) (eq. C23 in F's terms): the wrist centre from the shoulder, base axes, m."""
    f = arm_terms(q, parameters)
    return np.array([f.F7, f.F6, f.F3])


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


def generalized_inverse_rates(
    q: np.ndarray, tvel: np.ndarray, threshold: float, parameters: Mapping[str, float] | None = None
) -> np.ndarray:
    """Eq. 38: M* TVEL^, M* the Moore-Penrose inverse with singular values under
    ``threshold`` x sigma_1 treated as 0 (numpy's pinv, rad/s)."""
    return np.linalg.pinv(barker_m(q, parameters), rcond=threshold) @ np.asarray(tvel, dtype=float)


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


def along_the_arm(q: np.ndarray, parameters: Mapping[str, float] | None = None) -> np.ndarray:
    """The unit base-axes direction that M produces least (its last left singular vector),
    signed away from the shoulder (positive along :func:`wrist_centre_from_shoulder`): at a
    singularity of M, the wrist-centre velocity no joint rate gives."""
    direction = np.linalg.svd(barker_m(q, parameters))[0][:, -1]
    return -direction if direction @ wrist_centre_from_shoulder(q, parameters) < 0.0 else direction


# ---------------------------------------------------------------------- eq. 47-63, the wrist
def wrist_residual_rotation(q: np.ndarray, rvel: np.ndarray, arm_rates: np.ndarray) -> np.ndarray:
    """RVEL~ = RVEL^ - z0 theta1 - z1 theta2 - z2 theta3 (eq. 48; z of eq. C7, C8, C10), rad/s, base axes."""
    C1, S1 = math.cos(float(q[0])), math.sin(float(q[0]))
    z0, z1 = np.array([0.0, 0.0, 1.0]), np.array([-S1, C1, 0.0])  # z2 = z1: joints 2 and 3 parallel
    return np.asarray(rvel, dtype=float) - z0 * arm_rates[0] - z1 * (arm_rates[1] + arm_rates[2])


def wrist_terms(
    q: np.ndarray, rvel_tilde: np.ndarray, parameters: Mapping[str, float] | None = None
) -> tuple[float, float, float, float, float]:
    """(D1, D2, D3, D4, D5) of eq. 52-56 from RVEL~ (rad/s, base axes)."""
    alpha3 = _parameters(parameters)["alpha3"]
    t1, t2, t3 = (float(angle) for angle in q[:3])
    C1, S1, C23, S23 = math.cos(t1), math.sin(t1), math.cos(t2 + t3), math.sin(t2 + t3)
    R1, R2, R3 = (float(value) for value in rvel_tilde)
    D1 = C1 * R1 + S1 * R2  # eq. 52
    D2 = S1 * R1 - C1 * R2  # eq. 53
    D3 = S23 * D1 + C23 * R3  # eq. 54
    D4 = C23 * D1 - S23 * R3  # eq. 55
    D5 = math.cos(alpha3) * D3 + math.sin(alpha3) * D2  # eq. 56
    return D1, D2, D3, D4, D5


def wrist_system(
    q: np.ndarray, rvel_tilde: np.ndarray, parameters: Mapping[str, float] | None = None
) -> tuple[float, np.ndarray, np.ndarray]:
    """(theta5 rate of eq. 49, M2 of eq. 58, g2 of eq. 59): g2 = M2 [theta4 theta6]'."""
    alpha3 = _parameters(parameters)["alpha3"]
    _, D2, D3, D4, D5 = wrist_terms(q, rvel_tilde, parameters)
    t4, t5 = float(q[3]), float(q[4])
    C4, S4, C5, S5 = math.cos(t4), math.sin(t4), math.cos(t5), math.sin(t5)
    theta5 = -C4 * D5 - S4 * D4  # eq. 49
    M2 = np.array([[0.0, S5], [1.0, C5]])  # eq. 58
    g2 = np.array([-S4 * D5 + C4 * D4, math.sin(alpha3) * D3 - math.cos(alpha3) * D2])  # eq. 59
    return theta5, M2, g2


def wrist_rates(
    q: np.ndarray, rvel_tilde: np.ndarray, threshold: float = 0.0, parameters: Mapping[str, float] | None = None
) -> np.ndarray:
    """(theta4, theta5, theta6) rates (rad/s): theta5 by eq. 49, (theta4, theta6) = M2* g2
    (eq. 60), M2* the Moore-Penrose inverse with singular values under ``threshold`` x sigma_1
    cut (M2^-1 where theta5 is away from 0; at theta5 = 0 it splits theta4 + theta6 = D
    equally, eq. 61)."""
    theta5, M2, g2 = wrist_system(q, rvel_tilde, parameters)
    theta4, theta6 = np.linalg.pinv(M2, rcond=threshold) @ g2  # eq. 60
    return np.array([theta4, theta5, theta6])


def wrist_rule_rates(
    q: np.ndarray, rvel_tilde: np.ndarray, rule: str, parameters: Mapping[str, float] | None = None
) -> np.ndarray:
    """(theta4, theta5, theta6) rates (rad/s) at theta5 = 0 by Barker's rule: eq. 61 with the
    task split equally ("split"), eq. 62 theta4 = 0 ("hold_first"), eq. 63 theta6 held at its
    limit ("last_then_first"); theta5 by eq. 49, D = SAL3 D3 - CAL3 D2."""
    theta5, _, g2 = wrist_system(q, rvel_tilde, parameters)
    D = float(g2[1])
    theta4, theta6 = {"split": (D / 2, D / 2), "hold_first": (0.0, D), "last_then_first": (D, 0.0)}[rule]
    return np.array([theta4, theta5, theta6])


# ---------------------------------------------------------------------- appendix B, hand to base
def _p2(q: np.ndarray, alpha3: float, as_printed: bool) -> float:
    """P2 of eq. B11: -S23 (derived, module docstring), or -S23 CAL3 as printed."""
    s23 = math.sin(float(q[1]) + float(q[2]))
    return -s23 * math.cos(alpha3) if as_printed else -s23


def rotation_1_3(
    q: np.ndarray, parameters: Mapping[str, float] | None = None, *, as_printed: bool = False
) -> np.ndarray:
    """R_1^2 R_2^3 of eq. B4 from P1 = -C23 (eq. B10) and P2 (eq. B11: -S23 derived, -S23 CAL3
    with ``as_printed``): frame 3's axes in frame 1's, dimensionless."""
    alpha3 = _parameters(parameters)["alpha3"]
    SAL3, CAL3 = math.sin(alpha3), math.cos(alpha3)
    P1, P2 = -math.cos(float(q[1]) + float(q[2])), _p2(q, alpha3, as_printed)
    return np.array([[P1, -P2 * CAL3, P2 * SAL3], [P2, P1 * CAL3, -P1 * SAL3], [0.0, SAL3, CAL3]])


def hand_to_base(
    q: np.ndarray, parameters: Mapping[str, float] | None = None, *, as_printed: bool = False
) -> np.ndarray:
    """L = R_0^6 of eq. B2-B24: the hand's axes in base axes, so TVEL^ = L TVEL and
    RVEL^ = L RVEL (eq. B1). Entries as printed in eq. B16-B24 from Q1..Q4 (eq. B6-B9),
    P1, P2 (eq. B10-B11; P2 = -S23 derived, -S23 CAL3 with ``as_printed``) and T1..T4
    (eq. B12-B15); dimensionless."""
    alpha3 = _parameters(parameters)["alpha3"]
    SAL3, CAL3 = math.sin(alpha3), math.cos(alpha3)
    t1, _, _, t4, t5, t6 = (float(angle) for angle in q)
    C1, S1 = math.cos(t1), math.sin(t1)
    C4, S4, C5, S5, C6, S6 = math.cos(t4), math.sin(t4), math.cos(t5), math.sin(t5), math.cos(t6), math.sin(t6)
    Q1 = C4 * C5 * C6 - S4 * S6  # eq. B6
    Q2 = S4 * C5 * C6 + C4 * S6  # eq. B7
    Q3 = -C4 * C5 * S6 - S4 * C6  # eq. B8
    Q4 = -S4 * C5 * S6 + C4 * C6  # eq. B9
    P1 = -math.cos(float(q[1]) + float(q[2]))  # eq. B10
    P2 = _p2(q, alpha3, as_printed)  # eq. B11
    T1 = C1 * CAL3 * P2 - S1 * SAL3  # eq. B12
    T2 = -C1 * P2 * SAL3 - S1 * CAL3  # eq. B13
    T3 = S1 * CAL3 * P2 + C1 * SAL3  # eq. B14
    T4 = -S1 * P2 * SAL3 + C1 * CAL3  # eq. B15
    return np.array(
        [
            [
                -C1 * P1 * Q1 + T1 * Q2 - T2 * S5 * C6,  # eq. B16
                -C1 * P1 * Q3 + T1 * Q4 + T2 * S5 * S6,  # eq. B19
                -C1 * P1 * C4 * S5 + T1 * S4 * S5 + T2 * C5,  # eq. B22
            ],
            [
                -S1 * P1 * Q1 + T3 * Q2 - T4 * S5 * C6,  # eq. B17
                -S1 * P1 * Q3 + T3 * Q4 + T4 * S5 * S6,  # eq. B20
                -S1 * P1 * C4 * S5 + T3 * S4 * S5 + T4 * C5,  # eq. B23
            ],
            [
                P2 * Q1 + P1 * CAL3 * Q2 + P1 * SAL3 * S5 * C6,  # eq. B18
                P2 * Q3 + P1 * CAL3 * Q4 - P1 * SAL3 * S5 * S6,  # eq. B21
                P2 * C4 * S5 + P1 * CAL3 * S4 * S5 - P1 * SAL3 * C5,  # eq. B24
            ],
        ]
    )


def upper_arm_components(q: np.ndarray, tvel: np.ndarray) -> tuple[float, float]:
    """((TVEL)_X2, (TVEL)_Y2) of a base-axes TVEL^ (m/s): eq. B28-B29 as derived from eq. B27
    (module docstring), S2 (C1 TVEL(1) + S1 TVEL(2)) + C2 TVEL(3) and
    C2 (C1 TVEL(1) + S1 TVEL(2)) - S2 TVEL(3)."""
    C1, S1, C2, S2 = math.cos(q[0]), math.sin(q[0]), math.cos(q[1]), math.sin(q[1])
    T1, T2, T3 = (float(value) for value in tvel)
    radial = C1 * T1 + S1 * T2
    return S2 * radial + C2 * T3, C2 * radial - S2 * T3


def upper_arm_components_as_printed(
    q: np.ndarray, tvel: np.ndarray, *, bracket_mended: bool = False
) -> tuple[float, float]:
    """Eq. B28-B29 as the OCR'd paper prints them, S2 [C1 TVEL(1) - S1 TVEL(2) + C2 TVEL(3)] and
    C2 [C1 TVEL(1) - S1 TVEL(2) - S2 TVEL(3)]; with ``bracket_mended`` the bracket closed after
    the TVEL(2) term but its printed sign kept: S2 (C1 TVEL(1) - S1 TVEL(2)) + C2 TVEL(3) and
    C2 (C1 TVEL(1) - S1 TVEL(2)) - S2 TVEL(3) (m/s)."""
    C1, S1, C2, S2 = math.cos(q[0]), math.sin(q[0]), math.cos(q[1]), math.sin(q[1])
    T1, T2, T3 = (float(value) for value in tvel)
    if bracket_mended:
        return S2 * (C1 * T1 - S1 * T2) + C2 * T3, C2 * (C1 * T1 - S1 * T2) - S2 * T3
    return S2 * (C1 * T1 - S1 * T2 + C2 * T3), C2 * (C1 * T1 - S1 * T2 - S2 * T3)


# ---------------------------------------------------------------------- pinrate against the closed forms
def base_axes(robot: Robot, q: np.ndarray, twist: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(TVEL^, RVEL^): a hand-axes twist (m/s, rad/s) in base axes (eq. 20)."""
    hand = robot.frame_pose(q, "hand")[:3, :3]
    return hand @ twist[:3], hand @ twist[3:]


def hand_twist(robot: Robot, q: np.ndarray, tvel: np.ndarray, rvel: np.ndarray | None = None) -> np.ndarray:
    """The hand-axes twist (robot's twist) of base-axes TVEL^ and RVEL^ (0 when None)."""
    hand = robot.frame_pose(q, "hand")[:3, :3]
    return np.concatenate([hand.T @ tvel, hand.T @ (np.zeros(3) if rvel is None else rvel)])


def _relative(found: np.ndarray, expected: np.ndarray) -> float:
    return float(np.abs(found - expected).max() / max(1.0, float(np.abs(expected).max())))


def m_deviation(count: int = 100, **lengths: float) -> float:
    """max |R_hand A - M| (m) over random q: the robot's arm block in base axes against eq. 26."""
    robot = robots.barker_arm(**lengths)  # type: ignore[arg-type]  # lengths holds no tip or sensor
    worst = 0.0
    for q in robot.sample_configurations(count, 11):
        hand = robot.frame_pose(q, "hand")[:3, :3]
        worst = max(worst, float(np.abs(hand @ robot.jacobian(q)[:3, :3] - barker_m(q, lengths)).max()))
    return worst


def _well_conditioned(controller: Controller, count: int, seed: int) -> list[np.ndarray]:
    robot = controller.robot
    return [q for q in robot.sample_configurations(count, seed) if controller.conditioning(q).value >= 0.05]


def arm_rates_deviation(count: int = 100, **lengths: float) -> float:
    """max relative |step's arm rates - eq. 34-37| over random q off the singular region
    (c >= 0.05) and random twists, for ``algorithm="mca1"`` and ``"mca2"`` (B = 0 here)."""
    robot = robots.barker_arm(**lengths)  # type: ignore[arg-type]  # lengths holds no tip or sensor
    generator = np.random.default_rng(12)
    worst = 0.0
    for algorithm in ("mca1", "mca2"):
        controller = unlimited_controller(robot, algorithm)
        for q in _well_conditioned(controller, count, 13):
            twist = generator.normal(size=6) * 0.1
            tvel, _ = base_axes(robot, q, twist)
            step = controller.step(q, twist)
            worst = max(worst, _relative(step.joint_rates[:3], arm_rates_closed_form(q, tvel, lengths)))
    return worst


def printed_arm_rates_error(count: int = 100) -> float:
    """max relative |eq. 34-36 as printed - M^-1 TVEL^| over random q and TVEL^ (the misprints' size)."""
    robot = robots.barker_arm()
    generator = np.random.default_rng(14)
    worst = 0.0
    for q in robot.sample_configurations(count, 15):
        tvel = generator.normal(size=3) * 0.1
        worst = max(worst, _relative(arm_rates_as_printed(q, tvel), np.linalg.solve(barker_m(q), tvel)))
    return worst


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
        """|M x - TVEL^| of the step's arm rates, m/s."""
        return float(np.linalg.norm(barker_m(self.q) @ self.step_rates - self.tvel))

    @property
    def reduction_error(self) -> float:
        """|M x - TVEL^| of the reduction's rates, m/s."""
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
    return SingularCase(q, tvel, step, generalized_inverse_rates(q, tvel, threshold), reduction_2x2(q, tvel, threshold))


def generalized_inverse_deviation() -> float:
    """max |step's arm rates - M* TVEL^ (eq. 38)| (rad/s) at both arm singularities, feasible
    and infeasible commands, ``algorithm="mca1"`` and ``"mca2"``."""
    return max(
        float(np.abs(case.step_rates - case.generalized).max())
        for which in (0, 1)
        for along in (0.0, ALONG_THE_ARM)
        for algorithm in ("mca1", "mca2")
        for case in [singular_case(which, along, algorithm)]
    )


def reduction_deviation(count: int = 100) -> float:
    """max relative |step's arm rates (mca2) - eq. 39-44 with M1^-1| over random q off the
    singular region (c >= 0.05) and random twists."""
    robot = robots.barker_arm()
    controller = unlimited_controller(robot, "mca2")
    generator = np.random.default_rng(16)
    worst = 0.0
    for q in _well_conditioned(controller, count, 17):
        twist = generator.normal(size=6) * 0.1
        tvel, _ = base_axes(robot, q, twist)
        worst = max(worst, _relative(controller.step(q, twist).joint_rates[:3], reduction_2x2(q, tvel)))
    return worst


THETA1_ZERO_Q = np.array([0.0, 0.4, 0.8, 0.1, 0.6, 0.0])
"""theta1 = 0 with M well conditioned: the reduction's own singularity (det M1 = S1 det M)."""


def reduction_at_theta1_zero() -> tuple[float, float, float]:
    """(c of the controller's measured blocks, |det M1|, reduction's |M x - TVEL^| in m/s) at
    :data:`THETA1_ZERO_Q` for TVEL^ = :data:`REFERENCE_TVEL`, M1* cutting under the
    controller's ``singular_threshold``: the reduction drops TVEL^2."""
    robot = robots.barker_arm()
    controller = unlimited_controller(robot, "mca2")
    q = THETA1_ZERO_Q
    rates = reduction_2x2(q, REFERENCE_TVEL, controller.singular_threshold)
    M1, _ = reduced_system(q, REFERENCE_TVEL)
    error = float(np.linalg.norm(barker_m(q) @ rates - REFERENCE_TVEL))
    return controller.conditioning(q).value, abs(float(np.linalg.det(M1))), error


def _wrist_step(rule: str, q: np.ndarray, twist: np.ndarray) -> tuple[Step, np.ndarray]:
    """The step (mca2, generalized_inverse, ``wrist=rule``) and its q, theta6 put on the limit
    the rotation pushes it into for ``last_then_first``."""
    robot = robots.barker_arm()
    q = q.copy()
    if rule == "last_then_first":
        probe = unlimited_controller(robot, "mca2", wrist="hold_first").step(q, twist)
        limits = robot.joint_limits("theta6")
        if limits is None:
            raise InputError("eq. 63 (last_then_first) needs finite position limits on theta6")
        lower, upper = limits
        q[5] = upper if probe.joint_rates[5] > 0 else lower
    controller = Controller(
        robot, algorithm="mca2", singularity="generalized_inverse", wrist=rule, velocity_limits=np.inf
    )
    return controller.step(q, twist), q


def wrist_generalized_inverse_deviation(count: int = 100) -> tuple[float, float]:
    """(off theta5 = 0, at theta5 = 0): max |step's wrist rates - eq. 49, 60| (rad/s), mca2.

    Off: random q off the singular region (c >= 0.05), random twists, M2* = M2^-1. At:
    :data:`WRIST_SINGULAR_Q` and :data:`WRIST_TWIST`, ``wrist="split"``. RVEL~ (eq. 48) from
    the arm rates of eq. 34-37, not the step's."""
    robot = robots.barker_arm()
    controller = unlimited_controller(robot, "mca2")
    generator = np.random.default_rng(18)
    off = 0.0
    for q in _well_conditioned(controller, count, 19):
        twist = generator.normal(size=6) * 0.1
        tvel, rvel = base_axes(robot, q, twist)
        expected = wrist_rates(q, wrist_residual_rotation(q, rvel, arm_rates_closed_form(q, tvel)))
        off = max(off, _relative(controller.step(q, twist).joint_rates[3:], expected))
    step, q = _wrist_step("split", WRIST_SINGULAR_Q, WRIST_TWIST)
    tvel, rvel = base_axes(robot, q, WRIST_TWIST)
    expected = wrist_rates(q, wrist_residual_rotation(q, rvel, arm_rates_closed_form(q, tvel)))
    return off, float(np.abs(step.joint_rates[3:] - expected).max())


def wrist_region_rates(theta5: float = 0.02) -> tuple[np.ndarray, np.ndarray]:
    """(step's, eq. 49 and 60 with M2^-1) (theta4, theta5, theta6) rates (rad/s) at
    :data:`WRIST_SINGULAR_Q` with theta5 = ``theta5`` (inside the wrist region, not at 0) for
    :data:`WRIST_TWIST`, mca2, ``wrist="split"``: the rule holds theta4 = theta6 throughout the
    region, where eq. 60 gives rates that grow as 1 / S5."""
    q = WRIST_SINGULAR_Q.copy()
    q[4] = theta5
    step, _ = _wrist_step("split", q, WRIST_TWIST)
    tvel, rvel = base_axes(robots.barker_arm(), q, WRIST_TWIST)
    return step.joint_rates[3:], wrist_rates(q, wrist_residual_rotation(q, rvel, arm_rates_closed_form(q, tvel)))


def wrist_rule_deviations() -> dict[str, float]:
    """Per rule (eq. 61 split, 62 hold_first, 63 last_then_first): max |step's wrist rates -
    the rule's closed form| (rad/s) at :data:`WRIST_SINGULAR_Q` for :data:`WRIST_TWIST`, mca2."""
    robot = robots.barker_arm()
    deviations = {}
    for rule in WRIST_RULES:
        step, q = _wrist_step(rule, WRIST_SINGULAR_Q, WRIST_TWIST)
        tvel, rvel = base_axes(robot, q, WRIST_TWIST)
        expected = wrist_rule_rates(q, wrist_residual_rotation(q, rvel, arm_rates_closed_form(q, tvel)), rule)
        deviations[rule] = float(np.abs(step.joint_rates[3:] - expected).max())
    return deviations


def upper_arm_axes(q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(X2, Y2) in base axes: the first two rows of R_2^1 R_1^0 (eq. B25-B27). The printed
    B28-B29 misplace a bracket and flip the sign of the S1 TVEL(2) term (module docstring):
    (TVEL)_X2 = S2 (C1 TVEL(1) + S1 TVEL(2)) + C2 TVEL(3) and
    (TVEL)_Y2 = C2 (C1 TVEL(1) + S1 TVEL(2)) - S2 TVEL(3)."""
    C1, S1, C2, S2 = math.cos(q[0]), math.sin(q[0]), math.cos(q[1]), math.sin(q[1])
    r10 = np.array([[-C1, -S1, 0.0], [0.0, 0.0, 1.0], [-S1, C1, 0.0]])  # eq. B25
    r21 = np.array([[-S2, C2, 0.0], [-C2, -S2, 0.0], [0.0, 0.0, 1.0]])  # eq. B26
    x2, y2, _ = r21 @ r10
    return x2, y2


def hand_to_base_errors(count: int = 100, **lengths: float) -> tuple[float, float, float]:
    """Eq. B1-B24 against the robot, over random q: (max |L - R_hand| with P2 = -S23, the same
    with P2 as printed, max |B4 as printed - B4| entrywise), R_hand the robot's hand rotation
    (``robot.frame_pose(q, "hand")``); all dimensionless."""
    robot = robots.barker_arm(**lengths)  # type: ignore[arg-type]  # lengths holds no tip or sensor
    derived = printed = b4 = 0.0
    for q in robot.sample_configurations(count, 21):
        hand = robot.frame_pose(q, "hand")[:3, :3]
        derived = max(derived, float(np.abs(hand_to_base(q, lengths) - hand).max()))
        printed = max(printed, float(np.abs(hand_to_base(q, lengths, as_printed=True) - hand).max()))
        b4 = max(b4, float(np.abs(rotation_1_3(q, lengths, as_printed=True) - rotation_1_3(q, lengths)).max()))
    return derived, printed, b4


def upper_arm_component_errors(count: int = 100) -> tuple[float, float, float]:
    """Eq. B28-B29 against the robot, over random q and unit base-axes TVEL^: max |error| (m/s
    per m/s) of (derived, as printed, printed with only the bracket mended), the robot's
    components being TVEL^ . X2 and TVEL^ . Y2 with X2 the unit vector from the shoulder
    (joint theta2) to the elbow (joint theta3) across the theta2 axis and Y2 = z1 x X2, z1
    the robot's theta2 rotation axis in base axes (R_hand times column 2 of J's angular rows)."""
    robot = robots.barker_arm()
    generator = np.random.default_rng(22)
    worst = [0.0, 0.0, 0.0]
    for q in robot.sample_configurations(count, 23):
        hand = robot.frame_pose(q, "hand")[:3, :3]
        z1 = hand @ robot.jacobian(q)[3:, 1]
        shoulder, elbow = (robot.frame_pose(q, frame)[:3, 3] for frame in ("theta2", "theta3"))
        across = (elbow - shoulder) - ((elbow - shoulder) @ z1) * z1
        x2 = across / np.linalg.norm(across)
        y2 = np.cross(z1, x2)
        tvel = generator.normal(size=3)
        tvel /= np.linalg.norm(tvel)
        expected = np.array([tvel @ x2, tvel @ y2])
        candidates = (
            upper_arm_components(q, tvel),
            upper_arm_components_as_printed(q, tvel),
            upper_arm_components_as_printed(q, tvel, bracket_mended=True),
        )
        for i, found in enumerate(candidates):
            worst[i] = max(worst[i], float(np.abs(np.array(found) - expected).max()))
    return worst[0], worst[1], worst[2]


ELBOW_CASES = ((0.3, 0.4), (-1.1, 1.2), (2.0, -0.7))
"""(θ1, θ2) of the full-extension configurations (θ3 = 0) where eq. 45-46 are checked."""


def auxiliary_elbow_deviation(seed: int = 7) -> tuple[float, float]:
    """(relative deviation of θ3 from eq. 45, of θ2 from eq. 46) over commands along X2 and Y2 at
    θ3 = 0 (:data:`ELBOW_CASES`), ``singularity="auxiliary_elbow"``, K2 = 1 and
    |K3| = (WE + ES) / (ES WE sin β_r) (pinrate's gain, β_r the controller's elbow region);
    the sign of K3 bends the elbow the way of the home's θ3."""
    robot = robots.barker_arm()
    parameters = robots.parameters("barker_arm")
    es, we = parameters["es"], parameters["we"]
    controller = unlimited_controller(robot, "exact", singularity="auxiliary_elbow")
    k3 = -math.copysign(1.0, float(robot.home()[2])) * (we + es) / (es * we * math.sin(controller.elbow_region))
    rng = np.random.default_rng(seed)
    worst_elbow = worst_shoulder = 0.0
    for theta1, theta2 in ELBOW_CASES:
        q = np.array([theta1, theta2, 0.0, 0.3, 0.6, -0.2])
        x2, y2 = upper_arm_axes(q)
        for _ in range(6):
            along_x2, along_y2 = rng.normal(size=2) * 0.05
            rates = controller.step(q, hand_twist(robot, q, along_x2 * x2 + along_y2 * y2)).joint_rates
            elbow = 0.0 if along_x2 > 0.0 else k3 * along_x2  # eq. 45
            shoulder = -we / (we + es) * elbow + along_y2 / (we + es)  # eq. 46
            worst_elbow = max(worst_elbow, abs(rates[2] - elbow) / max(abs(elbow), 1e-12))
            worst_shoulder = max(worst_shoulder, abs(rates[1] - shoulder) / max(abs(shoulder), 1e-12))
    return worst_elbow, worst_shoulder


def elbow_bends(cycles: int = 3) -> list[float]:
    """θ3 after each retraction from full extension, ``cycles`` times: the arm starts bent
    +0.03 rad, is straightened by an outward command along X2 (0.05 m/s) and retracted by an
    inward one for 0.2 s. Barker: the bend changes sides each time."""
    robot = robots.barker_arm()
    controller = Controller(robot, singularity="auxiliary_elbow", velocity_limits=math.inf)
    q = np.array([0.2, 0.5, 0.03, 0.3, 0.6, -0.2])
    bends = []
    for _ in range(cycles):
        for outward, steps in ((1.0, 300), (-1.0, 20)):
            for _ in range(steps):
                x2, _ = upper_arm_axes(q)
                q = controller.step(q, hand_twist(robot, q, 0.05 * outward * x2)).q
        bends.append(float(q[2]))
    return bends


__all__ = [
    "ALONG_THE_ARM",
    "ELBOW_CASES",
    "REFERENCE_TVEL",
    "THETA1_ZERO_Q",
    "WRIST_RULES",
    "WRIST_SINGULAR_Q",
    "WRIST_TWIST",
    "ArmTerms",
    "SingularCase",
    "along_the_arm",
    "arm_rates_as_printed",
    "arm_rates_closed_form",
    "arm_rates_deviation",
    "arm_terms",
    "auxiliary_elbow_deviation",
    "barker_m",
    "barker_singular_configurations",
    "base_axes",
    "elbow_bends",
    "generalized_inverse_deviation",
    "generalized_inverse_rates",
    "hand_to_base",
    "hand_to_base_errors",
    "hand_twist",
    "m_deviation",
    "printed_arm_rates_error",
    "reduced_system",
    "reduction_2x2",
    "reduction_at_theta1_zero",
    "reduction_deviation",
    "rotation_1_3",
    "singular_case",
    "unlimited_controller",
    "upper_arm_axes",
    "upper_arm_component_errors",
    "upper_arm_components",
    "upper_arm_components_as_printed",
    "wrist_centre_from_shoulder",
    "wrist_generalized_inverse_deviation",
    "wrist_rates",
    "wrist_region_rates",
    "wrist_residual_rotation",
    "wrist_rule_deviations",
    "wrist_rule_rates",
    "wrist_system",
    "wrist_terms",
]
