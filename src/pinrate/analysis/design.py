"""Design questions: which joints matter, the worst ρ over the joint ranges, parameter limits.

The paper turns the Theorem into design rules (Shoham & Koren §5): "d2/l > 2" for the polar
robot, "l3 < 60 mm" for the Hirata ARH-300. Here the same questions for any robot:

* :func:`independent_joints`: the joints the sensor-frame Jacobian does not depend on (§2:
  in the sensor frame J is independent of theta1, so its encoder is not needed for rates);
* :func:`worst_spectral_radius`: the largest ρ(G) over a dense grid of the joints that
  matter (the others cannot change ρ), a deterministic check of "converges everywhere";
* :func:`largest_parameter`: bisection on a robot parameter (a tool length, a joint limit)
  for the largest value whose worst ρ stays below 1.
"""

from __future__ import annotations

import itertools
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from ..checks import MAX_GRID_POINTS, as_rng, check_count, check_positive
from ..errors import InputError
from ..kinematics.manipulator import Robot
from ..kinematics.partition import Partition, partition_for
from ..theorem.sampling import spectral_radius_at

_DEPENDENCE_TOL = 1e-9


def independent_joints(
    robot: Robot, *, partition: Partition | None = None, samples: int = 16, rng: int = 7
) -> tuple[str, ...]:
    """Partition joints whose value leaves the sensor-frame Jacobian unchanged.

    Checked by moving each joint to random values at random configurations: a joint is
    independent when no move changes any entry of J by more than 1e-9 (relative).
    """
    partition = partition_for(robot, partition)
    generator = as_rng(rng)
    base = robot.sample_configurations(check_count(samples, "samples", minimum=1), generator, joints=partition.joints)
    jacobians = np.array([robot.jacobian_unchecked(q) for q in base])
    scale = 1.0 + np.abs(jacobians).max()
    independent = []
    for joint in partition.joints:
        moved = base.copy()
        robot.set_joint_values(moved, joint, generator.uniform(*robot.joint_range(joint), samples))
        change = max(
            np.abs(robot.jacobian_unchecked(q) - jacobian).max() for q, jacobian in zip(moved, jacobians, strict=True)
        )
        if change <= _DEPENDENCE_TOL * scale:
            independent.append(joint)
    return tuple(independent)


@dataclass(frozen=True)
class GridCheck:
    """The Theorem's test on a grid over the joints ρ can depend on."""

    joints: tuple[str, ...]  # the grid's joints (the others do not change J)
    q: np.ndarray  # (N, nq) grid configurations
    spectral_radius: np.ndarray  # (N,)

    @property
    def worst(self) -> float:
        """The largest ρ on the grid (inf when a block is singular somewhere)."""
        return float(self.spectral_radius.max()) if self.spectral_radius.size else 0.0

    @property
    def worst_q(self) -> np.ndarray:
        """The grid configuration with the largest ρ."""
        return self.q[int(np.argmax(self.spectral_radius))]


def grid_check(
    robot: Robot,
    *,
    partition: Partition | None = None,
    points: int = 61,
    joints: Sequence[str] | None = None,
    max_configurations: int = 2_000_000,
    workers: int = 1,
    scheduler: object = None,
    progress: bool | None = None,
) -> GridCheck:
    """ρ at every point of a regular grid (``points`` per joint, limits included) over ``joints``.

    Default joints: the partition's joints that J depends on. Joints off the grid stay at
    the robot's home configuration.
    """
    partition = partition_for(robot, partition)
    if joints is None:
        skip = set(independent_joints(robot, partition=partition))
        joints = [j for j in partition.joints if j not in skip]
    joints = tuple(joints)
    points = check_count(points, "points", minimum=2, maximum=MAX_GRID_POINTS)
    count = points ** len(joints)
    if count > max_configurations:
        raise InputError(
            f"a grid of {points} points over {len(joints)} joints ({', '.join(joints)}) has "
            f"{count:,} configurations, above max_configurations={max_configurations:,}; "
            "use fewer points or sample_convergence"
        )
    axes = [np.linspace(*robot.joint_range(joint), points) for joint in joints]
    configurations = np.tile(robot.home(), (count, 1))
    for joint, values in zip(joints, np.array(list(itertools.product(*axes))).T if joints else [], strict=False):
        robot.set_joint_values(configurations, joint, values)
    radii = spectral_radius_at(
        robot, configurations, partition=partition, workers=workers, scheduler=scheduler, progress=progress
    )
    return GridCheck(joints=joints, q=configurations, spectral_radius=radii)


def worst_spectral_radius(robot: Robot, *, partition: Partition | None = None, points: int = 61) -> float:
    """The largest ρ(G) over a dense grid of the joints J depends on (see :func:`grid_check`)."""
    return grid_check(robot, partition=partition, points=points).worst


def largest_parameter(
    factory: Callable[[float], Robot],
    low: float,
    high: float,
    *,
    points: int = 61,
    tolerance: float = 1e-5,
    partition: Callable[[Robot], Partition] | None = None,
) -> float:
    """The largest x in [low, high] with worst ρ(G) < 1 for ``factory(x)``, by bisection.

    Assumes the robot converges everywhere at ``low`` and the worst ρ grows with x (a tool
    length, say); returns ``high`` if it still converges there. ``partition`` maps a robot
    to its partition (default: Partition.auto).
    """

    tolerance = check_positive(tolerance, "tolerance")

    def converges(value: float) -> bool:
        robot = factory(value)
        chosen = partition(robot) if partition else None
        return worst_spectral_radius(robot, partition=chosen, points=points) < 1.0

    if not converges(low):
        raise InputError(f"the robot does not converge everywhere even at the low end {low}")
    if converges(high):
        return high
    while high - low > tolerance:
        middle = (low + high) / 2
        if not low < middle < high:  # the interval is as narrow as doubles get
            break
        if converges(middle):
            low = middle
        else:
            high = middle
    return low


def smallest_parameter(
    factory: Callable[[float], Robot],
    low: float,
    high: float,
    *,
    points: int = 61,
    tolerance: float = 1e-5,
    partition: Callable[[Robot], Partition] | None = None,
) -> float:
    """The smallest x in [low, high] with worst ρ(G) < 1 (ρ shrinking with x), by bisection."""
    flipped = largest_parameter(
        lambda x: factory(-x), -high, -low, points=points, tolerance=tolerance, partition=partition
    )
    return -flipped
