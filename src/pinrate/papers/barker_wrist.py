"""Barker eq. 47-63: the wrist rates (theta4, theta5, theta6) that give the rotation the arm
leaves over, and pinrate's step against them, at the wrist singularity theta5 = 0 too (the
frames and units of :mod:`.barker`).

* eq. 48: RVEL~ = RVEL^ - z0 theta1 - z1 theta2 - z2 theta3 with z0 = (0, 0, 1) and
  z1 = z2 = (-S1, C1, 0) (eq. C7, C8, C10); eq. 52-56: D1 = C1 RVEL~1 + S1 RVEL~2,
  D2 = S1 RVEL~1 - C1 RVEL~2, D3 = S23 D1 + C23 RVEL~3, D4 = C23 D1 - S23 RVEL~3,
  D5 = CAL3 D3 + SAL3 D2.
* eq. 49: theta5 = -C4 D5 - S4 D4; eq. 57-60: g2 = M2 [theta4 theta6]',
  M2 = [[0, S5], [1, C5]], g2 = (-S4 D5 + C4 D4, SAL3 D3 - CAL3 D2), solved by M2*.
* eq. 61-63 at theta5 = 0 (D = SAL3 D3 - CAL3 D2): theta4 + theta6 = D; M2* splits it
  equally (eq. 60-61, pinrate's ``wrist="split"``); theta4 = 0, theta6 = D (eq. 62,
  ``"hold_first"``); theta6 held at its limit, theta4 = D (eq. 63, ``"last_then_first"``).

OCR garbles settled (derived again and tested in tests/papers/test_barker.py): eq. 47 prints
"z3 theta1 + z1 theta5": it is RVEL~ = z3 theta4 + z4 theta5 + z5 theta6 (eq. C2); eq. 59
prints "-S4 D6": it is -S4 D5 (eq. 50); "theta14" (eq. 60), "theta_l4" (eq. 63) and the double
dots of eq. 61-62 are theta4 and single dots.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping

import numpy as np

from .. import robots
from ..control.controller import Controller, Step
from ..errors import InputError
from ..kinematics.manipulator import Robot
from ..solvers.rates import joint_rates
from .barker import arm_parameters, base_axes, relative_deviation, unlimited_controller, well_conditioned
from .barker_arm_rates import arm_rates_closed_form
from .barker_hand_rotation import hand_to_base
from .table import Result, deviation_text, row

WRIST_SINGULAR_Q = np.array([0.3, 0.4, 0.7, 0.1, 0.0, 0.2])
"""A configuration at the wrist singularity theta5 = 0 with the arm well conditioned (rad)."""

WRIST_TWIST = np.array([0.02, 0.01, -0.03, 0.2, -0.1, 0.3])
"""The hand-axes twist (m/s, rad/s) commanded at :data:`WRIST_SINGULAR_Q`."""

WRIST_RULES = ("split", "hold_first", "last_then_first")
"""pinrate's names of Barker's wrist rules eq. 61, 62 and 63."""


# ---------------------------------------------------------------------- eq. 47-63, the closed forms
def wrist_residual_rotation(q: np.ndarray, rvel: np.ndarray, arm_rates: np.ndarray) -> np.ndarray:
    """RVEL~ = RVEL^ - z0 theta1 - z1 theta2 - z2 theta3 (eq. 48; z of eq. C7, C8, C10), rad/s, base axes."""
    C1, S1 = math.cos(float(q[0])), math.sin(float(q[0]))
    z0, z1 = np.array([0.0, 0.0, 1.0]), np.array([-S1, C1, 0.0])  # z2 = z1: joints 2 and 3 parallel
    return np.asarray(rvel, dtype=float) - z0 * arm_rates[0] - z1 * (arm_rates[1] + arm_rates[2])


def _wrist_terms(
    q: np.ndarray, rvel_tilde: np.ndarray, parameters: Mapping[str, float] | None = None
) -> tuple[float, float, float, float, float]:
    """(D1, D2, D3, D4, D5) of eq. 52-56 from RVEL~ (rad/s, base axes)."""
    alpha3 = arm_parameters(parameters)["alpha3"]
    t1, t2, t3 = (float(angle) for angle in q[:3])
    C1, S1, C23, S23 = math.cos(t1), math.sin(t1), math.cos(t2 + t3), math.sin(t2 + t3)
    R1, R2, R3 = (float(value) for value in rvel_tilde)
    D1 = C1 * R1 + S1 * R2  # eq. 52
    D2 = S1 * R1 - C1 * R2  # eq. 53
    D3 = S23 * D1 + C23 * R3  # eq. 54
    D4 = C23 * D1 - S23 * R3  # eq. 55
    D5 = math.cos(alpha3) * D3 + math.sin(alpha3) * D2  # eq. 56
    return D1, D2, D3, D4, D5


def _wrist_system(
    q: np.ndarray, rvel_tilde: np.ndarray, parameters: Mapping[str, float] | None = None
) -> tuple[float, np.ndarray, np.ndarray]:
    """(theta5 rate of eq. 49, M2 of eq. 58, g2 of eq. 59): g2 = M2 [theta4 theta6]'."""
    alpha3 = arm_parameters(parameters)["alpha3"]
    _, D2, D3, D4, D5 = _wrist_terms(q, rvel_tilde, parameters)
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
    theta5, M2, g2 = _wrist_system(q, rvel_tilde, parameters)
    theta4, theta6 = np.linalg.pinv(M2, rcond=threshold) @ g2  # eq. 60
    return np.array([theta4, theta5, theta6])


def wrist_rule_rates(
    q: np.ndarray, rvel_tilde: np.ndarray, rule: str, parameters: Mapping[str, float] | None = None
) -> np.ndarray:
    """(theta4, theta5, theta6) rates (rad/s) at theta5 = 0 by Barker's rule: eq. 61 with the
    task split equally ("split"), eq. 62 theta4 = 0 ("hold_first"), eq. 63 theta6 held at its
    limit ("last_then_first"); theta5 by eq. 49, D = SAL3 D3 - CAL3 D2."""
    theta5, _, g2 = _wrist_system(q, rvel_tilde, parameters)
    D = float(g2[1])
    theta4, theta6 = {"split": (D / 2, D / 2), "hold_first": (0.0, D), "last_then_first": (D, 0.0)}[rule]
    return np.array([theta4, theta5, theta6])


# ---------------------------------------------------------------------- eq. 49-51 for any solver's rates
RateSolver = Callable[[Robot, np.ndarray, np.ndarray], np.ndarray]
"""(robot, q, sensor-frame twist) -> joint rates (nv,): the solver a check is run on."""


def _mca2_rates(robot: Robot, q: np.ndarray, twist: np.ndarray) -> np.ndarray:
    return joint_rates(robot, q, twist, algorithm="mca2")


def barker_wrist_deviation(count: int = 200, *, solver: RateSolver | None = None, **lengths: float) -> float:
    """max relative residual of Barker's eq. 49-51 for the wrist rates a solver produces.

    At random q and random hand-axes twists (TVEL, RVEL) (m/s, rad/s) the solver (default
    pinrate's MCA2, :func:`joint_rates`) gives the six rates. The residual is computed from the
    paper alone: RVEL^ = L RVEL (eq. B1, L of eq. B16-B24 with P2 = -S23), RVEL~ = RVEL^ -
    z0 theta1 - z1 theta2 - z2 theta3 with the solver's arm rates (eq. 48; z of eq. C7-C10),
    D1..D5 (eq. 52-56), then

        theta5 + C4 D5 + S4 D4 (eq. 49),   S5 theta6 + S4 D5 - C4 D4 (eq. 50),
        theta4 + C5 theta6 - SAL3 D3 + CAL3 D2 (eq. 51),

    each over max(1, max ``|rate|``) (rad/s). It is rounding for rates that realise the commanded
    RVEL; wrong wrist (or arm) rates leave it at their error.
    """
    robot = robots.barker_arm(**lengths)  # type: ignore[arg-type]  # lengths holds no tip or sensor
    solve = _mca2_rates if solver is None else solver
    alpha3 = (robots.parameters("barker_arm") | lengths)["alpha3"]
    sal3, cal3 = math.sin(alpha3), math.cos(alpha3)
    generator = np.random.default_rng(9)
    worst = 0.0
    for q in robot.sample_configurations(count, 8):
        twist = generator.normal(size=6)
        rates = np.asarray(solve(robot, q, twist), dtype=float)
        rvel_hat = hand_to_base(q, lengths) @ twist[3:]  # eq. B1
        rvel_tilde = wrist_residual_rotation(q, rvel_hat, rates[:3])  # eq. 48
        _, D2, D3, D4, D5 = _wrist_terms(q, rvel_tilde, lengths)  # eq. 52-56
        C4, S4, C5, S5 = math.cos(q[3]), math.sin(q[3]), math.cos(q[4]), math.sin(q[4])
        residual = max(
            abs(rates[4] - (-C4 * D5 - S4 * D4)),  # eq. 49
            abs(S5 * rates[5] - (-S4 * D5 + C4 * D4)),  # eq. 50
            abs(rates[3] + C5 * rates[5] - (sal3 * D3 - cal3 * D2)),  # eq. 51
        )
        worst = max(worst, residual / max(1.0, float(np.abs(rates).max())))
    return worst


@row
def _wrist_residual_row() -> Result:
    """Barker eq. 49-51: pinrate's MCA2 rates put into the paper's wrist equations."""
    return Result(
        "Barker eq. 49-51",
        "theta5 = -C4 D5 - S4 D4, S5 theta6 = -S4 D5 + C4 D4, theta4 + C5 theta6 = SAL3 D3 - CAL3 D2, "
        "D1..D5 of eq. 52-56 from RVEL~ (eq. 48)",
        "pinrate's MCA2 rates for 200 random q and hand-axes twists, put into eq. 49-51 with RVEL^ = L RVEL "
        "(eq. B1) and RVEL~ from their arm rates: max residual / max(1, |rates|) "
        f"{deviation_text(barker_wrist_deviation())} rad/s (nominal), "
        f"{deviation_text(barker_wrist_deviation(alpha3=1.4, a3=0.05, r3=0.03))} "
        "(alpha3 = 1.4, a3 = 0.05, r3 = 0.03)",
        "papers/test_worked_examples.py::test_barker_wrist_rates",
    )


# ---------------------------------------------------------------------- eq. 57-63, pinrate's step
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
    """(off theta5 = 0, at theta5 = 0): max ``|step's wrist rates - eq. 49, 60|`` (rad/s), mca2.

    Off: random q off the singular region (c >= 0.05), random twists, M2* = M2^-1. At:
    :data:`WRIST_SINGULAR_Q` and :data:`WRIST_TWIST`, ``wrist="split"``. RVEL~ (eq. 48) from
    the arm rates of eq. 34-37, not the step's."""
    robot = robots.barker_arm()
    controller = unlimited_controller(robot, "mca2")
    generator = np.random.default_rng(18)
    off = 0.0
    for q in well_conditioned(controller, count, 19):
        twist = generator.normal(size=6) * 0.1
        tvel, rvel = base_axes(robot, q, twist)
        expected = wrist_rates(q, wrist_residual_rotation(q, rvel, arm_rates_closed_form(q, tvel)))
        off = max(off, relative_deviation(controller.step(q, twist).joint_rates[3:], expected))
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


@row
def _wrist_generalized_inverse_row() -> Result:
    """Barker eq. 57-60: the step's wrist rates against M2* g2, off and at theta5 = 0."""
    off, at_zero = wrist_generalized_inverse_deviation()
    region_step, region_closed_form = wrist_region_rates()
    return Result(
        "Barker eq. 57-60",
        "(theta4, theta6) = M2* g2, M2 = [[0, S5], [1, C5]]; at theta5 = 0 M2* splits theta4 + theta6 equally",
        f"MCA2 wrist rates vs eq. 49, 60: max relative deviation {deviation_text(off)} off theta5 = 0; at "
        f"theta5 = 0 (wrist=split) {deviation_text(at_zero)} rad/s; inside the wrist region off 0 split keeps "
        f"theta4 = theta6 (theta5 = 0.02: {region_step[0]:.2f}, {region_step[2]:.2f} rad/s) where M2^-1 gives "
        f"{region_closed_form[0]:.1f}, {region_closed_form[2]:.1f} rad/s",
        "papers/test_barker.py::test_wrist_eq_57_60",
    )


def wrist_rule_deviations() -> dict[str, float]:
    """Per rule (eq. 61 split, 62 hold_first, 63 last_then_first): max ``|step's wrist rates -
    the rule's closed form|`` (rad/s) at :data:`WRIST_SINGULAR_Q` for :data:`WRIST_TWIST`, mca2."""
    robot = robots.barker_arm()
    deviations = {}
    for rule in WRIST_RULES:
        step, q = _wrist_step(rule, WRIST_SINGULAR_Q, WRIST_TWIST)
        tvel, rvel = base_axes(robot, q, WRIST_TWIST)
        expected = wrist_rule_rates(q, wrist_residual_rotation(q, rvel, arm_rates_closed_form(q, tvel)), rule)
        deviations[rule] = float(np.abs(step.joint_rates[3:] - expected).max())
    return deviations


@row
def _wrist_rules_row() -> Result:
    """Barker eq. 61-63: the step at theta5 = 0 against each of Barker's rules."""
    rules = wrist_rule_deviations()
    return Result(
        "Barker eq. 61-63",
        "theta5 = 0: theta4 + theta6 = SAL3 D3 - CAL3 D2 shared equally (61), theta4 = 0 (62), "
        "theta6 at its limit and theta4 takes it (63)",
        f"MCA2 step vs the rule, max deviation: split {deviation_text(rules['split'])}, "
        f"hold_first {deviation_text(rules['hold_first'])}, "
        f"last_then_first {deviation_text(rules['last_then_first'])} rad/s",
        "papers/test_barker.py::test_wrist_rules_eq_61_63",
    )
