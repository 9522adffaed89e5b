"""Barker eq. 45-46 and B25-B29: the auxiliary elbow control near full extension, and the
upper arm's axes X2, Y2 its commands are resolved along (the frames and units of :mod:`.barker`).

* eq. B25-B27: X2 and Y2 are the first two rows of R_2^1 R_1^0, so (TVEL)_X2 and (TVEL)_Y2 are
  the components of TVEL^ along the upper arm (shoulder to elbow) and across it.
* eq. 45-46, near theta3 = 0: theta3 = K3 (TVEL)_X2, 0 for an outward command at theta3 = 0,
  and theta2 = -WE / (WE + ES) theta3 + K2 (TVEL)_Y2 / (WE + ES); the sign of K3 changes at
  each entry into the region, so the elbow bends to alternate sides (pinrate's
  ``singularity="auxiliary_elbow"``, :mod:`pinrate.control.elbow`).

Misprint settled (derived again and tested in tests/papers/test_barker.py): eq. B28-B29 print
(TVEL)_X2 = S2 [C1 TVEL(1) - S1 TVEL(2) + C2 TVEL(3)] and (TVEL)_Y2 =
C2 [C1 TVEL(1) - S1 TVEL(2) - S2 TVEL(3)]. Rows 1 and 2 of R_2^1 R_1^0 (eq. B25-B27) are
-S2 (-C1, -S1, 0) + C2 (0, 0, 1) = (S2 C1, S2 S1, C2) and -C2 (-C1, -S1, 0) - S2 (0, 0, 1) =
(C2 C1, C2 S1, -S2): (TVEL)_X2 = S2 (C1 TVEL(1) + S1 TVEL(2)) + C2 TVEL(3) and (TVEL)_Y2 =
C2 (C1 TVEL(1) + S1 TVEL(2)) - S2 TVEL(3). The bracket closes after the TVEL(2) term, and
that term's sign is + (the printed - is a second misprint, not a consequence of the
bracket: mending the bracket alone still gives S2 (C1 TVEL(1) - S1 TVEL(2)) + C2 TVEL(3)).
"""

from __future__ import annotations

import math

import numpy as np

from .. import robots
from ..control.controller import Controller
from .barker import hand_twist, unlimited_controller
from .table import Result, deviation_text, row


# ---------------------------------------------------------------------- eq. B25-B29, the upper arm's axes
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


def upper_arm_component_errors(count: int = 100) -> tuple[float, float, float]:
    """Eq. B28-B29 against the robot, over random q and unit base-axes TVEL^: max ``|error|`` (m/s
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


# ---------------------------------------------------------------------- eq. 45-46, the auxiliary elbow control
ELBOW_CASES = ((0.3, 0.4), (-1.1, 1.2), (2.0, -0.7))
"""(θ1, θ2) of the full-extension configurations (θ3 = 0) where eq. 45-46 are checked."""


def auxiliary_elbow_deviation(seed: int = 7) -> tuple[float, float]:
    """(relative deviation of θ3 from eq. 45, of θ2 from eq. 46) over commands along X2 and Y2 at
    θ3 = 0 (:data:`ELBOW_CASES`), ``singularity="auxiliary_elbow"``, K2 = 1 and
    ``|K3|`` = (WE + ES) / (ES WE sin β_r) (pinrate's gain, β_r the controller's elbow region);
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


@row
def _auxiliary_elbow_row() -> Result:
    """Barker eq. 45-46 against pinrate's auxiliary elbow control (:mod:`pinrate.control.elbow`)."""
    elbow, shoulder = auxiliary_elbow_deviation()
    bends = ", ".join(f"{bend:+.2f}" for bend in elbow_bends())
    return Result(
        "Barker eq. 45-46",
        "near theta3 = 0: theta3 = K3 (TVEL)_X2, 0 for an outward command at theta3 = 0; "
        "theta2 = -WE/(WE+ES) theta3 + K2 (TVEL)_Y2/(WE+ES); the sign of K3 changed at each entry "
        "(X2, Y2 are rows of R_2^1 R_1^0; the OCR's B28-B29 misplace a bracket and flip a sign, next row)",
        f"singularity=auxiliary_elbow at theta3 = 0, 18 commands along X2 and Y2 on 3 arm poses, K2 = 1: "
        f"max relative deviation {deviation_text(elbow)} (theta3, eq. 45) and {deviation_text(shoulder)} "
        f"(theta2, eq. 46); theta3 after three retractions from full extension: {bends} rad",
        "papers/test_barker.py::test_auxiliary_elbow_eq_45_46",
    )


@row
def _upper_arm_row() -> Result:
    """Barker eq. B27-B29 against the robot's upper arm (module docstring)."""
    components, as_printed, bracket_only = upper_arm_component_errors()
    return Result(
        "Barker eq. B27-B29",
        "(TVEL)_X2, (TVEL)_Y2 = rows 1-2 of R_2^1 R_1^0 TVEL^ (B27); B28-B29 print S2[C1 TVEL(1) - S1 TVEL(2) "
        "+ C2 TVEL(3)] and C2[C1 TVEL(1) - S1 TVEL(2) - S2 TVEL(3)]: the bracket closes after TVEL(2) and "
        "S1 TVEL(2) has sign + (rows (S2 C1, S2 S1, C2), (C2 C1, C2 S1, -S2))",
        f"derived B28-B29 vs TVEL^ along the robot's X2 (shoulder to elbow) and Y2 = z1 x X2, unit TVEL^: max "
        f"deviation {deviation_text(components)} m/s; as printed off by up to {as_printed:.2f} m/s, with only the "
        f"bracket mended {bracket_only:.2f} m/s",
        "papers/test_barker.py::test_upper_arm_components_b27_b29",
    )
