"""Shared fixtures and independent reference computations for the tests."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

import pinrate

DATA = Path(__file__).parent / "data"


@pytest.fixture(scope="session")
def ur5() -> pinrate.Robot:
    return pinrate.load("ur5")


@pytest.fixture(scope="session")
def panda() -> pinrate.Robot:
    return pinrate.load("panda")


@pytest.fixture(scope="session")
def mixed() -> pinrate.Robot:
    """Negative and non-z axes, a prismatic and a continuous joint; sensor mid-chain."""
    return pinrate.load(DATA / "mixed_joints.urdf", tip="tool", sensor="link2")


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
