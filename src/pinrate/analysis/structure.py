"""Which entries of the blocks A, B, U, W vanish everywhere, and what that means (eq. 22, §3)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..kinematics.kinematic_model import GENERIC_SEED
from ..kinematics.manipulator import Robot
from ..kinematics.partition import Partition, partition_for

_ZERO = 1e-9  # an entry is zero when below this times (1 + max |J|)


@dataclass(frozen=True)
class BlockStructure:
    """Which entries of A, B, U, W are zero at every sampled configuration."""

    zero: dict[str, np.ndarray]  # block name -> bool mask of identically zero entries
    partition: Partition

    @property
    def B_is_zero(self) -> bool:
        return bool(self.zero["B"].all())

    @property
    def U_is_zero(self) -> bool:
        return bool(self.zero["U"].all())

    def lines(self) -> list[str]:
        """A sentence per block, and what the zero blocks mean."""
        axes = {
            "A": (self.partition.linear, self.partition.arm),
            "B": (self.partition.linear, self.partition.wrist),
            "U": (self.partition.angular, self.partition.arm),
            "W": (self.partition.angular, self.partition.wrist),
        }
        lines = []
        for name, mask in self.zero.items():
            rows, columns = axes[name]
            if mask.size == 0:
                lines.append(f"{name}: empty ({len(rows)}x{len(columns)})")
            elif mask.all():
                lines.append(f"{name}: identically zero ({mask.shape[0]}x{mask.shape[1]})")
            else:
                zeros = [f"({rows[i]}, {columns[j]})" for i, j in zip(*np.nonzero(mask), strict=True)]
                lines.append(f"{name}: {mask.shape[0]}x{mask.shape[1]}, zero entries: {', '.join(zeros) or 'none'}")
        if self.B_is_zero and self.zero["B"].size:
            lines.append("B = 0: the wrist axes meet at the TCP, so MCA2 is exact here (eq. 22).")
        if self.U_is_zero and self.zero["U"].size:
            lines.append("U = 0: the arm does not turn the tool, so MCA1 is exact here (§3).")
        return lines


def block_structure(
    robot: Robot, *, partition: Partition | None = None, samples: int | None = None, rng: int | None = None
) -> BlockStructure:
    """Zero patterns of A, B, U, W over home and :meth:`Robot.generic_configurations` of the
    partition's joints (the set every test of what holds almost everywhere uses), or over
    ``samples`` configurations drawn with ``rng`` when given (the same seed by default)."""
    partition = partition_for(robot, partition)
    drawn = (
        robot.generic_configurations(partition.joints)
        if samples is None
        else robot.sample_configurations(samples, GENERIC_SEED if rng is None else rng, joints=partition.joints)
    )
    configurations = np.vstack([robot.home()[None, :], drawn])
    magnitude = [np.abs(block) for block in partition.blocks(robot, robot.jacobian_unchecked(configurations[0]))]
    for q in configurations[1:]:
        current = partition.blocks(robot, robot.jacobian_unchecked(q))
        magnitude = [np.maximum(a, np.abs(b)) for a, b in zip(magnitude, current, strict=True)]
    scale = 1.0 + max((float(m.max()) for m in magnitude if m.size), default=0.0)
    return BlockStructure({name: m <= _ZERO * scale for name, m in zip("ABUW", magnitude, strict=True)}, partition)
