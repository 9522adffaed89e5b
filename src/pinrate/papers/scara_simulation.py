"""Shoham & Koren Fig. 9: MCA2 on the SCARA from the printed poses, (a) on the elbow-down
branch, converging, (b) on the elbow-up branch, diverging.

Misprint found in the OCR'd text: Fig. 9(b): at the printed target (0.95, -0.06, -50°) G is
next to its pole (l2 S2 + l3 S23 = 0) and very sensitive; the printed start λ 1.62 is reached
at -49.75°.
"""

from __future__ import annotations

import math

import numpy as np

from .. import robots
from .mca2_simulation import Simulation, simulate_mca2
from .table import Result, row


def scara_configuration(
    x: float,
    y: float,
    orientation_deg: float,
    elbow: int,
    *,
    l1: float = 0.4,
    l2: float = 0.4,
    l3: float = 0.4,
    d: float = -0.1,
) -> np.ndarray:
    """SCARA inverse kinematics: TCP at (x, y) with the tool at ``orientation_deg``; elbow ±1."""
    phi = math.radians(orientation_deg)
    wx, wy = x - l3 * math.cos(phi), y - l3 * math.sin(phi)
    c2 = (wx * wx + wy * wy - l1 * l1 - l2 * l2) / (2 * l1 * l2)
    theta2 = elbow * math.acos(max(-1.0, min(1.0, c2)))
    theta1 = math.atan2(wy, wx) - math.atan2(l2 * math.sin(theta2), l1 + l2 * math.cos(theta2))
    return np.array([theta1, theta2, d, phi - theta1 - theta2])


FIG9_POSES = {
    "a": ((1.10, 0.155, -21.3, -1), (1.116, 0.124, -21.3, -1)),
    "b": ((1.0, -0.037, -50, 1), (0.95, -0.06, -50, 1)),
}
"""Fig. 9's printed (start, target) as (x, y in m, tool orientation in deg, elbow ±1) of
:func:`scara_configuration`."""


def _fig9_run(which: str) -> Simulation:
    """Fig. 9(``which``), ``which`` "a" or "b", from the printed poses (:data:`FIG9_POSES`),
    default servo."""
    start, target = FIG9_POSES[which]
    return simulate_mca2(robots.scara(), scara_configuration(*start), scara_configuration(*target), dead_beat=False)


def fig9() -> tuple[Simulation, Simulation]:
    """Fig. 9 from the printed poses, default servo: (a) elbow-down branch, (b) elbow-up branch.

    With λ > 0 real, Re λ > 1 makes the error grow for any gain, so no dead-beat sensor is
    needed to see (b) fail.
    """
    return _fig9_run("a"), _fig9_run("b")


@row
def _fig9a_row() -> Result:
    """S&K Fig. 9(a): λ 0.695 -> 0.718 converges."""
    converging = _fig9_run("a")
    return Result(
        "S&K Fig. 9(a)",
        "SCARA, MCA2: λ 0.695 -> 0.718, converges",
        f"printed poses, λ {converging.start_lambda:.3f} -> {converging.target_lambda:.3f}: {converging.outcome}",
        "papers/test_worked_examples.py::test_fig_9",
    )


@row
def _fig9b_row() -> Result:
    """S&K Fig. 9(b): λ 1.62 -> 1.70 diverges, until the servo crosses to the other elbow branch."""
    diverging = _fig9_run("b")
    return Result(
        "S&K Fig. 9(b)",
        "SCARA, MCA2: λ 1.62 -> 1.70, diverges",
        f"printed poses, λ {diverging.start_lambda:.3f} -> {diverging.target_lambda:.4g} (the target "
        f"sits next to G's pole; 1.62 is reached at -49.75°): "
        f"the error grows ×{diverging.error_growth:.2f} "
        f"while λ > 1, until the servo crosses the elbow singularity theta2 = 0 and "
        f"{'converges' if diverging.converged else 'stops'} on the other elbow branch "
        f"(λ {diverging.final_lambda:.2f})",
        "papers/test_worked_examples.py::test_fig_9",
    )
