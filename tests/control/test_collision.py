"""Self-collision in the loop (issue 11): the monitor stops a panda before two links touch —
distances from coal on the URDF's own meshes, not the monitor's hulls — allows the motion
away, follows the SRDF, and its approach rate matches finite differences."""

from __future__ import annotations

import warnings

import numpy as np
import pinocchio as pin
import pytest

import pinrate
from pinrate import Controller, InputError, JointJog, Status
from pinrate.control.collision import CollisionMonitor


def mesh_distances(robot: pinrate.Robot, monitor: CollisionMonitor, q: np.ndarray) -> dict[tuple[str, str], float]:
    """coal's distance of every monitored pair on the URDF's meshes (a fresh model and data)."""
    geometry = robot.collision_model.copy()
    geometry.addAllCollisionPairs()
    data, geometry_data = robot.model.createData(), pin.GeometryData(geometry)
    pin.computeDistances(robot.model, data, geometry, geometry_data, q)
    by_links: dict[tuple[str, str], float] = {}
    for pair, result in zip(geometry.collisionPairs, geometry_data.distanceResults, strict=True):
        first = robot.model.frames[geometry.geometryObjects[pair.first].parentFrame].name
        second = robot.model.frames[geometry.geometryObjects[pair.second].parentFrame].name
        key = (first, second)
        by_links[key] = min(by_links.get(key, np.inf), result.min_distance)
    return {pair: by_links[pair] for pair in monitor.pairs}


def fold(controller: Controller, steps: int = 600) -> tuple[np.ndarray, pinrate.Step]:
    """Tilt the panda's shoulder forward until its fingers reach the base (or the loop ends)."""
    q = controller.robot.home()
    for _ in range(steps):
        step = controller.step(q, JointJog({"panda_joint2": 0.6}))
        q = step.q
        if step.status is Status.HALT_FOR_COLLISION:
            break
    return q, step


def test_the_monitor_stops_a_panda_before_two_links_touch_and_lets_it_back() -> None:
    robot = pinrate.load("panda")
    guarded = Controller(robot, collision=True)
    monitor = guarded.collision
    unguarded_q, _ = fold(Controller(robot))
    assert min(mesh_distances(robot, monitor, unguarded_q).values()) <= 0.0  # the motion does collide
    q, step = fold(guarded)
    assert step.status is Status.HALT_FOR_COLLISION and "m apart" in step.detail
    nearest = min(mesh_distances(robot, monitor, q).values())
    assert monitor.stop_distance <= nearest < monitor.safety_distance  # stopped short, on the meshes too
    back = guarded.step(q, JointJog({"panda_joint2": -0.6}))
    assert back.status is Status.OK and back.joint_rates[1] == pytest.approx(-0.6)  # moving away: executed
    assert min(mesh_distances(robot, monitor, back.q).values()) > nearest


def test_the_approach_rate_is_the_derivative_of_the_distance() -> None:
    robot = pinrate.load("panda")
    monitor = CollisionMonitor(robot, safety_distance=0.3)
    rng = np.random.default_rng(3)
    q = robot.home()
    q[1] += 0.9
    rates = rng.normal(size=robot.nv) * 0.5
    distances = monitor._distances(q)
    near = [int(i) for i in np.flatnonzero(distances < 0.2)]
    assert near
    approach = monitor.approach_rates(q, rates, near)
    h = 1e-6
    ahead = monitor._distances(pin.integrate(robot.model, q, rates * h))
    np.testing.assert_allclose(approach, (ahead[near] - distances[near]) / h, rtol=1e-3, atol=1e-5)


def test_the_srdf_disabled_pairs_and_adjacent_links_are_not_monitored() -> None:
    monitor = CollisionMonitor(pinrate.load("panda"))
    pairs = {frozenset(pair) for pair in monitor.pairs}
    assert frozenset(("panda_link0", "panda_link2")) not in pairs  # <disable_collisions ... reason="Never"/>
    assert frozenset(("panda_link3", "panda_link4")) not in pairs  # adjacent
    assert frozenset(("panda_link0", "panda_leftfinger")) in pairs


def test_robots_without_collision_geometry_are_skipped_and_said_once() -> None:
    robot = pinrate.load("two_link_planar")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        first = Controller(robot, collision=True)
        Controller(robot, collision=True)
    assert first.collision is None
    assert sum("self-collision is not monitored" in str(warning.message) for warning in caught) <= 1
    assert first.step(robot.home(), np.zeros(first.index.rows.size)).status is Status.OK


def test_bad_collision_options_are_input_errors() -> None:
    robot = pinrate.load("panda")
    with pytest.raises(InputError, match="less than safety_distance"):
        CollisionMonitor(robot, safety_distance=0.01, stop_distance=0.02)
    with pytest.raises(InputError, match="collision must be"):
        Controller(robot, collision="yes")
    with pytest.raises(InputError, match="another Robot"):
        Controller(robot, collision=CollisionMonitor(pinrate.load("panda")))
