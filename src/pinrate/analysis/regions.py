"""Region maps: ρ over a grid of two joints, the others fixed (the papers' Fig. 5, 8, 12)."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from ..checks import MAX_GRID_POINTS, as_rng, check_count
from ..errors import InputError
from ..kinematics.manipulator import Robot
from ..kinematics.partition import Partition, partition_for
from ..theorem.sampling import spectral_radius_at

_SENSITIVITY_BASES = 24  # base configurations when ranking joints by their effect on ρ
_SENSITIVITY_STEPS = 9  # values of the moved joint per base configuration
_RHO_CLIP = 4.0  # ρ above this counts as 4 when ranking joints (poles would dominate)


@dataclass(frozen=True)
class RegionMap:
    """ρ on a grid of two joints, the others at ``base``."""

    joints: tuple[str, str]
    x: np.ndarray  # values of joints[0] (nx,)
    y: np.ndarray  # values of joints[1] (ny,)
    spectral_radius: np.ndarray  # (ny, nx)
    base: np.ndarray  # the configuration the other joints are taken from

    @property
    def fraction(self) -> float:
        """Share of the grid with ρ < 1."""
        return float(np.mean(self.spectral_radius < 1.0))


def joint_sensitivity(robot: Robot, *, partition: Partition | None = None, rng: int = 5) -> dict[str, float]:
    """How much ρ changes when each partition joint moves alone (mean spread, ρ clipped at 4)."""
    partition = partition_for(robot, partition)
    generator = as_rng(rng)
    bases = robot.sample_configurations(_SENSITIVITY_BASES, generator, joints=partition.joints)
    sensitivity = {}
    for joint in partition.joints:
        values = np.linspace(*robot.joint_range(joint), _SENSITIVITY_STEPS)
        configurations = np.repeat(bases, _SENSITIVITY_STEPS, axis=0)
        robot.set_joint_values(configurations, joint, np.tile(values, _SENSITIVITY_BASES))
        radii = np.minimum(spectral_radius_at(robot, configurations, partition=partition), _RHO_CLIP)
        sensitivity[joint] = float(np.mean(np.std(radii.reshape(_SENSITIVITY_BASES, _SENSITIVITY_STEPS), axis=1)))
    return sensitivity


def default_map_joints(robot: Robot, *, partition: Partition | None = None) -> tuple[str, str]:
    """The two 1-DOF partition joints ρ varies most with (ties: chain order)."""
    partition = partition_for(robot, partition)
    candidates = [joint for joint in partition.joints if len(robot.velocity_indices(joint)) == 1]
    if len(candidates) < 2:
        raise InputError(f"a region map needs two 1-DOF partition joints; {robot.name!r} has {list(partition.joints)}")
    sensitivity = joint_sensitivity(robot, partition=partition)
    ranked = sorted(candidates, key=lambda j: -sensitivity[j])[:2]
    return tuple(sorted(ranked, key=partition.joints.index))  # type: ignore[return-value]


def region_map(
    robot: Robot,
    *,
    joints: Sequence[str] | None = None,
    points: int = 121,
    partition: Partition | None = None,
    base: np.ndarray | None = None,
    workers: int = 1,
) -> RegionMap:
    """ρ over a ``points`` x ``points`` grid of two joints (default: the two ρ varies most with).

    ``workers``: threads of the compiled core, else processes (as in
    :func:`pinrate.theorem.spectral_radius_at`); the map does not depend on it.
    """
    partition = partition_for(robot, partition)
    points = check_count(points, "points", minimum=2, maximum=MAX_GRID_POINTS)
    pair = tuple(joints) if joints is not None else default_map_joints(robot, partition=partition)
    if len(pair) != 2 or pair[0] == pair[1]:
        raise InputError(f"a region map needs two different joints, got {list(pair)}")
    for joint in pair:
        if joint not in partition.joints:
            raise InputError(f"joint {joint!r} is not in the partition; choose from {', '.join(partition.joints)}")
        if len(robot.velocity_indices(joint)) != 1:
            raise InputError(
                f"joint {joint!r} has {len(robot.velocity_indices(joint))} DOF; a region map sweeps 1-DOF joints"
            )
    base = robot.home() if base is None else robot.check_q(base)
    x = np.linspace(*robot.joint_range(pair[0]), points)
    y = np.linspace(*robot.joint_range(pair[1]), points)
    configurations = np.tile(base, (points * points, 1))
    grid_x, grid_y = np.meshgrid(x, y)
    robot.set_joint_values(configurations, pair[0], grid_x.ravel())
    robot.set_joint_values(configurations, pair[1], grid_y.ravel())
    radii = spectral_radius_at(robot, configurations, partition=partition, workers=workers)
    radii = radii.reshape(points, points)
    return RegionMap(joints=pair, x=x, y=y, spectral_radius=radii, base=base)


def tcp_positions(robot: Robot, configurations: np.ndarray) -> np.ndarray:
    """TCP positions (N, 3) in the world."""
    return np.array([robot.pose(q)[:3, 3] for q in configurations])
