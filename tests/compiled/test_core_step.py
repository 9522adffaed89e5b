"""One control step, two implementations: ``Controller.step`` per call in the compiled core
(pinrate.control.core_step, Python taking the steps it hands back) against the pure-Python
stages, from the same q and command at every step.

The compiled step makes its own kinematics pass (the same Pinocchio calls on the same model
as the Python binding's), so where both paths make the same operations from q on (the sensor
at the tip, a closed-form kernel on square blocks of size <= 3: :func:`same_operations`) the
steps must agree to the bit; elsewhere within the bound of :func:`rates_tolerance` (and a
pose goal's twist within :func:`twist_tolerance`). The status, the conditions, the detail and
the frozen joints must be the same words. A caller's ``observation=`` is stepped from its own
J: there the sensor may be anywhere (:func:`test_a_callers_observation_agrees_to_the_bit`).
"""

from __future__ import annotations

from collections.abc import Iterator

import numpy as np
import pytest

import pinrate
from compiled_core import ROBOTS, bitwise, core_steps_taken, load, needs_core, path
from pinrate.control.controller import Controller
from pinrate.control.observation import Observation
from pinrate.control.status import Status
from pinrate.kinematics.targets import nearby_target

pytestmark = needs_core

EPS = np.finfo(float).eps


@pytest.fixture
def taken() -> Iterator[list[bool]]:
    """Each call of the core's per-call step: True where it took the step."""
    with core_steps_taken() as calls:
        yield calls


def teleop_twists(robot: pinrate.Robot, rng: np.random.Generator, segments: int, hold: int) -> Iterator[np.ndarray]:
    """An operator's twists: a random direction held for ``hold`` steps, ``segments`` times,
    the magnitudes from a crawl to four times the default speed limits (saturated)."""
    rows = pinrate.Partition.auto(robot).resolve(robot).rows.size
    for _ in range(segments):
        direction = rng.normal(size=rows)
        twist = direction / np.linalg.norm(direction) * rng.uniform(0.02, 4.0)
        for _ in range(hold):
            yield twist


def same_operations(robot: pinrate.Robot, algorithm: str) -> bool:
    """Whether both paths make the same float operations from q on: the sensor at the tip
    (else J and the pose error are turned into the sensor's axes by numpy's BLAS on one path,
    Eigen on the other) and a closed-form kernel on square blocks of size <= 3 (the exact and
    dls solves and the pseudo-inverses are numpy's LAPACK on one path, Eigen on the other)."""
    return bitwise(robot, algorithm)


def twist_tolerance(python: pinrate.Step, command: object) -> float:
    """How far a pose goal's twists may differ where the sensor is not at the tip: each
    component of the pose error is a 3-term dot product of a rotation row (entries <= 1) with
    a position (each path rounds it within 3 eps max|p|, |p| the tip's and the target's
    distances from the world origin, m) or, for rotation, log3 of a product of rotations
    (entries rounded within 3 eps, which log3 carries with a factor near 1 away from a half
    turn); the two paths' errors differ by twice that, the twist by gain times it. 16 covers
    the factors. 0 for a twist command (the same saturation from the same numbers)."""
    if not isinstance(command, pinrate.PoseGoal):
        return 0.0
    tip = python.observation.world_T_tip.translation
    reach = max(1.0, float(np.abs(tip).max()), float(np.abs(command.target.translation).max()))
    return 16 * EPS * command.gain * reach


def rates_tolerance(controller: Controller, q: np.ndarray, rates: np.ndarray) -> float:
    """Where the two paths solve with different operations (numpy's LAPACK and Eigen's LU or
    SVD, from the same J), both solves are
    backward stable: each rate vector is exact for a J perturbed by a few n eps relative, so
    they differ by at most about n eps kappa ||rates||. The core takes only steps whose measured
    block has sigma_r / sigma_1 >= the slow threshold (else it hands back), so kappa <= 1 / that
    conditioning; 64 covers the constants of LU, SVD and the row scaling (dls: kappa squared
    through its normal equations, bounded the same way as kappa of J J^T + lambda^2 I)."""
    kappa = 1.0 / controller.conditioning(q).value
    if controller.algorithm == "dls":
        kappa = kappa**2
    return 64 * controller.robot.nv * EPS * kappa * float(np.abs(rates).max(initial=1.0))


def assert_same_step(
    controller: Controller,
    q: np.ndarray,
    python: pinrate.Step,
    compiled: pinrate.Step,
    exact: bool,
    command: object = None,
) -> None:
    assert compiled.status is python.status
    assert compiled.conditions == python.conditions
    assert compiled.detail == python.detail
    assert compiled.frozen == python.frozen
    if exact:
        for field in ("q", "joint_rates", "twist"):
            np.testing.assert_array_equal(getattr(compiled, field), getattr(python, field), err_msg=field)
        return
    twist_atol = twist_tolerance(python, command)
    np.testing.assert_allclose(compiled.twist, python.twist, rtol=0, atol=twist_atol, err_msg="twist")
    tolerance = rates_tolerance(controller, q, python.joint_rates)
    np.testing.assert_allclose(compiled.joint_rates, python.joint_rates, rtol=0, atol=tolerance, err_msg="rates")
    # q + rates dt: the rates' difference times dt, and the integration's rounding of q
    q_tolerance = tolerance * controller.dt + 4 * EPS * float(np.abs(python.q).max())
    np.testing.assert_allclose(compiled.q, python.q, rtol=0, atol=q_tolerance, err_msg="q")


def two_paths(controller: Controller, q: np.ndarray, commands: Iterator[object], exact: bool) -> set[str]:
    """Each command stepped on both paths from the Python path's q; the words met."""
    words = set()
    for command in commands:
        with path("python"):
            python = controller.step(q, command)
        with path("compiled"):
            compiled = controller.step(q, command)
        assert_same_step(controller, q, python, compiled, exact, command)
        words.add(python.status.word)
        q = python.q
    return words


@pytest.mark.parametrize("algorithm", pinrate.ALGORITHMS)
@pytest.mark.parametrize("name", ROBOTS)
def test_teleop_twists_from_home_and_random_starts(name: str, algorithm: str, taken: list[bool]) -> None:
    """The URDF's velocity limits, position limits, decelerate near singularities."""
    robot = load(name)
    controller = Controller(robot, algorithm=algorithm, dt=0.02)
    with path("compiled"):
        assert controller.compiled() is not None, "this robot must run compiled"
    rng = np.random.default_rng(25)
    starts = [robot.home(), robot.random_configuration(rng), robot.random_configuration(rng)]
    for start in starts:
        two_paths(controller, start, teleop_twists(robot, rng, segments=8, hold=25), same_operations(robot, algorithm))
    # A twist held into a limit or the singular region makes every step Python's until it
    # turns (the SCARA and the Panda spend most of these runs there, up to 93 % of them): the
    # core must still take some, not all. (A share would be a property of the random starts.)
    assert 0 < sum(taken) < len(taken), f"the core took {sum(taken)} of {len(taken)} steps"


@pytest.mark.parametrize("algorithm", pinrate.ALGORITHMS)
@pytest.mark.parametrize("name", ROBOTS)
def test_pose_goals_per_call(name: str, algorithm: str, taken: list[bool]) -> None:
    """A user's own servo loop: Controller.step(q, PoseGoal) per call, far targets."""
    robot = load(name)
    controller = Controller(robot, algorithm=algorithm)
    partition = pinrate.Partition.auto(robot)
    for seed in range(2):
        _, target = nearby_target(robot, partition, seed, spread=0.5 + seed)
        goal = pinrate.PoseGoal.of(target, gain=2.0)
        two_paths(controller, robot.home(), iter([goal] * 150), same_operations(robot, algorithm))
    assert sum(taken) > len(taken) / 2, f"the core took only {sum(taken)} of {len(taken)} steps"


def test_limits_saturation_and_the_singular_region(taken: list[bool]) -> None:
    """Tight velocity limits and long holds: twists saturate, rates are scaled, joints reach
    their limits and the arm enters the singular region; those steps go back to Python, the
    rest stay compiled, and the two paths agree to the bit."""
    robot = pinrate.load("ur5")
    controller = Controller(robot, algorithm="mca1", velocity_limits=0.8, dt=0.05)
    rng = np.random.default_rng(7)
    words: set[str] = set()
    for _ in range(6):
        words |= two_paths(controller, robot.random_configuration(rng), teleop_twists(robot, rng, 6, 60), exact=True)
    assert {Status.RATE_LIMITED.word, Status.TWIST_SATURATED.word, Status.JOINT_LIMIT.word} <= words
    singular = (Status.DECELERATE_FOR_SINGULARITY, Status.WRIST_SINGULARITY, Status.NEAR_SINGULARITY)
    assert words & {status.word for status in singular}
    assert 0 < sum(taken) < len(taken), "both paths took steps"  # held twists: many steps at a limit


def test_the_callers_observation_is_used(taken: list[bool]) -> None:
    """observation= is honoured on the compiled path: the step is made from it (not from a
    kinematics pass of the core's own) and returned in the Step."""
    robot = pinrate.load("ur5")
    controller = Controller(robot, algorithm="mca1")
    q = robot.home()
    twist = np.array([0.05, -0.02, 0.03, 0.1, -0.05, 0.2])
    with path("compiled"):
        observation = controller.observe(q)
        step = controller.step(q, twist, observation=observation)
    assert taken == [True]
    assert step.observation is observation
    with path("python"):
        expected = controller.step(q, twist)
    np.testing.assert_array_equal(step.q, expected.q)


def test_the_callers_twist_is_not_changed() -> None:
    """The core saturates the step's own copy of the twist in place, never the caller's."""
    robot = pinrate.load("ur5")
    controller = Controller(robot)
    twist = np.array([2.0, 0.0, 0.0, 0.0, 0.0, 0.0])
    with path("compiled"):
        step = controller.step(robot.home(), twist)
    assert step.status is Status.TWIST_SATURATED
    assert twist[0] == 2.0 and step.twist[0] == controller.max_linear_speed


def test_a_callers_observation_agrees_to_the_bit(taken: list[bool]) -> None:
    """With ``observation=`` both paths step from the caller's J, so a closed-form kernel
    agrees to the bit wherever the sensor is (the Barker arm's is off the tip)."""
    robot = load("barker_arm")
    controller = Controller(robot, algorithm="mca1", dt=0.02)
    rng = np.random.default_rng(3)
    q = robot.home()
    for twist in teleop_twists(robot, rng, segments=4, hold=10):
        observation = controller.observe(q)
        with path("python"):
            python = controller.step(q, twist, observation=observation)
        with path("compiled"):
            compiled = controller.step(q, twist, observation=observation)
        assert compiled.observation is observation
        assert_same_step(controller, q, python, compiled, exact=True)
        q = python.q
    assert any(taken)


@pytest.mark.parametrize("name", ROBOTS)
def test_the_observation_of_a_compiled_step(name: str, taken: list[bool]) -> None:
    """The Step's observation, made from the core's kinematics pass when read, is the one
    Controller.observe makes at q: to the bit where both make the same Pinocchio calls (the
    sensor at the tip), else within the rounding of turning J into the sensor's axes (a
    3-term dot product of entries <= 1 with J's, 3 eps max|J| per path; 8 eps covers both)."""
    robot = load(name)
    controller = Controller(robot, algorithm="mca1")
    q = robot.home()
    twist = np.full(controller.index.rows.size, 0.01)
    with path("compiled"):
        step = controller.step(q, twist)
    assert taken == [True]
    seen, expected = step.observation, controller.observe(q)
    assert isinstance(seen, Observation)
    assert seen.q is q and seen.goal is None and seen.error is None
    assert (seen.algorithm, seen.index) == (expected.algorithm, expected.index)
    at_tip = robot.sensor_id == robot.tip_id
    atol = 0.0 if at_tip else 8 * EPS * float(np.abs(expected.jacobian).max())
    np.testing.assert_allclose(seen.jacobian, expected.jacobian, rtol=0, atol=atol)
    for pose in ("world_T_tip", "world_T_sensor"):
        np.testing.assert_array_equal(getattr(seen, pose).homogeneous, getattr(expected, pose).homogeneous)
    assert (seen.world_T_sensor is seen.world_T_tip) == at_tip
    if at_tip:
        assert seen.spectral_radius == expected.spectral_radius
    with pytest.raises(AttributeError, match="no_such_field"):
        seen.no_such_field  # noqa: B018


def refusals(robot: pinrate.Robot, controller: Controller) -> Iterator[tuple[str, object, object]]:
    """(what, q, command) a step refuses: q outside a limit, non-finite or beyond the bound,
    a wrong length; the twist non-finite, beyond the bound, of the wrong length."""
    q, twist = robot.home(), np.full(controller.index.rows.size, 0.01)
    limit = controller.joint_limits[1]
    outside = q.copy()
    outside[limit.q_index] = limit.upper + 0.1
    yield "q outside a limit", outside, twist
    for value in (np.nan, np.inf, 2e6):
        bad = q.copy()
        bad[2] = value
        yield f"q[2] = {value}", bad, twist
        yield f"twist[1] = {value}", q, np.concatenate([twist[:1], [value], twist[2:]])
    yield "q too short", q[:-1], twist
    yield "twist too long", q, np.append(twist, 0.0)
    yield "twist of ints", q, np.ones(twist.size, dtype=int) * 10**7
    yield "a 2-D twist", q, twist[None, :]


@pytest.mark.parametrize("name", ["ur5", "kinova"])
def test_refused_inputs_raise_pythons_words(name: str, taken: list[bool]) -> None:
    """What the checks refuse before a step raises the same InputError, word for word, on both
    paths (the core hands such a step to Python's checks), and the core takes none of it."""
    robot = load(name)
    controller = Controller(robot)
    cases = list(refusals(robot, controller))
    if name == "kinova":  # continuous joints: a (cos, sin) pair off unit norm
        q = robot.home()
        continuous = next(joint for joint in robot.model.joints[1:] if joint.nq == 2)
        q[continuous.idx_q : continuous.idx_q + 2] *= 1.1  # norm 1.1
        cases.append(("a (cos, sin) pair off unit norm", q, np.full(controller.index.rows.size, 0.01)))
    for what, q, command in cases:
        messages = []
        for choice in ("python", "compiled"):
            with path(choice), pytest.raises(pinrate.InputError) as refused:
                controller.step(q, command)
            messages.append(str(refused.value))
        assert messages[0] == messages[1], what
    assert not any(taken)


def test_inputs_the_core_does_not_read_are_checked_then_stepped(taken: list[bool]) -> None:
    """A q or twist given as a list (or of ints) goes through Python's checks, which convert
    it, and the step is then the core's, equal to the Python path's; a joint jog is Python's."""
    robot = pinrate.load("ur5")
    controller = Controller(robot, algorithm="mca1")
    q, twist = robot.home(), np.array([0.05, -0.02, 0.03, 0.1, -0.05, 0.2])
    with path("python"):
        expected = controller.step(q, twist)
    for given_q, given_twist in ((q.tolist(), twist), (q, twist.tolist()), (q, (twist * 0).astype(int))):
        with path("compiled"):
            step = controller.step(given_q, given_twist)
        if np.any(given_twist):
            np.testing.assert_array_equal(step.q, expected.q)
    assert taken == [False, True] * 3  # the call that could not read them, then the checked one
    taken.clear()
    with path("compiled"):
        jogged = controller.step(q, pinrate.JointJog({"shoulder_pan_joint": 0.1}))
    assert jogged.joint_rates[0] == 0.1 and taken == [False]  # Python's joint-space stage
