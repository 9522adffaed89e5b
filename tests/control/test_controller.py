"""Controller.step: the one step under the servo, checked against independent computations."""

from __future__ import annotations

import warnings

import numpy as np
import pinocchio as pin
import pytest

import pinrate
import pinrate.robots.loading
from pinrate.control import Controller, PoseGoal, Status
from pinrate.control.status import SEVERITY, most_severe


@pytest.mark.parametrize("algorithm", pinrate.ALGORITHMS)
def test_a_twist_step_is_joint_rates_integrated(ur5: pinrate.Robot, algorithm: str) -> None:
    controller = Controller(ur5, algorithm=algorithm, dt=0.02, max_linear_speed=np.inf, max_angular_speed=np.inf)
    q = ur5.home()
    twist = np.array([0.05, -0.02, 0.03, 0.1, -0.05, 0.2])
    step = controller.step(q, twist)
    rates = pinrate.joint_rates(ur5, q, twist, algorithm=algorithm)
    # The step's Jacobian comes from the kinematics pass that also gives the poses
    # (computeJointJacobians), joint_rates' from computeFrameJacobian: equal to rounding.
    np.testing.assert_allclose(step.joint_rates, rates, rtol=1e-12, atol=1e-15)
    np.testing.assert_array_equal(step.q, pin.integrate(ur5.model, q, step.joint_rates * 0.02))
    assert step.status is Status.OK
    assert step.frozen == ()
    # The step's own observation: the sensor-frame Jacobian at q.
    np.testing.assert_allclose(step.observation.jacobian, ur5.jacobian(q), atol=1e-15)


def test_saturation_scales_the_whole_twist_by_one_factor(ur5: pinrate.Robot) -> None:
    """Contract v2.1: |v| = 0.5 against 0.1 asks for 0.2, |ω| = 2 against 0.2 for 0.1; the
    one factor is the smaller, 0.1, for every component: the screw keeps its direction."""
    controller = Controller(ur5, max_linear_speed=0.1, max_angular_speed=0.2)
    twist = np.array([0.3, 0.4, 0.0, 0.0, 0.0, 2.0])
    step = controller.step(ur5.home(), twist)
    assert step.status is Status.TWIST_SATURATED
    np.testing.assert_allclose(step.twist, [0.03, 0.04, 0.0, 0.0, 0.0, 0.2], rtol=1e-15)
    # Only the linear part over its limit: the angular part shrinks by the same factor.
    step = controller.step(ur5.home(), np.array([0.0, 0.0, 1.0, 0.1, 0.0, 0.0]))
    np.testing.assert_allclose(step.twist, [0.0, 0.0, 0.1, 0.01, 0.0, 0.0], rtol=1e-15)
    # Both within their limits: untouched.
    assert controller.step(ur5.home(), np.array([0.1, 0, 0, 0, 0, 0.2])).status is Status.OK


def test_a_pose_goal_commands_gain_times_the_error(ur5: pinrate.Robot) -> None:
    controller = Controller(ur5, algorithm="exact", max_linear_speed=np.inf, max_angular_speed=np.inf)
    q = ur5.home()
    target = ur5.pose(q)
    target[:3, 3] += [0.01, -0.02, 0.005]  # a pure translation, in world axes
    step = controller.step(q, PoseGoal.of(target, gain=2.0))
    tip_rotation = ur5.pose(q)[:3, :3]  # the sensor is the tip: errors in tip axes
    expected = 2.0 * np.concatenate([tip_rotation.T @ np.array([0.01, -0.02, 0.005]), np.zeros(3)])
    np.testing.assert_allclose(step.twist, expected, atol=1e-15)


def test_a_wrist_singularity_is_the_wrist_strategy_s_not_a_halt(ur5: pinrate.Robot) -> None:
    q = ur5.home()
    q[4] = 0.0  # wrist_2 = 0: W is singular; the step goes on by wrist="split" (contract v2)
    step = Controller(ur5, algorithm="mca1").step(q, np.full(6, 0.1))
    assert step.status is Status.WRIST_SINGULARITY
    assert "wrist_1_joint and wrist_3_joint" in step.detail
    assert np.isfinite(step.q).all() and np.isfinite(step.joint_rates).all()
    assert step.observation.spectral_radius == np.inf


def test_a_joint_pushed_past_its_limit_is_clamped() -> None:
    robot = pinrate.robots.hirata_arh300()
    theta2 = robot.joint_names[1]
    lower, _ = robot.joint_limits(theta2)
    q = robot.home()
    q[1] = lower + 1e-4
    controller = Controller(robot, algorithm="exact", dt=0.1)
    # The joint-space rate that drives theta2 down, as a twist: J e2 (negated).
    direction = -robot.jacobian(q)[controller.index.rows][:, 1]
    step = controller.step(q, direction)
    assert step.status is Status.JOINT_LIMIT
    assert theta2 in step.detail
    assert step.q[1] == lower


def test_bad_commands_are_input_errors(ur5: pinrate.Robot) -> None:
    controller = Controller(ur5)
    with pytest.raises(pinrate.InputError, match="twist"):
        controller.step(ur5.home(), np.ones(5))
    with pytest.raises(pinrate.InputError, match="algorithm"):
        Controller(ur5, algorithm="mca4")
    with pytest.raises(pinrate.InputError, match="dt"):
        Controller(ur5, dt=0.0)
    with pytest.raises(pinrate.InputError, match="gain"):
        PoseGoal.of(np.eye(4), gain=-1.0)


def test_statuses_rank_as_the_contract_says() -> None:
    contract = [
        Status.OK,
        Status.RATE_LIMITED,
        Status.JOINT_LIMIT,
        Status.WRIST_SINGULARITY,
        Status.DECELERATE_FOR_SINGULARITY,
        Status.AUXILIARY_ELBOW,
        Status.FROZEN,
        Status.HALT_FOR_SINGULARITY,
    ]
    ranks = [SEVERITY.index(status) for status in contract]
    assert ranks == sorted(ranks)
    assert most_severe(Status.RATE_LIMITED, Status.FROZEN, Status.OK) is Status.FROZEN
    assert most_severe() is Status.OK
    assert isinstance(Status.OK, str)


def test_the_compiled_allow_list_names_every_option_and_fails_closed(monkeypatch) -> None:
    # Every Controller option has an entry: a new option cannot be ignored by the core unseen.
    import inspect

    from pinrate.control import compiled_twin as controller_module

    assert set(controller_module.COMPILED_COVERAGE) == set(inspect.signature(pinrate.Controller).parameters)
    robot = pinrate.load("ur5")
    coverage = dict(controller_module.COMPILED_COVERAGE)
    del coverage["wrist"]
    monkeypatch.setattr(controller_module, "COMPILED_COVERAGE", coverage)
    reason = pinrate.Controller(robot).compiled_reason()
    assert reason is not None and "'wrist'" in reason
    assert pinrate.Controller(robot).compiled() is None


def test_every_strategy_is_a_module_behind_one_protocol() -> None:
    from pinrate.control import singularity

    assert tuple(singularity.RULES) == singularity.STRATEGIES
    for name, rule in singularity.RULES.items():
        assert rule.__name__ == f"pinrate.control.singularity.{name}"
        assert isinstance(rule.decelerates, bool) and callable(rule.near)


def test_an_option_changed_after_construction_is_refused() -> None:
    # Every stage copies its options at construction: a later change would act half-way.
    controller = pinrate.Controller(pinrate.load("ur5"), posture="home")
    for name, value in (("posture_gain", 5.0), ("dt", 0.02), ("slow_threshold", 0.1), ("algorithm", "mca1")):
        with pytest.raises(AttributeError, match=f"Controller.{name} is fixed"):
            setattr(controller, name, value)
    assert controller.dt == 0.01 and controller.posture.gain == 1.0


# ---------------------------------------------------------------- a command of nothing moves nothing


@pytest.mark.parametrize("name", pinrate.robots.loading.known_names())
def test_a_zero_first_step_from_home_moves_nothing(name: str) -> None:
    """Issue 24: the very first step from home with a zero twist, or with a pose goal at the
    tip's own pose, returns rates that are exactly 0 and q unchanged to the bit, on every
    catalogue robot and algorithm, with the collision monitor and every limit on."""
    robot = pinrate.load(name)
    home = robot.home()
    for algorithm in pinrate.ALGORITHMS:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # a robot without collision geometry says so
            controller = Controller(robot, algorithm=algorithm, collision=True, position_limits=True)
        for command in (np.zeros(controller.index.rows.size), PoseGoal.of(robot.pose(home))):
            step = controller.step(home, command)
            assert not step.joint_rates.any(), (algorithm, command, step.joint_rates, step.status)
            assert np.array_equal(step.q, home), (algorithm, command)
            assert step.status is Status.OK, (algorithm, command, step.status, step.detail)
