"""Closed-loop servo of the TCP to a target pose: a loop over :meth:`Controller.step` and
its stop rules.

Each step the sensor sees the pose error and commands (Shoham & Koren §2, Fig. 3)

    v = gain * R_s^T (p_target - p_tip)                 (position error, sensor axes)
    Ω = gain * R_s^T log3(R_target R_tip^T)             (rotation error, sensor axes)

saturated to ``max_linear_speed`` (m/s) and ``max_angular_speed`` (rad/s), turned into
joint rates by the algorithm and integrated over ``dt`` (see :mod:`.controller`).

On the Theorem: with ``gain * dt = 1`` the sensor commands the whole error each sample and
the error of MCA1 maps as e <- G e (eq. 40 with β = 1), so |λ(G)| < 1 is the exact test.
With smaller ``gain * dt`` the step is e <- (I - gain dt (I - G)) e: |λ| < 1 remains
sufficient, and only Re λ < 1 is needed as gain dt -> 0.
"""

from __future__ import annotations

import math

import numpy as np

from ..checks import check_count, check_positive
from ..kinematics.manipulator import Robot
from ..kinematics.partition import Partition
from .controller import MAX_ANGULAR_SPEED, MAX_LINEAR_SPEED, Controller, Observation, PoseGoal, error_norms
from .status import Status
from .trajectory import Trajectory

DIVERGENCE_FACTOR = 3.0
"""Stop as diverging once position + orientation error exceeds this times its minimum so far."""


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
    controller = Controller(
        robot,
        algorithm=algorithm,
        partition=partition,
        dt=dt,
        max_linear_speed=max_linear_speed,
        max_angular_speed=max_angular_speed,
    )
    q = robot.check_q(q0)
    goal = PoseGoal.of(target, gain)
    tol = check_positive(tol, "tol")
    max_steps = check_count(max_steps, "max_steps")
    m = controller.index.m

    configurations, rates_log, status = [q], [], []
    position_errors, orientation_errors, radii = [], [], []

    def record(q: np.ndarray) -> Observation:
        observation = controller.observe(q, goal)
        position, orientation = error_norms(observation, m)
        position_errors.append(position)
        orientation_errors.append(orientation)
        radii.append(observation.spectral_radius)
        return observation

    best = math.inf
    reason, final = "", ""
    for step_number in range(max_steps + 1):
        observation = record(q)
        total = position_errors[-1] + orientation_errors[-1]
        if position_errors[-1] < tol and orientation_errors[-1] < tol:
            final, reason = "converged", f"converged in {step_number} steps"
            break
        best = min(best, total)
        if total > DIVERGENCE_FACTOR * best + tol:
            final = "diverging"
            growth = f"error {total:.4g} grew past {DIVERGENCE_FACTOR:g}x its best {best:.4g}"
            reason = f"diverging: {growth} at step {step_number}"
            break
        if step_number == max_steps:
            final, reason = "max steps", f"max_steps ({max_steps}) reached"
            break
        step = controller.step(q, goal, observation=observation)
        if step.status is Status.HALT_FOR_SINGULARITY:
            final, reason = "singular", f"singular: {step.detail} at step {step_number}"
            break
        status.append("saturated" if step.status is Status.TWIST_SATURATED else "moving")
        q = step.q
        rates_log.append(step.joint_rates)
        configurations.append(q)
        if step.status is Status.JOINT_LIMIT:
            record(q)  # q[-1] sits on the limit: its errors complete every per-q array
            final, reason = "joint limit", f"joint limit: {step.detail} at step {step_number + 1}"
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
        algorithm=controller.algorithm,
        dt=controller.dt,
        partition=controller.partition,
    )
