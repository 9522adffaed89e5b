"""Frames of a Pinocchio model: resolving a name, and the default tip of any URDF."""

from __future__ import annotations

import pinocchio as pin

from ..errors import FrameError, InputError, choices_hint

FRAME_PREFERENCE = (
    pin.FrameType.BODY,
    pin.FrameType.OP_FRAME,
    pin.FrameType.SENSOR,
    pin.FrameType.JOINT,
    pin.FrameType.FIXED_JOINT,
)
"""Frame types in the order a name is resolved: a link wins over a joint of the same name."""


def resolve_frame(model: pin.Model, name: str, *, role: str, robot: str = "") -> int:
    """Index of the frame called ``name``; a link wins over a joint of the same name.

    Raises:
        FrameError: no such frame (the message lists the frames, closest first).
    """
    if not isinstance(name, str):
        raise InputError(f"{role} must be a frame name (str), not {type(name).__name__}")
    for frame_type in FRAME_PREFERENCE:
        if model.existFrame(name, frame_type):
            return int(model.getFrameId(name, frame_type))
    frames = list(dict.fromkeys(frame.name for frame in model.frames))
    raise FrameError(
        f"robot {robot or model.name!r} has no frame {name!r} (asked as {role})."
        + choices_hint(name, frames, limit=200)
    )


def default_tip_frame(model: pin.Model) -> int:
    """The deepest frame at the end of the longest chain of moving joints (ties: model order).

    The longest chain ends at the moving joint with the most moving joints in its support;
    among the frames attached to it, the one with the most ancestor frames wins, links
    preferred over joint frames.
    """

    def moving_depth(joint_id: int) -> int:
        return sum(1 for j in model.supports[joint_id] if j > 0 and model.joints[j].nv > 0)

    moving = [j for j in range(1, model.njoints) if model.joints[j].nv > 0]
    if not moving:
        return len(model.frames) - 1
    end_joint = max(moving, key=lambda j: (moving_depth(j), -j))

    def frame_depth(frame_id: int) -> int:
        depth = 0
        while frame_id != 0 and model.frames[frame_id].parentJoint == end_joint:
            frame_id = model.frames[frame_id].parentFrame
            depth += 1
        return depth

    attached = [f for f, frame in enumerate(model.frames) if frame.parentJoint == end_joint]
    return max(attached, key=lambda f: (frame_depth(f), model.frames[f].type == pin.FrameType.BODY, -f))
