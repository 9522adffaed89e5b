"""One behaviour, two implementations: the compiled servo loop (pinrate_core, with Python
taking the steps it hands back) against the pure-Python loop.

Where both make the same Pinocchio calls and the same float operations (the sensor at the
tip, a closed-form block kernel) the runs must agree to the bit; where the Python side
goes through numpy's BLAS or LAPACK (the exact and dls solves, a sensor elsewhere on the
arm), to 1e-12. The statuses, the details and the reason must be the same words.
"""

from __future__ import annotations

import gc
import math
import signal
import subprocess
import sys
import time
import weakref
from collections.abc import Iterator
from concurrent.futures import ThreadPoolExecutor

import numpy as np
import pytest

import pinrate
from compiled_core import ROBOTS, bitwise, load, needs_core, path
from pinrate.control.controller import Controller
from pinrate.control.servo_run import DIVERGENCE_FACTOR, STALL_IMPROVEMENT, ServoLog
from pinrate.control.singularity import STRATEGIES
from pinrate.control.status import Status
from pinrate.kinematics.targets import nearby_target
from pinrate.theorem import spectral_radius_at
from support import DATA, spectral_radius_tolerance

pytestmark = needs_core

REFERENCE = np.load(DATA / "servo_reference.npz")
REFERENCE_RUNS = sorted({key.split("/")[0] for key in REFERENCE.files})


@pytest.fixture
def python_steps(monkeypatch: pytest.MonkeyPatch) -> Iterator[list[int]]:
    """Counts Controller.step calls: on the compiled path, the steps handed back."""
    calls: list[int] = []
    step = Controller.step

    def counted(self: Controller, *arguments: object, **keywords: object) -> pinrate.Step:
        calls.append(1)
        return step(self, *arguments, **keywords)

    monkeypatch.setattr(Controller, "step", counted)
    yield calls


def both(robot: pinrate.Robot, *arguments: object, **keywords: object) -> tuple[pinrate.Trajectory, ...]:
    runs = []
    for choice in ("python", "compiled"):
        with path(choice):
            runs.append(pinrate.servo(robot, *arguments, **keywords))
    return tuple(runs)


def assert_same(
    robot: pinrate.Robot, python: pinrate.Trajectory, compiled: pinrate.Trajectory, *, bitwise: bool
) -> None:
    """Bit for bit where both make the same operations; else q, rates and errors to 1e-12
    (they differ by rounding, fed back through a contracting loop), rates also by q's
    difference / dt on a step that lands a joint on its limit, and ρ within the bound of
    support.spectral_radius_tolerance (recorded, not fed back; an eigenvalue of a nearly
    defective G moves by a root of its rounding)."""
    assert compiled.reason == python.reason
    assert compiled.status == python.status
    assert compiled.detail == python.detail
    assert compiled.q.shape == python.q.shape
    for field in ("q", "joint_rates", "position_error", "orientation_error", "spectral_radius"):
        ours, theirs = getattr(compiled, field), getattr(python, field)
        if bitwise:
            np.testing.assert_array_equal(ours, theirs, err_msg=f"{field} not bit-identical")
        elif field == "spectral_radius":
            np.testing.assert_array_equal(np.isinf(ours), np.isinf(theirs), err_msg="rho: where A or W is singular")
            finite = np.isfinite(theirs)
            tolerance = spectral_radius_tolerance(robot, python.partition, python.q[finite])
            excess = np.abs(ours[finite] - theirs[finite]) - tolerance
            assert not np.any(excess > 0), f"rho differs beyond its bound at steps {np.flatnonzero(finite)[excess > 0]}"
        elif field == "joint_rates":
            # A step that lands a joint on its limit sets that joint's rate to (limit - q) / dt,
            # whatever word ranks first: q's rounding difference comes out divided by dt (the
            # subtraction and division add only 2 eps |rate|, inside the 1e-12 relative part).
            carried = np.max(np.abs(compiled.q[: len(ours)] - python.q[: len(ours)]), axis=1) / python.dt
            excess = np.abs(ours - theirs) - (1e-12 + 1e-12 * np.abs(theirs) + carried[:, None])
            beyond = np.flatnonzero(excess.max(axis=1) > 0)
            assert not beyond.size, f"joint_rates differ beyond rounding at steps {beyond}"
        else:
            np.testing.assert_allclose(ours, theirs, rtol=1e-12, atol=1e-12, err_msg=field)


@pytest.mark.parametrize("name", REFERENCE_RUNS)
def test_the_demo_runs_and_the_papers_simulations(name: str) -> None:
    robot = pinrate.load(str(REFERENCE[f"{name}/robot"]))
    algorithm = str(REFERENCE[f"{name}/algorithm"])
    settings = eval(str(REFERENCE[f"{name}/settings"]), {"inf": math.inf})  # a dict literal we wrote
    q0, target = REFERENCE[f"{name}/q0"], REFERENCE[f"{name}/target"]
    python, compiled = both(robot, q0, target, algorithm=algorithm, **settings)
    assert_same(robot, python, compiled, bitwise=bitwise(robot, algorithm, python.partition))


@pytest.mark.parametrize("algorithm", pinrate.ALGORITHMS)
@pytest.mark.parametrize("name", ROBOTS)
def test_random_targets_with_the_default_safety(name: str, algorithm: str, python_steps: list[int]) -> None:
    """The URDF's velocity limits, position limits, decelerate near singularities."""
    robot = load(name)
    partition = pinrate.Partition.auto(robot)
    with path("compiled"):
        assert Controller(robot, algorithm=algorithm).compiled() is not None, "this robot must run compiled"
    steps = handed_back = 0
    for seed in range(4):
        _, target = nearby_target(robot, partition, seed, spread=0.3 + 0.3 * seed)
        settings = {"algorithm": algorithm, "velocity_limits": None, "max_steps": 600}
        with path("python"):
            python = pinrate.servo(robot, robot.home(), target, **settings)
        python_steps.clear()
        with path("compiled"):
            compiled = pinrate.servo(robot, robot.home(), target, **settings)
        steps, handed_back = steps + compiled.steps, handed_back + len(python_steps)
        assert_same(robot, python, compiled, bitwise=bitwise(robot, algorithm))
    assert handed_back < steps / 2, f"the core took only {steps - handed_back} of {steps} steps"


def test_a_partition_that_cannot_make_every_twist_runs_on_python() -> None:
    """The honest step's residual (Status.UNACHIEVABLE_TWIST) is judged on Python: the core is
    refused with the reason, and both paths agree because both are Python's."""
    robot = load("al5d")
    with path("compiled"):
        controller = Controller(robot, algorithm="mca1")
        assert controller.compiled() is None
        assert "cannot make every twist" in str(controller.compiled_reason())


@pytest.mark.parametrize("algorithm", ["exact", "schur", "dls", "mca1"])
def test_a_five_dof_arm_puts_position_first_on_both_paths(algorithm: str) -> None:
    """A 5-DOF arm's steps (position first, the rotation given up said) are Python's on both
    paths: the core, which solves no tall W that way, is refused with the reason, and the
    runs agree bit for bit."""
    robot = pinrate.load(DATA / "five_dof_arm.urdf")
    with path("compiled"):
        controller = Controller(robot, algorithm=algorithm)
        assert controller.compiled() is None
        assert "cannot make every twist" in str(controller.compiled_reason())
    _, target = nearby_target(robot, pinrate.Partition.auto(robot), seed=2)
    python, compiled = both(robot, robot.home(), target, algorithm=algorithm, max_steps=3000)
    assert python.converged, python.reason
    assert_same(robot, python, compiled, bitwise=True)


def test_limits_and_singularities_hand_steps_back(python_steps: list[int]) -> None:
    """Far targets: joints run onto their limits, rates are scaled, the arm passes near its
    singularities; those steps go back to Python, the rest stay compiled, and the runs agree."""
    robot = pinrate.load("ur5")
    partition = pinrate.Partition.auto(robot)
    words: set[str] = set()
    handed_back = compiled_steps = 0
    for seed in range(6):
        _, target = nearby_target(robot, partition, seed, spread=2.5)
        python_steps.clear()
        with path("python"):
            python = pinrate.servo(robot, robot.home(), target, velocity_limits=0.8, max_steps=800)
        python_steps.clear()
        with path("compiled"):
            compiled = pinrate.servo(robot, robot.home(), target, velocity_limits=0.8, max_steps=800)
        handed_back += len(python_steps)
        compiled_steps += compiled.steps - len(python_steps)
        assert_same(robot, python, compiled, bitwise=True)
        words |= set(compiled.status)
    assert {Status.RATE_LIMITED.word, Status.TWIST_SATURATED.word} <= words
    near = (Status.JOINT_LIMIT, Status.DECELERATE_FOR_SINGULARITY, Status.WRIST_SINGULARITY, Status.NEAR_SINGULARITY)
    assert words & {*(status.word for status in near), "singular"}
    assert handed_back > 0 and compiled_steps > 10 * handed_back


def test_a_run_longer_than_the_first_arrays() -> None:
    """The log grows past its first 2048 steps on both paths alike."""
    robot = pinrate.load("ur5")
    _, target = nearby_target(robot, pinrate.Partition.auto(robot), 0)
    python, compiled = both(robot, robot.home(), target, tol=1e-12, max_steps=5000, gain=0.2)
    assert compiled.steps > 2048
    assert_same(robot, python, compiled, bitwise=True)


def test_a_prismatic_and_a_continuous_joint_and_a_sensor_mid_chain() -> None:
    robot = pinrate.load(DATA / "mixed_joints.urdf", tip="tool", sensor="link2")
    partition = pinrate.Partition(["yaw", "slide", "roll"], ["pitch"], linear="xyz", angular="z")
    with path("compiled"):
        assert Controller(robot, partition=partition).compiled() is not None
    for seed in range(3):
        _, target = nearby_target(robot, partition, seed)
        python, compiled = both(robot, robot.home(), target, partition=partition, algorithm="mca1", max_steps=400)
        assert_same(robot, python, compiled, bitwise=False)


@pytest.mark.parametrize("name", ["ur5", "scara", "barker_arm", "spherical_6dof", "kinova"])
def test_rho_maps_agree(name: str) -> None:
    """sample_convergence: the core's float closed forms against the batched numpy closed
    forms (the same formulas, another order of a few roundings, which an ill-conditioned A
    or W amplifies): ρ within support.spectral_radius_tolerance, and the verdicts wherever
    ρ is farther from 1 than that bound."""
    robot = pinrate.load(name)
    samples = {}
    for choice in ("python", "compiled"):
        with path(choice):
            samples[choice] = pinrate.sample_convergence(robot, 20_000, rng=7)
    python, compiled = samples["python"].spectral_radius, samples["compiled"].spectral_radius
    np.testing.assert_array_equal(samples["python"].q, samples["compiled"].q)
    np.testing.assert_array_equal(np.isinf(python), np.isinf(compiled))
    finite = np.isfinite(python)
    tolerance = spectral_radius_tolerance(robot, pinrate.Partition.auto(robot), samples["python"].q[finite])
    assert np.all(np.abs(compiled[finite] - python[finite]) <= tolerance)
    clear = ~finite  # the verdict where rho is known farther from 1 than its bound
    clear[finite] = np.abs(python[finite] - 1.0) > tolerance
    np.testing.assert_array_equal((compiled < 1.0)[clear], (python < 1.0)[clear])
    with path("compiled"):
        assert pinrate.backend().name == "compiled"


def test_ctrl_c_reaches_a_long_compiled_run() -> None:
    """The loop releases the GIL; every few thousand steps it takes it back to ask for
    signals, so Ctrl-C ends even a run of millions of steps within moments."""
    script = (
        "import pinrate\n"
        "from pinrate.compiled import use\n"
        "use('compiled')\n"
        "robot = pinrate.load('ur5')\n"
        "target = robot.pose(robot.home())\n"
        "target[:3, 3] += 0.2\n"
        "print('ready', flush=True)\n"
        # gain x dt = 1e-6: 1 % better every 10,000 steps; the longest run servo takes, seconds
        "pinrate.servo(robot, robot.home(), target, algorithm='exact', gain=1e-4, tol=1e-12, max_steps=1_000_000)\n"
        "print('finished', flush=True)\n"
    )
    process = subprocess.Popen(
        [sys.executable, "-c", script], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True
    )
    assert process.stdout is not None
    assert process.stdout.readline().strip() == "ready"
    time.sleep(1.0)
    sent = time.monotonic()
    process.send_signal(signal.SIGINT)
    out, err = process.communicate(timeout=30)
    assert time.monotonic() - sent < 2.0
    assert "finished" not in out
    assert process.returncode != 0 and "KeyboardInterrupt" in err


def test_a_robot_the_core_has_seen_can_be_freed() -> None:
    """The core's caches are keyed by the Robot and must not keep it alive."""
    robot = pinrate.load("ur5")
    _, target = nearby_target(robot, pinrate.Partition.auto(robot), 0)
    with path("compiled"):
        pinrate.servo(robot, robot.home(), target, max_steps=20)
        pinrate.sample_convergence(robot, 100, rng=0)
    alive = weakref.ref(robot)
    del robot
    gc.collect()
    assert alive() is None


def test_threads_sharing_a_robot_map_rho_alike() -> None:
    """A Dask worker's threads share one Robot: each ρ map works on its own copy of the
    kinematics, so the maps agree with one made alone."""
    robot = pinrate.load("ur5")
    configurations = robot.sample_configurations(20_000, 3)
    with path("compiled"):
        alone = spectral_radius_at(robot, configurations)
        with ThreadPoolExecutor(4) as pool:
            maps = list(pool.map(lambda _: spectral_radius_at(robot, configurations), range(8)))
    for radii in maps:
        np.testing.assert_array_equal(radii, alone)


def test_edited_limits_reach_the_next_run() -> None:
    robot = pinrate.load("ur5")
    _, target = nearby_target(robot, pinrate.Partition.auto(robot), 1, spread=0.6)
    with path("compiled"):
        free = pinrate.servo(robot, robot.home(), target, max_steps=300)
    upper = np.array(robot.model.upperPositionLimit)
    upper[:] = robot.home() + 0.01  # every joint may move up by 0.01 rad at most
    robot.model.upperPositionLimit = upper
    for choice in ("python", "compiled"):
        with path(choice):
            held = pinrate.servo(robot, robot.home(), target, max_steps=300)
        assert Status.JOINT_LIMIT.word in held.status and Status.JOINT_LIMIT.word not in free.status
        assert (held.q <= upper + 1e-12).all()


@pytest.mark.parametrize("singularity", [name for name in STRATEGIES if name != "auxiliary_elbow"])
@pytest.mark.parametrize("algorithm", ["exact", "mca1", "dls"])
@pytest.mark.parametrize("name", ["ur5", "panda", "scara"])
def test_the_singular_region_every_strategy_and_starts_away_from_home(
    name: str, algorithm: str, singularity: str
) -> None:
    """Far targets (through the singular region and onto the limits), from home and from a
    random start, each strategy with a wrist rule: the two paths agree as everywhere (the
    singular region's steps are Python's on both; what differs is rounding carried in)."""
    robot = pinrate.load(name)
    partition = pinrate.Partition.auto(robot)
    for seed, wrist in zip(range(2), ("split", "last_then_first"), strict=True):
        start = robot.home() if seed == 0 else robot.random_configuration(np.random.default_rng(seed))
        _, target = nearby_target(robot, partition, seed, spread=2.5)
        settings = {"algorithm": algorithm, "singularity": singularity, "wrist": wrist, "velocity_limits": None}
        python, compiled = both(robot, start, target, max_steps=800, **settings)
        assert_same(robot, python, compiled, bitwise=bitwise(robot, algorithm))


@pytest.mark.parametrize("wrist", ["turn", "split"])
def test_the_cause_of_a_stall_in_the_same_words(wrist: str) -> None:
    """A run across Barker's wrist singularity (passed by "turn", a stall named by "split"),
    and one that stalls with θ4 on its limit: both paths give the same reason, word for word
    (the steps in the singular region are Python's on both: q agrees to rounding)."""
    robot = pinrate.robots.barker_arm()
    q0 = robot.home()
    q0[4] = -0.007
    q_target = q0.copy()
    q_target[[3, 4, 5]] += [math.pi / 2, 0.307, -math.pi / 2]
    python, compiled = both(robot, q0, robot.pose(q_target), wrist=wrist)
    assert_same(robot, python, compiled, bitwise=False)
    assert python.converged if wrist == "turn" else "; wrist singularity on " in python.reason
    q0[4] = 0.3
    q_target = q0.copy()
    q_target[[1, 3, 4, 5]] += [0.1, 0.4, -0.6, -0.3]
    python, compiled = both(robot, q0, robot.pose(q_target), wrist=wrist)
    assert_same(robot, python, compiled, bitwise=False)
    assert python.reason.endswith("; at a joint limit on 500 of its 500 steps: held at a position limit: theta4")


@pytest.mark.parametrize("name", ROBOTS)
def test_a_first_compiled_step_at_the_target_moves_nothing(name: str) -> None:
    """Issue 24: the core's first step toward the tip's own pose (pose error zero; tol 0 so
    that the loop steps instead of stopping converged) applies rates that are exactly 0 and
    leaves q unchanged to the bit, with the position and velocity limits on."""
    robot = load(name)
    home = robot.home()
    for algorithm in pinrate.ALGORITHMS:
        core = Controller(robot, algorithm=algorithm).compiled()
        if core is None:
            continue  # this configuration runs on Python: test_controller covers it
        log = ServoLog(home, robot.nv, 2)
        core.run(
            q0=home,
            target=np.ascontiguousarray(robot.pose(home)),
            gain=1.0,
            tol=0.0,
            stall_steps=10,
            max_steps=1,
            divergence_factor=DIVERGENCE_FACTOR,
            stall_improvement=STALL_IMPROVEMENT,
            step_number=0,
            best=math.inf,
            progress=math.inf,
            progress_step=0,
            **log.arguments(),
        )
        assert log.position[0] == 0.0 and log.orientation[0] == 0.0, algorithm
        assert not log.rates[0].any(), (algorithm, log.rates[0])
        assert np.array_equal(log.q[1], home), algorithm
