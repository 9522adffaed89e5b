"""Closed-loop servo of the TCP to a target pose, the sensor commanding the twist each step.

Each step the sensor sees the pose error and commands (Shoham & Koren §2, Fig. 3)

    v = gain * R_s^T (p_target - p_tip)                 (position error, sensor axes)
    Ω = gain * R_s^T log3(R_target R_tip^T)             (rotation error, sensor axes)

where R_s is the sensor frame's rotation in the world and log3 the rotation vector.
Uncontrolled components (those not in the partition) are dropped; the linear and the
angular parts are each scaled down, direction kept, to at most ``max_linear_speed`` (m/s)
and ``max_angular_speed`` (rad/s). The joint rates from the chosen algorithm are
integrated over ``dt`` on the configuration space (``pin.integrate``).

On the Theorem: with ``gain * dt = 1`` the sensor commands the whole error each sample and
the error of MCA1 maps as e <- G e (eq. 40 with β = 1), so |λ(G)| < 1 is the exact test.
With smaller ``gain * dt`` the step is e <- (I - gain dt (I - G)) e: |λ| < 1 remains
sufficient, and only Re λ < 1 is needed as gain dt -> 0.
"""

from __future__ import annotations

import math
import numbers
from dataclasses import dataclass, field

import numpy as np
import pinocchio as pin

from . import _small
from .algorithms import check_algorithm, partition_rates
from .convergence import convergence_from_blocks
from .errors import InputError, SingularBlockError
from .partition import Partition, split_blocks
from .robot import Robot

MAX_LINEAR_SPEED = 0.5
"""Default speed limit of the commanded TCP velocity (m/s)."""

MAX_ANGULAR_SPEED = 1.0
"""Default speed limit of the commanded angular velocity (rad/s)."""

DIVERGENCE_FACTOR = 3.0
"""Stop as diverging once position + orientation error exceeds this times its minimum so far."""


@dataclass
class Trajectory:
    """A servo run: value i of every per-configuration array is taken at ``q[i]``.

    Attributes:
        q: configurations (N, nq), q[0] = q0.
        position_error: norm of the controlled position error (m), (N,).
        orientation_error: norm of the controlled rotation error (rad), (N,).
        spectral_radius: ρ of the smaller of G and H (inf where A or W is singular), (N,).
        status: per configuration, "moving", "saturated" (speed limit active) or the final
            state ("converged", "diverging", "joint limit", "singular", "max steps").
        joint_rates: the rates applied after each configuration but the last, (N - 1, nv).
        converged: both errors below tol at the last configuration.
        reason: why the run stopped, in words.
    """

    q: np.ndarray
    position_error: np.ndarray
    orientation_error: np.ndarray
    spectral_radius: np.ndarray
    status: list[str]
    joint_rates: np.ndarray
    converged: bool
    reason: str
    algorithm: str
    dt: float
    partition: Partition = field(repr=False)

    @property
    def steps(self) -> int:
        """Number of integration steps taken (N - 1)."""
        return self.q.shape[0] - 1

    @property
    def time(self) -> np.ndarray:
        """Time stamps (N,) in seconds."""
        return np.arange(self.q.shape[0]) * self.dt


def as_pose(target: object) -> pin.SE3:
    """A target pose from a 4x4 homogeneous matrix or a pinocchio SE3; InputError otherwise."""
    if isinstance(target, pin.SE3):
        matrix = np.array(target.homogeneous)
    else:
        try:
            matrix = np.asarray(target, dtype=float)
        except (TypeError, ValueError):
            raise InputError("target must be a 4x4 homogeneous matrix or a pinocchio.SE3") from None
    if matrix.shape != (4, 4):
        raise InputError(f"target must be a 4x4 homogeneous matrix, got shape {matrix.shape}")
    if not np.isfinite(matrix).all():
        raise InputError("target contains NaN or inf")
    rotation = matrix[:3, :3]
    if not np.allclose(rotation.T @ rotation, np.eye(3), atol=1e-6) or np.linalg.det(rotation) < 0:
        raise InputError("target's upper-left 3x3 block is not a rotation matrix")
    if not np.allclose(matrix[3], [0.0, 0.0, 0.0, 1.0]):
        raise InputError("target's last row must be [0, 0, 0, 1]")
    return pin.SE3(rotation, matrix[:3, 3])


def pose_error(world_T_tip: pin.SE3, world_T_sensor: pin.SE3, target: pin.SE3) -> np.ndarray:
    """[position error; rotation error] (6,) from the tip to the target, in sensor axes.

    With S the sensor pose: position R_s^T (p_target - p_tip) = (S^-1 T_target).p -
    (S^-1 T_tip).p and rotation R_s^T log3(R_target R_tip^T) = log3(R_a R_b^T) with
    R_a = R_s^T R_target and R_b = R_s^T R_tip (log3 commutes with conjugation).
    """
    sensor_T_target = world_T_sensor.actInv(target)
    if world_T_sensor is world_T_tip:
        return np.concatenate([sensor_T_target.translation, pin.log3(sensor_T_target.rotation)])
    sensor_T_tip = world_T_sensor.actInv(world_T_tip)
    return np.concatenate(
        [
            sensor_T_target.translation - sensor_T_tip.translation,
            pin.log3(sensor_T_target.rotation @ sensor_T_tip.rotation.T),
        ]
    )


def _saturate(values: np.ndarray, limit: float) -> tuple[np.ndarray, bool]:
    norm = math.sqrt(float(values @ values))
    if norm > limit:
        return values * (limit / norm), True
    return values, False


def _positive(value: float, name: str, *, allow_inf: bool = False) -> float:
    """``value`` as a float > 0 (finite unless ``allow_inf``); InputError naming ``name`` otherwise."""
    if (
        isinstance(value, bool)
        or not isinstance(value, numbers.Real)
        or math.isnan(value)
        or value <= 0
        or (value == math.inf and not allow_inf)
    ):
        bound = "a positive number (or inf)" if allow_inf else "a positive finite number"
        raise InputError(f"{name} must be {bound}, got {value!r}")
    return float(value)


def servo(
    robot: Robot,
    q0: object,
    target: object,
    *,
    algorithm: str = "mca1",
    partition: Partition | None = None,
    dt: float = 0.01,
    gain: float = 1.0,
    max_steps: int = 2000,
    tol: float = 1e-4,
    max_linear_speed: float = MAX_LINEAR_SPEED,
    max_angular_speed: float = MAX_ANGULAR_SPEED,
) -> Trajectory:
    """Servo the tip from q0 to ``target`` (4x4 pose in the world, or pinocchio.SE3).

    Stops when the norms of the controlled position error (m) and rotation error (rad) are
    both below ``tol`` (converged), or with a reason: the error grew past
    DIVERGENCE_FACTOR times its best (diverging), a partition joint reached a position limit
    (q is clamped there), a square block became singular, or ``max_steps`` ran out.
    """
    algorithm = check_algorithm(algorithm)
    q = robot.check_q(q0)
    goal = as_pose(target)
    dt, gain, tol = _positive(dt, "dt"), _positive(gain, "gain"), _positive(tol, "tol")
    max_linear_speed = _positive(max_linear_speed, "max_linear_speed", allow_inf=True)
    max_angular_speed = _positive(max_angular_speed, "max_angular_speed", allow_inf=True)
    if isinstance(max_steps, bool) or not isinstance(max_steps, int | np.integer) or max_steps < 0:
        raise InputError(f"max_steps must be a non-negative integer, got {max_steps!r}")
    partition = Partition.auto(robot) if partition is None else partition
    index = partition.resolve(robot)
    m, n_arm = index.m, index.arm_columns.size
    rows = np.ix_(index.rows, index.columns)
    limited = _limited_coordinates(robot, partition)

    configurations, rates_log, status = [q], [], []
    position_errors, orientation_errors, radii = [], [], []

    def measure(q: np.ndarray) -> tuple[np.ndarray, np.ndarray, _small.Blocks | None]:
        """Record the errors and ρ at q; return the Jacobian, the controlled error, the blocks."""
        jacobian, world_T_tip, world_T_sensor = robot.kinematics(q)
        error = pose_error(world_T_tip, world_T_sensor, goal)[index.rows]
        linear, angular = error[:m], error[m:]
        position_errors.append(math.sqrt(float(linear @ linear)))
        orientation_errors.append(math.sqrt(float(angular @ angular)))
        parts = _small.blocks(jacobian, index.selectors) if index.small else None
        try:
            if parts is not None:
                radii.append(_small.spectral_radius(parts))
            else:
                radii.append(convergence_from_blocks(*split_blocks(jacobian[rows], m, n_arm)).spectral_radius)
        except SingularBlockError:
            radii.append(math.inf)
        return jacobian, error, parts

    best = math.inf
    reason, final = "", ""
    for step in range(int(max_steps) + 1):
        jacobian, error, parts = measure(q)
        total = position_errors[-1] + orientation_errors[-1]
        if position_errors[-1] < tol and orientation_errors[-1] < tol:
            final, reason = "converged", f"converged in {step} steps"
            break
        best = min(best, total)
        if total > DIVERGENCE_FACTOR * best + tol:
            final = "diverging"
            reason = f"diverging: error {total:.4g} grew past {DIVERGENCE_FACTOR:g}x its best {best:.4g} at step {step}"
            break
        if step == max_steps:
            final, reason = "max steps", f"max_steps ({max_steps}) reached"
            break

        linear, saturated_linear = _saturate(gain * error[:m], max_linear_speed)
        angular, saturated_angular = _saturate(gain * error[m:], max_angular_speed)
        try:
            rates = partition_rates(jacobian, index, np.concatenate([linear, angular]), algorithm, parts)
        except SingularBlockError as singular:
            final, reason = "singular", f"singular: {singular} at step {step}"
            break
        status.append("saturated" if saturated_linear or saturated_angular else "moving")
        q = robot.integrate(q, rates, dt)
        hit = _clamp_to_limits(q, limited)
        rates_log.append(rates)
        configurations.append(q)
        if hit:
            measure(q)  # q[-1] sits on the limit: its errors complete every per-q array
            final, reason = "joint limit", f"joint limit: {hit} at step {step + 1}"
            break
    status.append(final)
    return Trajectory(
        q=np.array(configurations),
        position_error=np.array(position_errors),
        orientation_error=np.array(orientation_errors),
        spectral_radius=np.array(radii),
        status=status,
        joint_rates=np.array(rates_log).reshape(len(rates_log), robot.nv),
        converged=final == "converged",
        reason=reason,
        algorithm=algorithm,
        dt=dt,
        partition=partition,
    )


def _limited_coordinates(robot: Robot, partition: Partition) -> list[tuple[str, int, float, float]]:
    """(joint, q index, lower, upper) of the partition's 1-DOF joints with finite limits."""
    limited = []
    for joint in partition.joints:
        limits = robot.joint_limits(joint)
        if limits is not None:
            limited.append((joint, robot.model.joints[robot.joint_id(joint)].idx_q, *limits))
    return limited


def _clamp_to_limits(q: np.ndarray, limited: list[tuple[str, int, float, float]]) -> str:
    """Clamp q in place to the limits; describe the first joint that was past one ('' if none)."""
    hit = ""
    for joint, i, lower, upper in limited:
        if q[i] < lower or q[i] > upper:
            side, bound = ("lower", lower) if q[i] < lower else ("upper", upper)
            q[i] = bound
            hit = hit or f"{joint} reached its {side} limit {bound:.4g}"
    return hit
