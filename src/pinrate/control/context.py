"""What every stage of a control step reads and no step changes: the robot, the resolved
partition, the algorithm, the blocks it inverts and how they are measured, the thresholds,
dt. Built once per :class:`~pinrate.control.controller.Controller`; the stages
(:mod:`.limits`, :mod:`.singularity`, :mod:`.posture`, :mod:`.uncoupled`) take it instead of
the controller, so they import nothing above them."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..errors import SingularBlockError
from ..kinematics.axes import joint_unit, joint_value
from ..kinematics.manipulator import Robot
from ..kinematics.partition import Partition, PartitionIndex
from ..solvers.conditioning import inverse_condition_bound
from ..solvers.rates import partition_rates
from ..solvers.registry import REGISTRY
from .observation import Observation
from .singular_region import NOISE_FLOOR, Conditioning, conditioning


@dataclass(frozen=True, slots=True)
class StepContext:
    """A controller's fixed settings, as its stages read them.

    Attributes:
        robot: the robot; partition: its partition and index: the partition resolved.
        names: the partition's joints, arm then wrist (partition order); positions: name ->
            its position there; velocity_of: every joint's name -> its first velocity index.
        algorithm: the solver's name; measured: the blocks it inverts ("A", "W", "J").
        row_scale: (m + k,) 1/L on linear rows, 1 on angular (L the characteristic length,
            m); row_scale_column: the same as a column.
        ranks: generic ranks of J, A, W by name; square_j: J of the partition square and of
            full generic rank.
        singular_threshold, slow_threshold: inverse condition numbers (dimensionless).
        dt: control period (s); characteristic_length: L (m).
        closed_form: the algorithm's closed-form kernel solves the partition (made here).
    """

    robot: Robot
    partition: Partition
    index: PartitionIndex
    names: tuple[str, ...]
    positions: dict[str, int]
    velocity_of: dict[str, int]
    algorithm: str
    measured: tuple[str, ...]
    row_scale: np.ndarray
    row_scale_column: np.ndarray
    ranks: dict[str, int]
    square_j: bool
    singular_threshold: float
    slow_threshold: float
    dt: float
    characteristic_length: float
    closed_form: bool = field(init=False)

    def __post_init__(self) -> None:
        # Whether the algorithm's closed-form kernel solves this partition: only then does
        # a solve read the observation's blocks (a whole-J solve would make them for nothing).
        object.__setattr__(self, "closed_form", self.index.small and REGISTRY[self.algorithm].closed_form is not None)

    def reduced(self, jacobian: np.ndarray) -> np.ndarray:
        """J restricted to the partition (m + k, n), partition order."""
        index = self.index
        return jacobian if index.all_rows and index.all_columns else jacobian[np.ix_(index.rows, index.columns)]

    def reduced_rows(self, jacobian: np.ndarray) -> np.ndarray:
        """J's controlled rows (m + k, nv)."""
        return jacobian[self.index.rows]

    def conditioning(self, reduced: np.ndarray, n_arm: int) -> Conditioning:
        """The least c of the measured blocks of ``reduced`` (with ``n_arm`` arm columns)."""
        return conditioning(reduced, self.index.m, n_arm, self.measured, self.row_scale, self.ranks)

    def conditioning_at(self, q: np.ndarray) -> Conditioning:
        """:meth:`conditioning` of the partition's J at q (checked; one kinematics pass)."""
        jacobian = self.robot.kinematics(self.robot.check_q(q))[0]
        return self.conditioning(self.reduced(jacobian), self.index.arm_columns.size)

    def conditioning_bound(self, observation: Observation) -> float:
        """A cheap lower bound of the least c of the measured blocks (0.0 where none is cheap):
        1 / (||M||_F ||M^-1||_F) from the closed-form inverses of A, W and numpy's of J."""
        bound = math.inf
        for name in self.measured:
            if name == "J":
                if not self.square_j:
                    return 0.0
                scaled = self.reduced(observation.jacobian) * self.row_scale_column
                try:
                    bound = min(bound, inverse_condition_bound(scaled, np.linalg.inv(scaled)))
                except np.linalg.LinAlgError:
                    return 0.0
                continue
            parts = observation.blocks
            if parts is None:
                return 0.0
            block = parts[0] if name == "A" else parts[3]
            if not block or not block[0]:
                continue
            try:
                bound = min(bound, inverse_condition_bound(block, observation.block_inverse(name)))
            except SingularBlockError:
                return 0.0
        return bound

    def joint_said(self, position: int, q: np.ndarray) -> str:
        """The value of the partition's joint at ``position`` at q in words ("theta5 = -0.007
        rad"; rad or m), or "" for a joint of more freedoms. Under NOISE_FLOOR it is said as
        such: the two paths' q differ by rounding there, and so would the digits and the sign."""
        name = self.names[position]
        joint_id = self.robot.joint_id(name)
        value = joint_value(self.robot.model, joint_id, q)
        if value is None:
            return ""
        unit = joint_unit(self.robot.model, joint_id)
        return f"|{name}| < {NOISE_FLOOR:g} {unit}" if abs(value) < NOISE_FLOOR else f"{name} = {value:.3g} {unit}"

    def solve_without(self, observation: Observation, twist: np.ndarray, left_out: frozenset[str]) -> np.ndarray:
        """The algorithm's rates with the ``left_out`` joints removed from the partition (they
        get rate 0 here). Raises SingularBlockError as the algorithm does."""
        if not left_out:
            parts = observation.blocks if self.closed_form else None
            return partition_rates(observation.jacobian, self.index, twist, self.algorithm, parts)
        partition = self.partition
        reduced = Partition(
            [joint for joint in partition.arm if joint not in left_out],
            [joint for joint in partition.wrist if joint not in left_out],
            linear=partition.linear,
            angular=partition.angular,
        )
        return partition_rates(
            observation.jacobian,
            reduced.resolve(self.robot),
            twist,
            self.algorithm,
            position_first=self.index.position_first,
        )


__all__ = ["StepContext"]
