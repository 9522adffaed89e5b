"""The closed-loop servo: sensor commands from the pose error, integration on the manifold."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

import pinrate
from pinrate import Partition, Status
from pinrate.control import servo_loop
from pinrate.kinematics.targets import nearby_target


def rotation_angle(a: np.ndarray, b: np.ndarray) -> float:
    """Angle of the rotation between two rotation matrices, from the trace."""
    return math.acos(max(-1.0, min(1.0, (np.trace(a.T @ b) - 1) / 2)))


@pytest.mark.parametrize("algorithm", ["exact", "dls", "mca1", "mca2", "mca3", "schur"])
def test_ur5_reaches_a_target(ur5: pinrate.Robot, algorithm: str) -> None:
    _, target = nearby_target(ur5, Partition.auto(ur5), seed=4)
    trajectory = pinrate.servo(ur5, ur5.home(), target, algorithm=algorithm)
    assert trajectory.converged, trajectory.reason
    final = ur5.pose(trajectory.q[-1])
    assert np.linalg.norm(final[:3, 3] - target[:3, 3]) < 1e-4
    assert rotation_angle(final[:3, :3], target[:3, :3]) < 1e-4
    n = trajectory.q.shape[0]
    assert trajectory.position_error.shape == trajectory.orientation_error.shape == (n,)
    assert trajectory.spectral_radius.shape == (n,) and len(trajectory.status) == n
    assert trajectory.joint_rates.shape == (n - 1, ur5.nv)
    np.testing.assert_array_equal(trajectory.q[0], ur5.home())


def test_errors_are_measured_at_each_q(ur5: pinrate.Robot) -> None:
    _, target = nearby_target(ur5, Partition.auto(ur5), seed=1)
    trajectory = pinrate.servo(ur5, ur5.home(), target, max_steps=30)
    for i in (0, 10, 30):
        pose = ur5.pose(trajectory.q[i])
        assert trajectory.position_error[i] == pytest.approx(np.linalg.norm(pose[:3, 3] - target[:3, 3]))
        assert trajectory.orientation_error[i] == pytest.approx(rotation_angle(pose[:3, :3], target[:3, :3]), abs=1e-9)
        assert trajectory.spectral_radius[i] == pytest.approx(pinrate.convergence(ur5, trajectory.q[i]).spectral_radius)
    assert not trajectory.converged and trajectory.reason.startswith("max_steps")


def test_se3_target_is_accepted(ur5: pinrate.Robot) -> None:
    _, target = nearby_target(ur5, Partition.auto(ur5), seed=2)
    as_matrix = pinrate.servo(ur5, ur5.home(), target, max_steps=50)
    as_se3 = pinrate.servo(ur5, ur5.home(), pin.SE3(target), max_steps=50)
    np.testing.assert_allclose(as_matrix.q, as_se3.q)


def polar_pose(robot: pinrate.Robot, theta1: float, d2: float, theta3: float) -> np.ndarray:
    return robot.pose(np.array([theta1, d2, theta3]))


@pytest.mark.parametrize("algorithm", ["mca1", "mca2", "mca3"])
def test_polar_with_d2_over_l_above_two_converges(algorithm: str) -> None:
    # Eq. 58: with d2 / l > 2 everywhere, |G| < 1 everywhere and every MCA converges.
    robot = pinrate.robots.planar_polar(l=0.2)
    q0 = np.array([0.0, 0.6, 2.2])
    target = polar_pose(robot, 0.6, 0.45, 3.0)
    trajectory = pinrate.servo(robot, q0, target, algorithm=algorithm)
    assert trajectory.converged, trajectory.reason
    assert (trajectory.q[:, 1] > 2 * 0.2).all()
    assert (trajectory.spectral_radius < 1).all()
    np.testing.assert_allclose(robot.pose(trajectory.q[-1])[:2, 3], target[:2, 3], atol=1e-4)


def test_polar_outside_eq_58_diverges_with_a_dead_beat_sensor() -> None:
    # |G| > 1 and the sensor commanding the whole error each sample (gain dt = 1, eq. 40
    # with beta = 1): the orientation error of MCA1 is multiplied by G each step.
    robot = pinrate.robots.planar_polar(l=0.2)
    q0 = np.array([0.0, 0.12, 2.9])
    assert pinrate.convergence(robot, q0).spectral_radius > 1
    target = polar_pose(robot, 0.0, 0.12, 2.95)
    trajectory = pinrate.servo(
        robot,
        q0,
        target,
        algorithm="mca1",
        dt=0.01,
        gain=100.0,
        max_linear_speed=math.inf,
        max_angular_speed=math.inf,
        max_steps=200,
    )
    assert not trajectory.converged
    assert trajectory.reason.startswith("diverging")
    assert trajectory.status[-1] == "diverging"


def test_a_joint_limit_holds_the_joint_and_the_run_stalls_there() -> None:
    robot = pinrate.robots.planar_polar(l=0.2)
    q0 = np.array([0.0, 0.6, 0.3])
    # d2 = 1.3 lies past the 1.0 upper limit: the prismatic joint runs into it and is held
    # there (issue 11: a limit no longer ends the run); the others cannot reach the target.
    target = polar_pose(robot, 0.0, 1.3, 0.3)
    trajectory = pinrate.servo(robot, q0, target, algorithm="exact")
    assert not trajectory.converged
    assert trajectory.reason.startswith("stalled")
    assert trajectory.q[:, 1].max() == pytest.approx(1.0) and trajectory.q[:, 1].max() <= 1.0
    assert Status.JOINT_LIMIT.word in trajectory.status
    assert trajectory.position_error.shape == (trajectory.q.shape[0],)


def test_a_run_leaves_a_singular_start_and_halts_before_a_singular_end() -> None:
    robot = pinrate.robots.two_link_planar()
    position_only = Partition(["theta1", "theta2"], [], linear="xy", angular="")
    # From the stretched arm (A singular) towards a reachable target: the generalized inverse's
    # step raises A's conditioning, so decelerate executes it and the run converges.
    target = robot.pose(np.array([0.5, 1.0]))
    trajectory = pinrate.servo(robot, np.array([0.0, 0.0]), target, partition=position_only)
    assert trajectory.spectral_radius[0] == math.inf
    assert trajectory.converged, trajectory.reason
    # Towards a target beyond reach: the arm stretches, and halts before A is singular.
    far = np.eye(4)
    far[:3, 3] = [5.0, 1.0, 0.0]
    trajectory = pinrate.servo(robot, np.array([0.3, 0.8]), far, partition=position_only, max_steps=10**6)
    assert trajectory.reason.startswith("singular") and not trajectory.converged
    controller = pinrate.Controller(robot, partition=position_only, algorithm="mca1")
    last = controller.conditioning(trajectory.q[-1])
    # The servo's steps are big (0.5 m/s x 0.01 s): it halts where the next one would have
    # taken A under singular_threshold, here from about c = 0.03.
    assert controller.singular_threshold <= last.value < 2 * controller.slow_threshold
    assert last.block == "A" and "halted" in trajectory.reason


def test_speed_saturation(ur5: pinrate.Robot) -> None:
    _, target = nearby_target(ur5, Partition.auto(ur5), seed=3)
    trajectory = pinrate.servo(
        ur5,
        ur5.home(),
        target,
        algorithm="exact",
        max_steps=5,
        gain=50.0,
        max_linear_speed=0.1,
        max_angular_speed=10.0,
    )
    assert trajectory.status[0] == Status.TWIST_SATURATED.word
    # Exact rates realise the commanded twist: the TCP moves at most 0.1 m/s * dt per step.
    steps = np.linalg.norm(np.diff([ur5.pose(q)[:3, 3] for q in trajectory.q], axis=0), axis=1)
    assert steps.max() <= 0.1 * 0.01 * 1.01


@pytest.mark.parametrize(
    ("target", "match"),
    [
        (np.eye(3), "4x4"),
        (np.full((4, 4), np.nan), "NaN"),
        (np.diag([1.0, 1.0, 2.0, 1.0]), "rotation"),
        ("home", "4x4"),
    ],
)
def test_bad_targets(ur5: pinrate.Robot, target: object, match: str) -> None:
    with pytest.raises(pinrate.InputError, match=match):
        pinrate.servo(ur5, ur5.home(), target)


@pytest.mark.parametrize(
    ("keyword", "value"),
    [
        ("dt", 0.0),
        ("dt", math.inf),
        ("gain", -1.0),
        ("tol", math.nan),
        ("max_steps", -1),
        ("gain", True),
        ("max_linear_speed", 0.0),
        ("tol", 1e-13),
        ("gain", 1e300),
        ("dt", 1e7),
        ("max_steps", 2.5),
        ("stall_time", 0.0),
    ],
)
def test_bad_settings(ur5: pinrate.Robot, keyword: str, value: float) -> None:
    with pytest.raises(pinrate.InputError, match=keyword):
        pinrate.servo(ur5, ur5.home(), ur5.pose(ur5.home()), **{keyword: value})


@pytest.mark.parametrize("position", [1e7, 1e305, -1e308])
def test_targets_beyond_the_physical_bound_are_refused(ur5: pinrate.Robot, position: float) -> None:
    target = np.eye(4)
    target[0, 3] = position
    with pytest.raises(pinrate.InputError, match="physical bound"):
        pinrate.servo(ur5, ur5.home(), target)


TWO_LINK_CONTINUOUS = """<robot name="reach_two"><link name="a"/><link name="b"/><link name="c"/><link name="tip"/>
<joint name="shoulder" type="continuous"><parent link="a"/><child link="b"/><axis xyz="0 0 1"/></joint>
<joint name="elbow" type="continuous"><parent link="b"/><child link="c"/><origin xyz="1 0 0"/>
<axis xyz="0 0 1"/></joint>
<joint name="tool" type="fixed"><parent link="c"/><child link="tip"/><origin xyz="1 0 0"/></joint></robot>"""


@pytest.mark.parametrize(("algorithm", "stall_time"), [("exact", None), ("dls", 0.5), ("exact", 2.0)])
def test_an_unreachable_target_stalls_whatever_max_steps(tmp_path, algorithm: str, stall_time: float | None) -> None:
    # Continuous joints have no limit to stop at: the arm (reach 2 m) stretches towards a
    # target 5 m away and stays there. Before the stall rule, max_steps=10**12 ran for ever;
    # now the stall rule ends it well before the largest budget servo takes.
    path = tmp_path / "reach_two.urdf"
    path.write_text(TWO_LINK_CONTINUOUS, encoding="utf-8")
    robot = pinrate.load(path)
    partition = Partition(("shoulder", "elbow"), (), linear="xy", angular="")
    q0 = np.array([math.cos(0.3), math.sin(0.3), math.cos(0.8), math.sin(0.8)])
    target = np.eye(4)
    target[:3, 3] = [5.0, 0.0, 0.0]
    gain, dt = 1.0, 0.01
    # The generalized inverse lets the arm stretch on (decelerate would halt it, the test above).
    trajectory = pinrate.servo(
        robot,
        q0,
        target,
        algorithm=algorithm,
        partition=partition,
        max_steps=servo_loop.MAX_STEPS,
        stall_time=stall_time,
        singularity="generalized_inverse",
    )
    assert trajectory.status[-1] == "stalled" and trajectory.reason.startswith("stalled")
    window = round((max(1.0, 5.0 / gain) if stall_time is None else stall_time) / dt)
    error = trajectory.position_error + trajectory.orientation_error
    # The documented rule, replayed on the record: progress is a 1 % fall below the error at
    # the last progress; the run stops the first time a whole window passes without any.
    anchor, anchor_step = math.inf, 0
    for step, value in enumerate(error):
        if value < 0.99 * anchor:
            anchor, anchor_step = value, step
        elif step - anchor_step >= window:
            break
    assert step == len(error) - 1 and step - anchor_step == window
    assert np.linalg.norm(robot.pose(trajectory.q[-1])[:2, 3]) > 1.75  # stretched towards the target


def test_a_tiny_dt_stalls_after_the_step_cap(monkeypatch: pytest.MonkeyPatch) -> None:
    # dt = 1e-9: one second of simulated time would be 1e9 steps; the window is capped.
    monkeypatch.setattr(servo_loop, "STALL_MAX_STEPS", 300)
    scara = pinrate.load("scara")
    target = scara.pose(scara.home())
    target[0, 3] += 0.3
    trajectory = pinrate.servo(scara, scara.home(), target, dt=1e-9, max_steps=servo_loop.MAX_STEPS)
    assert trajectory.status[-1] == "stalled" and trajectory.steps == 300


def test_max_steps_is_bounded_as_documented(ur5: pinrate.Robot) -> None:
    # A run records every step (285-430 bytes on a 6-joint arm): with gain=2e-5 the error was
    # still improving by 1 % a window after 3 million steps, at 942 MB. The budget is capped.
    _, target = nearby_target(ur5, Partition.auto(ur5), 0)
    with pytest.raises(pinrate.InputError, match=r"max_steps must be at most 1,000,000 .*got 1,000,001$"):
        pinrate.servo(ur5, ur5.home(), target, max_steps=1_000_001)
    assert servo_loop.MAX_STEPS == 1_000_000


def test_bad_q0(ur5: pinrate.Robot) -> None:
    with pytest.raises(pinrate.InputError, match="q"):
        pinrate.servo(ur5, np.zeros(3), np.eye(4))


@pytest.mark.parametrize("seed", range(5))
def test_pose_error_is_the_definition_in_sensor_axes(seed: int) -> None:
    from pinrate.kinematics.spatial import pose_error

    rng = np.random.default_rng(seed)
    tip, sensor, target = (pin.SE3(pin.exp3(rng.normal(size=3)), rng.normal(size=3)) for _ in range(3))
    error = pose_error(tip, sensor, target)
    R_s = sensor.rotation
    np.testing.assert_allclose(error[:3], R_s.T @ (target.translation - tip.translation), atol=1e-12)
    np.testing.assert_allclose(error[3:], R_s.T @ pin.log3(target.rotation @ tip.rotation.T), atol=1e-9)
    # Sensor at the tip: the same definition with R_s = R_tip.
    at_tip = pose_error(tip, tip, target)
    R_tip = tip.rotation
    np.testing.assert_allclose(at_tip[:3], R_tip.T @ (target.translation - tip.translation), atol=1e-12)
    np.testing.assert_allclose(at_tip[3:], tip.rotation.T @ pin.log3(target.rotation @ tip.rotation.T), atol=1e-9)


def test_servo_takes_every_controller_option(ur5: pinrate.Robot) -> None:
    # Each option reaches the Controller the servo runs: checked on what the option does, not
    # on the controller object. collision=True: a drive into the UR5's own base halts before
    # contact ("collision"), where the same run without it goes on.
    import inspect

    from pinrate.control.servo_loop import CONTROLLER_OPTIONS

    assert set(CONTROLLER_OPTIONS) == set(inspect.signature(pinrate.Controller).parameters) - {"robot"}
    q0 = ur5.home()
    target = ur5.pose(q0)
    target[:3, 3] = [0.0, 0.0, 0.05]  # inside the base
    monitored = pinrate.servo(ur5, q0, target, collision=True, max_steps=3000)
    assert monitored.reason.startswith("collision")
    plain = pinrate.servo(ur5, q0, target, max_steps=3000)
    assert not plain.reason.startswith("collision")
    # acceleration limits: the first step's rates are at most a * dt
    limited = pinrate.servo(ur5, q0, target, acceleration_limits=1.0, max_steps=5)
    first = np.abs(np.diff(limited.q[:2], axis=0)[0]) / 0.01
    assert first.max() <= 1.0 * 0.01 + 1e-12


def test_servo_with_a_controller_and_bad_options(ur5: pinrate.Robot) -> None:
    controller = pinrate.Controller(ur5, algorithm="mca2", dt=0.02, velocity_limits=math.inf)
    q0 = ur5.home()
    target = ur5.pose(q0)
    target[:3, 3] += [0.05, 0.0, 0.0]
    given = pinrate.servo(ur5, q0, target, controller=controller)
    built = pinrate.servo(ur5, q0, target, algorithm="mca2", dt=0.02)
    np.testing.assert_array_equal(given.q, built.q)
    with pytest.raises(pinrate.InputError, match="drop algorithm"):
        pinrate.servo(ur5, q0, target, controller=controller, algorithm="exact")
    # an option equal to servo's own default is refused too, never silently replaced
    with pytest.raises(pinrate.InputError, match="drop algorithm, singularity"):
        pinrate.servo(ur5, q0, target, controller=controller, algorithm="mca1", singularity="decelerate")
    with pytest.raises(pinrate.InputError, match="drop collision"):
        pinrate.servo(ur5, q0, target, controller=controller, collision=True)
    with pytest.raises(pinrate.InputError, match="another Robot"):
        pinrate.servo(pinrate.load("ur5"), q0, target, controller=controller)
    with pytest.raises(pinrate.InputError, match=r"no option 'colision'.*collision"):
        pinrate.servo(ur5, q0, target, colision=True)


def test_a_controller_subclass_with_its_own_step_is_servoed_by_that_step(ur5: pinrate.Robot) -> None:
    # The compiled loop knows only Controller.step: a subclass that steps its own way (here it
    # never moves) must be run by Python, whichever backend is chosen.
    class Still(pinrate.Controller):
        def step(self, q, command, *, observation=None):  # type: ignore[no-untyped-def]
            step = super().step(q, command, observation=observation)
            step.q, step.joint_rates = np.array(q, dtype=float), np.zeros_like(step.joint_rates)
            return step

    q0 = ur5.home()
    target = ur5.pose(q0)
    target[:3, 3] += [0.05, 0.0, 0.0]
    still = Still(ur5, algorithm="mca1", velocity_limits=math.inf)
    assert "steps its own way" in still.compiled_reason() and still.compiled() is None
    run = pinrate.servo(ur5, q0, target, controller=still)
    assert not run.converged and np.array_equal(run.q[-1], q0)


@pytest.mark.parametrize("gain", [1e-300, 5e-324])
def test_a_tiny_gain_is_not_an_error_of_the_stall_time_nobody_gave(ur5: pinrate.Robot, gain: float) -> None:
    # The default window, 5 / gain seconds, is past stall_time's bound (or inf): it was refused
    # as "stall_time must be ..." (or raised OverflowError); STALL_MAX_STEPS caps it.
    trajectory = pinrate.servo(ur5, ur5.home(), ur5.pose(ur5.random_configuration(0)), gain=gain, max_steps=50)
    assert not trajectory.converged and trajectory.reason.startswith("max_steps")


@pytest.mark.parametrize("algorithm", ["exact", "schur", "dls", "mca1"])
@pytest.mark.parametrize("seed", [1, 2, 3])
def test_a_five_dof_arm_reaches_a_reachable_pose(algorithm: str, seed: int) -> None:
    """A yaw-pitch-pitch-pitch-roll arm (6 rows, 5 joints, position first for exact, schur and
    dls): a pose it can reach (forward kinematics of a nearby q) is reached in position and
    orientation, each within the servo's tol of 1e-4 (m, rad). The trajectory keeps each
    step's words: on the way, the pose error's rotation is not all the arm's to make."""
    robot = pinrate.load(Path(__file__).parent.parent / "data" / "five_dof_arm.urdf")
    _, target = nearby_target(robot, Partition.auto(robot), seed=seed)
    trajectory = pinrate.servo(robot, robot.home(), target, algorithm=algorithm, max_steps=5000)
    assert trajectory.converged, trajectory.reason
    final = robot.pose(trajectory.q[-1])
    assert np.linalg.norm(final[:3, 3] - target[:3, 3]) < 1e-4
    assert rotation_angle(final[:3, :3], target[:3, :3]) < 1e-4
    said = "position first" if algorithm != "mca1" else "the joints cannot make"
    assert any(said in detail for detail in trajectory.detail)
