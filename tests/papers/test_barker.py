"""Barker 1983 eq. 25-44 and 57-63 (pinrate.papers.barker_*): each closed form against an
independent computation (the robot's Jacobian, numpy's solve and pinv, finite sums), and
the control step against the closed forms (the rows of docs/paper-results.md)."""

from __future__ import annotations

import math

import numpy as np
import pytest

import pinrate
from pinrate import Controller, Status
from pinrate.papers import barker_arm_rates, barker_elbow, barker_hand_rotation, barker_jacobian, barker_wrist
from pinrate.papers.barker_jacobian import barker_singular_configurations

OFF_NOMINAL = {"alpha3": 1.4, "a3": 0.05, "r3": 0.03}


def arm_block_in_base_axes(robot: pinrate.Robot, q: np.ndarray) -> np.ndarray:
    """R_hand A: the robot's arm block, wrist-centre velocity per arm rate, in base axes (eq. 20)."""
    return robot.frame_pose(q, "hand")[:3, :3] @ robot.jacobian(q)[:3, :3]


# ---------------------------------------------------------------------- the closed forms
@pytest.mark.parametrize("lengths", [{}, OFF_NOMINAL])
def test_m_eq_25_31(lengths: dict[str, float]) -> None:
    assert barker_jacobian.m_deviation(count=30, **lengths) < 1e-12


def test_f2_needs_sn_plus_r3() -> None:
    # Eq. 28 as OCR'd (F2 = SN + CAL3 WE) misses R3 (eq. C19): with r3 = 0.03 it is off by r3.
    robot = pinrate.robots.barker_arm(**OFF_NOMINAL)
    q = np.array([0.3, 0.4, 0.8, 0.1, 0.6, 0.0])
    without_r3 = barker_jacobian.barker_m(q, OFF_NOMINAL | {"sn": pinrate.robots.parameters("barker_arm")["sn"] - 0.03})
    assert np.abs(arm_block_in_base_axes(robot, q) - barker_jacobian.barker_m(q, OFF_NOMINAL)).max() < 1e-12
    assert np.abs(arm_block_in_base_axes(robot, q) - without_r3).max() > 0.02


@pytest.mark.parametrize("lengths", [{}, OFF_NOMINAL])
def test_wrist_centre_from_shoulder_is_f7_f6_f3(lengths: dict[str, float]) -> None:
    robot = pinrate.robots.barker_arm(**lengths)
    shoulder = np.array([0.0, 0.0, pinrate.robots.parameters("barker_arm")["no"]])
    for q in robot.sample_configurations(10, 3):
        position = robot.frame_pose(q, "wrist_centre")[:3, 3]
        np.testing.assert_allclose(
            barker_jacobian.wrist_centre_from_shoulder(q, lengths), position - shoulder, atol=1e-12
        )


@pytest.mark.parametrize("lengths", [{}, OFF_NOMINAL])
def test_arm_rates_eq_34_37_solve_the_robots_arm_block(lengths: dict[str, float]) -> None:
    robot = pinrate.robots.barker_arm(**lengths)
    rng = np.random.default_rng(1)
    for q in robot.sample_configurations(30, 2):
        tvel = rng.normal(size=3) * 0.1
        expected = np.linalg.solve(arm_block_in_base_axes(robot, q), tvel)
        scale = max(1.0, np.abs(expected).max())
        np.testing.assert_allclose(
            barker_arm_rates.arm_rates_closed_form(q, tvel, lengths), expected, atol=1e-9 * scale
        )
        f = barker_jacobian.arm_terms(q, lengths)
        assert f.det_m == pytest.approx(np.linalg.det(barker_jacobian.barker_m(q, lengths)), rel=1e-9, abs=1e-14)
        assert expected[0] == pytest.approx((f.C1 * tvel[1] - f.S1 * tvel[0]) / f.F1, rel=1e-9)  # eq. 34 simplified


def test_printed_eq_35_36_are_misprints() -> None:
    q = np.array([0.3, 0.4, 0.8, 0.1, 0.6, 0.0])
    tvel = np.array([0.05, -0.03, 0.02])
    printed, derived = barker_arm_rates.arm_rates_as_printed(q, tvel), barker_arm_rates.arm_rates_closed_form(q, tvel)
    assert printed[0] == pytest.approx(derived[0], rel=1e-12)  # eq. 34 is right
    assert printed[1] == pytest.approx(-derived[1], rel=1e-12)  # eq. 35: the overall sign
    assert abs(printed[2] - derived[2]) > 1e-3  # eq. 36: the sign of TVEL(2) F6
    assert barker_arm_rates.printed_arm_rates_error(count=30) > 0.5


def test_reduction_eq_39_44_solves_eq_25_and_det_m1_is_s1_det_m() -> None:
    robot = pinrate.robots.barker_arm()
    rng = np.random.default_rng(4)
    for q in robot.sample_configurations(30, 5):
        tvel = rng.normal(size=3) * 0.1
        M = arm_block_in_base_axes(robot, q)
        expected = np.linalg.solve(M, tvel)
        scale = max(1.0, np.abs(expected).max())
        np.testing.assert_allclose(barker_arm_rates.reduction_2x2(q, tvel), expected, atol=1e-8 * scale)
        M1, _ = barker_arm_rates.reduced_system(q, tvel)
        assert np.linalg.det(M1) == pytest.approx(math.sin(q[0]) * np.linalg.det(M), rel=1e-9, abs=1e-14)


def test_reduction_drops_tvel_2_at_theta1_zero() -> None:
    # det M1 = S1 det M: at theta1 = 0, M1's first row vanishes with g1's first entry, and M1*
    # answers row 3 alone; M is well conditioned there and solves the command exactly.
    q, tvel = barker_arm_rates.THETA1_ZERO_Q, barker_arm_rates.REFERENCE_TVEL
    M1, g1 = barker_arm_rates.reduced_system(q, tvel)
    assert np.abs(M1[0]).max() < 1e-15 and abs(g1[0]) < 1e-15
    condition, det_m1, error = barker_arm_rates.reduction_at_theta1_zero()
    assert condition > 0.1 and det_m1 < 1e-15 and error > 0.1
    assert (
        np.linalg.norm(barker_jacobian.barker_m(q) @ np.linalg.solve(barker_jacobian.barker_m(q), tvel) - tvel) < 1e-15
    )


def test_along_the_arm_is_what_m_cannot_produce() -> None:
    for q in barker_singular_configurations():
        direction = barker_arm_rates.along_the_arm(q)
        assert np.abs(direction @ barker_jacobian.barker_m(q)).max() < 1e-12
        assert direction @ barker_jacobian.wrist_centre_from_shoulder(q) > 0.0


def test_z0_z1_z2_of_eq_48_are_the_robots_arm_axes() -> None:
    robot = pinrate.robots.barker_arm()
    rng = np.random.default_rng(6)
    for q in robot.sample_configurations(10, 7):
        rates, rvel = rng.normal(size=3), rng.normal(size=3)
        rotated = robot.frame_pose(q, "hand")[:3, :3] @ robot.jacobian(q)[3:, :3]
        np.testing.assert_allclose(
            barker_wrist.wrist_residual_rotation(q, rvel, rates), rvel - rotated @ rates, atol=1e-12
        )


def wrist_block_in_base_axes(robot: pinrate.Robot, q: np.ndarray) -> np.ndarray:
    """[z3 z4 z5] from the robot: R_hand W."""
    return robot.frame_pose(q, "hand")[:3, :3] @ robot.jacobian(q)[3:, 3:]


@pytest.mark.parametrize("lengths", [{}, OFF_NOMINAL])
def test_wrist_rates_eq_49_60_produce_rvel_tilde(lengths: dict[str, float]) -> None:
    robot = pinrate.robots.barker_arm(**lengths)
    rng = np.random.default_rng(8)
    for q in robot.sample_configurations(30, 9):
        rvel_tilde = rng.normal(size=3)
        rates = barker_wrist.wrist_rates(q, rvel_tilde, parameters=lengths)
        produced = wrist_block_in_base_axes(robot, q) @ rates
        np.testing.assert_allclose(produced, rvel_tilde, atol=1e-9 * max(1.0, np.abs(rates).max()))


def test_wrist_at_theta5_zero_m2_star_is_the_moore_penrose_solution_split_equally() -> None:
    robot = pinrate.robots.barker_arm()
    q = barker_wrist.WRIST_SINGULAR_Q
    rng = np.random.default_rng(10)
    for _ in range(5):
        rvel_tilde = rng.normal(size=3)
        rates = barker_wrist.wrist_rates(q, rvel_tilde)
        expected = np.linalg.pinv(wrist_block_in_base_axes(robot, q), rcond=1e-9) @ rvel_tilde
        np.testing.assert_allclose(rates, expected, atol=1e-12)
        np.testing.assert_allclose(barker_wrist.wrist_rule_rates(q, rvel_tilde, "split"), rates, atol=1e-15)  # eq. 61


@pytest.mark.parametrize("rule", barker_wrist.WRIST_RULES)
def test_every_wrist_rule_produces_the_reachable_rotation(rule: str) -> None:
    # At theta5 = 0 the wrist turns about z3 = z5 and z4 only: each rule (eq. 61-63) gives the
    # least-squares rotation, the part of RVEL~ along the lost direction left out.
    robot = pinrate.robots.barker_arm()
    q = barker_wrist.WRIST_SINGULAR_Q
    W = wrist_block_in_base_axes(robot, q)
    rvel_tilde = np.array([0.2, -0.4, 0.1])
    reachable = W @ np.linalg.pinv(W, rcond=1e-9) @ rvel_tilde
    rates = barker_wrist.wrist_rule_rates(q, rvel_tilde, rule)
    np.testing.assert_allclose(W @ rates, reachable, atol=1e-12)
    assert {"split": rates[0] == rates[2], "hold_first": rates[0] == 0.0, "last_then_first": rates[2] == 0.0}[rule]


# ---------------------------------------------------------------------- the step against them
@pytest.mark.parametrize("lengths", [{}, OFF_NOMINAL])
def test_arm_rates_eq_34_37(lengths: dict[str, float]) -> None:
    assert barker_arm_rates.arm_rates_deviation(count=40, **lengths) < 1e-9


def test_generalized_inverse_eq_38() -> None:
    assert barker_arm_rates.generalized_inverse_deviation() < 1e-12
    for which in (0, 1):
        case = barker_arm_rates.singular_case(which, barker_arm_rates.ALONG_THE_ARM)
        assert case.step.status is Status.NEAR_SINGULARITY and "block A" in case.step.detail
        assert case.step_error == pytest.approx(barker_arm_rates.ALONG_THE_ARM, rel=1e-9)  # only the unreachable part


def test_reduction_eq_39_44() -> None:
    assert barker_arm_rates.reduction_deviation(count=40) < 1e-9


def test_eq_38_and_39_44_at_full_extension() -> None:
    q = barker_singular_configurations()[0]
    f = barker_jacobian.arm_terms(q)
    null = np.array([0.0, f.F4, -f.F3])  # θ3 = 0: M's null vector, no θ1
    assert np.abs(barker_jacobian.barker_m(q) @ null).max() < 1e-12
    feasible = barker_arm_rates.singular_case(0)
    assert feasible.step_error < 1e-12 and feasible.reduction_error < 1e-12
    assert abs(feasible.step_rates @ null) < 1e-12  # least norm among the exact solutions
    np.testing.assert_allclose(feasible.step_rates, feasible.reduction, atol=1e-12)
    outward = barker_arm_rates.singular_case(0, barker_arm_rates.ALONG_THE_ARM)
    assert outward.reduction_error > 2 * outward.step_error  # a different least-squares metric
    assert abs(outward.reduction[0]) > 2 * abs(outward.step_rates[0])


def test_eq_38_and_39_44_at_least_radius() -> None:
    q = barker_singular_configurations()[1]
    f = barker_jacobian.arm_terms(q)
    assert abs(f.F1) < 1e-12
    null = np.array([f.F3, f.F2, 0.0])  # S2 ES + F5 = 0: M's null vector moves θ1
    assert np.abs(barker_jacobian.barker_m(q) @ null).max() < 1e-12
    case = barker_arm_rates.singular_case(1)
    assert case.step_error < 1e-12 and case.reduction_error < 1e-12  # both exact
    assert abs(case.step_rates @ null) < 1e-12 and abs(case.reduction[1]) < 1e-12
    assert np.abs(case.step_rates - case.reduction).max() > 1e-3  # ... and different
    # the difference is a null motion: the same wrist-centre velocity
    difference = case.reduction - case.step_rates
    assert np.linalg.norm(np.cross(difference, null)) < 1e-12 * np.linalg.norm(null) + 1e-15


def test_wrist_eq_57_60() -> None:
    off, at_zero = barker_wrist.wrist_generalized_inverse_deviation(count=40)
    assert off < 1e-9 and at_zero < 1e-12
    step, closed_form = barker_wrist.wrist_region_rates()
    assert step[0] == pytest.approx(step[2], rel=1e-12) and abs(closed_form[0]) > 10 * abs(step[0])
    assert step[1] == pytest.approx(closed_form[1], rel=1e-9)  # θ5 by eq. 49 either way


@pytest.mark.parametrize("rule", barker_wrist.WRIST_RULES)
def test_wrist_rules_eq_61_63(rule: str) -> None:
    assert barker_wrist.wrist_rule_deviations()[rule] < 1e-12
    robot = pinrate.robots.barker_arm()
    controller = Controller(robot, algorithm="mca2", wrist=rule, velocity_limits=np.inf)
    step = controller.step(barker_wrist.WRIST_SINGULAR_Q, barker_wrist.WRIST_TWIST)
    assert Status.WRIST_SINGULARITY in step.conditions and "theta4 and theta6" in step.detail


def test_auxiliary_elbow_eq_45_46() -> None:
    elbow, shoulder = barker_elbow.auxiliary_elbow_deviation()
    assert elbow < 1e-9 and shoulder < 1e-9
    bends = barker_elbow.elbow_bends()
    assert all(abs(bend) > 0.05 for bend in bends)
    assert [math.copysign(1.0, bend) for bend in bends] == [-1.0, 1.0, -1.0]  # from +0.03: each the other way


def test_upper_arm_axes_are_the_robots_link_2_axes() -> None:
    robot = pinrate.robots.barker_arm()
    for q in robot.sample_configurations(10, 4):
        x2, y2 = barker_elbow.upper_arm_axes(q)
        # X2 runs from the shoulder to the elbow at any θ3, Y2 is normal to it and to θ2's axis
        shoulder, elbow = (robot.frame_pose(q, frame)[:3, 3] for frame in ("theta2", "theta3"))
        axis = robot.frame_pose(q, "theta2")[:3, 2]  # the URDF turns every joint about its z
        across = (elbow - shoulder) - ((elbow - shoulder) @ axis) * axis
        np.testing.assert_allclose(x2, across / np.linalg.norm(across), atol=1e-12)
        np.testing.assert_allclose(abs(float(np.cross(x2, y2) @ axis)), 1.0, atol=1e-12)


# ---------------------------------------------------------------------- appendix B
def appendix_a_rotations(q: np.ndarray, alpha3: float) -> list[np.ndarray]:
    """R_0^1 .. R_5^6: the upper-left 3x3 of Barker's eq. A1-A6, written from the paper."""
    C1, S1, C2, S2, C3, S3, C4, S4, C5, S5, C6, S6 = (f(angle) for angle in q for f in (math.cos, math.sin))
    SAL3, CAL3 = math.sin(alpha3), math.cos(alpha3)
    return [
        np.array([[-C1, 0.0, -S1], [-S1, 0.0, C1], [0.0, 1.0, 0.0]]),  # A1
        np.array([[-S2, -C2, 0.0], [C2, -S2, 0.0], [0.0, 0.0, 1.0]]),  # A2
        np.array([[-S3, -C3 * CAL3, C3 * SAL3], [C3, -S3 * CAL3, S3 * SAL3], [0.0, SAL3, CAL3]]),  # A3
        np.array([[-C4, 0.0, -S4], [-S4, 0.0, C4], [0.0, 1.0, 0.0]]),  # A4
        np.array([[-C5, 0.0, -S5], [-S5, 0.0, C5], [0.0, 1.0, 0.0]]),  # A5
        np.array([[C6, -S6, 0.0], [S6, C6, 0.0], [0.0, 0.0, 1.0]]),  # A6
    ]


@pytest.mark.parametrize("lengths", [{}, OFF_NOMINAL])
def test_hand_to_base_b1_b24(lengths: dict[str, float]) -> None:
    # Eq. B11 prints P2 = -S23 CAL3; the first column of R_1^2 R_2^3 (eq. A2 A3) is
    # (-C23, -S23, 0): P2 = -S23. With it, B4 is that product and L (B16-B24) the product
    # of all six, i.e. the robot's hand rotation; with the printed P2 neither holds.
    alpha3 = (pinrate.robots.parameters("barker_arm") | lengths)["alpha3"]
    robot = pinrate.robots.barker_arm(**lengths)
    for q in robot.sample_configurations(20, 26):
        r01, r12, r23, r34, r45, r56 = appendix_a_rotations(q, alpha3)
        np.testing.assert_allclose(barker_hand_rotation.rotation_1_3(q, lengths), r12 @ r23, atol=1e-14)
        product = r01 @ r12 @ r23 @ r34 @ r45 @ r56
        np.testing.assert_allclose(barker_hand_rotation.hand_to_base(q, lengths), product, atol=1e-14)
        np.testing.assert_allclose(product, robot.frame_pose(q, "hand")[:3, :3], atol=1e-12)
        error = abs(math.sin(q[1] + q[2])) * (1 - math.cos(alpha3))  # |P2 printed - P2|
        b4_printed = barker_hand_rotation.rotation_1_3(q, lengths, as_printed=True)
        assert np.abs(b4_printed - r12 @ r23).max() == pytest.approx(error, abs=1e-12)
    derived, printed, b4 = barker_hand_rotation.hand_to_base_errors(count=50, **lengths)
    assert derived < 1e-12
    assert printed > 0.5 and b4 > 0.9 * (1 - math.cos(alpha3))


def test_upper_arm_components_b27_b29() -> None:
    # B27: (TVEL)_X2, (TVEL)_Y2 are rows 1-2 of R_2^1 R_1^0 (the transposes of eq. A2, A1)
    # times TVEL^. The printed B28-B29, bracket mended or not, differ from them; with the
    # bracket mended they differ by exactly the sign of the S1 TVEL(2) term.
    rng = np.random.default_rng(27)
    robot = pinrate.robots.barker_arm()
    for q in robot.sample_configurations(20, 28):
        r01, r12, *_ = appendix_a_rotations(q, math.pi / 2)
        tvel = rng.normal(size=3)
        expected = (r12.T @ r01.T @ tvel)[:2]
        np.testing.assert_allclose(barker_elbow.upper_arm_components(q, tvel), expected, atol=1e-14)
        mended = np.array(barker_elbow.upper_arm_components_as_printed(q, tvel, bracket_mended=True))
        sign_term = 2 * math.sin(q[0]) * tvel[1] * np.array([math.sin(q[1]), math.cos(q[1])])
        np.testing.assert_allclose(expected - mended, sign_term, atol=1e-14)
    derived, printed, bracket_only = barker_elbow.upper_arm_component_errors(count=50)
    assert derived < 1e-12
    assert printed > 0.5 and bracket_only > 0.5
