"""Independent reference computations and paths shared by the tests (on sys.path: ``pythonpath`` in pyproject)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pinocchio as pin

import pinrate

ROOT = Path(__file__).resolve().parents[1]
"""The repository root."""

DATA = Path(__file__).parent / "data"


def finite_difference_jacobian(robot: pinrate.Robot, q: np.ndarray, step: float = 1e-6) -> np.ndarray:
    """The sensor-frame TCP Jacobian from central differences of robot.pose alone.

    Column i: the tip origin's velocity and the angular velocity (from log3 of the relative
    rotation) when joint velocity i is 1, rotated into the sensor frame's axes at q.
    """
    sensor_rotation = robot.frame_pose(q, robot.sensor)[:3, :3]
    columns = []
    for i in range(robot.nv):
        tangent = np.zeros(robot.nv)
        tangent[i] = step
        ahead = robot.pose(pin.integrate(robot.model, q, tangent))
        behind = robot.pose(pin.integrate(robot.model, q, -tangent))
        velocity = (ahead[:3, 3] - behind[:3, 3]) / (2 * step)
        angular = pin.log3(ahead[:3, :3] @ behind[:3, :3].T) / (2 * step)
        columns.append(np.concatenate([sensor_rotation.T @ velocity, sensor_rotation.T @ angular]))
    return np.column_stack(columns)


def fuzz_count(base: int) -> int:
    """How many cases a fuzz test runs: ``base`` in ``make test`` (seeded, bounded), times
    ``PINRATE_FUZZ_SCALE`` for a longer hunt (``PINRATE_FUZZ_SCALE=100 pytest tests/fuzz``)."""
    import os

    return base * max(1, int(os.environ.get("PINRATE_FUZZ_SCALE", "1")))


def partition_rows_and_columns(robot: pinrate.Robot, partition: pinrate.Partition) -> tuple[list[int], list[int]]:
    """Rows (twist components, linear then angular) and columns (joints, arm then wrist) of
    a partition in J (6, nv), written here from the contract rather than taken from pinrate."""
    rows = ["xyz".index(a) for a in partition.linear] + [3 + "xyz".index(a) for a in partition.angular]
    columns = [c for joint in partition.joints for c in robot.velocity_indices(joint)]
    return rows, columns
