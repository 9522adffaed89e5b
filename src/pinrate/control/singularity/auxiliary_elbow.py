"""``singularity="auxiliary_elbow"`` (Barker eq. 45-46, :mod:`pinrate.control.elbow`): while
the elbow is within ``elbow_region`` of full extension, the elbow follows the command's
component along the upper arm (the impossible outward one ignored), the shoulder retracts
the hand on the line to the shoulder and pitches the arm, the other joints serve the rest;
the elbow bends the other way each time the arm reaches full extension (K3 changes sign).
The elbow control acts only where Barker's generalized inverse (eq. 38) cannot make the
command (:meth:`AuxiliaryElbow.inverse_serves`: it cuts a commanded direction, or it would
turn the elbow toward full extension); elsewhere, in the region and out of it, the strategy
is ``"generalized_inverse"``'s (:func:`near`), as in Barker, whose auxiliary control
supplements the generalized inverse near θ3 = 0 ("Equation (39) specifies azimuth
movement"). It never halts a command the inverse makes: on Barker's arm, retracting from
full extension keeps the wrist centre on the minimum-radius line (eq. 32: S2 ES + F5 = 0 at
θ1 fixed), where ``"decelerate"`` halts though the command is in M's range.

:class:`AuxiliaryElbow` owns the strategy's state: the elbow found, its region, the side of
the next bend.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
import pinocchio as pin

from ...errors import SingularBlockError
from ...solvers.conditioning import inverse_condition
from ..context import StepContext
from ..elbow import ELBOW_REGION, EXTENDED, Elbow, arm_frame, elbow_rate, find_elbow, remaining_rates
from ..observation import Observation
from ..reach import REACH_TOLERANCE
from ..singular_region import ColumnMap, Conditioning, c_said, carrying_joints
from ..status import Status
from . import generalized_inverse
from .plan import plan_step, solve_planned
from .wrist import wrist_rule

decelerates = False
near = generalized_inverse.near


class Auxiliary(NamedTuple):
    """A step under Barker's auxiliary elbow control (:mod:`.elbow`)."""

    bend: float  # elbow - straight (rad)
    outward: float  # the command's component along the upper arm (m/s)
    directions: np.ndarray  # p and, when commanded, n: world directions over the sensor's linear axes (r, m)
    targets: np.ndarray  # TVEL along them (m/s)
    dropped: frozenset[int]  # the wrist rule's held joint
    merged: tuple[int, int, float] | None
    released_by: tuple[int, int] | None
    statuses: tuple[Status, ...]
    details: tuple[str, ...]


CONTROLLED_SHARE = 0.5
"""A world direction counts as commanded when the partition's linear components carry at
least this share of it (a planar arm's twist has no component normal to its plane)."""


class AuxiliaryElbow:
    """Barker's auxiliary elbow control of one controller.

    Args:
        context: the controller's fixed settings.
        wrist: its wrist strategy (the rows left to the other joints may be a wrist pair's).
        elbow: the arm's elbow and shoulder (:func:`find` finds them).
        region: rad; the elbow acts while closer than this to full extension; None: the bend
            at which c of the measured blocks reaches ``slow_threshold`` (at most
            :data:`~pinrate.control.elbow.ELBOW_REGION`).
    """

    def __init__(self, context: StepContext, wrist: str, elbow: Elbow, region: float | None) -> None:
        self.context = context
        self.wrist = wrist
        self.elbow = elbow
        self.data = context.robot.model.createData()
        bent = float(context.robot.home()[elbow.q_index]) - elbow.straight
        self.first_bend_sign = -1.0 if bent < 0.0 else 1.0  # the first bend goes the home's way
        self.bend_sign = self.first_bend_sign
        self.region = self.slow_bend() if region is None else region

    @classmethod
    def find(cls, context: StepContext, wrist: str, region: float | None) -> AuxiliaryElbow | None:
        """The strategy on the partition's arm, or None when it has no elbow (a joint whose
        block becomes singular at full extension, carrying the lost motion)."""

        def singular_with(q: np.ndarray, position: int) -> bool:
            weakest = context.conditioning_at(q)
            return weakest.value < context.singular_threshold and position in carrying_joints(weakest)

        elbow = find_elbow(context.robot, context.partition, singular_with)
        return None if elbow is None else cls(context, wrist, elbow, region)

    def reset(self) -> None:
        """The next bend from full extension goes the home's way."""
        self.bend_sign = self.first_bend_sign

    def slow_bend(self) -> float:
        """The bend from full extension (rad, toward home's side, others at home) at which c of
        the measured blocks reaches ``slow_threshold``, by bisection; at most ELBOW_REGION."""
        q = self.context.robot.home()
        elbow, sense = self.elbow, self.bend_sign

        def slow_at(bend: float) -> bool:
            q[elbow.q_index] = elbow.straight + sense * bend
            return self.context.conditioning_at(q).value < self.context.slow_threshold

        if slow_at(ELBOW_REGION):
            return ELBOW_REGION
        low, high = 0.0, ELBOW_REGION
        for _ in range(30):
            middle = 0.5 * (low + high)
            low, high = (middle, high) if slow_at(middle) else (low, middle)
        return high

    def plan(self, observation: Observation, twist: np.ndarray) -> Auxiliary | None:
        """Barker's auxiliary elbow control at this q, or None: the elbow is outside its region,
        the upper arm's direction is not among the commanded linear components, or the
        generalized inverse makes the command here (:meth:`inverse_serves`)."""
        elbow = self.elbow
        q = observation.q
        bend = float(q[elbow.q_index]) - elbow.straight
        if abs(bend) >= self.region:
            return None
        pin.forwardKinematics(self.context.robot.model, self.data, q)
        frame = arm_frame(elbow, self.data, np.array(observation.world_T_tip.translation))
        if frame is None:
            return None
        index = self.context.index
        m = index.m
        sensor_rotation = observation.world_T_sensor.rotation
        axes = index.rows[:m]  # the sensor's linear axes the twist commands
        commanded = sensor_rotation[:, axes]  # their world directions (3, m)
        if np.linalg.norm(commanded.T @ frame.outward) < CONTROLLED_SHARE or self.inverse_serves(
            observation, twist, bend
        ):
            return None
        world_linear = commanded @ twist[:m]  # TVEL in the world (m/s)
        directions = [
            world for world in (frame.pitch, frame.normal) if np.linalg.norm(commanded.T @ world) >= CONTROLLED_SHARE
        ]
        n_arm = index.arm_columns.size
        dropped: frozenset[int] = frozenset()
        merged = released_by = None
        statuses = [Status.AUXILIARY_ELBOW]
        outward = float(frame.outward @ world_linear)
        way = "retracts" if outward < 0.0 else "straightens" if abs(bend) > EXTENDED else "holds (outward command)"
        details = [f"{elbow.joint} {abs(bend):.3g} rad from full extension: auxiliary elbow control, the elbow {way}"]
        rows = np.array([commanded.T @ world for world in directions]).reshape(len(directions), m)
        # The rows left to the joints other than the elbow: near singular, they are the wrist's
        # (two aligned axes: the wrist rule) or another block's (the generalized inverse cuts).
        others = ColumnMap.of(n_arm, index.wrist_columns.size, frozenset([elbow.position]), None).matrix
        left = self.rows(observation, rows) @ others
        if left.size:
            value, motion = inverse_condition(left, min(left.shape))
            if value < self.context.slow_threshold:
                weakest = Conditioning(value, "rows left to the other joints", others @ motion)
                rule = wrist_rule(self.wrist, self.context, weakest, n_arm, q)
                if rule is not None:
                    dropped, merged, released_by, detail = rule
                    statuses.append(Status.WRIST_SINGULARITY)
                    details.append(detail)
                else:
                    statuses.append(Status.NEAR_SINGULARITY)
                    details.append(f"the rows left to the other joints are near singular ({c_said(value)})")
        return Auxiliary(
            bend,
            outward,
            rows,
            np.array([float(world @ world_linear) for world in directions]),
            dropped,
            merged,
            released_by,
            tuple(statuses),
            tuple(details),
        )

    def inverse_serves(self, observation: Observation, twist: np.ndarray, bend: float) -> bool:
        """Whether Barker's generalized inverse (eq. 38, the strategy's solve outside the elbow's
        action) makes the command at q, so that the elbow control need not act (Barker: it is
        for what the inverse cannot do near the singular position): its rates x leave a
        residual ``‖twist - J_r x‖`` of at most :data:`~pinrate.control.reach.REACH_TOLERANCE`
        ``‖twist‖`` (m/s and rad/s in one norm; no commanded direction cut), and they do not
        turn the elbow toward full extension (``bend`` rad from it), where the inverse's elbow
        rate grows as 1 / sin(bend) and a step would cross the singularity."""
        context = self.context
        plan = plan_step(context, generalized_inverse, self.wrist, observation, twist)
        try:
            if plan is None:
                rates = context.solve_without(observation, twist, frozenset())
            else:
                rates = solve_planned(context, observation, twist, plan, frozenset())
        except SingularBlockError:
            return False
        solved = rates[context.index.columns]
        residual = float(np.linalg.norm(twist - context.reduced(observation.jacobian) @ solved))
        toward_extension = solved[self.elbow.position] * bend < 0.0
        return residual <= REACH_TOLERANCE * float(np.linalg.norm(twist)) and not toward_extension

    def solve(
        self, observation: Observation, twist: np.ndarray, auxiliary: Auxiliary, left_out: frozenset[str]
    ) -> np.ndarray:
        """Rates (nv,) under auxiliary elbow control: the elbow by eq. 45; the shoulder and the
        other joints (less ``left_out`` and the wrist rule's held joint) by the generalized
        inverse of the pitch row (eq. 46's coefficients for shoulder and elbow), the normal
        row and the angular rows, less what the elbow produces there (:mod:`.elbow`)."""
        elbow = self.elbow
        index = self.context.index
        m = index.m
        partition_rates = np.zeros(index.columns.size)
        if elbow.joint not in left_out:
            partition_rates[elbow.position] = elbow_rate(
                elbow, auxiliary.bend, self.bend_sign, auxiliary.outward, self.region, self.context.dt
            )
        dropped = auxiliary.dropped | {self.context.positions[name] for name in left_out}
        if auxiliary.released_by is not None and auxiliary.released_by[1] in dropped:
            dropped = dropped - {auxiliary.released_by[0]}
        columns = ColumnMap.of(
            index.arm_columns.size, index.wrist_columns.size, dropped | {elbow.position}, auxiliary.merged
        )
        matrix = self.rows(observation, auxiliary.directions)
        target = np.concatenate([auxiliary.targets / self.context.characteristic_length, twist[m:]])
        partition_rates += remaining_rates(
            matrix, target - matrix @ partition_rates, columns.matrix, self.context.singular_threshold
        )
        rates = np.zeros(self.context.robot.nv)
        rates[index.columns] = partition_rates
        return rates

    def rows(self, observation: Observation, directions: np.ndarray) -> np.ndarray:
        """The rows solved under auxiliary elbow control (r + k, n): the velocities along
        ``directions`` (p, and n when commanded; over the sensor's linear axes) per joint rate,
        over the characteristic length as the generalized inverse's rows, then J's angular rows."""
        reduced = self.context.reduced(observation.jacobian)
        linear = directions @ reduced[: self.context.index.m]
        return np.vstack([linear / self.context.characteristic_length, reduced[self.context.index.m :]])

    def reach_extension(self, q: np.ndarray, next_q: np.ndarray) -> None:
        """After any step (a twist, a jog, a playback): a step that brings the elbow to full
        extension puts it exactly there, and one that reaches or crosses it makes the next bend
        from full extension go the other way (Barker: K3 changes sign each time)."""
        elbow = self.elbow
        bend = float(q[elbow.q_index]) - elbow.straight
        after = float(next_q[elbow.q_index]) - elbow.straight
        if abs(bend) > EXTENDED and (abs(after) <= EXTENDED or after * bend < 0.0):
            if abs(after) <= EXTENDED:
                next_q[elbow.q_index] = elbow.straight
            self.bend_sign = -math.copysign(1.0, bend)


__all__ = ["CONTROLLED_SHARE", "Auxiliary", "AuxiliaryElbow", "decelerates", "near"]
