"""Shoham & Koren Fig. 6: MCA2 on the planar polar robot, (a) converging, (b) diverging.

Misprint found in the OCR'd text: the printed polar poses cannot give the printed λ under any
reading tried (TCP or wrist point, absolute or relative orientation); the simulation is rerun
from poses built to have the printed λ values (:func:`polar_pose_with_lambda`).

What the figure's statement measures (read from the text, computed as read): Fig. 6(b), "the
convergence condition is not fulfilled and the trajectory diverges": ``|λ|`` = 1.5 > 1 at the
start (the target's -0.9 is inside). The dead-beat MCA2 iteration (the Theorem's setting)
first moves away (the servo's divergence stop fires at step 4), then, without joint limits,
crosses G's pole d2 + l C3 = 0, takes d2 through 0 and converges on the mirror branch d2 < 0
(theta1 - 180°, theta3 + 180°: the same pose), which the robot's stroke (d2 >= 0.05 m) and the
paper's d2 > 0 exclude; with the limits held it stops at d2 = 0.05 m, theta3 = 180° short of
the target (:func:`fig6b_continued`). So the figure's outcome holds on the robot, while
``|λ|`` > 1 at the start alone does not make the iteration diverge: the Theorem's condition is
sufficient, not necessary.
"""

from __future__ import annotations

import math

import numpy as np

from .. import robots
from .mca2_simulation import Continuation, Simulation, continue_dead_beat_mca2, simulate_mca2
from .table import Result, row

FIG6_POSES = {
    "a": ((0.50, 0.0, 60.0), (0.45, 20.0, 40.0)),
    "b": ((-1.5, 0.0, 150.0), (-0.9, 20.0, 130.0)),
}
"""Fig. 6's (start, target) as (λ, theta1 in deg, theta3 in deg) of :func:`polar_pose_with_lambda`."""


def polar_pose_with_lambda(lam: float, theta1_deg: float, theta3_deg: float, l: float = 0.2) -> np.ndarray:  # noqa: E741
    """The polar configuration with G = lam at the given angles: d2 = l C3 (1 / lam - 1)."""
    c3 = math.cos(math.radians(theta3_deg))
    return np.array([math.radians(theta1_deg), l * c3 * (1 / lam - 1), math.radians(theta3_deg)])


def fig6_poses(which: str) -> tuple[np.ndarray, np.ndarray]:
    """(q0, q_target) of Fig. 6(``which``), ``which`` "a" or "b" (:data:`FIG6_POSES`)."""
    start, target = FIG6_POSES[which]
    return polar_pose_with_lambda(*start), polar_pose_with_lambda(*target)


def _fig6_run(which: str) -> Simulation:
    """Fig. 6(``which``), ``which`` "a" or "b", rerun with the dead-beat sensor from poses
    with the printed λ (:func:`fig6_poses`)."""
    return simulate_mca2(robots.planar_polar(), *fig6_poses(which), dead_beat=True)


def fig6() -> tuple[Simulation, Simulation]:
    """Fig. 6 rerun from poses with the printed λ: (a) 0.50 -> 0.45, (b) -1.5 -> -0.9."""
    return _fig6_run("a"), _fig6_run("b")


@row
def _fig6a_row() -> Result:
    """S&K Fig. 6(a): λ 0.50 -> 0.45 converges."""
    converging = _fig6_run("a")
    return Result(
        "S&K Fig. 6(a)",
        "polar, MCA2: λ 0.50 -> 0.45, converges",
        f"dead-beat sensor, λ {converging.start_lambda:.2f} -> {converging.target_lambda:.2f}: "
        f"{converging.outcome} (poses built for the printed λ: the printed poses give other λ)",
        "papers/test_worked_examples.py::test_fig_6",
    )


def fig6b_continued(max_steps: int = 2000) -> tuple[Continuation, Continuation]:
    """Fig. 6(b)'s dead-beat MCA2 past the servo's divergence stop: (without joint limits,
    with the URDF's limits held: 0.05 <= d2 <= 1 m, ``|theta1|``, ``|theta3|`` <= 180°)."""
    robot = robots.planar_polar()
    q0, q_target = fig6_poses("b")
    return (
        continue_dead_beat_mca2(robot, q0, q_target, position_limits=False, max_steps=max_steps),
        continue_dead_beat_mca2(robot, q0, q_target, position_limits=True, max_steps=max_steps),
    )


def polar_pole_crossings(q: np.ndarray, l: float = 0.2) -> int:  # noqa: E741
    """How often d2 + l C3, the denominator of G (eq. 56), changes sign along q (steps, nq)."""
    denominator = q[:, 1] + l * np.cos(q[:, 2])
    return int(np.count_nonzero(np.diff(np.sign(denominator)) != 0))


@row
def _fig6b_row() -> Result:
    """S&K Fig. 6(b): the servo's run and its step continued past the stop rules (module docstring)."""
    servo_run = _fig6_run("b")
    free, held = fig6b_continued()
    total, total_free = servo_run.total_error, free.total_error
    stop = len(total) - 1
    below_zero = int(np.argmax(free.q[:, 1] < 0)) if (free.q[:, 1] < 0).any() else -1
    turn1, turn3 = (
        abs(math.degrees(math.remainder(float(offset), 2 * math.pi)))
        for offset in free.q[-1, [0, 2]] - fig6_poses("b")[1][[0, 2]]
    )
    return Result(
        "S&K Fig. 6(b)",
        "polar, MCA2: λ -1.5 (start) -> -0.9 (target), |λ| > 1 at the start: "
        '"the convergence condition is not fulfilled and the trajectory diverges"',
        f"dead-beat sensor, λ {servo_run.start_lambda:.2f} -> {servo_run.target_lambda:.2f}: the servo stops at "
        f"step {stop} (diverging: error ×{total[-1] / total[0]:.1f} its start, ×{total[-1] / total.min():.1f} its "
        f"best). Its step iterated on, no stop rule: without joint limits the error grows to "
        f"×{total_free.max() / total_free[0]:.1f} at step {int(np.argmax(total_free))}, G's pole d2 + l C3 = 0 is "
        f"crossed {polar_pole_crossings(free.q)} times, d2 < 0 from step {below_zero}, and it "
        f"{'converges' if free.converged else 'does not converge'} in {free.steps} steps on the mirror branch "
        f"d2 = {free.q[-1, 1]:.3f} m (theta1 {turn1:.0f}°, theta3 {turn3:.0f}° from the target's: the target pose, "
        f"outside the stroke 0.05-1 m); with the URDF's limits held it ends at d2 = {held.q[-1, 1]:.2f} m, theta3 = "
        f"{math.degrees(held.q[-1, 2]):.0f}°, {held.position_error[-1]:.3f} m and {held.orientation_error[-1]:.2f} "
        f"rad from the target after {held.steps} steps. On the robot the paper's outcome holds; |λ| > 1 at the "
        "start alone does not make the iteration diverge (the Theorem's condition is sufficient only)",
        "papers/test_worked_examples.py::test_fig_6b_continued",
    )
