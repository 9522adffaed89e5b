"""The error map of any algorithm for any block shapes (pinrate.solvers.error_map), checked
against the Theorem's G and H computed here with numpy (square blocks) and against finite
differences of one real servo cycle (any shapes)."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

import pinrate
from pinrate.solvers.error_map import error_map
from support import partition_rows_and_columns

MCAS = ("mca1", "mca2", "mca3")


def nonzero(values: np.ndarray) -> np.ndarray:
    magnitudes = np.sort(np.abs(values))
    return magnitudes[magnitudes > 1e-9]


@pytest.mark.parametrize("algorithm", MCAS)
@pytest.mark.parametrize("size", [1, 2, 3])
def test_for_square_blocks_the_map_has_the_eigenvalues_of_G(algorithm: str, size: int) -> None:
    rng = np.random.default_rng(size)
    for _ in range(20):
        A, B, U, W = (rng.normal(size=(size, size)) for _ in range(4))
        G = U @ np.linalg.inv(A) @ B @ np.linalg.inv(W)  # eq. 32
        mapped = error_map(np.block([[A, B], [U, W]]), size, size, algorithm)
        expected = np.abs(np.linalg.eigvals(G))
        # MCA3's map is diag(H, G): each non-zero eigenvalue twice (H and G share them).
        expected = np.sort(np.concatenate([expected, expected]) if algorithm == "mca3" else expected)
        np.testing.assert_allclose(nonzero(mapped.eigenvalues), expected[expected > 1e-9], rtol=1e-7)


def test_the_coupling_is_U_A_inverse_for_mca1_and_B_W_inverse_for_mca2() -> None:
    rng = np.random.default_rng(7)
    A, B, U, W = (rng.normal(size=(3, 3)) for _ in range(4))
    J = np.block([[A, B], [U, W]])
    P, Q = U @ np.linalg.inv(A), B @ np.linalg.inv(W)  # eq. 30, 49
    np.testing.assert_allclose(error_map(J, 3, 3, "mca1").coupling, (np.linalg.norm(P, 2), 0.0), atol=1e-9)
    np.testing.assert_allclose(error_map(J, 3, 3, "mca2").coupling, (0.0, np.linalg.norm(Q, 2)), atol=1e-9)
    np.testing.assert_allclose(error_map(J, 3, 3, "mca3").coupling, (0.0, 0.0), atol=1e-9)


def servo_cycle(robot: pinrate.Robot, q: np.ndarray, target: np.ndarray, algorithm: str, partition) -> np.ndarray:
    """One cycle of the paper's iteration, written here from the definitions: the pose error
    in the tip's axes (sensor = tip) is the command, the rates are integrated for 1 s."""
    world_T_tip = robot.pose(q)
    rotation, position = world_T_tip[:3, :3], world_T_tip[:3, 3]
    error = np.concatenate([rotation.T @ (target[:3, 3] - position), pin.log3(rotation.T @ target[:3, :3])])
    rows, _ = partition_rows_and_columns(robot, partition)
    rates = pinrate.joint_rates(robot, q, error[rows], algorithm=algorithm, partition=partition)
    return robot.integrate(q, rates, 1.0)


UR5_TALL_ARM = pinrate.Partition(
    ["shoulder_pan_joint", "shoulder_lift_joint"], ["elbow_joint", "wrist_1_joint", "wrist_2_joint", "wrist_3_joint"]
)


@pytest.mark.parametrize("algorithm", MCAS)
@pytest.mark.parametrize("case", ["so100 (W 3x2, J 6x5)", "ur5 (A 3x2, W 3x4)"])
def test_the_map_is_the_linearised_servo_cycle_for_any_shapes(case: str, algorithm: str) -> None:
    name = case.split()[0]
    robot = pinrate.load(name)
    partition = UR5_TALL_ARM if name == "ur5" else pinrate.Partition.auto(robot)
    rows, columns = partition_rows_and_columns(robot, partition)
    for seed in range(3):
        q_star = robot.random_configuration(seed + 3)
        target = robot.pose(q_star)
        step = 1e-6
        derivative = np.zeros((robot.nv, robot.nv))
        for j in range(robot.nv):
            offset = np.zeros(robot.nv)
            offset[j] = step
            ahead = servo_cycle(robot, robot.integrate(q_star, offset, 1.0), target, algorithm, partition)
            behind = servo_cycle(robot, robot.integrate(q_star, -offset, 1.0), target, algorithm, partition)
            derivative[:, j] = (ahead - behind) / (2 * step)
        cycle = np.sort(np.abs(np.linalg.eigvals(derivative[np.ix_(columns, columns)])))
        jacobian = robot.jacobian(q_star)[np.ix_(rows, columns)]
        mapped = error_map(jacobian, partition.m, len(partition.arm), algorithm)
        np.testing.assert_allclose(np.sort(np.abs(mapped.eigenvalues)), cycle, atol=1e-5)


def test_an_over_determined_arm_gets_an_honest_verdict() -> None:
    # A UR5 partition whose arm has 2 joints for 3 linear rows: the pseudo-inverse G says
    # "converges" (ρ = 0.32 here), but MCA1 does not correct, to first order, the linear
    # direction A cannot produce (the wrist serves only angular rows): the error map has an
    # eigenvalue 1, so the frozen-J test can promise nothing either way.
    robot = pinrate.load("ur5")
    q = robot.random_configuration(3)
    result = pinrate.convergence(robot, q, partition=UR5_TALL_ARM)
    pseudo_G = np.max(np.abs(np.linalg.eigvals(result.G)))
    assert pseudo_G < 1 and not result.theorem_applies
    assert result.spectral_radius == pytest.approx(1.0, abs=1e-9) and not result.converges
    assert result.verdict() == "inconclusive"
    # A square partition of the same robot keeps the Theorem's verdict.
    square = pinrate.convergence(robot, q)
    assert square.theorem_applies and square.verdict() == ("converges" if square.spectral_radius < 1 else "diverges")


def test_a_wide_A_or_a_tall_W_of_full_rank_keeps_the_pseudo_inverse_G() -> None:
    # panda: A 3x4; so100: W 3x2. The servo and the work-volume share take the cheap G there.
    for name in ("panda", "so100"):
        robot = pinrate.load(name)
        partition = pinrate.Partition.auto(robot)
        columns = [c for joint in partition.joints for c in robot.velocity_indices(joint)]
        arm = len(partition.arm)
        for seed in range(5):
            jacobian = robot.jacobian(robot.random_configuration(seed))[:, columns]
            A, B, U, W = jacobian[:3, :arm], jacobian[:3, arm:], jacobian[3:, :arm], jacobian[3:, arm:]
            G = U @ np.linalg.pinv(A) @ B @ np.linalg.pinv(W)
            mapped = error_map(jacobian, 3, arm, "mca1")
            assert mapped.spectral_radius == pytest.approx(np.abs(np.linalg.eigvals(G)).max(), rel=1e-8, abs=1e-12)
