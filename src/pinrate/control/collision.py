"""Self-collision in the control loop: Pinocchio's collision model (coal), the SRDF's
disabled pairs, and a velocity damper on the nearest pairs (Faverjon & Tournassoud 1987).

The monitored pairs are every pair of collision geometries less: the pairs the SRDF next to
the URDF disables (``<disable_collisions>``, as MoveIt's setup assistant writes them); pairs
on the same joint or on a joint and its parent (their meshes touch at the joint); and,
without an SRDF, pairs already within the stop distance at home or at the neutral pose
(always in contact, as the setup assistant would find; read on the hulls, as every distance
here).

Each mesh is replaced by its convex hull, once, when the monitor is built: coal computes it
with qhull (``buildConvexHull``, about 1 ms a mesh on the UR5 and the panda). The hull
contains the mesh, so two links' hulls are never farther apart than their meshes, and the
monitor never reads a pair farther apart than its meshes are: d <= d_mesh + ε (1 + abs(d)), ε
the DistanceRequest's ``gjk_tolerance`` (1e-6 by default), because coal stops GJK once the
distance it returns exceeds its lower bound on the hulls' distance by at most ε (1 + d).
Overlapping hulls read d < 0 (EPA's depth). A mesh qhull cannot hull (under 4 vertices,
flat, or refused by coal) stays a mesh, which is exact, and a warning says so once. GJK on
hulls is also far faster than coal's distance on meshes: about 0.1 ms a configuration for the
UR5's 20 pairs, against 7 ms.

For a pair at signed distance d (m) with nearest points p_a, p_b (world) and n the unit
normal from a to b (coal: p_b - p_a = d n, so n = (p_b - p_a) / d, against p_b - p_a when the
hulls overlap), the step's joint rates q̇ move them apart at ḋ = n · (v_b(p_b) - v_a(p_a))
(m/s), each point's velocity from its joint's Jacobian (``LOCAL_WORLD_ALIGNED``) shifted to
the point. The damper bounds the speed at which a pair may approach under
``safety_distance``: ξ (d - stop) / (safety - stop), ξ = :data:`APPROACH_SPEED`, falling to 0
at ``stop_distance``. A pair that approaches (ḋ < 0) limits the common scale s of all rates to

    s (-ḋ) <= ξ (d - stop) / (safety - stop)        and        d + s ḋ dt >= stop,

so a fast approach slows as d falls and the step ends before ``stop_distance`` (a scale under
:data:`HALT_SCALE` halts), while a pair that drifts closer slowly, well within that speed,
does not slow the command (two links a centimetre apart at home, whose distance barely
changes as the arm moves, would otherwise cap every motion); a pair that separates (ḋ >= 0)
never limits it, so motion away is always executed. The first-order prediction is checked
at the integrated q when a pair is near: a step that would still end under the stop distance
with that pair closer halts.

The compiled core runs this monitor too (:mod:`.core_collision`): this module decides what
is watched and says the verdicts (:meth:`CollisionMonitor.verdict`); the core makes the same
coal calls and the same float operations on its own kinematics.
"""

from __future__ import annotations

import math
import warnings
from typing import NamedTuple

import coal
import numpy as np
import pinocchio as pin

from ..checks import check_positive
from ..errors import InputError
from ..kinematics.manipulator import Robot
from .status import Status

SAFETY_DISTANCE = 0.05
"""m: under this distance an approaching pair slows the step (MoveIt Servo's default scene
threshold is 0.02 m; pinrate starts earlier, with an approach speed bound that falls linearly)."""

STOP_DISTANCE = 0.01
"""m: a step that would bring a pair this close halts."""

APPROACH_SPEED = 0.1
"""m/s: the speed ξ at which a pair may approach at ``safety_distance``; the bound falls
linearly to 0 at ``stop_distance`` (Faverjon & Tournassoud's velocity damper)."""

HALT_SCALE = 0.01
"""A step the monitor would scale under this factor halts instead: the damper's scale falls to
0 only as the distance reaches the stop distance, and creeping at 1 % of the command is a halt
in all but name."""

COINCIDENT = 1e-9
"""m: nearest points closer than this give no direction from a to b; coal's normal is taken."""

_FLAT = 1e-6
"""A mesh thinner than this fraction of its length is kept as a mesh: qhull finds no 3-D hull
of flat points, and coal 3.0 then crashes (a flat quad does; thickness/length 3e-8 did, 1e-7
did not, whatever the offset from the origin)."""

_WARNED: set[str] = set()


class Proximity(NamedTuple):
    """The nearest monitored pair: ``distance`` (m), the two links, their nearest points in
    the world (m)."""

    distance: float
    first: str
    second: str
    first_point: np.ndarray
    second_point: np.ndarray


class CollisionVerdict(NamedTuple):
    """What the monitor makes of a step: the factor for every rate (in [0, 1]), the status
    (OK, DECELERATE_FOR_COLLISION or HALT_FOR_COLLISION) and a detail in words."""

    scale: float
    status: Status
    detail: str


class CollisionMonitor:
    """The self-collision monitor of one robot (its own Pinocchio data: one per thread).

    Args:
        robot: the robot; its URDF's ``<collision>`` elements and the SRDF beside it.
        safety_distance, stop_distance: m, 0 < stop < safety.

    Attributes:
        active: False when the robot has no collision geometry or no pair to watch (a warning
            says so once per robot name); :meth:`limit` then always returns scale 1.
        pairs: the monitored pairs, as (link, link) names.
    """

    def __init__(
        self, robot: Robot, *, safety_distance: float = SAFETY_DISTANCE, stop_distance: float = STOP_DISTANCE
    ) -> None:
        self.robot = robot
        self.safety_distance = check_positive(safety_distance, "safety_distance")
        self.stop_distance = check_positive(stop_distance, "stop_distance")
        if self.stop_distance >= self.safety_distance:
            raise InputError(
                f"stop_distance ({self.stop_distance} m) must be less than safety_distance ({self.safety_distance} m)"
            )
        model = robot.model
        self._model = model
        self._data = model.createData()
        self._geometry = robot.collision_model.copy()
        self.sources = tuple(geometry_object.geometry for geometry_object in self._geometry.geometryObjects)
        """Each geometry as the URDF gave it (a hulled one's mesh): what the compiled monitor
        rebuilds (:mod:`.core_collision`)."""
        for geometry_object in self._geometry.geometryObjects:
            kept = _to_convex_hull(geometry_object)
            geometry_object.geometry.computeLocalAABB()  # GJK starts from the boxes' centres
            if kept and f"{robot.name}/{geometry_object.name}" not in _WARNED:
                _WARNED.add(f"{robot.name}/{geometry_object.name}")
                warnings.warn(
                    f"{robot.name}: {geometry_object.name} is monitored as its mesh, not its convex hull ({kept}):"
                    " exact, but slower",
                    stacklevel=2,
                )
        self._geometry.addAllCollisionPairs()
        if robot.srdf_path is not None:
            pin.removeCollisionPairs(model, self._geometry, str(robot.srdf_path))
        self._remove_adjacent_pairs()
        self._geometry_data = _geometry_data(self._geometry)
        if robot.srdf_path is None:
            self._remove_pairs_in_contact([robot.home(), pin.neutral(model)])
        objects = self._geometry.geometryObjects
        self._pairs = [(pair.first, pair.second) for pair in self._geometry.collisionPairs]
        self.pairs = tuple((self._link(objects[a]), self._link(objects[b])) for a, b in self._pairs)
        self.active = bool(self._pairs)
        if not self.active and robot.name not in _WARNED:
            _WARNED.add(robot.name)
            why = "has no collision geometry" if not self._geometry.ngeoms else "has no pair of links to watch"
            warnings.warn(f"{robot.name}: self-collision is not monitored: the robot {why}", stacklevel=2)

    def _link(self, geometry_object: pin.GeometryObject) -> str:
        return self._model.frames[geometry_object.parentFrame].name

    def _remove_adjacent_pairs(self) -> None:
        """Pairs on one joint, or on a joint and its parent, touch at the joint by design.

        The pairs are read as index pairs first: the binding's CollisionPair items are views of
        slots in the C++ vector, which removeCollisionPair shifts under them (each removal
        skipped the next pair: the loop left 14 of so101's 36 adjacent pairs)."""
        parents = self._model.parents
        objects = self._geometry.geometryObjects
        for first, second in [(pair.first, pair.second) for pair in self._geometry.collisionPairs]:
            a, b = objects[first].parentJoint, objects[second].parentJoint
            if a == b or parents[a] == b or parents[b] == a:
                self._geometry.removeCollisionPair(pin.CollisionPair(first, second))

    def _remove_pairs_in_contact(self, configurations: list[np.ndarray]) -> None:
        in_contact = set()
        for q in configurations:
            pin.computeDistances(self._model, self._data, self._geometry, self._geometry_data, q)
            for index, result in enumerate(self._geometry_data.distanceResults):
                if result.min_distance <= self.stop_distance:
                    in_contact.add(index)
        pairs = [(pair.first, pair.second) for pair in self._geometry.collisionPairs]
        for index in sorted(in_contact):
            self._geometry.removeCollisionPair(pin.CollisionPair(*pairs[index]))
        self._geometry_data = _geometry_data(self._geometry)

    # ------------------------------------------------------------------ measuring
    def _distances(self, q: np.ndarray) -> np.ndarray:
        pin.computeDistances(self._model, self._data, self._geometry, self._geometry_data, q)
        return np.array([result.min_distance for result in self._geometry_data.distanceResults])

    def _near_distances(self, indices: list[int], q: np.ndarray) -> list[float]:
        """The distances (m) of the pairs ``indices`` alone at q (the others' are not read)."""
        model, data, geometry, geometry_data = self._model, self._data, self._geometry, self._geometry_data
        pin.forwardKinematics(model, data, q)
        pin.updateGeometryPlacements(model, data, geometry, geometry_data)
        return [pin.computeDistance(geometry, geometry_data, index).min_distance for index in indices]

    def nearest(self, q: object) -> Proximity | None:
        """The nearest monitored pair at q (None when nothing is monitored)."""
        if not self.active:
            return None
        distances = self._distances(self.robot.check_q(q))
        index = int(np.argmin(distances))
        result = self._geometry_data.distanceResults[index]
        first, second = self.pairs[index]
        return Proximity(
            float(distances[index]),
            first,
            second,
            np.array(result.getNearestPoint1()),
            np.array(result.getNearestPoint2()),
        )

    def approach_rates(self, q: np.ndarray, joint_rates: np.ndarray, indices: list[int]) -> np.ndarray:
        """ḋ (m/s) of the pairs ``indices`` under ``joint_rates``, after ``_distances`` at q.

        In floats, operation for operation as the compiled monitor makes them
        (``core/src/collision.hpp``): from the same nearest points, J and rates both give the
        same doubles (and numpy's calls on 3-vectors cost more than the arithmetic)."""
        pin.computeJointJacobians(self._model, self._data, q)
        objects = self._geometry.geometryObjects
        results = self._geometry_data.distanceResults
        rates = joint_rates.tolist()
        approach = np.empty(len(indices))
        for slot, index in enumerate(indices):
            result = results[index]
            first = np.asarray(result.getNearestPoint1(), dtype=float).tolist()
            second = np.asarray(result.getNearestPoint2(), dtype=float).tolist()
            dx, dy, dz = second[0] - first[0], second[1] - first[1], second[2] - first[2]
            length = math.sqrt(dx * dx + dy * dy + dz * dz)
            # coal: p_b - p_a = d n with d signed, so p_b - p_a points against n when the
            # hulls overlap (d < 0); n (from a to b) is the gradient of d either way.
            if length > COINCIDENT:
                if result.min_distance < 0.0:
                    dx, dy, dz = -dx, -dy, -dz
                nx, ny, nz = dx / length, dy / length, dz / length
            else:
                nx, ny, nz = np.asarray(result.normal, dtype=float).tolist()
            a, b = self._pairs[index]
            va = self._point_velocity(objects[a].parentJoint, first, rates)
            vb = self._point_velocity(objects[b].parentJoint, second, rates)
            approach[slot] = nx * (vb[0] - va[0]) + ny * (vb[1] - va[1]) + nz * (vb[2] - va[2])
        return approach

    def _point_velocity(self, joint: int, point: list[float], rates: list[float]) -> tuple[float, float, float]:
        """World velocity (m/s) of ``point`` (world, m) fixed to ``joint``'s body under
        ``rates`` (nv,): the joint's ``LOCAL_WORLD_ALIGNED`` twist (v, ω), v + ω × (p - o)."""
        if joint == 0:
            return 0.0, 0.0, 0.0
        jacobian = pin.getJointJacobian(self._model, self._data, joint, pin.ReferenceFrame.LOCAL_WORLD_ALIGNED)
        twist = []
        for row in jacobian.reshape(6, self._model.nv).tolist():  # one joint: eigenpy's vector
            total = 0.0
            for entry, rate in zip(row, rates, strict=True):
                total += entry * rate
            twist.append(total)
        vx, vy, vz, wx, wy, wz = twist
        origin = self._data.oMi[joint].translation.tolist()
        rx, ry, rz = point[0] - origin[0], point[1] - origin[1], point[2] - origin[2]
        return vx + (wy * rz - wz * ry), vy + (wz * rx - wx * rz), vz + (wx * ry - wy * rx)

    # ------------------------------------------------------------------ limiting
    def limit(self, q: np.ndarray, joint_rates: np.ndarray, dt: float) -> CollisionVerdict:
        """The verdict on a step of ``joint_rates`` (nv,) over ``dt`` (s) from q (see the module)."""
        if not self.active:
            return CollisionVerdict(1.0, Status.OK, "")
        distances = self._distances(q)
        near = [int(index) for index in np.flatnonzero(distances < self.safety_distance)]
        if not near:
            return CollisionVerdict(1.0, Status.OK, "")
        approach = self.approach_rates(q, joint_rates, near)
        span = self.safety_distance - self.stop_distance
        scale, limiting = 1.0, -1
        for index, rate in zip(near, approach, strict=True):
            if rate >= 0.0:
                continue  # separating: never limited
            room = float(distances[index]) - self.stop_distance
            allowed = min(APPROACH_SPEED * room / (span * -rate), room / (-rate * dt))
            if allowed < scale:
                scale, limiting = max(allowed, 0.0), index
        if scale > 0.0:
            after = self._near_distances(near, self.robot.integrate(q, joint_rates * scale, dt))
            closing = [i for i, d in zip(near, after, strict=True) if d < self.stop_distance and d < distances[i]]
            if closing:
                scale, limiting = 0.0, closing[0]
        if limiting < 0:
            return CollisionVerdict(1.0, Status.OK, "")
        return self.verdict(scale, limiting, float(distances[limiting]))

    def verdict(self, scale: float, limiting: int, distance: float) -> CollisionVerdict:
        """The verdict of a step whose rates the pair ``limiting`` (its index in the pair list,
        ``distance`` m apart at q) scales by ``scale``: a halt under :data:`HALT_SCALE`, else a
        deceleration; in words (the compiled monitor's verdicts are said here too)."""
        first, second = self.pairs[limiting]
        where = f"{first} and {second} are {distance:.3g} m apart"
        if scale < HALT_SCALE:
            return CollisionVerdict(0.0, Status.HALT_FOR_COLLISION, f"{where}: halted before {self.stop_distance:g} m")
        return CollisionVerdict(scale, Status.DECELERATE_FOR_COLLISION, f"{where}: rates scaled by {scale:.2g}")


def _geometry_data(geometry: pin.GeometryModel) -> pin.GeometryData:
    """pin's GeometryData for ``geometry``, each pair's GJK started from its bounding boxes'
    centres (every geometry's local box is computed when the monitor is built), or from
    coal's default guess where a kept mesh is in the pair (GJK then runs on its triangles,
    which have no box). pin's requests start it from the pair's last result
    (``enable_cached_gjk_guess``), which makes a distance depend, within GJK's tolerance, on
    the queries made before it; from the boxes, each is a function of q alone, as fast on the
    UR5 (33 µs for its 20 pairs against 35, and 50 from the default guess), and the compiled
    monitor reads the same to the bit whatever either was asked before (a step handed back to
    Python, a ``nearest()``)."""
    data = pin.GeometryData(geometry)
    objects = geometry.geometryObjects
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", DeprecationWarning)  # coal's binding deprecates the flag
        for pair, request in zip(geometry.collisionPairs, data.distanceRequests, strict=True):
            request.enable_cached_gjk_guess = False
            meshes = any(hasattr(objects[index].geometry, "num_tris") for index in (pair.first, pair.second))
            if not meshes:
                request.gjk_initial_guess = coal.GJKInitialGuess.BoundingVolumeGuess
    return data


def _to_convex_hull(geometry_object: pin.GeometryObject) -> str:
    """Replace a triangle mesh by its convex hull, computed by coal (qhull) on a copy of the
    mesh (the robot's collision model keeps its own). The hull contains the mesh, so GJK never
    reads two hulls farther apart than their meshes (up to GJK's tolerance: see the module);
    and GJK on hulls is far faster than coal's distance on meshes.

    Not ``buildConvexRepresentation``: that wraps the mesh's own triangles as a ``Convex``,
    whose support point coal finds (past 32 vertices) by climbing from vertex to neighbouring
    vertex, which reaches the extreme vertex only on a convex polyhedron: on a non-convex mesh
    it stops at a vertex extreme among its neighbours alone, and GJK reads the links too far
    apart (issue 23: a UR5 whose meshes touch read 1.6 cm apart; on the same vertices, a point
    read up to 0.44 m farther from the upper arm than from its hull).

    Returns "" when the geometry was hulled or is not a mesh (boxes, cylinders... stay as they
    are), else why the mesh is kept as it is: fewer than 4 vertices, non-finite or flat ones
    (qhull finds no hull, and coal 3.0 then ends the process instead of raising: see
    :data:`_FLAT`), or coal's error (a hull vertex with 255 neighbours or more). A kept mesh
    is exact, so still conservative, only slower."""
    geometry = geometry_object.geometry
    if not hasattr(geometry, "buildConvexHull") or geometry.num_tris == 0:
        return ""
    points = np.asarray(geometry.vertices(), dtype=float)
    if len(points) < 4 or not np.isfinite(points).all():
        return f"{len(points)} vertices" if len(points) < 4 else "non-finite vertices"
    centered = points - points.mean(axis=0)
    axes = np.linalg.svd(centered, full_matrices=False)[2]
    extents = np.ptp(centered @ axes.T, axis=0)  # along the principal axes, largest first
    if extents[2] <= _FLAT * extents[0]:
        return f"flat ({extents[2]:.3g} m thick across {extents[0]:.3g} m)"
    mesh = geometry.clone()
    try:
        mesh.buildConvexHull(False, "")
    except (RuntimeError, ValueError) as error:
        return f"coal: {str(error).strip().splitlines()[-1]}"
    geometry_object.geometry = mesh.convex
    return ""


def monitor_for(robot: Robot, collision: object) -> CollisionMonitor | None:
    """The monitor ``Controller(collision=...)`` asks for on ``robot``: None for False (or
    None) and where the robot has no collision geometry; a new one for True; the given one,
    built on this very Robot. InputError otherwise."""
    if isinstance(collision, CollisionMonitor):
        if collision.robot is not robot:
            raise InputError("the CollisionMonitor was built for another Robot object; build it on this one")
        return collision if collision.active else None
    if collision is False or collision is None:
        return None
    if collision is True:
        monitor = CollisionMonitor(robot)
        return monitor if monitor.active else None
    raise InputError(f"collision must be True, False or a CollisionMonitor, not {collision!r}")


__all__ = [
    "APPROACH_SPEED",
    "COINCIDENT",
    "HALT_SCALE",
    "SAFETY_DISTANCE",
    "STOP_DISTANCE",
    "CollisionMonitor",
    "CollisionVerdict",
    "Proximity",
    "monitor_for",
]
