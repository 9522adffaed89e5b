"""reference.position_first (task priority by blocks, for a square A and a tall W) against an
independent computation: numpy's least squares over the null space of the position rows."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import pinrate
from pinrate import Partition
from pinrate.solvers import reference

FIVE_DOF = Path(__file__).parent.parent / "data" / "five_dof_arm.urdf"


def least_orientation_miss(J: np.ndarray, m: int, twist: np.ndarray) -> tuple[float, np.ndarray]:
    """(min ‖J_o x - Ω‖ over every x with J_p x = v, the unit direction J_o's rates cannot
    reach while the position rows hold): x = x0 + N z with x0 = J_p^+ v and N a basis of J_p's
    null space (numpy's SVD), z by numpy's lstsq."""
    linear, angular = J[:m], J[m:]
    x0 = np.linalg.lstsq(linear, twist[:m], rcond=None)[0]
    _, values, right_t = np.linalg.svd(linear)
    null = right_t[int(np.sum(values > 1e-12 * values[0])) :].T
    z = np.linalg.lstsq(angular @ null, twist[m:] - angular @ x0, rcond=None)[0]
    left = np.linalg.svd(angular @ null)[0]
    return float(np.linalg.norm(angular @ (x0 + null @ z) - twist[m:])), left[:, -1]


@pytest.mark.parametrize("seed", range(20))
def test_position_first_makes_the_velocity_and_the_least_rotation_miss(seed: int) -> None:
    robot = pinrate.load(FIVE_DOF)
    partition = Partition.auto(robot)
    assert (len(partition.arm), len(partition.wrist), partition.m, partition.k) == (3, 2, 3, 3)
    rng = np.random.default_rng(seed)
    q = robot.sample_configurations(1, rng)[0]
    index = partition.resolve(robot)
    J = robot.jacobian(q)[np.ix_(index.rows, index.columns)]
    twist = rng.normal(size=6) * 0.1
    arm, wrist = reference.position_first(*partition.blocks(robot, robot.jacobian(q)), twist[:3], twist[3:])
    made = J @ np.concatenate([arm, wrist])
    # Rates of a few rad/s on entries of J below 1 m/rad: rounding of the order of 1e-15.
    np.testing.assert_allclose(made[:3], twist[:3], atol=1e-12)
    least, direction = least_orientation_miss(J, 3, twist)
    missed = twist[3:] - made[3:]
    assert np.linalg.norm(missed) == pytest.approx(least, rel=1e-9, abs=1e-13)  # both solve the same problem
    # The miss lies along the one direction the wrist cannot reach while the arm holds the velocity.
    assert abs(direction @ missed) == pytest.approx(np.linalg.norm(missed), rel=1e-9, abs=1e-13)


@pytest.mark.parametrize("seed", range(5))
def test_the_step_algorithms_that_put_position_first(seed: int) -> None:
    """exact and schur give position_first's rates; dls makes the velocity up to its damping:
    v - J_p x = λ² (A A^T + λ² I)^-1 (v - B w), so within λ² / (σ_min(A)² + λ²) of ‖v - B w‖."""
    robot = pinrate.load(FIVE_DOF)
    partition = Partition.auto(robot)
    rng = np.random.default_rng(100 + seed)
    q = robot.sample_configurations(1, rng)[0]
    twist = rng.normal(size=6) * 0.1
    A, B, U, W = partition.blocks(robot, robot.jacobian(q))
    arm, wrist = reference.position_first(A, B, U, W, twist[:3], twist[3:])
    index = partition.resolve(robot)
    for algorithm in ("exact", "schur"):
        rates = pinrate.joint_rates(robot, q, twist, algorithm=algorithm)[index.columns]
        np.testing.assert_allclose(rates, np.concatenate([arm, wrist]), rtol=1e-12, atol=1e-14)
    rates = pinrate.joint_rates(robot, q, twist, algorithm="dls")[index.columns]
    damped_wrist = rates[3:]
    sigma = np.linalg.svd(A, compute_uv=False)[-1]
    lam = reference.DLS_DAMPING
    bound = lam**2 / (sigma**2 + lam**2) * np.linalg.norm(twist[:3] - B @ damped_wrist)
    assert np.linalg.norm(twist[:3] - A @ rates[:3] - B @ damped_wrist) <= bound * (1 + 1e-9) + 1e-15


def test_square_blocks_give_the_exact_inverse() -> None:
    """For square blocks position_first is eq. 20's N form: J^-1 s (UR5 at home)."""
    robot = pinrate.load("ur5")
    partition = Partition.auto(robot)
    q = robot.home()
    J = robot.jacobian(q)
    twist = np.array([0.1, -0.2, 0.05, 0.3, -0.1, 0.2])
    arm, wrist = reference.position_first(*partition.blocks(robot, J), twist[:3], twist[3:])
    np.testing.assert_allclose(np.concatenate([arm, wrist]), np.linalg.solve(J, twist), rtol=1e-10, atol=1e-12)
