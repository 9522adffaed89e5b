"""A non-singular home for any URDF (contract v2, "Robot defaults for any URDF").

Pinocchio's neutral pose (all zeros) is singular for most arms: a stretched elbow, aligned
wrist axes. ``Robot.home()`` is never singular when a well-conditioned configuration exists
within the joint limits: the SRDF's group_state named ``home`` (else its first) when that is
well-conditioned, else neutral when it is well-conditioned and clear of the limits, else the
best of a deterministic search near neutral (clear of the limits), else neutral.

Well-conditioned means: the smallest singular value of the partition's Jacobian, and of
each square block A and W that MCA1/2/3 invert (Shoham & Koren eq. 19, 24-25), is at least
:data:`WELL_CONDITIONED` (m/rad or 1/rad, in the sensor frame's units).
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from .manipulator import Robot
from .partition import Partition, split_blocks

WELL_CONDITIONED = 1e-3
"""Smallest singular value a home's partition Jacobian and square blocks must reach."""

SEARCH_FRACTIONS = (0.05, 0.1, 0.2, 0.4, 0.7, 1.0)
"""How far from neutral the search looks, as fractions of each joint's half range, in order."""

LIMIT_MARGIN = 0.05
"""Searched homes keep this fraction of each joint's range away from its limits."""

SEARCH_DRAWS = 32
"""Configurations tried at each distance (seeded: the search is deterministic)."""


def conditioning(robot: Robot, partition: Partition, q: np.ndarray) -> float:
    """min over the partition's J and its square blocks A, W of the smallest singular value at q."""
    index = partition.resolve(robot)
    jacobian = robot.jacobian_unchecked(q)[np.ix_(index.rows, index.columns)]
    if jacobian.size == 0:
        return 0.0
    values = [float(np.linalg.svd(jacobian, compute_uv=False).min())]
    A, _, _, W = split_blocks(jacobian, index.m, len(index.arm_columns))
    for block in (A, W):
        if block.size and block.shape[0] == block.shape[1]:
            values.append(float(np.linalg.svd(block, compute_uv=False).min()))
    return min(values)


def srdf_states(path: Path) -> list[str]:
    """The group_state names of an SRDF, in file order (empty when it cannot be read)."""
    try:
        root = ET.parse(path).getroot()
    except (ET.ParseError, OSError):
        return []
    return [state.get("name", "") for state in root.iter("group_state") if state.get("name")]


def find_home(
    robot: Robot, partition: Partition, named: Sequence[tuple[str, np.ndarray]] = ()
) -> tuple[np.ndarray, str]:
    """(q, why): the first of ``named`` (label, q) that is well-conditioned, else neutral if it
    is, else the best-conditioned of SEARCH_DRAWS seeded draws at the smallest distance from
    neutral (SEARCH_FRACTIONS) where one passes, else neutral."""
    for label, q in named:
        if conditioning(robot, partition, q) >= WELL_CONDITIONED:
            return q.copy(), label
    neutral = robot.neutral()
    if conditioning(robot, partition, neutral) >= WELL_CONDITIONED and not _near_a_limit(robot, partition, neutral):
        return neutral, "neutral (well-conditioned)"
    generator = np.random.default_rng(0)
    joints = [joint for joint in partition.joints if robot.model.joints[robot.joint_id(joint)].nv == 1]
    for fraction in SEARCH_FRACTIONS:
        draws = np.tile(neutral, (SEARCH_DRAWS, 1))
        for joint in joints:
            low, high = robot.joint_range(joint)
            # A home on a limit would stop the first motion towards it: keep a margin.
            low, high = low + LIMIT_MARGIN * (high - low), high - LIMIT_MARGIN * (high - low)
            centre = 0.0 if low <= 0.0 <= high else (low + high) / 2  # neutral, or mid-range if outside
            half = (high - low) / 2 if math.isfinite(high - low) else math.pi
            values = np.clip(centre + fraction * half * generator.uniform(-1.0, 1.0, SEARCH_DRAWS), low, high)
            robot.set_joint_values(draws, joint, values)
        scores = [conditioning(robot, partition, q) for q in draws]
        best = int(np.argmax(scores))
        if scores[best] >= WELL_CONDITIONED:
            return draws[best], (
                f"searched near neutral: the best-conditioned of {SEARCH_DRAWS} configurations within "
                f"{fraction:.0%} of each joint's half range (smallest singular value {scores[best]:.3g})"
            )
    return neutral, "neutral (singular; no well-conditioned configuration found near it)"


def _near_a_limit(robot: Robot, partition: Partition, q: np.ndarray) -> bool:
    """Whether a partition joint of q is within LIMIT_MARGIN of its range from a limit."""
    for joint in partition.joints:
        limits = robot.joint_limits(joint)
        if limits is None:
            continue
        low, high = limits
        value = q[robot.model.joints[robot.joint_id(joint)].idx_q]
        if min(value - low, high - value) < LIMIT_MARGIN * (high - low):
            return True
    return False
