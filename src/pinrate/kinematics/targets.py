"""Reachable targets near a configuration: what the demo and the benchmarks servo to."""

from __future__ import annotations

import numpy as np

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
    offset in [-spread, spread] of each partition joint, clipped to the joint limits.
    Reachable by construction."""
    rng = np.random.default_rng(seed)
    home = robot.home() if start is None else robot.check_q(start)
    offset = np.zeros(robot.nv)
    for joint in partition.joints:
        offset[robot.velocity_indices(joint)] = rng.uniform(-spread, spread)
    q_target = robot.integrate(home, offset, 1.0)
    lower, upper = robot.position_limits()
    q_target = np.where(np.isfinite(lower) & np.isfinite(upper), np.clip(q_target, lower, upper), q_target)
    return q_target, robot.pose(q_target)
