"""Barker eq. 25-33 and D9: the arm's Jacobian M in base axes, its determinant and its
singular surfaces (the frames and units of :mod:`.barker`).

* eq. 25-31: TVEL^ = M [theta1 theta2 theta3]' with
  M = [[-S1 F1 - C1 F2, C1 F3, C1 F4], [C1 F1 - S1 F2, S1 F3, S1 F4], [0, -F1, -F5]],
  F1 = S2 ES + F5, F2 = SN~ + CAL3 WE, F3 = C2 ES + F4, F4 = C23 SAL3 WE - S23 A3,
  F5 = S23 SAL3 WE + C23 A3; also F6 = S1 F1 + C1 F2 (eq. 41), F7 = C1 F1 - S1 F2 (eq. 37).
  (F7, F6, F3) is the wrist centre relative to the shoulder (eq. C23: p_06 - p_01).
* eq. D9: det M = (S2 ES + F5)(SAL3 WE S3 + A3 C3) ES, so M is singular where
  S2 ES + F5 = 0 (eq. 32, the wrist centre at its least radius from Z0) or
  SAL3 WE S3 + A3 C3 = 0 (eq. 33, theta3 = 0 on the nominal arm: full extension).

OCR garble settled (derived again and tested in tests/papers/test_barker.py): eq. 28 prints
F2 = SN + CAL3 WE: it is SN~ = SN + R3 (eq. C19, and eq. 39's text "SN~ != 0 so that, from
equation (28), F2 != 0"); with r3 = 0.03 m plain SN is off by r3.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from .. import robots
from ..errors import SingularBlockError
from ..kinematics.partition import Partition
from ..solvers.rates import joint_rates
from .barker import arm_parameters
from .table import Result, deviation_text, row, yes_no


# ---------------------------------------------------------------------- eq. 25-31, M
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
    values = arm_parameters(parameters)
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


# ---------------------------------------------------------------------- eq. D9, det M
def barker_det_deviation(count: int = 300, **lengths: float) -> float:
    """max ``|det A - eq. D9|`` / (1 + ``|eq. D9|``), with (S2 ES + F5)(SAL3 WE S3 + A3 C3) ES."""
    robot = robots.barker_arm(**lengths)  # type: ignore[arg-type]  # lengths holds no tip or sensor
    parameters = robots.parameters("barker_arm") | lengths
    es, we, a3 = parameters["es"], parameters["we"], parameters["a3"]
    sal3 = math.sin(parameters["alpha3"])
    partition = Partition.auto(robot)

    def deviation(q: np.ndarray) -> float:
        s2, s3, s23, c23, c3 = (
            math.sin(q[1]),
            math.sin(q[2]),
            math.sin(q[1] + q[2]),
            math.cos(q[1] + q[2]),
            math.cos(q[2]),
        )
        f5 = s23 * sal3 * we + c23 * a3
        closed_form = (s2 * es + f5) * (sal3 * we * s3 + a3 * c3) * es
        A = partition.blocks(robot, robot.jacobian(q))[0]
        return abs(float(np.linalg.det(A)) - closed_form) / (1 + abs(closed_form))

    return max(deviation(q) for q in robot.sample_configurations(count, 0))


@row
def _determinant_row() -> Result:
    """Barker eq. D9: det M against the robot's arm block."""
    return Result(
        "Barker eq. D9",
        "det M = (S2 ES + F5)(SAL3 WE S3 + A3 C3) ES, F5 = S23 SAL3 WE + C23 A3",
        f"max relative deviation {deviation_text(barker_det_deviation())} (nominal), "
        f"{deviation_text(barker_det_deviation(alpha3=1.4, a3=0.05, r3=0.03))} (alpha3 = 1.4, a3 = 0.05, r3 = 0.03)",
        "papers/test_worked_examples.py::test_barker_determinant",
    )


# ---------------------------------------------------------------------- eq. 32-33, the singular surfaces
def barker_singular_configurations() -> tuple[np.ndarray, np.ndarray]:
    """q on each singular surface of the nominal arm: theta3 = 0 (eq. 33) and S2 ES + S23 WE = 0 (eq. 32)."""
    theta2 = 0.5
    theta3 = (
        math.asin(-math.sin(theta2) * robots.parameters("barker_arm")["es"] / robots.parameters("barker_arm")["we"])
        - theta2
    )
    return np.array([0.3, 0.4, 0.0, 0.1, 0.6, 0.0]), np.array([0.3, theta2, theta3, 0.1, 0.6, 0.0])


def barker_singular(q: np.ndarray) -> bool:
    """Whether MCA2 reports block A singular at q on the nominal Barker arm."""
    robot = robots.barker_arm()
    try:
        joint_rates(robot, q, np.ones(6), algorithm="mca2")
    except SingularBlockError as error:
        return error.block == "A"
    return False


@row
def _singularities_row() -> Result:
    """Barker eq. 32-33: MCA2 reports block A singular on both surfaces."""
    extended, folded = barker_singular_configurations()
    return Result(
        "Barker eq. 32-33",
        "singular when S2 ES + F5 = 0 or SAL3 WE S3 + A3 C3 = 0",
        f"MCA2 reports A singular at theta3 = 0: {yes_no(barker_singular(extended))}; "
        f"at S2 ES + S23 WE = 0: {yes_no(barker_singular(folded))}",
        "papers/test_worked_examples.py::test_barker_singularities",
    )


# ---------------------------------------------------------------------- eq. 25-31 against the robot
def m_deviation(count: int = 100, **lengths: float) -> float:
    """max ``|R_hand A - M|`` (m) over random q: the robot's arm block in base axes against eq. 26."""
    robot = robots.barker_arm(**lengths)  # type: ignore[arg-type]  # lengths holds no tip or sensor
    worst = 0.0
    for q in robot.sample_configurations(count, 11):
        hand = robot.frame_pose(q, "hand")[:3, :3]
        worst = max(worst, float(np.abs(hand @ robot.jacobian(q)[:3, :3] - barker_m(q, lengths)).max()))
    return worst


@row
def _m_row() -> Result:
    """Barker eq. 25-31: M against the robot's arm block in base axes (F2 with SN~)."""
    return Result(
        "Barker eq. 25-31",
        "TVEL^ = M [theta1 theta2 theta3]', M from F1..F5; F2 = SN~ + CAL3 WE with SN~ = SN + R3 "
        "(the OCR drops the tilde, eq. C19)",
        f"R_hand A (the robot's arm block in base axes) vs M: max deviation {deviation_text(m_deviation())} m "
        f"(nominal), {deviation_text(m_deviation(alpha3=1.4, a3=0.05, r3=0.03))} "
        f"(alpha3 = 1.4, a3 = 0.05, r3 = 0.03)",
        "papers/test_barker.py::test_m_eq_25_31",
    )
