"""The convergence Theorem of Shoham & Koren (1987, §4) at one configuration.

With P = U A^-1 (k x m) and Q = B W^-1 (m x k),

    G = P Q = U A^-1 B W^-1   (k x k, eq. 32)      H = Q P = B W^-1 U A^-1   (m x m, eq. 50)

The error of MCA1 obeys e(i+1) = β G e(i) + G Ω(i) (eq. 40); freezing G along the
trajectory, it dies out when every eigenvalue of G lies inside the unit circle (Result 1);
MCA2 needs the same of H (Result 2). PQ and QP share their non-zero eigenvalues, so the
smaller of G and H decides for all three algorithms (the Theorem).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import InputError, SingularBlockError
from ..kinematics.manipulator import Robot
from ..kinematics.partition import Partition, partition_for
from ..solvers import reference


@dataclass(frozen=True)
class Convergence:
    """The Theorem's test at one configuration.

    Attributes:
        G: U A^-1 B W^-1 (k x k, eq. 32), H: B W^-1 U A^-1 (m x m, eq. 50): dimensionless
            maps of the twist error (in the sensor frame's axes).
        eigenvalues: of the smaller of G and H (they share their non-zero eigenvalues).
        spectral_radius: the largest |eigenvalue| (0.0 when there is none).
        converges: spectral_radius < 1, the Theorem's condition at q.
    """

    G: np.ndarray
    H: np.ndarray
    eigenvalues: np.ndarray
    spectral_radius: float
    converges: bool


def convergence_from_blocks(A: np.ndarray, B: np.ndarray, U: np.ndarray, W: np.ndarray) -> Convergence:
    """The Theorem's test from the blocks of eq. 19 (numpy reference: LAPACK eigenvalues).

    Shapes: A (m, a), B (m, w), U (k, a), W (k, w); InputError otherwise.
    """
    A, B, U, W = (np.asarray(block, dtype=float) for block in (A, B, U, W))
    if any(block.ndim != 2 for block in (A, B, U, W)) or not (
        A.shape[0] == B.shape[0] and U.shape[0] == W.shape[0] and A.shape[1] == U.shape[1] and B.shape[1] == W.shape[1]
    ):
        raise InputError(
            f"blocks must be A (m, a), B (m, w), U (k, a), W (k, w); got {A.shape}, {B.shape}, {U.shape}, {W.shape}"
        )
    G, H = reference.convergence_matrices(A, B, U, W)
    eigenvalues = reference.smaller_eigenvalues(G, H)
    radius = float(np.max(np.abs(eigenvalues))) if eigenvalues.size else 0.0
    return Convergence(G=G, H=H, eigenvalues=eigenvalues, spectral_radius=radius, converges=radius < 1.0)


def convergence(robot: Robot, q: object, *, partition: Partition | None = None) -> Convergence:
    """The Theorem's test at configuration q: G, H, eigenvalues of the smaller, ρ, ρ < 1.

    Raises:
        SingularBlockError: A or W is square and singular at q (G and H do not exist).
    """
    partition = partition_for(robot, partition)
    q = robot.check_q(q)
    try:
        return convergence_from_blocks(*partition.blocks(robot, robot.kinematics(q)[0]))
    except SingularBlockError as error:
        raise error.at(robot.name, q, " (G and H are undefined there)") from None
