"""Barker 1983's arm: the paper, its frames and units, and what every check against it shares.

L. K. Barker, "Kinematic Equations for Resolved-Rate Control of an Industrial Robot Arm",
NASA TM-85685 (1983). The closed forms are written from the paper (derived again where the
OCR'd text is garbled), each in the module of its equations, next to the rows of
``docs/paper-results.md`` that measure how far :class:`pinrate.Controller`'s step is from
them:

* :mod:`.barker_jacobian`: M and F1 .. F7 (eq. 25-31), det M (eq. D9), the singular
  surfaces (eq. 32-33);
* :mod:`.barker_arm_rates`: the arm rates (eq. 34-37), the generalized inverse (eq. 38), the
  2x2 reduction (eq. 39-44) and how the two differ at M's singularities;
* :mod:`.barker_elbow`: the auxiliary elbow control (eq. 45-46) and the upper arm's axes
  (eq. B25-B29);
* :mod:`.barker_hand_rotation`: the hand's axes in base axes, L = R_0^6 (eq. B1-B24);
* :mod:`.barker_wrist`: the wrist rates (eq. 47-63).

Frames and units. The base axes X0 Y0 Z0 are the world of :func:`pinrate.robots.barker_arm`;
its tip is the wrist centre (frames 4, 5 and 6 of Barker's eq. 22 coincide there) and its
sensor the hand frame 6, so the robot's twist (TVEL, RVEL) is in the hand's axes and the
paper's base-axes ("caret") quantities are TVEL^ = R_hand TVEL, RVEL^ = R_hand RVEL
(eq. 20, R_hand = ``robot.frame_pose(q, "hand")[:3, :3]``; :func:`base_axes`). Every closed
form takes and returns base-axes quantities: TVEL^ in m/s, RVEL^ in rad/s, joint rates in
rad/s, lengths (ES, WE, SN, A3, R3) in m. q is the paper's (theta1 .. theta6) in rad;
``parameters`` is the robot's generator keywords (:func:`pinrate.robots.parameters`), the
nominal arm when None. In the equations C = cos, S = sin, C23 = cos(theta2 + theta3),
SAL3 = sin alpha3, CAL3 = cos alpha3.

OCR garbles and misprints settled, each derived again, tested in tests/papers/test_barker.py
and documented in the module of its row:

* eq. 28, F2 = SN + CAL3 WE: it is SN~ = SN + R3 (:mod:`.barker_jacobian`);
* eq. 35 and 36, a wrong overall sign and a wrong sign of TVEL^2 F6 (:mod:`.barker_arm_rates`);
* eq. 47, 59, 60, 61-63, garbled symbols (:mod:`.barker_wrist`);
* eq. B11, P2 = -S23 CAL3: it is -S23 (:mod:`.barker_hand_rotation`);
* eq. B28-B29, a misplaced bracket and a flipped sign (:mod:`.barker_elbow`).
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from .. import robots
from ..control.controller import Controller
from ..kinematics.manipulator import Robot


def arm_parameters(parameters: Mapping[str, float] | None) -> dict[str, float]:
    """The arm's lengths (m) and alpha3 (rad): the nominal arm's, updated by ``parameters``."""
    return robots.parameters("barker_arm") | dict(parameters or {})


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


def well_conditioned(controller: Controller, count: int, seed: int) -> list[np.ndarray]:
    """The configurations of ``count`` random ones (``seed``) off the singular region: the
    controller's conditioning c >= 0.05."""
    robot = controller.robot
    return [q for q in robot.sample_configurations(count, seed) if controller.conditioning(q).value >= 0.05]


def base_axes(robot: Robot, q: np.ndarray, twist: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(TVEL^, RVEL^): a hand-axes twist (m/s, rad/s) in base axes (eq. 20)."""
    hand = robot.frame_pose(q, "hand")[:3, :3]
    return hand @ twist[:3], hand @ twist[3:]


def hand_twist(robot: Robot, q: np.ndarray, tvel: np.ndarray, rvel: np.ndarray | None = None) -> np.ndarray:
    """The hand-axes twist (robot's twist) of base-axes TVEL^ and RVEL^ (0 when None)."""
    hand = robot.frame_pose(q, "hand")[:3, :3]
    return np.concatenate([hand.T @ tvel, hand.T @ (np.zeros(3) if rvel is None else rvel)])


def relative_deviation(found: np.ndarray, expected: np.ndarray) -> float:
    """max ``|found - expected|`` over max(1, max ``|expected|``): a rate's error relative to the rates' size."""
    return float(np.abs(found - expected).max() / max(1.0, float(np.abs(expected).max())))
