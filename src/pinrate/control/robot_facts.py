"""What a controller needs of its robot and partition that no option changes: the joints'
position limits, the URDF's velocity limits, the characteristic length, the generic ranks,
the wrist's axes; computed once per robot and partition (a servo call builds a controller,
and these cost more than its loop)."""

from __future__ import annotations

import weakref
from typing import NamedTuple

import numpy as np

from ..kinematics.axes import Axis, wrist_axes
from ..kinematics.home import generic_ranks
from ..kinematics.manipulator import Robot
from ..kinematics.partition import Partition
from ..solvers.conditioning import characteristic_length


class Limit(NamedTuple):  # a tuple: the per-step test reads it on Python floats
    """A 1-DOF joint's position limits (rad or m) and where it sits in q and v."""

    joint: str
    q_index: int  # into q
    velocity: int  # into v
    lower: float
    upper: float

    def onto_the_limit(self, q: np.ndarray, rate: float, dt: float) -> float:
        """The rate, cut so that the joint ends the step on its limit at most; a joint already
        past a limit (a controller without position limits) is never driven further out, nor
        snapped back: its outward rate is cut to 0."""
        value = q[self.q_index]
        if value > self.upper:
            return min(rate, 0.0)
        if value < self.lower:
            return max(rate, 0.0)
        return min(max(rate, (self.lower - value) / dt), (self.upper - value) / dt)


VELOCITY_LIMIT_UNLIMITED = 1e6
"""A URDF velocity limit of 0 (what converters write for "unknown") or above this (rad/s or
m/s) means no limit."""


class Facts(NamedTuple):
    """What a controller needs of its robot and partition that no option changes."""

    # every 1-DOF joint with finite position limits (a jog may move any), a leader's narrowed by its
    # mimic joints' (Robot.coupled_limits); mimic joints follow their leaders, so none of their own
    limits: tuple[Limit, ...]
    urdf_velocity_limits: np.ndarray  # (nv,), inf where the URDF gives none
    characteristic_length: float  # L of J at home
    ranks: tuple[int, int, int]  # generic ranks of J, A, W
    velocity_of: dict[str, int]  # joint name -> its first velocity index
    joggable: tuple[str, ...]  # the 1-DOF joints but mimic joints (their leaders move them)
    wrist_axes: tuple[Axis, ...]  # the wrist's first two rotating joints
    wrist_body: int  # the joint whose body carries the wrist centre


FACTS_CACHE: weakref.WeakKeyDictionary[Robot, dict[Partition, tuple[tuple[bytes, ...], Facts]]] = (
    weakref.WeakKeyDictionary()
)


def robot_facts(robot: Robot, partition: Partition) -> Facts:
    """The :class:`Facts` of ``robot`` and ``partition``, computed once (a servo call builds a
    controller, and these cost more than the run's loop), and again when the model's limits or
    the home configuration they depend on were edited since."""
    model = robot.model
    home_q = robot.home()
    edited = (
        np.asarray(model.lowerPositionLimit).tobytes(),
        np.asarray(model.upperPositionLimit).tobytes(),
        np.asarray(model.velocityLimit).tobytes(),
        home_q.tobytes(),
    )
    cache = FACTS_CACHE.setdefault(robot, {})
    if partition not in cache or cache[partition][0] != edited:
        index = partition.resolve(robot)
        limits = []
        for joint in robot.joint_names:
            if joint in robot.mimics.relations:
                continue  # a mimic joint's limits are kept through its leader's (coupled_limits)
            bounds = robot.coupled_limits(joint)
            if bounds is not None:
                joint_model = model.joints[robot.joint_id(joint)]
                limits.append(Limit(joint, joint_model.idx_q, joint_model.idx_v, *bounds))
        urdf = np.array(model.velocityLimit, dtype=float)
        home = robot.jacobian_unchecked(home_q)[np.ix_(index.rows, index.columns)]
        wrist_ids = [robot.joint_id(name) for name in partition.wrist]
        cache[partition] = (
            edited,
            Facts(
                limits=tuple(limits),
                urdf_velocity_limits=np.where((urdf > 0) & (urdf < VELOCITY_LIMIT_UNLIMITED), urdf, np.inf),
                characteristic_length=characteristic_length(home, index.m),
                ranks=generic_ranks(robot, partition),
                velocity_of={name: model.joints[robot.joint_id(name)].idx_v for name in robot.joint_names},
                joggable=tuple(
                    name
                    for name in robot.joint_names
                    if model.joints[robot.joint_id(name)].nv == 1 and name not in robot.mimics.relations
                ),
                wrist_axes=wrist_axes(model, wrist_ids),
                # The wrist centre rides on the body that carries the first wrist joint of the
                # chain (or the tip's body without a wrist).
                wrist_body=model.parents[min(wrist_ids)] if wrist_ids else model.frames[robot.tip_id].parentJoint,
            ),
        )
    return cache[partition][1]


__all__ = ["VELOCITY_LIMIT_UNLIMITED", "Facts", "Limit", "robot_facts"]
