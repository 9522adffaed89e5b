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
5. q is integrated over dt on the configuration space (``pin.integrate``) and clamped to
   the partition joints' position limits.

:meth:`Controller.step` returns a :class:`Step`: the next q, the rates applied, and a
:class:`~pinrate.control.status.Status` saying what limited the step.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

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
from .status import Status

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


@dataclass(frozen=True)
class _Limit:
    joint: str
    index: int  # into q
    lower: float
    upper: float


class Controller:
    """The resolved-rate control step of a robot (one Robot per controller and thread).

    Args:
        robot: the robot; its tip and sensor frames fix what twists mean.
        algorithm: a name of :data:`pinrate.ALGORITHMS`.
        partition: which joints and twist rows take part; None means ``Partition.auto(robot)``.
        dt: control period in seconds.
        max_linear_speed, max_angular_speed: saturation of the commanded twist (m/s, rad/s;
            inf for none).

    Raises:
        InputError: an unknown algorithm, a bad partition, a dt or speed that is not positive.
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
    ) -> None:
        self.robot = robot
        self.algorithm = check_algorithm(algorithm)
        self.partition = partition_for(robot, partition)
        self.index = self.partition.resolve(robot)
        self.dt = check_positive(dt, "dt")
        self.max_linear_speed = check_positive(max_linear_speed, "max_linear_speed", allow_inf=True)
        self.max_angular_speed = check_positive(max_angular_speed, "max_angular_speed", allow_inf=True)
        self._limits = self._position_limits()

    def _position_limits(self) -> list[_Limit]:
        """The partition's 1-DOF joints with finite position limits."""
        limits = []
        for joint in self.partition.joints:
            bounds = self.robot.joint_limits(joint)
            if bounds is not None:
                limits.append(_Limit(joint, self.robot.model.joints[self.robot.joint_id(joint)].idx_q, *bounds))
        return limits

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
        rates 0); a joint pushed past a position limit is clamped there
        (``Status.JOINT_LIMIT``). Never raises for what the robot does.
        """
        if observation is None:
            observation = self.observe(q)
        if not isinstance(command, PoseGoal):
            command = check_vector(command, self.index.rows.size, "twist (linear then angular components)")
        twist, saturated = self.command_twist(observation, command)
        try:
            rates = partition_rates(observation.jacobian, self.index, twist, self.algorithm, observation.blocks)
        except SingularBlockError as singular:
            return Step(
                observation.q,
                np.zeros(self.robot.nv),
                Status.HALT_FOR_SINGULARITY,
                (),
                twist,
                observation,
                str(singular),
            )
        next_q = self.robot.integrate(observation.q, rates, self.dt)
        hit = self._clamp(next_q)
        if hit:
            return Step(next_q, rates, Status.JOINT_LIMIT, (), twist, observation, hit)
        return Step(next_q, rates, Status.TWIST_SATURATED if saturated else Status.OK, (), twist, observation)

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
