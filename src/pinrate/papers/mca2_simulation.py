"""MCA2 servo runs like Shoham & Koren's Fig. 6 and 9: the servo from a start to a target pose
(:func:`simulate_mca2`), and its dead-beat step iterated with no stop rule
(:func:`continue_dead_beat_mca2`). The figures' rows are :mod:`.polar_simulation`'s (Fig. 6)
and :mod:`.scara_simulation`'s (Fig. 9).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..control.commands import PoseGoal
from ..control.controller import Controller, error_norms
from ..control.servo_loop import servo
from ..kinematics.manipulator import Robot
from ..theorem import convergence


@dataclass(frozen=True)
class Simulation:
    """An MCA2 servo run like the paper's Fig. 6 and 9."""

    start_lambda: float
    target_lambda: float
    final_lambda: float
    converged: bool
    reason: str
    error_growth: float  # the largest total error over the initial one
    final_q: np.ndarray
    q: np.ndarray  # (steps + 1, nq): the servo's configurations, q0 first
    total_error: np.ndarray  # (steps + 1,): position + orientation error norms (m + rad) at each q

    @property
    def outcome(self) -> str:
        """The run in the table's words: "converges", or "diverges (why, error ×growth)"."""
        if self.converged:
            return "converges"
        return f"diverges ({self.reason.split(':')[0]}, error ×{self.error_growth:.1f})"


def simulate_mca2(robot: Robot, q0: np.ndarray, q_target: np.ndarray, *, dead_beat: bool) -> Simulation:
    """MCA2 from q0 to the pose at q_target.

    ``dead_beat``: the sensor commands the whole error each sample (gain dt = 1, no speed
    limits: the setting of the Theorem, eq. 40 with beta = 1); otherwise the default servo
    (gain 1, dt 0.01, speed limits).
    """
    settings = (
        {"gain": 100.0, "max_linear_speed": math.inf, "max_angular_speed": math.inf, "max_steps": 500}
        if dead_beat
        else {"max_steps": 5000}
    )
    trajectory = servo(robot, q0, robot.pose(q_target), algorithm="mca2", dt=0.01, tol=1e-6, **settings)
    total = trajectory.position_error + trajectory.orientation_error
    return Simulation(
        start_lambda=float(convergence(robot, q0).G[0, 0]),
        target_lambda=float(convergence(robot, q_target).G[0, 0]),
        final_lambda=float(convergence(robot, trajectory.q[-1]).G[0, 0]),
        converged=trajectory.converged,
        reason=trajectory.reason,
        error_growth=float(total.max() / total[0]),
        final_q=trajectory.q[-1],
        q=trajectory.q,
        total_error=total,
    )


DEAD_BEAT_GAIN = 100.0
"""1/s: with dt = 0.01 s, gain dt = 1, the sensor commands the whole error each sample."""


@dataclass(frozen=True)
class Continuation:
    """The servo's dead-beat MCA2 step iterated with no stop rule (Fig. 6(b))."""

    q: np.ndarray  # (steps + 1, nq), q0 first
    position_error: np.ndarray  # (steps + 1,) m, sensor axes
    orientation_error: np.ndarray  # (steps + 1,) rad
    converged: bool  # both norms below tol at the last q
    statuses: tuple[str, ...]  # each step's Status name

    @property
    def steps(self) -> int:
        """Steps taken."""
        return len(self.q) - 1

    @property
    def total_error(self) -> np.ndarray:
        """Position + orientation error norms (m + rad) at each q: the servo's stop-rule measure."""
        return self.position_error + self.orientation_error


def continue_dead_beat_mca2(
    robot: Robot,
    q0: np.ndarray,
    q_target: np.ndarray,
    *,
    position_limits: bool,
    max_steps: int = 2000,
    tol: float = 1e-6,
) -> Continuation:
    """:func:`simulate_mca2`'s dead-beat step (MCA2, gain 100 1/s, dt 0.01 s, no speed or
    velocity limits) taken again and again from q0 towards the pose at q_target until both
    error norms are under ``tol`` (m, rad) or ``max_steps`` ran out: the servo without its
    stop rules (it has no switch for them). ``singularity="generalized_inverse"`` keeps a
    near-singular A from halting the run (it changes a step only where a singular value of A
    falls under the controller's threshold); ``position_limits`` holds the URDF's limits."""
    controller = Controller(
        robot,
        algorithm="mca2",
        dt=0.01,
        singularity="generalized_inverse",
        velocity_limits=math.inf,
        position_limits=position_limits,
        max_linear_speed=math.inf,
        max_angular_speed=math.inf,
    )
    goal = PoseGoal.of(robot.pose(q_target), DEAD_BEAT_GAIN)
    q = robot.check_q(q0)
    configurations: list[np.ndarray] = [q]
    positions: list[float] = []
    orientations: list[float] = []
    statuses: list[str] = []
    while True:
        position, orientation = error_norms(controller.observe(q, goal), controller.index.m)
        positions.append(position)
        orientations.append(orientation)
        converged = position < tol and orientation < tol
        if converged or len(statuses) == max_steps:
            break
        step = controller.step(q, goal)
        q = step.q
        configurations.append(q)
        statuses.append(step.status.name)
    errors = np.array(positions), np.array(orientations)
    return Continuation(np.array(configurations), *errors, converged, tuple(statuses))
