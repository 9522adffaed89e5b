"""Frames of a Pinocchio model: resolving a name, and the default tip of any URDF."""

from __future__ import annotations

import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

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


TOOL_NAMES = (
    ("tcp", "tool_center", "toolcenter", "grasp"),
    ("tool0", "tool"),
    ("end_effector", "endeffector", "eef", "ee"),
    ("gripper",),
    ("hand", "flange"),
)
"""Name fragments of tool-centre frames, best first (matched on ``_``-separated words, and
as substrings for the longer ones)."""

HAND_JOINT_WORDS = ("finger", "gripper", "jaw", "thumb", "knuckle", "claw", "palm", "pinch", "hand")
"""Words in a moving joint's name that make it a joint of a gripper or hand, not of the arm."""


@dataclass(frozen=True)
class TipChoice:
    """The default tip of a model and why: its frame, the joints left out of the arm (gripper
    and hand joints; mimic joints that follow an arm joint, :func:`arm_mimics`)."""

    frame_id: int
    reason: str
    hand_joints: tuple[str, ...]
    arm_mimics: tuple[str, ...] = ()


def mimic_groups(model: pin.Model, mimic: Mapping[str, str] | None) -> list[set[int]]:
    """Joints coupled by ``<mimic>`` (joint -> the joint it mimics), as sets of joint ids: a
    mimicked joint with every joint that mimics it, directly or through another mimic."""
    groups: list[set[int]] = []
    for follower, leader in (mimic or {}).items():
        if not (model.existJointName(follower) and model.existJointName(leader)):
            continue
        pair = {int(model.getJointId(follower)), int(model.getJointId(leader))}
        touching = [group for group in groups if group & pair]
        merged = pair.union(*touching)
        groups = [group for group in groups if not group & pair] + [merged]
    return groups


def hand_joints(model: pin.Model, mimic: Mapping[str, str] | None = None) -> tuple[str, ...]:
    """Moving joints of grippers and hands, which are not part of the arm (contract v2):
    joints whose range is zero, joints named like a hand part (:data:`HAND_JOINT_WORDS`), and,
    at the end of the chain, prismatic joints and mimic groups (a mimicked joint and the joints
    that mimic it).

    At the end of the chain: no moving joint of the arm below any joint of the group (only
    the group's own joints and other hand joints; repeated, as one finger may sit below
    another). A group with arm joints below it is part of the arm's kinematics, not a hand:
    its mimicked joint stays in the arm (an IRB 6640's shoulder with its parallelogram links,
    an SDA10F's torso) and the joints that mimic it follow it (:func:`arm_mimics`).
    Empty when that would leave no joint at all (a hand on its own is its own arm).
    """
    moving = [j for j in range(1, model.njoints) if model.joints[j].nv > 0]
    names = {j: model.names[j] for j in moving}
    hand = set()
    for joint_id, name in names.items():
        joint_model = model.joints[joint_id]
        words = set(re.split(r"[^a-z0-9]+", name.lower()))
        lower = model.lowerPositionLimit[joint_model.idx_q : joint_model.idx_q + joint_model.nq]
        upper = model.upperPositionLimit[joint_model.idx_q : joint_model.idx_q + joint_model.nq]
        if (joint_model.nq == 1 and float(upper[0] - lower[0]) <= 0.0) or any(
            _names_part(word, name, words) for word in HAND_JOINT_WORDS
        ):
            hand.add(joint_id)
    prismatic = [{j} for j in moving if model.joints[j].shortname().startswith("JointModelP")]
    candidates = [group & set(moving) for group in mimic_groups(model, mimic)] + prismatic
    changed = True
    while changed:
        changed = False
        for group in candidates:
            if group <= hand:
                continue
            below = {j for joint in group for j in model.subtrees[joint] if j in names} - group - hand
            if not below:
                hand |= group
                changed = True
    if len(hand) == len(moving):
        return ()
    return tuple(names[j] for j in moving if j in hand)


def arm_mimics(model: pin.Model, mimic: Mapping[str, str] | None, hand: Sequence[str]) -> tuple[str, ...]:
    """Mimic joints whose group is part of the arm (not in ``hand``): they follow the joint
    they mimic, so they are never an arm or wrist joint of their own (contract v2)."""
    left_out = set(hand)
    return tuple(
        follower
        for follower, leader in (mimic or {}).items()
        if model.existJointName(follower) and model.existJointName(leader) and follower not in left_out
    )


def _names_part(word: str, name: str, words: set[str]) -> bool:
    """Whether ``name`` (split into ``words``) names a hand part: a long word anywhere
    (``jointGripper``), a short one only as a whole word or followed by digits (``hand``,
    ``jaw1``; not ``handle``)."""
    if len(word) > 4:
        return word in name.lower()
    return any(part == word or (part.startswith(word) and part[len(word) :].isdigit()) for part in words)


def _tool_rank(name: str) -> int:
    """0 for the best tool-centre name, len(TOOL_NAMES) for a name like no tool at all."""
    words = set(re.split(r"[^a-z0-9]+", name.lower()))
    for rank, fragments in enumerate(TOOL_NAMES):
        for fragment in fragments:
            if fragment in words or (len(fragment) > 3 and fragment in name.lower()):
                return rank
    return len(TOOL_NAMES)


def default_tip_frame(model: pin.Model, mimic: Mapping[str, str] | None = None) -> TipChoice:
    """The tool frame of the main arm (contract v2, "Robot defaults for any URDF").

    The arm is the moving joints less the hand joints (:func:`hand_joints`) and the mimic
    joints that follow an arm joint (:func:`arm_mimics`); the main arm ends at the arm joint
    with the most arm joints in its support (ties: model order). Among the frames fixed to
    that joint, a name like a tool centre wins (:data:`TOOL_NAMES`, best first), then the
    deepest frame, links before joint frames.
    """
    left_out = set(hand_joints(model, mimic))
    followers = arm_mimics(model, mimic, tuple(left_out))
    arm = [
        j
        for j in range(1, model.njoints)
        if model.joints[j].nv > 0 and model.names[j] not in left_out and model.names[j] not in followers
    ]
    if not arm:
        return TipChoice(len(model.frames) - 1, "the last frame (no moving joint)", (), followers)

    def arm_depth(joint_id: int) -> int:
        return sum(1 for j in model.supports[joint_id] if j in arm)

    end_joint = max(arm, key=lambda j: (arm_depth(j), -j))

    def frame_depth(frame_id: int) -> int:
        depth = 0
        while frame_id != 0 and model.frames[frame_id].parentJoint == end_joint:
            frame_id = model.frames[frame_id].parentFrame
            depth += 1
        return depth

    attached = [f for f, frame in enumerate(model.frames) if frame.parentJoint == end_joint]
    best = min(
        attached,
        key=lambda f: (
            _tool_rank(model.frames[f].name),
            -frame_depth(f),
            model.frames[f].type != pin.FrameType.BODY,
            f,
        ),
    )
    named = _tool_rank(model.frames[best].name) < len(TOOL_NAMES)
    how = "named like a tool centre" if named else "the deepest frame"
    reason = f"chosen: {how} on {model.names[end_joint]!r}, the last joint of the longest arm chain"
    if left_out:
        shown = ", ".join(sorted(left_out)[:6]) + (" ..." if len(left_out) > 6 else "")
        reason += f" (gripper/hand joints left out: {shown})"
    if followers:
        reason += f" (mimic joints following an arm joint: {', '.join(sorted(followers))})"
    return TipChoice(best, reason, tuple(sorted(left_out)), followers)
