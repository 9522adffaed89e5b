"""One control step, the seam that the servo and teleoperation share.

Each step at configuration q (Shoham & Koren §2, Fig. 3):

1. kinematics at q, one Pinocchio pass: the sensor-frame Jacobian J (eq. 1-8), the tip and
   sensor poses, and ρ of the smaller of G and H (eq. 32, 50) — an :class:`Observation`;
2. the command becomes a twist in the sensor frame's axes (m/s, rad/s): a twist is taken as
   it is; a :class:`PoseGoal` commands ``gain`` times the pose error, position error
   R_s^T (p_target - p_tip) and rotation error R_s^T log3(R_target R_tip^T);
3. the linear and the angular parts are each scaled down, direction kept, to at most
   ``max_linear_speed`` and ``max_angular_speed``;
4. the algorithm turns the twist into joint rates (:mod:`pinrate.solvers`);
5. position limits: a joint whose commanded rate would carry it past a limit within dt is
   *blocked*: the rates are solved again without it (the others serve the command as well as
   they can), and it moves at most onto the limit. A joint on its limit whose command points
   away is not blocked: motion away is always executed. The test is on the commanded rate,
   never on a measured one, so a joint held at a limit does not cycle between stop and go
   (MoveIt Servo issue #2898);
6. velocity limits: when a rate exceeds its joint's limit, every rate is scaled by the same
   factor, the largest that meets every limit, so the direction of motion is kept;
7. q is integrated over dt on the configuration space (``pin.integrate``) and clamped to
   the limits (a guard against rounding: step 5 already keeps q inside).

:meth:`Controller.step` returns a :class:`Step`: the next q, the rates applied, and a
:class:`~pinrate.control.status.Status` saying what limited the step.
"""

from __future__ import annotations

import math
from collections.abc import Collection
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
import pinocchio as pin

from ..checks import as_pose, check_positive, check_vector
from ..errors import InputError, SingularBlockError
from ..kinematics.manipulator import Robot
from ..kinematics.partition import Partition, partition_for
from ..kinematics.spatial import pose_error, saturate
from ..solvers import closed_form
from ..solvers.rates import partition_rates, partition_spectral_radius
from ..solvers.registry import check_algorithm
from .status import Status, most_severe

MAX_LINEAR_SPEED = 0.5
"""Default speed limit of the commanded TCP velocity (m/s)."""

MAX_ANGULAR_SPEED = 1.0
"""Default speed limit of the commanded angular velocity (rad/s)."""


@dataclass(frozen=True)
class PoseGoal:
    """A command to move the tip to ``target`` (a pose in the world): twist = gain x pose error.

    ``gain`` is in 1/s: the twist commanded per metre and per radian of error.
    """

    target: pin.SE3
    gain: float = 1.0

    @classmethod
    def of(cls, target: object, gain: float = 1.0) -> PoseGoal:
        """A checked goal from a 4x4 homogeneous matrix or a pinocchio.SE3, and a gain > 0."""
        return cls(as_pose(target), check_positive(gain, "gain"))


@dataclass(slots=True)  # a record, read-only by convention: frozen dataclasses cost ~1 µs per step
class Observation:
    """What the controller sees at q, from one kinematics pass.

    Attributes:
        q: the configuration (nq,).
        jacobian: the sensor-frame Jacobian (6, nv).
        world_T_tip, world_T_sensor: the tip and sensor poses in the world.
        blocks: A, B, U, W as nested lists when the closed-form kernels apply, else None.
        spectral_radius: ρ of the smaller of G and H (inf where A or W is singular).
        goal: the pose goal ``error`` was measured against, if any.
        error: the controlled pose error (m + k,) in partition order, sensor axes (m, rad).
    """

    q: np.ndarray
    jacobian: np.ndarray
    world_T_tip: pin.SE3
    world_T_sensor: pin.SE3
    blocks: closed_form.Blocks | None
    spectral_radius: float
    goal: PoseGoal | None = None
    error: np.ndarray | None = None


@dataclass(slots=True)  # a record, read-only by convention
class Step:
    """The outcome of one control step from ``observation.q``.

    Attributes:
        q: the next configuration (nq,): the rates integrated over dt, clamped to the limits.
        joint_rates: the rates applied (nv,), 0 for joints outside the partition.
        status: the most severe condition met in this step.
        frozen: names of the joints held still in this step.
        twist: the twist commanded after saturation (m + k,), partition order, sensor axes.
        observation: what the controller saw at the start of the step.
        detail: why the status is not OK, in words ("" when OK).
    """

    q: np.ndarray
    joint_rates: np.ndarray
    status: Status
    frozen: tuple[str, ...]
    twist: np.ndarray
    observation: Observation
    detail: str = ""


class _Limit(NamedTuple):  # a tuple: the per-step test reads it on Python floats
    joint: str
    index: int  # into q
    velocity: int  # into v
    lower: float
    upper: float

    def onto_the_limit(self, q: np.ndarray, rate: float, dt: float) -> float:
        """The rate, cut so that the joint ends the step on its limit at most."""
        value = q[self.index]
        return min(max(rate, (self.lower - value) / dt), (self.upper - value) / dt)


VELOCITY_LIMIT_UNLIMITED = 1e6
"""A URDF velocity limit of 0 (what converters write for "unknown") or above this (rad/s or
m/s) means no limit."""


class Controller:
    """The resolved-rate control step of a robot (one Robot per controller and thread).

    Args:
        robot: the robot; its tip and sensor frames fix what twists mean.
        algorithm: a name of :data:`pinrate.ALGORITHMS`.
        partition: which joints and twist rows take part; None means ``Partition.auto(robot)``.
        dt: control period in seconds.
        max_linear_speed, max_angular_speed: saturation of the commanded twist (m/s, rad/s;
            inf for none).
        velocity_limits: None for the URDF's ``<limit velocity>`` of each joint (none where it
            gives 0 or none), a number for every joint, or one per velocity component (nv,),
            in rad/s or m/s; inf for none. When one binds, all rates are scaled alike.
        position_limits: keep q within the joints' position limits (see the module docstring).

    Raises:
        InputError: an unknown algorithm, a bad partition, a dt or speed that is not positive,
            velocity limits that are not positive or of the wrong length.
    """

    def __init__(
        self,
        robot: Robot,
        *,
        algorithm: str = "exact",
        partition: Partition | None = None,
        dt: float = 0.01,
        max_linear_speed: float = MAX_LINEAR_SPEED,
        max_angular_speed: float = MAX_ANGULAR_SPEED,
        velocity_limits: object = None,
        position_limits: bool = True,
    ) -> None:
        self.robot = robot
        self.algorithm = check_algorithm(algorithm)
        self.partition = partition_for(robot, partition)
        self.index = self.partition.resolve(robot)
        self.dt = check_positive(dt, "dt")
        self.max_linear_speed = check_positive(max_linear_speed, "max_linear_speed", allow_inf=True)
        self.max_angular_speed = check_positive(max_angular_speed, "max_angular_speed", allow_inf=True)
        if not isinstance(position_limits, bool):
            raise InputError(f"position_limits must be True or False, not {position_limits!r}")
        self.position_limits = position_limits
        self._limits = self._position_limits()
        self.velocity_limits = self._velocity_limits(velocity_limits)
        self._rate_limit_rows = [
            (velocity, float(limit)) for velocity, limit in enumerate(self.velocity_limits) if math.isfinite(limit)
        ]

    def _position_limits(self) -> list[_Limit]:
        """The partition's 1-DOF joints with finite position limits."""
        limits = []
        for joint in self.partition.joints:
            bounds = self.robot.joint_limits(joint)
            if bounds is not None:
                model = self.robot.model.joints[self.robot.joint_id(joint)]
                limits.append(_Limit(joint, model.idx_q, model.idx_v, *bounds))
        return limits

    def _velocity_limits(self, limits: object) -> np.ndarray:
        """Per velocity component (nv,), inf where there is none."""
        if limits is None:
            urdf = np.array(self.robot.model.velocityLimit, dtype=float)
            return np.where((urdf > 0) & (urdf < VELOCITY_LIMIT_UNLIMITED), urdf, np.inf)
        if np.ndim(limits) == 0:
            value = check_positive(limits, "velocity_limits", allow_inf=True)
            return np.full(self.robot.nv, value)
        try:
            values = np.array(limits, dtype=float)
        except (TypeError, ValueError):
            raise InputError(f"velocity_limits must be numbers, not {type(limits).__name__}") from None
        if values.shape != (self.robot.nv,):
            raise InputError(
                f"velocity_limits must be one number or {self.robot.nv} (one per velocity component of "
                f"{self.robot.name!r}), got shape {values.shape}"
            )
        if np.isnan(values).any() or (values <= 0).any():
            raise InputError(f"velocity_limits must be positive (inf for none), got {values}")
        return values

    # ------------------------------------------------------------------ seeing
    def observe(self, q: object, goal: PoseGoal | None = None) -> Observation:
        """Kinematics, blocks and ρ at q (one Pinocchio pass); the pose error to ``goal`` too
        when given. q is checked (:meth:`Robot.check_q`)."""
        if goal is not None and not isinstance(goal, PoseGoal):
            raise InputError(f"goal must be a PoseGoal (PoseGoal.of(target, gain)), not {type(goal).__name__}")
        return self.observe_unchecked(self.robot.check_q(q), goal)

    def observe_unchecked(self, q: np.ndarray, goal: PoseGoal | None = None) -> Observation:
        """:meth:`observe` at a q that already went through :meth:`Robot.check_q` (or came out
        of a step): the servo's hot path."""
        index = self.index
        jacobian, world_T_tip, world_T_sensor = self.robot.kinematics(q)
        error = None if goal is None else pose_error(world_T_tip, world_T_sensor, goal.target)[index.rows]
        parts = closed_form.blocks(jacobian, index.selectors) if index.small else None
        radius = partition_spectral_radius(jacobian, index, parts, self.algorithm)
        return Observation(q, jacobian, world_T_tip, world_T_sensor, parts, radius, goal, error)

    # ------------------------------------------------------------------ acting
    def command_twist(self, observation: Observation, command: np.ndarray | PoseGoal) -> tuple[np.ndarray, bool]:
        """(twist, saturated): the command as a saturated twist in partition order, sensor axes."""
        m = self.index.m
        if isinstance(command, PoseGoal):
            error = observation.error if observation.goal is command else None
            if error is None:
                error = pose_error(observation.world_T_tip, observation.world_T_sensor, command.target)[self.index.rows]
            wanted = command.gain * error
        else:
            wanted = command
        linear, saturated_linear = saturate(wanted[:m], self.max_linear_speed)
        angular, saturated_angular = saturate(wanted[m:], self.max_angular_speed)
        return np.concatenate([linear, angular]), saturated_linear or saturated_angular

    def step(self, q: object, command: object, *, observation: Observation | None = None) -> Step:
        """One control step from q: command -> twist -> joint rates -> next q.

        Args:
            q: the configuration (nq,); checked unless ``observation`` (taken at q) is given.
            command: a twist (m + k,) in partition order, sensor axes (m/s, rad/s), or a
                :class:`PoseGoal`.
            observation: :meth:`observe` at q, when the caller already has it (the servo
                measures its stop rules on it): it is reused, not recomputed.

        A singular square block halts the step (``Status.HALT_FOR_SINGULARITY``, q kept,
        rates 0); joints that the command would carry past a position limit are held at it
        while the others serve the command (``Status.JOINT_LIMIT``, ``frozen``); rates over
        a velocity limit are all scaled alike (``Status.RATE_LIMITED``). Never raises for
        what the robot does.
        """
        if observation is None:
            observation = self.observe(q)
        if not isinstance(command, PoseGoal):
            command = check_vector(command, self.index.rows.size, "twist (linear then angular components)")
        twist, saturated = self.command_twist(observation, command)
        try:
            rates = partition_rates(observation.jacobian, self.index, twist, self.algorithm, observation.blocks)
        except SingularBlockError as singular:
            return self._halt(observation, twist, str(singular))
        statuses = [Status.TWIST_SATURATED] if saturated else []
        details: list[str] = []
        frozen: tuple[str, ...] = ()
        passing = self._passing(observation.q, rates, ()) if self.position_limits else []
        if passing:
            try:
                rates, frozen = self._respect_position_limits(observation, twist, rates, passing)
            except SingularBlockError as singular:
                return self._halt(observation, twist, f"{singular}, with the joints at their limits left out")
            if frozen:
                statuses.append(Status.JOINT_LIMIT)
                details.append(f"held at a position limit: {', '.join(frozen)}")
        scale = self._rate_scale(rates)
        if scale < 1.0:
            rates = rates * scale
            statuses.append(Status.RATE_LIMITED)
            details.append(f"rates scaled by {scale:.3g} to meet the velocity limits")
        next_q = self.robot.integrate(observation.q, rates, self.dt)
        if self.position_limits:
            hit = self._clamp(next_q)
            if hit and not frozen:
                statuses.append(Status.JOINT_LIMIT)
                details.append(hit)
        return Step(next_q, rates, most_severe(*statuses), frozen, twist, observation, "; ".join(details))

    def _halt(self, observation: Observation, twist: np.ndarray, detail: str) -> Step:
        return Step(observation.q, np.zeros(self.robot.nv), Status.HALT_FOR_SINGULARITY, (), twist, observation, detail)

    def _passing(self, q: np.ndarray, rates: np.ndarray, skipped: Collection[_Limit]) -> list[_Limit]:
        """The limits, less ``skipped``, that the commanded rates carry their joints past
        within dt. On Python floats: numpy's per-call cost exceeds the arithmetic for a
        handful of joints, and this runs every step."""
        q_values, rate_values, dt = q.tolist(), rates.tolist(), self.dt
        passing = []
        for limit in self._limits:
            value = q_values[limit.index] + rate_values[limit.velocity] * dt
            if (value > limit.upper or value < limit.lower) and limit not in skipped:
                passing.append(limit)
        return passing

    def _respect_position_limits(
        self, observation: Observation, twist: np.ndarray, rates: np.ndarray, passing: list[_Limit]
    ) -> tuple[np.ndarray, tuple[str, ...]]:
        """(rates, blocked joints), from the limits ``passing`` at ``rates``: those joints are
        left out and the rates solved again, until no remaining joint passes a limit; each
        blocked joint goes on at its commanded rate up to its limit, and stops there."""
        q = observation.q
        blocked: dict[_Limit, float] = {}  # each blocked joint's rate when it was blocked
        while passing:
            blocked.update((limit, float(rates[limit.velocity])) for limit in passing)
            rates = self._solve_without(observation, twist, {limit.joint for limit in blocked})
            passing = self._passing(q, rates, blocked)
        for limit, commanded in blocked.items():
            rates[limit.velocity] = limit.onto_the_limit(q, commanded, self.dt)
        return rates, tuple(limit.joint for limit in blocked)

    def _solve_without(self, observation: Observation, twist: np.ndarray, left_out: set[str]) -> np.ndarray:
        """The algorithm's rates with the ``left_out`` joints removed from the partition (they
        get rate 0 here). Raises SingularBlockError as the algorithm does."""
        partition = self.partition
        reduced = Partition(
            [joint for joint in partition.arm if joint not in left_out],
            [joint for joint in partition.wrist if joint not in left_out],
            linear=partition.linear,
            angular=partition.angular,
        )
        return partition_rates(observation.jacobian, reduced.resolve(self.robot), twist, self.algorithm)

    def _rate_scale(self, rates: np.ndarray) -> float:
        """The largest factor <= 1 that brings every rate within its velocity limit."""
        scale = 1.0
        rate_values = rates.tolist()
        for velocity, limit in self._rate_limit_rows:
            magnitude = abs(rate_values[velocity])
            if magnitude * scale > limit:
                scale = limit / magnitude
        return scale

    def _clamp(self, q: np.ndarray) -> str:
        """Clamp q in place to the limits; describe the first joint that was past one ('' if none)."""
        hit = ""
        for limit in self._limits:
            value = q[limit.index]
            if value < limit.lower or value > limit.upper:
                side, bound = ("lower", limit.lower) if value < limit.lower else ("upper", limit.upper)
                q[limit.index] = bound
                hit = hit or f"{limit.joint} reached its {side} limit {bound:.4g}"
        return hit


def error_norms(observation: Observation, m: int) -> tuple[float, float]:
    """(position error in m, rotation error in rad) of an observation taken against a goal."""
    assert observation.error is not None
    linear, angular = observation.error[:m], observation.error[m:]
    return math.sqrt(float(linear @ linear)), math.sqrt(float(angular @ angular))


__all__ = [
    "MAX_ANGULAR_SPEED",
    "MAX_LINEAR_SPEED",
    "Controller",
    "Observation",
    "PoseGoal",
    "Step",
    "error_norms",
]
