"""Barker's auxiliary elbow control (eq. 45-46) against the paper's closed forms: the upper
arm's axes X2, Y2 from R_2^1 R_1^0 (eq. B25-B29, :func:`pinrate.papers.barker_elbow.upper_arm_axes`),
F1 from eq. 27; and on the UR5, the hand retracting toward the shoulder."""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin
import pytest

import pinrate
from pinrate import Controller, InputError, JointJog, Status
from pinrate.papers.barker_elbow import upper_arm_axes

UNLIMITED = {"velocity_limits": np.inf, "position_limits": False}


def barker_axes(q: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(X2, Y2, normal) in base axes: rows of R_2^1 R_1^0 (eq. B25-B27), and X2 x Y2."""
    x2, y2 = upper_arm_axes(q)
    return x2, y2, np.cross(x2, y2)


def barker_at_extension(theta1: float, theta2: float) -> np.ndarray:
    return np.array([theta1, theta2, 0.0, 0.3, 0.6, -0.2])


def twist_for(
    robot: pinrate.Robot, q: np.ndarray, base_velocity: np.ndarray, angular: np.ndarray | None = None
) -> np.ndarray:
    """The twist in the hand's axes that commands ``base_velocity`` (TVEL in base axes)."""
    hand = robot.frame_pose(q, "hand")[:3, :3]
    return np.concatenate([hand.T @ base_velocity, np.zeros(3) if angular is None else angular])


@pytest.mark.parametrize("theta1, theta2", [(0.3, 0.4), (-1.1, 1.2), (2.0, -0.7)])
def test_barker_eq_45_46_at_full_extension(theta1: float, theta2: float) -> None:
    robot = pinrate.robots.barker_arm()
    parameters = pinrate.robots.parameters("barker_arm")
    es, we = parameters["es"], parameters["we"]
    controller = Controller(robot, singularity="auxiliary_elbow", **UNLIMITED)
    assert (controller.elbow.joint, controller.elbow.shoulder) == ("theta3", "theta2")
    q = barker_at_extension(theta1, theta2)
    x2, y2, _ = barker_axes(q)
    rng = np.random.default_rng(7)
    for _ in range(5):
        along_x2, along_y2 = rng.normal(size=2) * 0.05
        step = controller.step(q, twist_for(robot, q, along_x2 * x2 + along_y2 * y2))
        assert step.status is Status.AUXILIARY_ELBOW, step.detail
        theta1_rate, theta2_rate, theta3_rate = step.joint_rates[:3]
        if along_x2 > 0.0:  # eq. 45, first case: the impossible outward motion
            assert theta3_rate == 0.0
        else:  # eq. 45; |K3| = d_s / (ES d_e sin β_r); the bend goes the way of the home's elbow
            k3 = -math.copysign(1.0, robot.home()[2]) * (we + es) / (es * we * math.sin(controller.elbow_region))
            assert theta3_rate == pytest.approx(k3 * along_x2, rel=1e-9)
        # eq. 46 with K2 = 1
        assert theta2_rate == pytest.approx(-we / (we + es) * theta3_rate + along_y2 / (we + es), rel=1e-9, abs=1e-15)
        assert abs(theta1_rate) < 1e-12  # nothing normal to the arm's plane was commanded


def test_barker_first_joint_serves_the_normal_component_and_the_wrist_the_rotation() -> None:
    robot = pinrate.robots.barker_arm()
    parameters = pinrate.robots.parameters("barker_arm")
    controller = Controller(robot, singularity="auxiliary_elbow", **UNLIMITED)
    q = barker_at_extension(0.5, 0.9)
    _, _, normal = barker_axes(q)
    angular = np.array([0.1, -0.2, 0.05])
    step = controller.step(q, twist_for(robot, q, 0.04 * normal, angular))
    es, we, sn = parameters["es"], parameters["we"], parameters["sn"]
    F1 = math.sin(q[1]) * (es + we)  # eq. 27 at θ3 = 0, A3 = 0, α3 = 90°
    theta1 = 0.04 / F1
    # θ1 also moves the wrist centre by -SN θ1 along the horizontal in-plane direction t
    # (eq. 39's coefficient F2 = SN); the shoulder cancels its pitch part, eq. 46 extended.
    _, y2, _ = barker_axes(q)
    t = np.array([math.cos(q[0]), math.sin(q[0]), 0.0])
    theta2 = sn * (t @ y2) * theta1 / (es + we)
    np.testing.assert_allclose(step.joint_rates[:3], [theta1, theta2, 0.0], atol=1e-12)
    hand = robot.frame_pose(q, "hand")[:3, :3]
    velocity = robot.jacobian(q) @ step.joint_rates
    base_linear = hand @ velocity[:3]
    assert base_linear @ normal == pytest.approx(0.04, abs=1e-12)  # the normal command, by θ1
    assert base_linear @ y2 == pytest.approx(0.0, abs=1e-12)  # no pitch: it was not commanded
    np.testing.assert_allclose(velocity[3:], angular, atol=1e-12)  # the wrist serves the rotation


def test_outward_commands_straighten_the_elbow_onto_full_extension_and_the_bend_alternates() -> None:
    robot = pinrate.robots.barker_arm()
    controller = Controller(robot, singularity="auxiliary_elbow", velocity_limits=np.inf)
    q = barker_at_extension(0.2, 0.5)
    q[2] = 0.03
    bends = []
    straight = controller.elbow.straight
    for outward in (1.0, -1.0, 1.0, -1.0, 1.0, -1.0):
        for _ in range(300 if outward > 0.0 else 20):
            x2, _, _ = barker_axes(q)
            before = q[2] - straight
            step = controller.step(q, twist_for(robot, q, 0.05 * outward * x2))
            assert np.isfinite(step.q).all()
            assert (step.q[2] - straight) * before >= 0.0  # never past full extension in one step
            q = step.q
        bends.append(q[2] - straight)
    out_bends, in_bends = bends[0::2], bends[1::2]
    assert all(bend == 0.0 for bend in out_bends)  # stopped exactly at full extension, held there
    signs = [math.copysign(1.0, bend) for bend in in_bends]
    assert all(abs(bend) > 0.1 for bend in in_bends)
    assert signs[0] == -1.0 and signs == [-1.0, 1.0, -1.0]  # from +0.03, each retraction bends the other way


def test_ur5_retracts_the_hand_toward_the_shoulder_at_full_extension() -> None:
    robot = pinrate.load("ur5")
    controller = Controller(robot, singularity="auxiliary_elbow")
    elbow = controller.elbow
    assert (elbow.joint, elbow.shoulder) == ("elbow_joint", "shoulder_lift_joint")
    assert elbow.straight == pytest.approx(0.0, abs=1e-12)
    q = robot.home()
    q[1:3] = -0.8, 0.0  # the upper arm reaching forward and up, the arm straight
    data = robot.model.createData()

    def shoulder_and_wrist(q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        pin.forwardKinematics(robot.model, data, q)
        shoulder = data.oMi[robot.joint_id("shoulder_lift_joint")].translation
        wrist = data.oMi[robot.joint_id("wrist_1_joint")].translation
        return np.array(shoulder), np.array(wrist)

    shoulder, wrist = shoulder_and_wrist(q)
    inward = (shoulder - wrist) / np.linalg.norm(shoulder - wrist)
    tool = robot.frame_pose(q, robot.sensor)[:3, :3]
    start = q.copy()

    def retract(controller: Controller, q: np.ndarray) -> np.ndarray:
        """The wrist centre's displacement after 1 s of a 0.05 m/s command toward the shoulder."""
        _, wrist = shoulder_and_wrist(q)
        for _ in range(100):
            step = controller.step(q, np.concatenate([tool.T @ (0.05 * inward), np.zeros(3)]))
            assert np.isfinite(step.q).all()
            q = step.q
        return shoulder_and_wrist(q)[1] - wrist

    moved = retract(controller, start)
    # Toward the shoulder, on the line (eq. 46 cancels the elbow's motion across it) ...
    assert moved @ inward > 0.02
    assert np.linalg.norm(moved - (moved @ inward) * inward) < 0.05 * (moved @ inward)
    # ... where the default strategy (decelerate, on the generalized inverse) cuts the lost direction.
    assert retract(Controller(robot), start) @ inward < 0.1 * (moved @ inward)


def test_arms_without_an_elbow_singularity_solve_by_the_generalized_inverse() -> None:
    robot = pinrate.load("xarm7")
    controller = Controller(robot, singularity="auxiliary_elbow")
    assert controller.elbow is None
    reference = Controller(robot, singularity="generalized_inverse")  # Barker's eq. 38, which eq. 45-46 supplement
    rng = np.random.default_rng(2)
    for q in robot.sample_configurations(5, 3):
        twist = rng.normal(size=6) * 0.1
        np.testing.assert_array_equal(controller.step(q, twist).joint_rates, reference.step(q, twist).joint_rates)


def test_the_default_region_is_the_elbows_singular_region() -> None:
    robot = pinrate.load("ur5")
    controller = Controller(robot, singularity="auxiliary_elbow")
    q = robot.home()
    for factor, inside in ((0.999, True), (1.001, False)):
        q[2] = controller.elbow.straight + math.copysign(controller.elbow_region, q[2]) * factor
        assert (controller.conditioning(q).value < controller.slow_threshold) is inside
    assert Controller(robot, singularity="auxiliary_elbow", elbow_region=0.05).elbow_region == 0.05
    with pytest.raises(InputError, match="elbow_region"):
        Controller(robot, singularity="auxiliary_elbow", elbow_region=-0.1)


def test_the_wrist_rule_applies_inside_the_elbow_region() -> None:
    robot = pinrate.load("ur5")
    q = robot.home()
    q[1:3] = -0.8, 0.1  # in the elbow's region
    q[4] = 0.04  # wrist_2 near 0: wrist_1 and wrist_3 nearly aligned
    step = Controller(robot, singularity="auxiliary_elbow").step(q, np.array([0.0, 0.0, 0.0, 0.2, 0.0, 0.0]))
    assert Status.AUXILIARY_ELBOW in step.conditions and Status.WRIST_SINGULARITY in step.conditions
    assert "wrist_1_joint and wrist_3_joint" in step.detail
    assert np.abs(step.joint_rates).max() < 0.5  # the aligned pair shares the rotation, no spike


def test_a_jog_to_full_extension_also_turns_the_next_bend_and_reset_restores_it() -> None:
    robot = pinrate.robots.barker_arm()
    controller = Controller(robot, singularity="auxiliary_elbow", velocity_limits=np.inf)
    straight = controller.elbow.straight
    q = barker_at_extension(0.2, 0.5)
    q[2] = straight + 0.03
    while q[2] - straight > 0.0:  # jog the elbow straight
        q = controller.step(q, JointJog({"theta3": -(q[2] - straight) / controller.dt})).q
    assert q[2] == straight
    x2, _, _ = barker_axes(q)
    retract = twist_for(robot, q, -0.05 * x2)
    assert controller.step(q, retract).joint_rates[2] < 0.0  # it came from +: it bends to -
    controller.reset()
    home_side = math.copysign(1.0, robot.home()[2] - straight)
    assert math.copysign(1.0, controller.step(q, retract).joint_rates[2]) == home_side


def barker_wrist_centre(q: np.ndarray, parameters: dict[str, float]) -> np.ndarray:
    """The wrist centre in base axes (m), A3 = R3 = 0, α3 = 90°: (C1 F1 - S1 F2, S1 F1 + C1 F2,
    NO + F3) with F1 .. F5 of eq. 27-31 — the position whose derivative is eq. 26's M (d/dθ2
    of F1 is F3, of F3 is -F1; d/dθ3 of F5 is F4, of F4 is -F5)."""
    no, es, sn, we = (parameters[name] for name in ("no", "es", "sn", "we"))
    f1 = math.sin(q[1]) * es + math.sin(q[1] + q[2]) * we
    f3 = math.cos(q[1]) * es + math.cos(q[1] + q[2]) * we
    c1, s1 = math.cos(q[0]), math.sin(q[0])
    return np.array([c1 * f1 - s1 * sn, s1 * f1 + c1 * sn, no + f3])


def barker_m(q: np.ndarray, parameters: dict[str, float]) -> np.ndarray:
    """Eq. 26 with A3 = R3 = 0, α3 = 90° (F2 = SN, F4 = C23 WE, F5 = S23 WE): TVEL^ = M θ̇_1..3."""
    es, sn, we = (parameters[name] for name in ("es", "sn", "we"))
    c1, s1 = math.cos(q[0]), math.sin(q[0])
    f4, f5 = math.cos(q[1] + q[2]) * we, math.sin(q[1] + q[2]) * we
    f1, f3 = math.sin(q[1]) * es + f5, math.cos(q[1]) * es + f4
    return np.array([[-s1 * f1 - c1 * sn, c1 * f3, c1 * f4], [c1 * f1 - s1 * sn, s1 * f3, s1 * f4], [0.0, -f1, -f5]])


def test_barker_fig3_down_command_is_executed_and_each_step_says_how() -> None:
    """Barker's Fig. 3 pose (every θ 0: the arm straight up, at full extension θ3 = 0 and at
    the minimum radius of eq. 32) and 1 s of 0.05 m/s "down" in the hand's axes: a command
    toward the shoulder, feasible by bending the elbow. The elbow control acts only while
    eq. 38 cuts the elbow's direction; then eq. 38 carries the hand down the line to the
    shoulder, which is the minimum-radius line, where "decelerate" halts (issue 24: it halted
    after 20.4 mm)."""
    robot = pinrate.robots.barker_arm()
    parameters = pinrate.robots.parameters("barker_arm")
    controller = Controller(robot, singularity="auxiliary_elbow", velocity_limits=np.inf)
    q = np.zeros(6)
    np.testing.assert_allclose(robot.frame_pose(q, "hand")[:3, :3], np.eye(3), atol=1e-12)  # hand axes = base axes
    np.testing.assert_allclose(barker_wrist_centre(q, parameters), robot.frame_pose(q, robot.tip)[:3, 3], atol=1e-12)
    speed, dt, steps = 0.05, controller.dt, 100
    down = np.array([0.0, 0.0, -speed])
    twist = np.concatenate([down, np.zeros(3)])
    # At Fig. 3 eq. 38 cannot make it: M*'s rates (rcond = the controller's cut) move the hand
    # nowhere down, since the elbow's direction is M's null direction there.
    assert (barker_m(q, parameters) @ np.linalg.pinv(barker_m(q, parameters), rcond=0.005) @ down)[2] == 0.0
    start = barker_wrist_centre(q, parameters)
    elbow_steps = []
    for k in range(steps):
        step = controller.step(q, twist)
        made = robot.jacobian(q)[:6] @ step.joint_rates  # the twist these rates make at q, hand axes
        missed = float(np.linalg.norm(made - twist)) / speed
        # Honest: a step that does not make the command says the elbow control took it;
        # one that makes it (to the rounding of REACH_TOLERANCE, 1e-6) is eq. 38's, said
        # near the minimum-radius singularity (c of J about 1e-6 all the way).
        if missed > 1e-6:
            assert step.status is Status.AUXILIARY_ELBOW, (k, step.detail)
            elbow_steps.append(k)
        else:
            assert step.status is Status.NEAR_SINGULARITY, (k, step.status, step.detail)
        q = step.q
        if k == 1:
            handover = q.copy()
    # The elbow control acts from full extension until eq. 38 no longer cuts the elbow's
    # direction: its first two steps (θ3 = 0, then 1.7e-2 rad).
    assert elbow_steps == [0, 1]
    moved = barker_wrist_centre(q, parameters) - start
    # Straight down: the elbow control keeps the hand on the line to the shoulder, eq. 38 on its command.
    assert np.linalg.norm(moved[:2]) < 1e-6
    # Each elbow-control step moves the hand down by 0 to v dt (it retracts at v sin β / sin β_r
    # <= v): the travel is v T to within those two steps' v dt, 1 mm.
    assert abs(-moved[2] - speed * dt * steps) <= 2 * speed * dt
    # After the hand-over, the steps are eq. 38: M* (numpy's pinv, the cut 0.005) integrated by
    # eq. 21 from the same pose reaches the same height. Both make the command to first order
    # in every step; their joint paths differ by M's null motion (θ1 with θ2 at the minimum
    # radius), which moves the wrist centre only sideways: 1e-6 m bounds the rest.
    theta = handover[:3].copy()
    for _ in range(steps - 2):
        theta = theta + dt * np.linalg.pinv(barker_m(theta, parameters), rcond=0.005) @ down
    eq38 = barker_wrist_centre(np.concatenate([theta, np.zeros(3)]), parameters)
    assert eq38[2] == pytest.approx(start[2] + moved[2], abs=1e-6)
