"""Reachable targets near a configuration: what the demo and the benchmarks servo to."""

from __future__ import annotations

import numpy as np

from .home import LIMIT_MARGIN
from .manipulator import Robot
from .partition import Partition

TARGET_SPREAD = 0.4
"""Half-width (rad or m) of the uniform offset from home that picks a nearby target."""


def nearby_target(
    robot: Robot,
    partition: Partition,
    seed: int | None,
    *,
    spread: float = TARGET_SPREAD,
    start: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """(q_target, world_T_tip at q_target): ``start`` (default: home) moved by a uniform random
    offset in [-spread, spread] of each partition joint, clipped to the joint limits less
    :data:`~pinrate.kinematics.home.LIMIT_MARGIN` of each range (a target on a limit would
    stop the servo there). Reachable by construction."""
    rng = np.random.default_rng(seed)
    home = robot.home() if start is None else robot.check_q(start)
    offset = np.zeros(robot.nv)
    for joint in partition.joints:
        offset[robot.velocity_indices(joint)] = rng.uniform(-spread, spread)
    q_target = robot.integrate(home, offset, 1.0)
    for joint in partition.joints:
        limits = robot.joint_limits(joint)  # None for continuous and multi-DOF joints
        if limits is not None:
            low, high = limits
            margin = LIMIT_MARGIN * (high - low)
            index = robot.model.joints[robot.joint_id(joint)].idx_q
            q_target[index] = min(max(q_target[index], low + margin), high - margin)
    return q_target, robot.pose(q_target)
