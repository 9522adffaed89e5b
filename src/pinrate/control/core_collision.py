"""The self-collision monitor in the compiled core: a :class:`~.collision.CollisionMonitor`
handed to ``pinrate_core.Collision`` once, as plain arrays (``core/src/collision.hpp``).

The Python monitor decides what is watched: its geometries and pairs (the SRDF's, the
adjacent and the in-contact pairs removed) and its rules (its safety and stop distances,
:data:`~.collision.APPROACH_SPEED`, :data:`~.collision.HALT_SCALE`,
:data:`~.collision.COINCIDENT`, and the settings of its distance requests). The core gets,
per geometry, its parent joint, its placement in that joint's frame (4x4, m) and its shape:
a hulled mesh's vertices (the core hulls them by the same coal call on the same vertices, so
the hulls are the same), a mesh kept as it is (vertices and triangles), or a box, sphere,
cylinder or capsule by its dimensions (m). Per step it makes the monitor's calls on its own
forward kinematics: coal's distance per pair, the velocity damper, the check at the
integrated q (:meth:`.CollisionMonitor.limit`); it returns the limiting pair, its distance
and the scale, which :meth:`.CollisionMonitor.verdict` says in words.

coal is a shared library the core links: the core is used for the monitor only where the
coal that runs is the release it was built on (``pinrate_core.COAL_VERSION``), since coal
makes no promise of a stable binary interface between releases.
"""

from __future__ import annotations

import warnings
import weakref
from typing import Any

import coal
import numpy as np

from ..compiled import core_kinematics, core_module
from ..errors import UnsupportedByCoreError
from .collision import APPROACH_SPEED, COINCIDENT, HALT_SCALE, CollisionMonitor

_PRIMITIVES = {
    # coal shape: (the core's kind, its dimensions (m) as the core takes them)
    "Box": ("box", lambda shape: [float(x) for x in shape.halfSide]),
    "Sphere": ("sphere", lambda shape: [float(shape.radius)]),
    "Cylinder": ("cylinder", lambda shape: [float(shape.radius), float(shape.halfLength)]),
    "Capsule": ("capsule", lambda shape: [float(shape.radius), float(shape.halfLength)]),
}

_built: weakref.WeakKeyDictionary[CollisionMonitor, Any] = weakref.WeakKeyDictionary()


def _shape(monitor: CollisionMonitor, index: int, used: bool) -> tuple[str, list[float], list[int]]:
    """Geometry ``index`` of the monitor as the core takes it: (kind, numbers, triangles).

    Raises:
        UnsupportedByCoreError: a shape the core does not rebuild, or one inflated by a swept
            sphere.
    """
    if not used:
        return "unused", [], []
    placed = monitor._geometry.geometryObjects[index]
    shape, source = placed.geometry, monitor.sources[index]
    kind = type(shape).__name__
    if hasattr(shape, "getSweptSphereRadius") and shape.getSweptSphereRadius() != 0.0:
        raise UnsupportedByCoreError(f"{placed.name} is inflated by a swept sphere, which the compiled core does not")
    if kind.startswith("Convex") and type(source).__name__.startswith("BVHModel"):
        # hulled by the monitor (a URDF gives meshes, never hulls): the core hulls the same vertices
        return "hull", np.asarray(source.vertices(), dtype=float).ravel().tolist(), []
    if hasattr(shape, "num_tris") and hasattr(shape, "vertices"):  # a mesh kept as it is
        triangles = [int(corner) for i in range(shape.num_tris) for corner in _corners(shape.tri_indices(i))]
        return "mesh", np.asarray(shape.vertices(), dtype=float).ravel().tolist(), triangles
    if kind in _PRIMITIVES:
        name, dimensions = _PRIMITIVES[kind]
        return name, dimensions(shape), []
    raise UnsupportedByCoreError(f"{placed.name} is a {kind}, which the compiled collision monitor does not rebuild")


def _corners(triangle: Any) -> tuple[int, int, int]:
    return int(triangle[0]), int(triangle[1]), int(triangle[2])


def _build(core: Any, monitor: CollisionMonitor) -> Any:
    kinematics = core_kinematics(monitor.robot)
    built_on = getattr(core, "COAL_VERSION", None)
    if built_on != coal.__version__:
        raise UnsupportedByCoreError(
            f"the compiled core was built on coal {built_on}, and coal {coal.__version__} runs: the collision "
            "monitor runs on the Python path (rebuild the core: pip install ./core)"
        )
    objects = monitor._geometry.geometryObjects
    pairs = monitor._pairs
    used = {index for pair in pairs for index in pair}
    shapes = [_shape(monitor, index, index in used) for index in range(len(objects))]
    request = monitor._geometry_data.distanceRequests[0]
    with warnings.catch_warnings():
        # coal's binding deprecates the flag, which pin's GeometryData still sets on every request
        warnings.simplefilter("ignore", DeprecationWarning)
        cached_gjk_guess = bool(request.enable_cached_gjk_guess)
    return core.Collision(
        kinematics=kinematics,
        kinds=[kind for kind, _, _ in shapes],
        numbers=[numbers for _, numbers, _ in shapes],
        triangles=[triangles for _, _, triangles in shapes],
        joints=[int(geometry_object.parentJoint) for geometry_object in objects],
        placements=np.ascontiguousarray(
            np.array([geometry_object.placement.homogeneous for geometry_object in objects]).reshape(-1, 4, 4)
        ),
        firsts=[first for first, _ in pairs],
        seconds=[second for _, second in pairs],
        safety_distance=monitor.safety_distance,
        stop_distance=monitor.stop_distance,
        approach_speed=APPROACH_SPEED,
        halt_scale=HALT_SCALE,
        coincident=COINCIDENT,
        gjk_tolerance=float(request.gjk_tolerance),
        cached_gjk_guess=cached_gjk_guess,
        gjk_initial_guesses=[str(each.gjk_initial_guess.name) for each in monitor._geometry_data.distanceRequests],
    )


def core_monitor(monitor: CollisionMonitor) -> Any:
    """``monitor``'s ``pinrate_core.Collision`` (built once per monitor and kept with it).

    Raises:
        UnsupportedByCoreError: the Python path is chosen, the robot or a geometry is not
            rebuilt by the core, or the core was built on another coal release.
    """
    core = core_module()
    if core is None:
        raise UnsupportedByCoreError("the Python path is chosen")
    built = _built.get(monitor)
    if built is None:
        try:
            built = _built[monitor] = _build(core, monitor)
        except UnsupportedByCoreError as unsupported:
            _built[monitor] = unsupported
            raise
    if isinstance(built, UnsupportedByCoreError):
        raise UnsupportedByCoreError(str(built))
    return built


def python_reason(monitor: CollisionMonitor | None) -> str | None:
    """Why ``monitor`` runs on Python (None where the core runs it, or there is no monitor)."""
    if monitor is None:
        return None
    try:
        core_monitor(monitor)
    except UnsupportedByCoreError as unsupported:
        return str(unsupported)
    return None


def core_verdict_detail(monitor: CollisionMonitor, compiled: Any) -> str:
    """The detail of the compiled monitor's last verdict, in the Python monitor's words."""
    _, scale, pair, distance = compiled.last()
    return monitor.verdict(scale, pair, distance).detail


__all__ = ["core_monitor", "core_verdict_detail", "python_reason"]
