"""The control step near singular blocks (contract v2, issue 11): every strategy finite at
exactly singular configurations; Barker's generalized inverse (eq. 38, 39-44, 60) and wrist
rules (eq. 61-63) against the paper's closed forms written here; decelerate halts before a
block is singular and always executes a way out."""

from __future__ import annotations

import math

import numpy as np
import pytest

import pinrate
from pinrate import Controller, Status
from pinrate.control.singularity import STRATEGIES, WRIST_STRATEGIES
from pinrate.papers.barker_jacobian import barker_m, barker_singular_configurations

UNLIMITED = {"velocity_limits": np.inf, "position_limits": False}


def ur5_at(**joints: float) -> tuple[pinrate.Robot, np.ndarray]:
    robot = pinrate.load("ur5")
    q = robot.home()
    for name, value in joints.items():
        q[robot.joint_names.index(name)] = value
    return robot, q


def singular_cases() -> list[tuple[str, pinrate.Robot, np.ndarray]]:
    ur5 = pinrate.load("ur5")
    elbow, wrist = ur5.home(), ur5.home()
    elbow[2] = 0.0
    wrist[4] = 0.0
    barker = pinrate.robots.barker_arm()
    theta3, shoulder = barker_singular_configurations()  # θ3 = 0 and S2 ES + F5 = 0
    theta5 = np.array([0.3, 0.4, 0.7, 0.1, 0.0, 0.2])
    return [
        ("ur5 elbow 0", ur5, elbow),
        ("ur5 wrist_2 0", ur5, wrist),
        ("barker θ3 = 0", barker, theta3),
        ("barker θ5 = 0", barker, theta5),
        ("barker S2 ES + F5 = 0", barker, shoulder),
    ]


@pytest.mark.parametrize("algorithm", ["exact", "mca1", "mca3", "schur", "dls"])
@pytest.mark.parametrize("wrist", WRIST_STRATEGIES)
@pytest.mark.parametrize("singularity", STRATEGIES)
def test_every_strategy_is_finite_at_exactly_singular_configurations(algorithm, wrist, singularity) -> None:
    rng = np.random.default_rng(3)
    for name, robot, q in singular_cases():
        controller = Controller(robot, algorithm=algorithm, singularity=singularity, wrist=wrist)
        for _ in range(3):
            step = controller.step(q, rng.normal(size=6) * 0.2)
            assert np.isfinite(step.q).all() and np.isfinite(step.joint_rates).all(), (name, step.detail)
            if controller.conditioning(q).value < controller.slow_threshold:  # not A, W of an MCA at the elbow
                assert step.status.severity > Status.JOINT_LIMIT.severity and step.detail, (name, step.detail)


def test_barker_m_is_the_arm_block_in_base_axes() -> None:
    robot = pinrate.robots.barker_arm()
    for q in robot.sample_configurations(20, 1):
        hand = robot.frame_pose(q, "hand")[:3, :3]
        np.testing.assert_allclose(hand @ robot.jacobian(q)[:3, :3], barker_m(q), atol=1e-12)


@pytest.mark.parametrize("which", [0, 1])
def test_generalized_inverse_is_barker_eq_38_at_the_arm_singularities(which: int) -> None:
    robot = pinrate.robots.barker_arm()
    q = barker_singular_configurations()[which]
    controller = Controller(robot, algorithm="mca1", singularity="generalized_inverse", **UNLIMITED)
    hand = robot.frame_pose(q, "hand")[:3, :3]
    twist = np.array([0.05, -0.03, 0.02, 0.0, 0.0, 0.0])
    step = controller.step(q, twist)
    assert step.status is Status.NEAR_SINGULARITY and "block A" in step.detail
    # M* by numpy's pinv with the same relative cut-off; TVEL in base axes (eq. 20).
    expected = np.linalg.pinv(barker_m(q), rcond=controller.singular_threshold) @ (hand @ twist[:3])
    np.testing.assert_allclose(step.joint_rates[:3], expected, atol=1e-12)


def test_barker_2x2_reduction_eq_39_44_equals_the_step_off_the_singularities() -> None:
    robot = pinrate.robots.barker_arm()
    controller = Controller(robot, algorithm="mca2", **UNLIMITED)
    rng = np.random.default_rng(5)
    for q in robot.sample_configurations(20, 2):
        parameters = pinrate.robots.parameters("barker_arm")
        M = barker_m(q)
        if controller.conditioning(q).value < controller.slow_threshold:
            continue
        t1 = q[0]
        C1, S1 = math.cos(t1), math.sin(t1)
        F1, F3, F4, F5 = -M[2, 1], M[0, 1] / C1, M[0, 2] / C1, -M[2, 2]
        F2 = parameters["sn"] + math.cos(parameters["alpha3"]) * parameters["we"]
        F6 = S1 * F1 + C1 * F2  # eq. 41
        twist = np.concatenate([rng.normal(size=3) * 0.01, np.zeros(3)])
        T = robot.frame_pose(q, "hand")[:3, :3] @ twist[:3]
        g1 = np.array([F2 * T[0] - F6 * (C1 * T[0] + S1 * T[1]), T[2]])  # eq. 42
        M1 = np.array([[(C1 * F2 - F6) * F3, (C1 * F2 - F6) * F4], [-F1, -F5]])  # eq. 43
        theta23 = np.linalg.pinv(M1) @ g1  # eq. 44
        theta1 = (F3 * theta23[0] + F4 * theta23[1] - C1 * T[0] - S1 * T[1]) / F2  # eq. 39
        step = controller.step(q, twist)
        assert step.status is Status.OK, step.detail
        np.testing.assert_allclose(step.joint_rates[:3], [theta1, *theta23], rtol=1e-9, atol=1e-12)


def barker_wrist_rhs(robot: pinrate.Robot, q: np.ndarray, arm_rates: np.ndarray, twist: np.ndarray):
    """(eq. 49's θ5 rate, D of eq. 61) from RVEL~ (eq. 48) in base axes, D1-D5 (eq. 52-56)."""
    alpha3 = pinrate.robots.parameters("barker_arm")["alpha3"]
    hand = robot.frame_pose(q, "hand")[:3, :3]
    J = robot.jacobian(q)
    residual = hand @ (twist[3:] - J[3:, :3] @ arm_rates)  # RVEL - z0 θ1 - z1 θ2 - z2 θ3
    t1, t2, t3, t4 = q[:4]
    C1, S1, S23, C23 = math.cos(t1), math.sin(t1), math.sin(t2 + t3), math.cos(t2 + t3)
    C4, S4 = math.cos(t4), math.sin(t4)
    D1 = C1 * residual[0] + S1 * residual[1]
    D2 = S1 * residual[0] - C1 * residual[1]
    D3 = S23 * D1 + C23 * residual[2]
    D4 = C23 * D1 - S23 * residual[2]
    D5 = math.cos(alpha3) * D3 + math.sin(alpha3) * D2
    return -C4 * D5 - S4 * D4, math.sin(alpha3) * D3 - math.cos(alpha3) * D2


@pytest.mark.parametrize("wrist", WRIST_STRATEGIES)
def test_barker_wrist_rules_eq_60_to_63_at_theta5_zero(wrist: str) -> None:
    robot = pinrate.robots.barker_arm()
    q = np.array([0.3, 0.4, 0.7, 0.1, 0.0, 0.2])
    twist = np.array([0.02, 0.01, -0.03, 0.2, -0.1, 0.3])
    # MCA2 is Barker's order: the arm from TVEL (B = 0 at the wrist centre), then the wrist
    # from RVEL less the arm's rotation (eq. 48).
    controller = Controller(robot, algorithm="mca2", wrist=wrist, velocity_limits=np.inf)
    if wrist == "last_then_first":  # θ6 sits on the limit the rotation pushes it into
        probe = Controller(robot, algorithm="mca2", wrist="hold_first", **UNLIMITED).step(q, twist)
        lower, upper = robot.joint_limits("theta6")
        q[5] = upper if probe.joint_rates[5] > 0 else lower
    step = controller.step(q, twist)
    assert Status.WRIST_SINGULARITY in step.conditions and "theta4 and theta6" in step.detail
    theta5, D = barker_wrist_rhs(robot, q, step.joint_rates[:3], twist)
    assert step.joint_rates[4] == pytest.approx(theta5, abs=1e-12)  # eq. 49
    if wrist == "turn":
        # Eq. 61 (θ4 + θ6 = D), and the pair's opposite turning toward the rotation the aligned
        # axes cannot make, about u = z4 x z5 (sensor axes): at θ5 = 0, W = [z4 z5 z4] has
        # σ = √2, 1, 0, so the gain is 1 / (slow_threshold √2) along n = (1, 0, -1) / √2, i.e.
        # |θ4 - θ6| = |b| / slow_threshold, b = u · (RVEL less the arm's rotation): θ5 and
        # θ4 + θ6 make nothing along u. The sign at σ = 0 is the SVD's (either wrist solution).
        J = robot.jacobian(q)
        lost = np.cross(J[3:, 3], J[3:, 4])
        lost /= np.linalg.norm(lost)
        b = float(lost @ (twist[3:] - J[3:, :3] @ step.joint_rates[:3]))
        theta4, theta6 = step.joint_rates[[3, 5]]
        assert theta4 + theta6 == pytest.approx(D, abs=1e-12)
        assert abs(b) > 0.05 and abs(theta4 - theta6) == pytest.approx(abs(b) / controller.slow_threshold, rel=1e-9)
        return
    expected = {
        "split": (D / 2, D / 2),  # eq. 60-61: M2* splits θ4 + θ6 = D equally
        "hold_first": (0.0, D),  # eq. 62
        "last_then_first": (D, 0.0),  # eq. 63: θ6 at its limit, θ4 goes on
    }[wrist]
    np.testing.assert_allclose(step.joint_rates[[3, 5]], expected, atol=1e-12)


def test_decelerate_slows_then_halts_before_the_elbow_singularity_and_lets_the_arm_back() -> None:
    robot, q = ur5_at(elbow_joint=0.4)
    controller = Controller(robot, dt=0.002, velocity_limits=np.inf)
    jacobian = robot.jacobian(q)
    outward = np.linalg.svd(jacobian)[0][:, -1]  # J's weakest task direction near the stretch
    outward *= 0.1 / np.linalg.norm(outward[:3])
    if controller.step(q, outward).joint_rates[2] > 0:  # the sign that straightens the elbow
        outward = -outward
    statuses, values = [], []
    for _ in range(4000):
        step = controller.step(q, outward)
        statuses.append(step.status)
        values.append(controller.conditioning(step.q).value)
        if step.status is Status.HALT_FOR_SINGULARITY:
            break
        q = step.q
    assert statuses[0] is Status.OK
    assert Status.DECELERATE_FOR_SINGULARITY in statuses and statuses[-1] is Status.HALT_FOR_SINGULARITY
    assert min(values) >= controller.singular_threshold
    assert not step.joint_rates.any() and np.array_equal(step.q, q)  # the halt keeps q
    # Backing away raises the conditioning: executed at once, unscaled.
    back = controller.step(q, -outward)
    unscaled = Controller(robot, dt=0.002, singularity="generalized_inverse", velocity_limits=np.inf)
    assert back.status is Status.NEAR_SINGULARITY and "raises c" in back.detail
    np.testing.assert_allclose(back.joint_rates, unscaled.step(q, -outward).joint_rates, atol=1e-12)


def test_decelerate_halts_at_the_same_step_whatever_the_rounding() -> None:
    """The halt is a decision with a margin (singularity.HALT_MARGIN), not a race of c toward
    singular_threshold that rounding ends: starts a few ulps apart (what another CPU or numpy
    makes of the same start) halt at the same step, and soon. Without the margin they halted
    after 216 to 222 steps here, or never (4,000 steps) on another machine."""
    halted_at = set()
    for offset in (0.0, 1e-15, -1e-15, 3e-15, -1e-14, 1e-13):
        robot, q = ur5_at(elbow_joint=0.4)
        q = q + offset
        controller = Controller(robot, dt=0.002, velocity_limits=np.inf)
        outward = np.linalg.svd(robot.jacobian(q))[0][:, -1]
        outward *= 0.1 / np.linalg.norm(outward[:3])
        if controller.step(q, outward).joint_rates[2] > 0:
            outward = -outward
        for number in range(1000):
            step = controller.step(q, outward)
            if step.status is Status.HALT_FOR_SINGULARITY:
                halted_at.add(number)
                break
            q = step.q
        else:
            pytest.fail(f"no halt in 1000 steps from an offset of {offset}")
    assert len(halted_at) == 1, f"the halt step depends on rounding: {sorted(halted_at)}"


def test_freeze_holds_the_joints_that_carry_the_lost_direction() -> None:
    robot, q = ur5_at(elbow_joint=0.02)
    controller = Controller(robot, singularity="freeze", **UNLIMITED)
    outward = np.linalg.svd(robot.jacobian(q))[0][:, -1] * 0.05
    step = controller.step(q, outward)
    if step.status is not Status.FROZEN:  # the other sign is the one that worsens c
        step = controller.step(q, -outward)
    assert step.status is Status.FROZEN and "elbow_joint" in step.frozen
    for name in step.frozen:
        assert step.joint_rates[robot.joint_names.index(name)] == 0.0


def test_adaptive_dls_and_generalized_inverse_equal_the_algorithm_outside_the_region() -> None:
    robot, q = ur5_at(elbow_joint=1.2)
    twist = np.array([0.05, -0.02, 0.03, 0.1, -0.05, 0.2])
    plain = pinrate.joint_rates(robot, q, twist, algorithm="exact")
    for singularity in STRATEGIES:
        step = Controller(robot, singularity=singularity, **UNLIMITED).step(q, twist)
        assert step.status is Status.OK
        np.testing.assert_allclose(step.joint_rates, plain, atol=1e-12)


def test_adaptive_dls_damps_more_as_the_block_nears_singular() -> None:
    gains = []
    for elbow in (0.1, 0.03, 0.0):
        robot, q = ur5_at(elbow_joint=elbow)
        direction = np.linalg.svd(robot.jacobian(q))[0][:, -1] * 0.05
        step = Controller(robot, singularity="adaptive_dls", **UNLIMITED).step(q, direction)
        assert step.status is Status.NEAR_SINGULARITY and "λ" in step.detail
        gains.append(np.linalg.norm(step.joint_rates))
    assert np.isfinite(gains).all() and gains[-1] < gains[0]


def test_bad_strategy_and_threshold_values_are_input_errors() -> None:
    robot = pinrate.load("ur5")
    with pytest.raises(pinrate.InputError, match="decelerate"):
        Controller(robot, singularity="slowdown")
    with pytest.raises(pinrate.InputError, match="hold_first"):
        Controller(robot, wrist="hold")
    with pytest.raises(pinrate.InputError, match="singular_threshold < slow_threshold"):
        Controller(robot, singular_threshold=0.1, slow_threshold=0.05)
    custom = Controller(robot, singular_threshold=0.001, slow_threshold=0.01)
    assert (custom.singular_threshold, custom.slow_threshold) == (0.001, 0.01)


def test_a_conditioning_under_the_noise_floor_is_said_as_such() -> None:
    # c of a block at a singularity is rounding: its digits must not reach the words.
    from pinrate.control.singular_region import NOISE_FLOOR, c_said

    assert c_said(0.0134) == "c = 0.013"
    assert c_said(0.003, "c(W)") == "c(W) = 0.003"
    assert c_said(9.8e-15) == c_said(9.9e-15) == c_said(0.0) == "c < 1e-09"
    assert c_said(NOISE_FLOOR) == "c = 1e-09"


def test_freeze_near_barkers_minimum_radius_holds_theta1_not_theta2_theta3() -> None:
    """Barker's example freezes θ2 and θ3, the variables det M is written in; pinrate holds the
    joints that carry the lost motion (freeze.py says why). Near the minimum radius (eq. 32),
    holding θ2 and θ3 would lose a feasible "down" command entirely; holding θ1 makes it."""
    robot = pinrate.robots.barker_arm()
    parameters = pinrate.robots.parameters("barker_arm")
    es, sn, we = parameters["es"], parameters["sn"], parameters["we"]
    q = np.array([0.3, -0.25, 0.5, 0.0, 0.6, 0.0])
    f1 = math.sin(q[1]) * es + math.sin(q[1] + q[2]) * we  # eq. 27: 0 at the minimum radius
    f3 = math.cos(q[1]) * es + math.cos(q[1] + q[2]) * we  # eq. 29 (A3 = 0, α3 = 90°)
    assert abs(f1) < 1e-3
    m = barker_m(q)
    # M's weakest motion is θ1 with θ2 at F2/F3 of it (F2 = SN; exact at F1 = 0, off by
    # O(F1 / F3) <= 2e-3 at this F1): θ1 carries it.
    weakest = np.linalg.svd(m)[2][-1]
    expected = np.array([f3, sn, 0.0]) / math.hypot(f3, sn)
    np.testing.assert_allclose(weakest * math.copysign(1.0, weakest[0]), expected, atol=2e-3)
    down = np.array([0.0, 0.0, -0.05])  # base axes, m/s: in M's range (the lost direction is radial, horizontal)
    # Barker's choice: θ1 alone moves the wrist centre, and M's θ1 column has no vertical part.
    theta1_only = m[:, :1]
    missed = down - theta1_only @ np.linalg.lstsq(theta1_only, down, rcond=None)[0]
    assert np.linalg.norm(missed) == pytest.approx(0.05, rel=1e-12)
    # pinrate's freeze: θ1 held (with a wrist joint cancelling its turn of the hand), θ2 and
    # θ3 free, and the command made to the rounding of the reduced system (κ <= 1e4: 1e-6).
    controller = Controller(robot, singularity="freeze", **UNLIMITED)
    hand = robot.frame_pose(q, "hand")[:3, :3]
    twist = np.concatenate([hand.T @ down, np.zeros(3)])
    step = controller.step(q, twist)
    assert step.status is Status.FROZEN, step.detail
    assert "theta1" in step.frozen and not {"theta2", "theta3"} & set(step.frozen)
    assert set(step.frozen) - {"theta1"} <= {"theta4", "theta5", "theta6"}
    made = robot.jacobian(q) @ step.joint_rates
    assert np.linalg.norm(made - twist) < 1e-6 * 0.05
