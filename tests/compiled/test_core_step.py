"""One control step, two implementations: ``Controller.step`` per call in the compiled core
(pinrate.control.core_step, Python taking the steps it hands back) against the pure-Python
stages, from the same q and command at every step.

Both paths solve from the same J (the observation's, from Pinocchio's Python binding), so
where both make the same operations after it (a closed-form kernel on square blocks of size
<= 3: :func:`same_operations`, wherever the sensor is) the steps must agree to the bit;
elsewhere within the bound of :func:`rates_tolerance`. The status, the conditions, the detail and the frozen joints must
be the same words.
"""

from __future__ import annotations

from collections.abc import Iterator

import numpy as np
import pytest

import pinrate
from compiled_core import CLOSED_FORM, ROBOTS, load, needs_core, path
from pinrate.control import core_step
from pinrate.control.controller import Controller
from pinrate.control.status import Status
from pinrate.kinematics.targets import nearby_target

pytestmark = needs_core

EPS = np.finfo(float).eps


@pytest.fixture
def taken() -> Iterator[list[bool]]:
    """Records each call of the core's step: True where it took the step, False where it
    handed it back."""
    calls: list[bool] = []
    original = core_step.CoreStep.__call__

    def counted(self: core_step.CoreStep, *arguments: object) -> pinrate.Step | bool | None:
        step = original(self, *arguments)  # type: ignore[arg-type]
        calls.append(isinstance(step, pinrate.Step))
        return step

    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(core_step.CoreStep, "__call__", counted)
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
    """Whether both paths make the same float operations from J on: a closed-form kernel on
    square blocks of size <= 3 (the exact and dls solves and the pseudo-inverses are numpy's
    LAPACK on one path, Eigen on the other)."""
    return algorithm in CLOSED_FORM and pinrate.Partition.auto(robot).resolve(robot).small


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
    controller: Controller, q: np.ndarray, python: pinrate.Step, compiled: pinrate.Step, exact: bool
) -> None:
    assert compiled.status is python.status
    assert compiled.conditions == python.conditions
    assert compiled.detail == python.detail
    assert compiled.frozen == python.frozen
    if exact:
        for field in ("q", "joint_rates", "twist"):
            np.testing.assert_array_equal(getattr(compiled, field), getattr(python, field), err_msg=field)
        return
    np.testing.assert_array_equal(compiled.twist, python.twist, err_msg="twist: the same float operations")
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
        assert_same_step(controller, q, python, compiled, exact)
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
