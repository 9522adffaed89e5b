"""The convergence Theorem of Shoham & Koren (1987, §4) at one configuration.

With P = U A^-1 (k x m) and Q = B W^-1 (m x k),

    G = P Q = U A^-1 B W^-1   (k x k, eq. 32)      H = Q P = B W^-1 U A^-1   (m x m, eq. 50)

The error of MCA1 obeys e(i+1) = β G e(i) + G Ω(i) (eq. 40); freezing G along the
trajectory, it dies out when every eigenvalue of G lies inside the unit circle (Result 1);
MCA2 needs the same of H (Result 2). PQ and QP share their non-zero eigenvalues, so the
smaller of G and H decides for all three algorithms (the Theorem).

The Theorem is stated for square, invertible A and W. For other shapes (a 5-DOF arm's 3 x 2
W, a user partition with a tall A) the test is the spectral radius of the algorithm's error
map I − J K or I − K J (:mod:`pinrate.solvers.error_map`), which reduces to ρ(G) for square
blocks. Either way ρ < 1 is a test at one configuration with J frozen: along a path, MCA1's
coupling term −U A⁻¹ v (eq. 30) can make it diverge while ρ < 1 everywhere, so the
coupling is reported beside ρ.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import InputError, SingularBlockError
from ..kinematics.manipulator import Robot
from ..kinematics.partition import Partition, partition_for
from ..solvers import reference
from ..solvers.error_map import MARGINAL, THEOREM_ALGORITHMS, error_map
from ..solvers.registry import check_algorithm


@dataclass(frozen=True)
class Convergence:
    """The Theorem's test at one configuration.

    Attributes:
        G: U A^-1 B W^-1 (k x k, eq. 32), H: B W^-1 U A^-1 (m x m, eq. 50): dimensionless
            maps of the twist error (in the sensor frame's axes).
        eigenvalues: of the smaller of G and H (they share their non-zero eigenvalues).
        spectral_radius: the largest ``|eigenvalue|`` (0.0 when there is none).
        converges: spectral_radius < 1, the Theorem's condition at q.
        algorithm: whose error map gave the coupling (and ρ where the Theorem does not apply).
        theorem_applies: A and W are square (and invertible: otherwise the test raised), as
            the Theorem assumes. When False, ``eigenvalues`` and ``spectral_radius`` are the
            error map's (:mod:`pinrate.solvers.error_map`), G and H the pseudo-inverse ones.
        coupling: (rad/m, m/rad): the error map's off-diagonal norms, ‖U A⁻¹‖ for MCA1
            (eq. 30), ‖B W⁻¹‖ for MCA2 (eq. 49); large values warn that ρ < 1 at each point
            of a path does not make the algorithm converge along it.
    """

    G: np.ndarray
    H: np.ndarray
    eigenvalues: np.ndarray
    spectral_radius: float
    converges: bool
    algorithm: str = "mca1"
    theorem_applies: bool = True
    coupling: tuple[float, float] = (0.0, 0.0)

    def verdict(self) -> str:
        """ "converges" (ρ < 1), "diverges" (ρ > 1) or "inconclusive" (ρ = 1 within
        :data:`MARGINAL`: some direction is not corrected to first order, typically one the
        algorithm's blocks cannot produce; the nonlinear terms decide)."""
        if abs(self.spectral_radius - 1.0) <= MARGINAL:
            return "inconclusive"
        return "converges" if self.spectral_radius < 1.0 else "diverges"

    def basis(self) -> str:
        """What the verdict rests on, in words."""
        if self.theorem_applies:
            return "the Theorem: eigenvalues of G = U A^-1 B W^-1 (eq. 32), A and W square"
        return f"the error map of {self.algorithm} (I - J K): A or W is not square, so the Theorem does not apply"


def convergence_from_blocks(
    A: np.ndarray, B: np.ndarray, U: np.ndarray, W: np.ndarray, *, algorithm: str = "mca1"
) -> Convergence:
    """The Theorem's test from the blocks of eq. 19 (numpy reference: LAPACK eigenvalues).

    Shapes: A (m, a), B (m, w), U (k, a), W (k, w); InputError otherwise. Where A or W is
    not square the verdict is the error map's of ``algorithm`` (an MCA; default MCA1).
    """
    algorithm = check_algorithm(algorithm)
    if algorithm not in THEOREM_ALGORITHMS:
        raise InputError(f"the convergence test is about {', '.join(THEOREM_ALGORITHMS)}, not {algorithm!r}")
    A, B, U, W = (np.asarray(block, dtype=float) for block in (A, B, U, W))
    if any(block.ndim != 2 for block in (A, B, U, W)) or not (
        A.shape[0] == B.shape[0] and U.shape[0] == W.shape[0] and A.shape[1] == U.shape[1] and B.shape[1] == W.shape[1]
    ):
        raise InputError(
            f"blocks must be A (m, a), B (m, w), U (k, a), W (k, w); got {A.shape}, {B.shape}, {U.shape}, {W.shape}"
        )
    G, H = reference.convergence_matrices(A, B, U, W)
    mapped = error_map(np.block([[A, B], [U, W]]), A.shape[0], A.shape[1], algorithm)
    square = A.shape[0] == A.shape[1] and W.shape[0] == W.shape[1]
    eigenvalues = reference.smaller_eigenvalues(G, H) if square else mapped.eigenvalues
    largest = float(np.max(np.abs(eigenvalues))) if eigenvalues.size else 0.0
    radius = largest if square else mapped.spectral_radius
    return Convergence(
        G=G,
        H=H,
        eigenvalues=eigenvalues,
        spectral_radius=radius,
        converges=radius < 1.0,
        algorithm=algorithm,
        theorem_applies=square,
        coupling=mapped.coupling,
    )


def convergence(robot: Robot, q: object, *, partition: Partition | None = None, algorithm: str = "mca1") -> Convergence:
    """The Theorem's test at configuration q: G, H, eigenvalues of the smaller, ρ, ρ < 1, and
    the coupling of ``algorithm``'s error map (whose ρ decides where A or W is not square).

    Raises:
        SingularBlockError: A or W is square and singular at q (G and H do not exist).
    """
    partition = partition_for(robot, partition)
    q = robot.check_q(q)
    try:
        return convergence_from_blocks(*partition.blocks(robot, robot.kinematics(q)[0]), algorithm=algorithm)
    except SingularBlockError as error:
        raise error.at(robot.name, q, " (G and H are undefined there)") from None


def coupling_along(
    robot: Robot, configurations: np.ndarray, *, partition: Partition | None = None, algorithm: str = "mca1"
) -> np.ndarray:
    """The coupling of ``algorithm``'s error map at each configuration (N,): ‖U A⁻¹‖₂ in rad/m
    for MCA1 (the term −U A⁻¹ v of eq. 30), ‖B W⁻¹‖₂ in m/rad for MCA2 (eq. 49), 0 for
    MCA3; inf where A or W is square and singular."""
    partition = partition_for(robot, partition)
    which = 1 if algorithm == "mca2" else 0
    values = []
    for q in robot.check_configurations(configurations):
        try:
            values.append(convergence(robot, q, partition=partition, algorithm=algorithm).coupling[which])
        except SingularBlockError:
            values.append(float("inf"))
    return np.array(values)
