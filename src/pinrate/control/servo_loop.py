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

Stop rules, on the error measure e = |position error| + |rotation error| (m + rad, the two
norms ``tol`` applies to):

- **converged**: both norms below ``tol``.
- **diverging**: e > DIVERGENCE_FACTOR × min(e so far) + tol. Near the target the error maps
  linearly, e_k+1 ≈ M e_k; with ρ(M) > 1 it grows geometrically, so it passes 3× its minimum
  after ln 3 / ln ρ steps (12 steps at ρ = 1.1). With ρ(M) < 1 it can still grow for a while
  (M is not normal; far from the target the map is not linear), by at most the condition
  number of M's eigenvectors: a factor of 3 over the best error is past what a convergent run
  shows in pinrate's robots and tests, and cheap to detect early.
- **stalled**: e has not fallen below (1 - STALL_IMPROVEMENT) × its value at the last
  improvement for ``stall_time`` seconds of simulated time (default: max(1 s, 5 / gain), five
  time constants of the first-order error decay e(t) = e0 exp(-gain t) that an exact solver
  gives), or for STALL_MAX_STEPS steps, whichever is fewer. Every continuing window improves
  e by 1 %, and e cannot fall below ``tol`` without converging, so a run ends after at most
  ln(e0 / tol) / ln(1 / 0.99) windows whatever ``max_steps`` is.
- **singular**: the step halted for a singularity (``singularity="decelerate"``: the next
  step would have made a block singular; or the algorithm met a singular block).
- **collision**: the step halted before two links would come within the collision monitor's
  stop distance (``Controller(collision=True)``).
- **max steps**: ``max_steps`` ran out.

A joint limit does not stop the run: the step holds the joint on its limit while the others
go on serving the error (a target the held joint was needed for then ends as "stalled").
"""

from __future__ import annotations

import math

import numpy as np

from ..checks import check_count, check_positive
from ..errors import InputError
from ..kinematics.manipulator import Robot
from ..kinematics.partition import Partition
from .commands import PoseGoal
from .controller import MAX_ANGULAR_SPEED, MAX_LINEAR_SPEED, Controller, Observation, error_norms
from .status import Status
from .trajectory import Trajectory

DIVERGENCE_FACTOR = 3.0
"""Stop as diverging once position + orientation error exceeds this times its minimum so far."""

STALL_IMPROVEMENT = 0.01
"""The relative fall of the error that counts as progress for the stall rule."""

STALL_TIME_CONSTANTS = 5.0
"""Default stall window in time constants (1 / gain) of the error's decay; at least 1 s."""

STALL_MAX_STEPS = 100_000
"""Most steps in a stall window, whatever ``stall_time / dt``: an error that needs more steps
than this to fall 1 % is not progressing at a useful rate (and a tiny dt would otherwise
make the window, and the run, endless in wall-clock time)."""

_STEP_WORDS = {
    Status.TWIST_SATURATED: "saturated",
    Status.JOINT_LIMIT: "joint limit",
    Status.RATE_LIMITED: "rate limited",
    Status.WRIST_SINGULARITY: "wrist singularity",
    Status.NEAR_SINGULARITY: "near singularity",
    Status.DECELERATE_FOR_SINGULARITY: "decelerating",
    Status.AUXILIARY_ELBOW: "auxiliary elbow",
    Status.FROZEN: "frozen",
    Status.DECELERATE_FOR_COLLISION: "slowing for collision",
}
"""The word a step's status leaves in ``Trajectory.status`` ("moving" for the others)."""

MIN_TOL = 1e-12
"""Smallest ``tol`` (m and rad): finer than double precision resolves a pose of a 1 m arm."""


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
    stall_time: float | None = None,
    velocity_limits: object = math.inf,
    singularity: str = "decelerate",
    wrist: str = "split",
) -> Trajectory:
    """Servo the tip from q0 to ``target`` (4x4 pose in the world, or pinocchio.SE3).

    Stops when the norms of the controlled position error (m) and rotation error (rad) are
    both below ``tol`` (converged), or with a reason (see the module's stop rules): the error
    grew past DIVERGENCE_FACTOR times its best (diverging), it has not improved by
    STALL_IMPROVEMENT for ``stall_time`` seconds (stalled; default max(1 s, 5 / gain)), a
    step halted for a singularity, or ``max_steps`` ran out. Joints are held at their position
    limits while the others go on (:class:`Controller`). ``velocity_limits``, ``singularity``
    and ``wrist`` as for :class:`Controller`: the default velocity limits, none, keep the
    papers' simulations as they were; None takes the URDF's.
    """
    controller = Controller(
        robot,
        algorithm=algorithm,
        partition=partition,
        dt=dt,
        max_linear_speed=max_linear_speed,
        max_angular_speed=max_angular_speed,
        velocity_limits=velocity_limits,
        singularity=singularity,
        wrist=wrist,
    )
    q = robot.check_q(q0)
    goal = PoseGoal.of(target, gain)
    tol = check_positive(tol, "tol")
    if tol < MIN_TOL:
        raise InputError(f"tol must be at least {MIN_TOL:g} (m and rad), got {tol!r}")
    max_steps = check_count(max_steps, "max_steps")
    if stall_time is None:
        stall_time = max(1.0, STALL_TIME_CONSTANTS / goal.gain)
    stall_steps = min(math.ceil(check_positive(stall_time, "stall_time") / controller.dt), STALL_MAX_STEPS)
    m = controller.index.m

    configurations, rates_log, status, details = [q], [], [], []
    position_errors, orientation_errors, radii = [], [], []

    def record(q: np.ndarray) -> Observation:
        observation = controller.observe_unchecked(q, goal)
        position, orientation = error_norms(observation, m)
        position_errors.append(position)
        orientation_errors.append(orientation)
        radii.append(observation.spectral_radius)
        return observation

    best = math.inf
    progress, progress_step = math.inf, 0  # the error at the last 1 % improvement, and when
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
        if total < (1.0 - STALL_IMPROVEMENT) * progress:
            progress, progress_step = total, step_number
        elif step_number - progress_step >= stall_steps:
            final = "stalled"
            reason = (
                f"stalled: error {total:.4g} (m + rad) has not improved by {STALL_IMPROVEMENT:.0%} on "
                f"{progress:.4g} (step {progress_step}) for {stall_steps * controller.dt:g} s, at step {step_number}"
            )
            break
        if step_number == max_steps:
            final, reason = "max steps", f"max_steps ({max_steps}) reached"
            break
        step = controller.step(q, goal, observation=observation)
        if step.status is Status.HALT_FOR_SINGULARITY:
            final, reason = "singular", f"singular: {step.detail} at step {step_number}"
            break
        if step.status is Status.HALT_FOR_COLLISION:
            final, reason = "collision", f"collision: {step.detail} at step {step_number}"
            break
        status.append(_STEP_WORDS.get(step.status, "moving"))
        details.append(step.detail)
        q = step.q
        rates_log.append(step.joint_rates)
        configurations.append(q)
    status.append(final)
    details.append(reason)
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
        detail=details,
    )
