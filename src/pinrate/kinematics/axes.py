"""Joint axes and the wrist centre in the world, from Pinocchio's joint placements.

A revolute joint's axis is fixed in its own frame (:func:`local_axis`); after
``pinocchio.forwardKinematics`` at q its world direction is ``oMi.rotation @ axis``. The wrist
centre (Barker's wrist-centre decoupling) is where the first two wrist axes meet, or the
middle of their common perpendicular when they do not. A 1-DOF joint's value at q
(:func:`joint_value`) is its angle or stroke.
"""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin

PARALLEL = 1e-6
"""``|a × b|`` (or 1 - (a · b)²) under this: two unit axes are parallel."""

Axis = tuple[int, tuple[float, float, float]]
"""A revolute joint: its Pinocchio id and its unit axis in its own joint frame."""


def local_axis(model: pin.Model, joint_id: int) -> tuple[float, float, float] | None:
    """The unit axis of a 1-DOF rotating joint in its own frame (the angular part of its motion
    subspace: unit joint velocity); None for a joint that does not rotate (prismatic)."""
    data = model.createData()
    velocity = np.zeros(model.nv)
    velocity[model.joints[joint_id].idx_v] = 1.0
    pin.forwardKinematics(model, data, pin.neutral(model), velocity)
    angular = np.array(data.v[joint_id].angular)
    norm = float(np.linalg.norm(angular))
    if norm < PARALLEL:
        return None
    return tuple(float(value) for value in angular / norm)  # type: ignore[return-value]


def wrist_axes(model: pin.Model, joint_ids: list[int]) -> tuple[Axis, ...]:
    """The first two rotating 1-DOF joints among ``joint_ids`` in chain order (Pinocchio's ids
    grow from the base), with their axes: the joints that locate the wrist centre."""
    axes: list[Axis] = []
    for joint_id in sorted(joint_ids):
        if model.joints[joint_id].nv == 1 and len(axes) < 2:
            axis = local_axis(model, joint_id)
            if axis is not None:
                axes.append((joint_id, axis))
    return tuple(axes)


def world_axis(data: pin.Data, axis: Axis) -> np.ndarray:
    """The joint's unit axis in the world, after ``forwardKinematics``."""
    joint_id, local = axis
    return data.oMi[joint_id].rotation @ np.array(local)


def wrist_centre(data: pin.Data, wrist: tuple[Axis, ...], tip: np.ndarray) -> np.ndarray:
    """The wrist centre in the world (m), after ``forwardKinematics``: the midpoint of the
    common perpendicular of the first two wrist axes (their intersection on a spherical
    wrist), the first wrist joint's origin when they are parallel or there is one, ``tip``
    (the tip's origin) when there is none."""
    if not wrist:
        return tip
    first_origin = np.array(data.oMi[wrist[0][0]].translation)
    if len(wrist) == 1:
        return first_origin
    a, b = world_axis(data, wrist[0]), world_axis(data, wrist[1])
    second_origin = np.array(data.oMi[wrist[1][0]].translation)
    offset = second_origin - first_origin
    ab = float(a @ b)
    denominator = 1.0 - ab * ab
    if denominator < PARALLEL:
        return first_origin
    along_a = (float(a @ offset) - ab * float(b @ offset)) / denominator
    along_b = (ab * float(a @ offset) - float(b @ offset)) / denominator
    return 0.5 * ((first_origin + along_a * a) + (second_origin + along_b * b))


def distance_to_axis(point: np.ndarray, origin: np.ndarray, axis: np.ndarray) -> float:
    """Perpendicular distance (m) of ``point`` from the line through ``origin`` along unit ``axis``."""
    offset = point - origin
    return float(np.linalg.norm(offset - (offset @ axis) * axis))


def joint_value(model: pin.Model, joint_id: int, q: np.ndarray) -> float | None:
    """A 1-DOF joint's value at q: q itself for a joint of one coordinate (rad or m), the
    angle atan2(sin, cos) for a continuous joint (rad, its q is (cos, sin)), None for a joint
    of more freedoms."""
    joint = model.joints[joint_id]
    if joint.nq == 1:
        return float(q[joint.idx_q])
    if joint.nq == 2 and joint.nv == 1:
        return math.atan2(float(q[joint.idx_q + 1]), float(q[joint.idx_q]))
    return None


def joint_unit(model: pin.Model, joint_id: int) -> str:
    """The unit of a 1-DOF joint's value: "m" for a prismatic joint, "rad" otherwise."""
    return "m" if model.joints[joint_id].shortname().startswith("JointModelP") else "rad"


__all__ = [
    "PARALLEL",
    "Axis",
    "distance_to_axis",
    "joint_unit",
    "joint_value",
    "local_axis",
    "world_axis",
    "wrist_axes",
    "wrist_centre",
]
