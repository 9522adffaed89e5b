"""Self-collision in the loop (issue 11): the monitor stops a panda before two links touch —
distances from coal on the URDF's own meshes, not the monitor's hulls — allows the motion
away, follows the SRDF, and its approach rate matches finite differences; and (issue 23) its
convex hulls never read a pair farther apart than the meshes are, so drives into itself stop
before the meshes touch."""

from __future__ import annotations

import warnings

import coal
import numpy as np
import pinocchio as pin
import pytest

import pinrate
from pinrate import Controller, InputError, JointJog, Status
from pinrate.control.collision import CollisionMonitor
from pinrate.kinematics.targets import nearby_target
from support import flat_plate


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
    # fingers closed (both on their mimic relation): opened 1 mm, as the home has them, the
    # right finger's nearest point to link5 sits where two faces tie (a kink of the distance)
    q[7] = q[8] = 0.0
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


@pytest.mark.parametrize("name", ["z1", "kinova"])
def test_no_pair_on_one_joint_or_a_joint_and_its_parent_is_monitored(name: str) -> None:
    # Links with several collision geometries: removing a pair used to shift the binding's
    # pair list under the loop, and the pair after each removal stayed monitored (z1: 3,
    # kinova: 2; the loop left 14 of so101's 36 adjacent pairs).
    robot = pinrate.load(name)
    monitor = CollisionMonitor(robot)
    objects, parents = monitor._geometry.geometryObjects, robot.model.parents
    adjacent = []
    for first, second in monitor._pairs:
        a, b = objects[first].parentJoint, objects[second].parentJoint
        if a == b or parents[a] == b or parents[b] == a:
            adjacent.append((objects[first].name, objects[second].name))
    assert monitor.pairs and not adjacent


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


# --------------------------------------------------------------------- the hulls (issue 23)
# The monitor reads distances between convex hulls; a hull contains its mesh, so the reading
# d is at most the meshes' distance, up to GJK's stopping rule: coal stops GJK when its upper
# bound (the returned ‖x_k‖ = d) exceeds its lower bound on the hulls' distance by at most
# ε (1 + d), ε = DistanceRequest.gjk_tolerance (1e-6 m by default): d <= d_hull + ε (1 + |d|)
# <= d_mesh + ε (1 + |d|). The reference distances are coal's on an unmodified GeometryModel
# built by Pinocchio from the same URDF, on the meshes themselves.

UR5_CONTACT_Q = np.array(
    [
        -4.474200778749099,
        0.5138148911866368,
        2.8314890898513143,
        4.5305152532311155,
        1.5066148034016587,
        -5.583897837514347,
    ]
)
"""A UR5 whose base_link and wrist_1_link meshes touch, read 1.6 cm apart before issue 23."""

URDF = {"ur5": "ur_description/urdf/ur5_robot.urdf", "panda": "panda_description/urdf/panda.urdf"}


class MeshReference:
    """The monitored pairs (by geometry index) on the URDF's meshes, loaded by Pinocchio anew."""

    def __init__(self, robot: pinrate.Robot, monitor: CollisionMonitor, name: str) -> None:
        from pinrate.robots.catalog import example_robot_data_share, example_robot_path

        self.model, self.data = robot.model, robot.model.createData()
        path, share = example_robot_path(URDF[name]), example_robot_data_share()
        kind = pin.GeometryType.COLLISION
        self.geometry = pin.buildGeomFromUrdf(self.model, str(path), kind, package_dirs=[str(share)])
        names = [geometry_object.name for geometry_object in self.geometry.geometryObjects]
        assert names == [geometry_object.name for geometry_object in robot.collision_model.geometryObjects]
        assert all(
            isinstance(geometry_object.geometry, (coal.BVHModelBase, coal.Box))
            for geometry_object in self.geometry.geometryObjects
        )  # meshes (and the URDF's boxes), no hulls
        for first, second in monitor._pairs:
            self.geometry.addCollisionPair(pin.CollisionPair(first, second))
        self.geometry_data = pin.GeometryData(self.geometry)

    def distances(self, q: np.ndarray) -> np.ndarray:
        pin.computeDistances(self.model, self.data, self.geometry, self.geometry_data, q)
        return np.array([result.min_distance for result in self.geometry_data.distanceResults])

    def touching(self, q: np.ndarray) -> list[int]:
        pin.computeCollisions(self.model, self.data, self.geometry, self.geometry_data, q, False)
        return [i for i, result in enumerate(self.geometry_data.collisionResults) if result.isCollision()]


def gjk_slack(monitor: CollisionMonitor, distances: np.ndarray) -> np.ndarray:
    """ε (1 + |d|): how far GJK's reading may lie above the hulls' distance (see above)."""
    tolerances = {request.gjk_tolerance for request in monitor._geometry_data.distanceRequests}
    assert len(tolerances) == 1
    return tolerances.pop() * (1.0 + np.abs(distances))


def test_the_ur5_whose_meshes_touch_reads_as_touching() -> None:
    robot = pinrate.load("ur5")
    monitor = CollisionMonitor(robot)
    reference = MeshReference(robot, monitor, "ur5")
    pair = monitor.pairs.index(("base_link", "wrist_1_link"))
    assert pair in reference.touching(UR5_CONTACT_Q)  # the meshes touch...
    meshes = reference.distances(UR5_CONTACT_Q)[pair]
    read = monitor._distances(UR5_CONTACT_Q)[pair]
    assert read <= meshes + gjk_slack(monitor, np.array([read]))[0]  # ...and the monitor says so (it read 0.016 m)
    assert read < monitor.stop_distance


@pytest.mark.parametrize("name", ["ur5", "panda"])
def test_the_monitor_never_reads_a_pair_farther_apart_than_its_meshes(name: str) -> None:
    # Seeded configurations, uniform in the joint limits, every monitored pair (boxes too).
    robot = pinrate.load(name)
    monitor = CollisionMonitor(robot)
    reference = MeshReference(robot, monitor, name)
    rng = np.random.default_rng(23)
    lower, upper = robot.model.lowerPositionLimit, robot.model.upperPositionLimit
    near = 0
    for _ in range(250):
        q = rng.uniform(lower, upper)
        read, meshes = monitor._distances(q), reference.distances(q)
        over = read - meshes - gjk_slack(monitor, read)
        worst = int(np.argmax(over))
        where = f"{monitor.pairs[worst]} at q={q.tolist()}"
        assert over[worst] <= 0.0, f"{where}: {read[worst]} m read, the meshes {meshes[worst]} m apart"
        near += int(np.sum(meshes < monitor.safety_distance))
    assert near > 100  # the pairs that matter: near or in contact (ur5 ~2400, panda ~160 of them)


def test_drives_into_itself_end_before_the_meshes_touch() -> None:
    # A UR5 jogged in joint space, in a straight line from a free pose (nothing touching, the
    # monitor above its stop distance) toward a pose where monitored meshes touch: no step
    # may end with meshes in contact. Before issue 23 these drives ended in contact.
    robot = pinrate.load("ur5")
    controller = Controller(robot, collision=True)
    monitor = controller.collision
    assert monitor is not None
    reference = MeshReference(robot, monitor, "ur5")
    joints = [robot.model.names[joint] for joint in range(1, robot.model.njoints)]
    lower, upper = robot.model.lowerPositionLimit, robot.model.upperPositionLimit
    for seed in range(5):
        rng = np.random.default_rng(seed)
        target = rng.uniform(lower, upper)
        while not reference.touching(target):
            target = rng.uniform(lower, upper)
        start = rng.uniform(lower, upper)
        while reference.touching(start) or monitor._distances(start).min() <= monitor.stop_distance:
            start = rng.uniform(lower, upper)
        direction = pin.difference(robot.model, start, target)
        jog = JointJog(dict(zip(joints, 2.0 * direction / np.abs(direction).max(), strict=True)))
        q, halted, statuses = start, 0, set()
        for _ in range(400):
            step = controller.step(q, jog)
            q, statuses = step.q, statuses | set(step.conditions)
            touching = reference.touching(q)
            assert not touching, f"drive {seed}: {[monitor.pairs[i] for i in touching]} touch at q={q.tolist()}"
            halted = halted + 1 if step.status is Status.HALT_FOR_COLLISION else 0
            if halted == 3:
                break
        assert statuses & {Status.DECELERATE_FOR_COLLISION, Status.HALT_FOR_COLLISION}  # the monitor had work to do


def test_the_approach_rate_of_overlapping_hulls_is_the_derivative_of_the_signed_distance() -> None:
    # Hulls are fatter than meshes: a robot may start with two hulls overlapping (d < 0). The
    # nearest points then point against the normal; ḋ must still be the derivative of d, or
    # the motion away halts and the motion deeper is let through.
    robot = pinrate.load("ur5")
    monitor = CollisionMonitor(robot)
    rng = np.random.default_rng(5)
    lower, upper = robot.model.lowerPositionLimit, robot.model.upperPositionLimit
    checked, h = 0, 1e-5
    while checked < 30:
        q = rng.uniform(lower, upper)
        distances = monitor._distances(q)
        overlapping = [int(i) for i in np.flatnonzero(distances < 0.0)]
        if not overlapping:
            continue
        rates = rng.normal(size=robot.nv) * 0.5
        approach = monitor.approach_rates(q, rates, overlapping)
        after = monitor._distances(pin.integrate(robot.model, q, rates * h))[overlapping]
        before = monitor._distances(pin.integrate(robot.model, q, -rates * h))[overlapping]
        ahead, behind = (after - distances[overlapping]) / h, (distances[overlapping] - before) / h
        smooth = np.abs(ahead - behind) < 1e-3  # not on a kink of d (a change of nearest features)
        np.testing.assert_allclose(approach[smooth], ahead[smooth], rtol=1e-2, atol=1e-3)
        checked += int(smooth.sum())


def test_a_mesh_with_no_hull_is_monitored_as_its_mesh_and_said_once() -> None:
    # A flat plate (two triangles): qhull finds no 3-D hull, and coal 3.0's convexHull would
    # end the process on it. The monitor keeps the mesh (exact, so still conservative).
    robot = pinrate.load("ur5")
    flat_plate(robot, "plate")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        monitor = CollisionMonitor(robot)
        CollisionMonitor(robot)
    said = [str(warning.message) for warning in caught if "plate" in str(warning.message)]
    assert len(said) == 1 and "mesh" in said[0] and "flat" in said[0]
    kinds = {o.name: type(o.geometry).__name__ for o in monitor._geometry.geometryObjects}
    assert kinds["plate"] == "BVHModelOBBRSS" and kinds["base_link_0"] == "ConvexBase"
    assert ("base_link", "wrist_3_link") in monitor.pairs and monitor.nearest(robot.home()) is not None


def test_links_that_sit_close_but_barely_approach_do_not_slow_the_arm() -> None:
    """Three UR5 pairs sit 1.4-1.6 cm apart at home (meshes and hulls agree); scaling every
    command by the distance, as the damper first did, kept servo runs from home crawling
    (none of six converged in 3000 steps). Bounding the approach speed instead, the runs are
    the runs without the monitor, step for step."""
    robot = pinrate.load("ur5")
    partition = pinrate.Partition.auto(robot)
    for seed in range(3):
        _, target = nearby_target(robot, partition, seed)
        free = pinrate.servo(robot, robot.home(), target, algorithm="mca1")
        guarded = pinrate.servo(robot, robot.home(), target, algorithm="mca1", collision=True)
        assert guarded.converged and guarded.steps == free.steps
