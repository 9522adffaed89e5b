"""A Robot's kinematics rebuilt in the compiled core: its joints, placements, tip and sensor.

The core rebuilds a private Pinocchio model from the Python model's arrays (joint kinds,
parents, placements, the tip and sensor frames), so it links no Pinocchio library and makes
the same Pinocchio calls on the same numbers as the Python side. It reads them once per
Robot: after editing ``robot.model``'s joints or frames in place, load a new Robot (limits
are not part of the rebuilt model: the controller passes them each run).
"""

from __future__ import annotations

import weakref
from typing import Any

import numpy as np
import pinocchio as pin

from ..errors import UnsupportedByCoreError
from ..kinematics.manipulator import Robot
from .boundary import REBUILT_JOINTS
from .core import core_module

_UNALIGNED = ("JointModelRevoluteUnaligned", "JointModelRevoluteUnboundedUnaligned", "JointModelPrismaticUnaligned")


_cache: weakref.WeakKeyDictionary[Robot, Any] = weakref.WeakKeyDictionary()


def _joint_arrays(robot: Robot) -> tuple[list[str], list[int], np.ndarray, np.ndarray]:
    """(kinds, parents, axes (nj, 3), placements (nj, 4, 4)) of the joints 1.. of the model.

    Raises:
        UnsupportedByCoreError: a joint kind outside :data:`REBUILT_JOINTS`.
    """
    model = robot.model
    kinds, parents, axes, placements = [], [], [], []
    for joint_id in range(1, model.njoints):
        joint = model.joints[joint_id]
        kind = joint.shortname()
        if kind not in REBUILT_JOINTS:
            name = model.names[joint_id]
            raise UnsupportedByCoreError(f"joint {name!r} is a {kind}, which the compiled core does not rebuild")
        axis = _unaligned_axis(model, joint_id, kind) if kind in _UNALIGNED else np.zeros(3)
        kinds.append(kind)
        parents.append(int(model.parents[joint_id]))
        axes.append(axis)
        placements.append(np.array(model.jointPlacements[joint_id].homogeneous))
    return kinds, parents, np.array(axes).reshape(-1, 3), np.array(placements).reshape(-1, 4, 4)


def _unaligned_axis(model: pin.Model, joint_id: int, kind: str) -> np.ndarray:
    """The joint's axis as Pinocchio stores it: its motion at unit joint velocity, in its own
    frame (pin exposes ``axis`` on some unaligned joints only; S times 1.0 is the axis to the
    bit)."""
    data = model.createData()
    velocity = np.zeros(model.nv)
    velocity[model.joints[joint_id].idx_v] = 1.0
    pin.forwardKinematics(model, data, pin.neutral(model), velocity)
    motion = data.v[joint_id]
    return np.array(motion.linear if kind == "JointModelPrismaticUnaligned" else motion.angular, dtype=float)


def core_kinematics(robot: Robot) -> Any:
    """The robot's ``pinrate_core.Kinematics`` (built once per Robot), or None where the
    Python path is chosen.

    Raises:
        UnsupportedByCoreError: the robot has a joint the core does not rebuild, or a mimic
            joint between the base and the tip (the core's Jacobian does not fold it into its
            leader's column, :mod:`pinrate.kinematics.mimic`).
    """
    core = core_module()
    if core is None:
        return None
    if robot.folds_mimics:
        on_path = [name for name in robot.tip_chain() if name in robot.mimics.relations]
        raise UnsupportedByCoreError(
            f"mimic joint {', '.join(map(repr, on_path))} lies between the base and the tip, and the compiled "
            "core's Jacobian does not fold a mimic joint into its leader's column: the Python path runs"
        )
    kinematics = _cache.get(robot)
    if kinematics is None:
        kinds, parents, axes, placements = _joint_arrays(robot)
        frames = robot.model.frames
        tip, sensor = frames[robot.tip_id], frames[robot.sensor_id]
        kinematics = core.Kinematics(
            kinds=kinds,
            parents=parents,
            axes=np.ascontiguousarray(axes),
            placements=np.ascontiguousarray(placements),
            tip_joint=int(tip.parentJoint),
            tip_placement=np.ascontiguousarray(tip.placement.homogeneous),
            sensor_joint=int(sensor.parentJoint),
            sensor_placement=np.ascontiguousarray(sensor.placement.homogeneous),
            same_frame=robot.sensor_id == robot.tip_id,
        )
        _cache[robot] = kinematics
    return kinematics
