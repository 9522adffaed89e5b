"""Barker eq. B1-B24: the hand's axes in base axes, L = R_0^6, so that TVEL^ = L TVEL and
RVEL^ = L RVEL (eq. B1), from the rotations of appendix A (the frames and units of
:mod:`.barker`).

Misprint settled (derived again and tested in tests/papers/test_barker.py): eq. B11 prints
P2 = -S23 CAL3: it is P2 = -S23. Derivation: with R_1^2, R_2^3 the rotations of eq. A2, A3,
the first column of R_1^2 R_2^3 is (S2 S3 - C2 C3, -(C2 S3 + S2 C3), 0) = (-C23, -S23, 0) =
(P1, P2, 0) of eq. B4, whose other columns (-P2 CAL3, P1 CAL3, SAL3) and
(P2 SAL3, -P1 SAL3, CAL3) need the same P2 = -S23. With the printed P2 (0 on the nominal arm,
CAL3 = 0) the hand-to-base rotation L of eq. B16-B24 is not a rotation of the arm.
"""

from __future__ import annotations

import math
from collections.abc import Mapping

import numpy as np

from .. import robots
from .barker import arm_parameters
from .table import Result, deviation_text, row


def _p2(q: np.ndarray, alpha3: float, as_printed: bool) -> float:
    """P2 of eq. B11: -S23 (derived, module docstring), or -S23 CAL3 as printed."""
    s23 = math.sin(float(q[1]) + float(q[2]))
    return -s23 * math.cos(alpha3) if as_printed else -s23


def rotation_1_3(
    q: np.ndarray, parameters: Mapping[str, float] | None = None, *, as_printed: bool = False
) -> np.ndarray:
    """R_1^2 R_2^3 of eq. B4 from P1 = -C23 (eq. B10) and P2 (eq. B11: -S23 derived, -S23 CAL3
    with ``as_printed``): frame 3's axes in frame 1's, dimensionless."""
    alpha3 = arm_parameters(parameters)["alpha3"]
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
    alpha3 = arm_parameters(parameters)["alpha3"]
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


def hand_to_base_errors(count: int = 100, **lengths: float) -> tuple[float, float, float]:
    """Eq. B1-B24 against the robot, over random q: (max ``|L - R_hand|`` with P2 = -S23, the same
    with P2 as printed, max ``|B4 as printed - B4|`` entrywise), R_hand the robot's hand rotation
    (``robot.frame_pose(q, "hand")``); all dimensionless."""
    robot = robots.barker_arm(**lengths)  # type: ignore[arg-type]  # lengths holds no tip or sensor
    derived = printed = b4 = 0.0
    for q in robot.sample_configurations(count, 21):
        hand = robot.frame_pose(q, "hand")[:3, :3]
        derived = max(derived, float(np.abs(hand_to_base(q, lengths) - hand).max()))
        printed = max(printed, float(np.abs(hand_to_base(q, lengths, as_printed=True) - hand).max()))
        b4 = max(b4, float(np.abs(rotation_1_3(q, lengths, as_printed=True) - rotation_1_3(q, lengths)).max()))
    return derived, printed, b4


@row
def _hand_to_base_row() -> Result:
    """Barker eq. B1-B24 against the robot's hand rotation, P2 derived and as printed."""
    derived, printed, b4 = hand_to_base_errors()
    derived_off, printed_off, b4_off = hand_to_base_errors(alpha3=1.4, a3=0.05, r3=0.03)
    return Result(
        "Barker eq. B1-B24",
        "TVEL^ = L TVEL, RVEL^ = L RVEL, L = R_0^6 from P1, P2, Q1..Q4, T1..T4 (B6-B24); B11 prints "
        "P2 = -S23 CAL3: it is -S23 (R_1^2 R_2^3 of eq. A2-A3 has first column (-C23, -S23, 0))",
        f"L with P2 = -S23 vs the robot's hand rotation: max deviation {deviation_text(derived)} (nominal), "
        f"{deviation_text(derived_off)} (alpha3 = 1.4, a3 = 0.05, r3 = 0.03); with the printed P2, L is off by "
        f"up to {printed:.2f} (nominal) and {printed_off:.2f} (alpha3 = 1.4), B4 by up to {b4:.2f} and "
        f"{b4_off:.2f} per entry (max |S23| (1 - CAL3))",
        "papers/test_barker.py::test_hand_to_base_b1_b24",
    )
