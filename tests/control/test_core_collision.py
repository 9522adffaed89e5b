"""The self-collision monitor in the compiled core (pinrate.control.core_collision) against the
Python monitor (pinrate.control.collision), on robots whose collision models hold hulled
meshes, boxes (UR5, Panda) and cylinders (Z1).

Both monitors make the same coal calls on the same geometries (the core hulls the same
vertices with the same qhull call) with the same distance requests (GJK started from the
bounding boxes, so a distance is a function of q alone), and the approach rates with the
same float operations. Their inputs differ only where the core's Pinocchio build places a
geometry a few ulps away from pin's; GJK then stops within its tolerance of the hulls'
distance on either side: every distance within 2 eps_gjk (1 + |d|) of the other (eps_gjk the
requests' tolerance, 1e-6; EPA's for overlapping hulls is 1e-6 too). Where the step's own
operations are the same on both paths (:func:`compiled_core.bitwise`) the steps agree to the
bit; elsewhere within :func:`rates_tolerance`.
"""

from __future__ import annotations

import warnings
from collections.abc import Iterator

import coal
import numpy as np
import pinocchio as pin
import pytest

import pinrate
from compiled_core import bitwise, core_steps_taken, needs_core, path
from pinrate import Controller, Status
from pinrate.control import core_collision
from pinrate.control.collision import CollisionMonitor
from pinrate.control.core_collision import core_monitor, python_reason
from support import flat_plate

pytestmark = needs_core

ROBOTS = ("ur5", "panda", "z1")
"""Hulled meshes and a box (UR5), eight boxes (Panda), eight cylinders (Z1)."""


def gjk_slack(monitor: CollisionMonitor, distances: np.ndarray) -> np.ndarray:
    """How far the two monitors' distances (m) may differ: each within eps (1 + |d|) of the
    hulls' distance (GJK's stopping rule; EPA's tolerance below 0), on either side."""
    tolerance = monitor._geometry_data.distanceRequests[0].gjk_tolerance
    return 2.0 * tolerance * (1.0 + np.abs(distances))


def monitor_of(name: str) -> tuple[pinrate.Robot, CollisionMonitor]:
    robot = pinrate.load(name)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # a mesh kept as a mesh is said once: not this test's matter
        return robot, CollisionMonitor(robot)


@pytest.fixture
def taken() -> Iterator[list[bool]]:
    """Each call of the core's per-call step: True where it took the step."""
    with core_steps_taken() as calls:
        yield calls


@pytest.mark.parametrize("name", ROBOTS)
def test_the_compiled_monitor_reads_the_python_monitors_distances(name: str) -> None:
    robot, monitor = monitor_of(name)
    with path("compiled"):
        compiled = core_monitor(monitor)
    assert compiled.pair_count == len(monitor.pairs)
    rng = np.random.default_rng(3)
    exact = 0
    for _ in range(100):
        q = robot.random_configuration(rng)
        python, ours = monitor._distances(q), np.array(compiled.distances(q))
        np.testing.assert_array_less(np.abs(ours - python), gjk_slack(monitor, python))
        exact += int(np.sum(ours == python))
    assert exact > 0  # the same calls on the same numbers: most distances agree to the bit


def drive(robot: pinrate.Robot, monitor: CollisionMonitor, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """A start where every monitored pair is beyond the stop distance (the UR5 and the Z1
    keep some pairs within the safety distance everywhere) and a joint-space direction
    (rad/s, largest 1) toward a configuration where two hulls overlap."""
    rng = np.random.default_rng(seed)
    target = robot.random_configuration(rng)
    while monitor._distances(target).min() >= 0.0:
        target = robot.random_configuration(rng)
    start = robot.random_configuration(rng)
    while monitor._distances(start).min() <= monitor.stop_distance:
        start = robot.random_configuration(rng)
    direction = pin.difference(robot.model, start, target)
    return start, direction / np.abs(direction).max()


def twist_along(controller: Controller, q: np.ndarray, joint_rates: np.ndarray) -> np.ndarray:
    """The twist (partition rows, sensor axes) whose exact step at q is ``joint_rates``."""
    observation = controller.observe(q)
    return observation.jacobian[controller.index.rows] @ joint_rates


def mesh_distance(robot: pinrate.Robot, monitor: CollisionMonitor, q: np.ndarray) -> float:
    """The least distance (m) of the monitored pairs on the URDF's own meshes and shapes."""
    geometry = robot.collision_model.copy()
    geometry.removeAllCollisionPairs()
    for first, second in monitor._pairs:
        geometry.addCollisionPair(pin.CollisionPair(first, second))
    data, geometry_data = robot.model.createData(), pin.GeometryData(geometry)
    pin.computeDistances(robot.model, data, geometry, geometry_data, q)
    return min(result.min_distance for result in geometry_data.distanceResults)


def rates_tolerance(python: pinrate.Step, compiled: pinrate.Step, slack: float, room: float) -> float:
    """How far the two paths' rates (rad/s) may differ where their operations differ (the
    Panda's 3x4 A: numpy's LAPACK on one path, Eigen on the other). The monitor's scale s is
    (d - stop) over an approach rate: a distance read ``slack`` apart moves s by at most
    s slack / (d - stop) (``room``: d - stop, m), the rates by that times their size. The
    unscaled rates differ by a few eps kappa relative (tests/compiled/test_core_step.py's
    bound), and s, a ratio of a linear function of them, by as much times the approach rate's
    cancellation (its largest point speed over the rate itself); 1e-9 relative covers
    kappa <= 1 / slow_threshold = 50 and a cancellation of 1e4 (measured here: 1e-15)."""
    size = max(float(np.abs(python.joint_rates).max()), float(np.abs(compiled.joint_rates).max()), 1.0)
    return size * (slack / max(room, 1e-9) + 1e-9)


@pytest.mark.parametrize("name", ROBOTS)
def test_the_two_paths_agree_per_call_on_drives_into_itself(name: str, taken: list[bool]) -> None:
    # The drives and the tolerances are read on a monitor of their own (a distance does not
    # depend on the queries before it: the controller's would read the same).
    robot, probe = monitor_of(name)
    monitor = CollisionMonitor(robot)
    algorithm = "mca1" if name != "panda" else "exact"
    controller = Controller(robot, collision=monitor, algorithm=algorithm, dt=0.02)
    exact = bitwise(robot, algorithm)
    with path("compiled"):
        assert controller.compiled() is not None, controller.compiled_reason()
    words: set[Status] = set()
    statuses: list[Status] = []  # each step's, in the order of ``taken`` (one core call a step)
    for seed in range(3):
        q, direction = drive(robot, probe, seed)
        halted = 0
        for _ in range(500):
            twist = twist_along(controller, q, direction)
            with path("python"):
                python = controller.step(q, twist)
            with path("compiled"):
                compiled = controller.step(q, twist)
            assert compiled.status is python.status, (python.detail, compiled.detail)
            assert compiled.conditions == python.conditions
            assert compiled.detail == python.detail
            distances = probe._distances(q)
            near = distances < probe.safety_distance
            room = float(distances[near].min() - probe.stop_distance) if near.any() else 1.0
            slack = float(gjk_slack(probe, distances).max())
            atol = rates_tolerance(python, compiled, slack, room)
            if exact:
                np.testing.assert_array_equal(compiled.joint_rates, python.joint_rates)
                np.testing.assert_array_equal(compiled.q, python.q)
            else:
                np.testing.assert_allclose(compiled.joint_rates, python.joint_rates, rtol=0, atol=atol)
                np.testing.assert_allclose(compiled.q, python.q, rtol=0, atol=atol * controller.dt + 1e-12)
            words |= set(python.conditions)
            statuses.append(python.status)
            q = python.q
            halted = halted + 1 if python.status is Status.HALT_FOR_COLLISION else 0
            if halted == 3:
                break
    assert {Status.DECELERATE_FOR_COLLISION, Status.HALT_FOR_COLLISION} <= words
    # The core took the monitor's steps itself (others, in the singular region or at a joint
    # limit, it hands back as before).
    by_core = {status for status, took in zip(statuses, taken, strict=True) if took}
    assert {Status.DECELERATE_FOR_COLLISION, Status.HALT_FOR_COLLISION} <= by_core


@pytest.mark.parametrize("choice", ["python", "compiled"])
def test_a_drive_into_itself_halts_before_the_meshes_touch_on_either_path(choice: str) -> None:
    robot, monitor = monitor_of("ur5")
    controller = Controller(robot, collision=monitor, algorithm="mca1", dt=0.02)
    halts = 0
    with path(choice):
        for seed in range(3):
            q, direction = drive(robot, monitor, seed)
            for _ in range(500):
                step = controller.step(q, twist_along(controller, q, direction))
                q = step.q
                assert mesh_distance(robot, monitor, q) > 0.0, f"drive {seed}: the meshes touch at q={q.tolist()}"
                if step.status is Status.HALT_FOR_COLLISION:
                    halts += 1
                    break
    assert halts >= 2  # a drive may end held at a joint limit or in the singular region instead


def test_the_servo_loop_hands_the_monitors_steps_back() -> None:
    # A servo run into the UR5's own base: the core runs the loop, Python the steps the
    # monitor slows or halts; the run ends as the pure-Python one, step for step.
    ur5 = pinrate.load("ur5")
    q0 = ur5.home()
    target = ur5.pose(q0)
    target[:3, 3] = [0.0, 0.0, 0.05]  # inside the base
    runs = {}
    for choice in ("python", "compiled"):
        with path(choice):
            runs[choice] = pinrate.servo(ur5, q0, target, collision=True, algorithm="mca1", max_steps=3000)
    python, compiled = runs["python"], runs["compiled"]
    assert python.reason.startswith("collision")
    assert compiled.reason == python.reason and compiled.status == python.status and compiled.detail == python.detail
    # The steps the core took are the mca1 step on both paths (bitwise on the UR5); the
    # monitor's steps are Python's on both.
    np.testing.assert_array_equal(compiled.q, python.q)


def test_a_core_built_on_another_coal_leaves_the_monitor_on_python(monkeypatch: pytest.MonkeyPatch) -> None:
    robot, monitor = monitor_of("ur5")
    monkeypatch.setattr(coal, "__version__", "0.0.0")
    with path("compiled"):
        reason = python_reason(monitor)
        controller = Controller(robot, collision=monitor)
        assert reason is not None and "coal 0.0.0" in reason
        assert controller.compiled() is None and controller.compiled_reason() == reason
        assert controller.step(robot.home(), np.zeros(6)).status is Status.OK  # on Python
    with path("python"):
        assert python_reason(monitor) is not None  # the Python path is chosen: nothing is cached
    monkeypatch.undo()
    with path("compiled"):
        assert core_collision.python_reason(CollisionMonitor(robot)) is None


def test_a_kept_mesh_is_monitored_in_the_core_as_a_mesh() -> None:
    # A flat plate qhull cannot hull stays a mesh (test_collision.py): the core rebuilds it
    # from its vertices and triangles, and reads the same distances and verdicts.
    robot = pinrate.load("ur5")
    # Its own name: the monitor warns once per robot and geometry name, and test_collision.py
    # counts the warning of its "plate".
    flat_plate(robot, "core_plate")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        monitor = CollisionMonitor(robot)
    with path("compiled"):
        compiled = core_monitor(monitor)
    plate_pairs = [i for i, pair in enumerate(monitor.pairs) if "wrist_3_link" in pair]
    assert plate_pairs
    rng = np.random.default_rng(11)
    for _ in range(50):
        q = robot.random_configuration(rng)
        python, ours = monitor._distances(q), np.array(compiled.distances(q))
        np.testing.assert_array_less(np.abs(ours - python), gjk_slack(monitor, python))
        rates = rng.normal(size=robot.nv)
        verdict, (kind, scale, pair, distance) = monitor.limit(q, rates, 0.01), compiled.limit(q, rates, 0.01)
        assert verdict.status.word == [Status.OK, Status.DECELERATE_FOR_COLLISION, Status.HALT_FOR_COLLISION][kind].word
        if kind:
            assert monitor.verdict(scale, pair, distance).detail == verdict.detail
