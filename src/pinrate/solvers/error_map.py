"""The error map of a resolved-rate algorithm, for blocks of any shape (Shoham & Koren §4
generalised; issue 10).

An algorithm turns a twist command s (m linear + k angular components, sensor axes) into
joint rates q̇ = K s, K its (approximate) inverse of the partition's Jacobian J. One servo
cycle with the remaining error as its command (the paper's iteration, eq. 40) leaves the
error

    e ← (I − J K) e                       (task space, r = m + k rows)
    δ ← (I − K J) δ                       (joint space, δ = q − q*, n joints)

The two maps share their non-zero eigenvalues. pinrate uses the smaller: I − J K when
r <= n (every task direction must be corrected), I − K J when r > n (a tall J: only the
n directions the joints span exist near a reachable target, where e = J δ to first order).
The iteration converges where the spectral radius ρ of that map is below 1; with a gain
β = gain · dt < 1 the servo's map is I − β J K, which converges for small β where every
eigenvalue λ of J K has Re λ > 0 (implied by ρ < 1).

For square, invertible A and W the maps reduce to the Theorem's (P = U A⁻¹, Q = B W⁻¹,
G = P Q, H = Q P; eq. 24-25, 44-45, 51-52):

    MCA1:  J K = [[I, 0], [P, I − G]]      I − J K = [[0, 0], [−P, G]]
    MCA2:  J K = [[I − H, Q], [0, I]]      I − J K = [[H, −Q], [0, 0]]
    MCA3:  J K = [[I − H, 0], [0, I − G]]  I − J K = [[H, 0], [0, G]]

so ρ(I − J K) = ρ(G) = ρ(H) for all three, the Theorem's test. The off-diagonal block is
the *coupling*: −P = −U A⁻¹ puts MCA1's angular error term −U A⁻¹ v (eq. 30) into the map,
−Q = −B W⁻¹ MCA2's linear term −B W⁻¹ Ω (eq. 49). It does not change the eigenvalues, but
it grows without bound as A (or W) nears singularity, and along a path, where J changes
from cycle to cycle, a large coupling can make an algorithm diverge while ρ < 1 at every
point: ρ < 1 along a path is necessary for the frozen-J argument, not sufficient.

K is built by applying the algorithm itself to the unit twists (one column each), so this
module holds no second copy of any algorithm's formula.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..kinematics.partition import split_blocks
from .registry import REGISTRY

THEOREM_ALGORITHMS = ("mca1", "mca2", "mca3")
"""The algorithms the Theorem is about; for the others ρ says nothing about convergence."""

MARGINAL = 1e-9
"""``|ρ − 1|`` up to which ρ is reported as exactly 1: an eigenvalue 1 is structural (a direction
the algorithm's blocks never correct), and rounding must not turn it into "converges"."""


@dataclass(frozen=True)
class ErrorMap:
    """The error map of one algorithm at one configuration.

    Attributes:
        matrix: I − J K (r x r, task space) when r <= n, else I − K J (n x n, joint space).
        space: "task" or "joint", which of the two ``matrix`` is.
        eigenvalues: of ``matrix``.
        spectral_radius: the largest ``|eigenvalue|`` (0.0 for an empty map).
        coupling: (‖(I − J K)[angular, linear]‖₂ in rad/m, ‖(I − J K)[linear, angular]‖₂ in
            m/rad): how much of a linear command becomes angular error and the reverse
            (MCA1: ‖U A⁻¹‖, 0; MCA2: 0, ‖B W⁻¹‖; MCA3, exact: 0, 0 for square blocks).
    """

    matrix: np.ndarray
    space: str
    eigenvalues: np.ndarray
    spectral_radius: float
    coupling: tuple[float, float]


def _approximate_inverse(jacobian: np.ndarray, m: int, arm_columns: int, algorithm: str) -> np.ndarray:
    """K (n x r): the algorithm's rates for each unit twist, J the partition's (r x n) with
    its m linear rows first and its arm_columns arm joints first.

    Raises:
        SingularBlockError: a block algorithm met a singular square block.
    """
    rows, columns = jacobian.shape
    entry = REGISTRY[algorithm]
    inverse = np.zeros((columns, rows))
    blocks = split_blocks(jacobian, m, arm_columns)
    for j, twist in enumerate(np.eye(rows)):
        if entry.whole is not None:
            inverse[:, j] = entry.whole(jacobian, twist)
        else:
            assert entry.blocks is not None
            arm, wrist = entry.blocks(*blocks, twist[:m], twist[m:])
            inverse[:arm_columns, j] = arm
            inverse[arm_columns:, j] = wrist
    return inverse


def error_map(jacobian: np.ndarray, m: int, arm_columns: int, algorithm: str) -> ErrorMap:
    """The algorithm's :class:`ErrorMap` for the partition's Jacobian (r x n, sensor axes).

    Raises:
        SingularBlockError: a block algorithm met a singular square block.
    """
    rows, columns = jacobian.shape
    inverse = _approximate_inverse(jacobian, m, arm_columns, algorithm)
    task = np.eye(rows) - jacobian @ inverse
    matrix, space = (task, "task") if rows <= columns else (np.eye(columns) - inverse @ jacobian, "joint")
    eigenvalues = np.linalg.eigvals(matrix) if matrix.size else np.zeros(0, dtype=complex)
    radius = float(np.abs(eigenvalues).max()) if eigenvalues.size else 0.0
    if abs(radius - 1.0) <= MARGINAL:
        radius = 1.0
    coupling = (_norm(task[m:, :m]), _norm(task[:m, m:]))
    return ErrorMap(matrix=matrix, space=space, eigenvalues=eigenvalues, spectral_radius=radius, coupling=coupling)


def _norm(block: np.ndarray) -> float:
    return float(np.linalg.norm(block, 2)) if block.size else 0.0
