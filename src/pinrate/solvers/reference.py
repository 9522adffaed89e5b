"""The numpy reference of every block algorithm: joint rates from a sensor-frame twist, and
the Theorem's matrices G and H.

Every function here is pure mathematics over the partitioned Jacobian of eq. 19,

    J = [[A, B], [U, W]],   twist = [v; Ω],   rates = [qdot_arm; qdot_wrist],

with v (the m controlled linear components) and Ω (the k controlled angular components)
expressed in the sensor frame's axes, exactly as the rows of J. Blocks that are not square
are inverted with the Moore-Penrose pseudo-inverse. A square block is *singular* by the
rule of :mod:`pinrate.solvers.singular`; the MCA algorithms then raise
:class:`SingularBlockError` naming the block, while ``exact`` falls back to the minimum-norm
least-squares solution and ``dls`` is always finite.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from ..errors import SingularBlockError
from .singular import PINV_RCOND, invertible

EXACT_RCOND = 1e-10
"""``exact`` falls back to the pseudo-inverse when J's condition number exceeds 1 / EXACT_RCOND."""

DLS_DAMPING = 1e-2
"""Damping λ of :func:`dls` (in the twist's mixed units: m/s and rad/s per unit rate)."""

Blocks = tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]

Inverter = Callable[[np.ndarray, str], np.ndarray]
"""(block, its name) -> its inverse: :func:`inverse`, or a generalized inverse that stays
finite at singular blocks (:mod:`pinrate.solvers.generalized`)."""


def inverse(M: np.ndarray, block: str) -> np.ndarray:
    """M^-1 for a non-singular square block, M^+ for a rectangular one.

    Raises:
        SingularBlockError: a square block that the singularity rule calls singular.
    """
    rows, cols = M.shape
    if rows == 0 or cols == 0:
        return np.zeros((cols, rows))
    if rows != cols:
        return np.linalg.pinv(M, rcond=PINV_RCOND)
    column_norms_squared = np.einsum("ij,ij->j", M, M)
    if not invertible(float(np.linalg.det(M)), float(np.prod(column_norms_squared))):
        raise SingularBlockError(f"block {block} ({rows}x{cols}) is singular", block=block)
    return np.linalg.inv(M)


def exact(J: np.ndarray, twist: np.ndarray) -> np.ndarray:
    """The exact resolved-rate solution qdot = J^-1 s (eq. 4, 18).

    Square: one LAPACK solve, no error. Since ||J||_F ||qdot|| <= cond(J) ||s||, a solution
    with ||J||_F ||qdot|| > ||s|| / EXACT_RCOND betrays a (numerically) singular J; it and
    every non-square J get the minimum-norm least-squares solution J^+ s instead, whose
    twist error (I - J J^+) s is the part of the command the joints cannot produce.
    """
    rows, cols = J.shape
    if rows == cols and rows > 0:
        try:
            rates = np.linalg.solve(J, twist)
        except np.linalg.LinAlgError:
            rates = None
        if rates is not None:
            flat = J.ravel()
            # ndarray.dot: the same BLAS dot as @ on vectors, without matmul's dispatch.
            growth = float(flat.dot(flat)) * float(rates.dot(rates)) * EXACT_RCOND**2
            if growth <= float(twist.dot(twist)):  # also False for NaN/inf rates
                return rates
    return np.linalg.pinv(J, rcond=PINV_RCOND) @ twist if J.size else np.zeros(cols)


def schur(
    A: np.ndarray,
    B: np.ndarray,
    U: np.ndarray,
    W: np.ndarray,
    v: np.ndarray,
    omega: np.ndarray,
    invert: Inverter = inverse,
) -> tuple[np.ndarray, np.ndarray]:
    """The exact inverse by blocks (eq. 20), through the Schur complement of W:

        K = (A - B W^-1 U)^-1,  N = (W - U A^-1 B)^-1,  L = -A^-1 B N,  M = -W^-1 U K
        qdot_arm   = K v + L Ω = K (v - B W^-1 Ω)
        qdot_wrist = M v + N Ω = W^-1 (Ω - U qdot_arm)

    The last form follows from Woodbury's identity N = W^-1 + W^-1 U K B W^-1 and needs
    neither A^-1 nor N: one complement and W^-1. With a wide arm (A is m x n, n > m) K is
    the pseudo-inverse of the m x n complement and the result still solves J q̇ = s exactly
    (a particular solution, not the minimum-norm one). Error: none when W and K exist.
    (The OCR'd eq. 20 prints "U = -A^-1 B N" for L.)
    """
    W_inv = invert(W, "W")
    arm = invert(A - B @ W_inv @ U, "A - B W^-1 U") @ (v - B @ (W_inv @ omega))
    return arm, W_inv @ (omega - U @ arm)


def position_first(
    A: np.ndarray,
    B: np.ndarray,
    U: np.ndarray,
    W: np.ndarray,
    v: np.ndarray,
    omega: np.ndarray,
    invert: Inverter = inverse,
) -> tuple[np.ndarray, np.ndarray]:
    """Position exact, orientation in least squares over the motions that keep it (task
    priority by blocks, for a square A and a tall W: a 5-DOF arm's 3x3 A and 3x2 W):

        S = W - U A^-1 B                               (the Schur complement of A)
        qdot_wrist = S^+ (Ω - U A^-1 v)
        qdot_arm   = A^-1 (v - B qdot_wrist)

    Every rate vector whose linear rows make v is (A^-1 (v - B w), w) for some wrist rates w,
    and its angular rows miss Ω by (Ω - U A^-1 v) - S w; S^+ takes the w of least miss
    (the least-norm one where S loses rank). For square blocks this is eq. 20's N form,
    N = S^-1, L = -A^-1 B N, and gives J^-1 s. Error: e_v = 0 and
    e_Ω = (I - S S^+)(Ω - U A^-1 v), in the sensor frame's axes (rad/s): the rotation about
    the directions S cannot make (for a 3x2 S of rank 2, its left null vector).

    Raises:
        SingularBlockError: A is singular (by ``invert``'s rule; a filtering inverter never raises).
    """
    A_inv = invert(A, "A")
    wrist = invert(W - U @ A_inv @ B, "W - U A^-1 B") @ (omega - U @ (A_inv @ v))
    return A_inv @ (v - B @ wrist), wrist


def mca1(
    A: np.ndarray,
    B: np.ndarray,
    U: np.ndarray,
    W: np.ndarray,
    v: np.ndarray,
    omega: np.ndarray,
    invert: Inverter = inverse,
) -> tuple[np.ndarray, np.ndarray]:
    """First motion control algorithm (eq. 23-25): J^-1 with U taken as 0.

        qdot_arm = A^-1 v - A^-1 B W^-1 Ω        (eq. 24)
        qdot_wrist = W^-1 Ω                       (eq. 25)

    Error: the velocity is exact, v' = v (eq. 28); the angular velocity is off by
    e = Ω - Ω' = -U qdot_arm = -U A^-1 v + G Ω (eq. 30-31), G = U A^-1 B W^-1 (eq. 32).
    Exact when U = 0 (a Cartesian arm).
    """
    A_inv, W_inv = invert(A, "A"), invert(W, "W")
    wrist = W_inv @ omega
    return A_inv @ (v - B @ wrist), wrist


def mca2(
    A: np.ndarray,
    B: np.ndarray,
    U: np.ndarray,
    W: np.ndarray,
    v: np.ndarray,
    omega: np.ndarray,
    invert: Inverter = inverse,
) -> tuple[np.ndarray, np.ndarray]:
    """Second motion control algorithm (eq. 22, 44-45): J^-1 with B taken as 0.

        qdot_arm = A^-1 v                          (eq. 44)
        qdot_wrist = -W^-1 U A^-1 v + W^-1 Ω        (eq. 45)

    Error: the angular velocity is exact, Ω' = Ω (eq. 47); the velocity is off by
    e_v = v - v' = -B qdot_wrist = H v - B W^-1 Ω (eq. 48-49), H = B W^-1 U A^-1 (eq. 50).
    Exact when B = 0: the wrist axes meet at the TCP (eq. 22).
    """
    A_inv, W_inv = invert(A, "A"), invert(W, "W")
    arm = A_inv @ v
    return arm, W_inv @ (omega - U @ arm)


def mca3(
    A: np.ndarray,
    B: np.ndarray,
    U: np.ndarray,
    W: np.ndarray,
    v: np.ndarray,
    omega: np.ndarray,
    invert: Inverter = inverse,
) -> tuple[np.ndarray, np.ndarray]:
    """Third (general) motion control algorithm (eq. 21, 51-52): K ≈ A^-1, N ≈ W^-1.

        qdot_arm = A^-1 v - A^-1 B W^-1 Ω           (eq. 51)
        qdot_wrist = -W^-1 U A^-1 v + W^-1 Ω         (eq. 52)

    Error: e_v = H v (eq. 53) and e_Ω = G Ω (eq. 54).
    """
    A_inv, W_inv = invert(A, "A"), invert(W, "W")
    return A_inv @ (v - B @ (W_inv @ omega)), W_inv @ (omega - U @ (A_inv @ v))


def dls(J: np.ndarray, twist: np.ndarray, damping: float = DLS_DAMPING) -> np.ndarray:
    """Damped least squares: qdot = J^T (J J^T + λ² I)^-1 s, λ = ``damping``.

    The singularity-robust baseline (Nakamura & Hanafusa 1986; Wampler 1986): finite
    everywhere, with a twist error λ² (J J^T + λ² I)^-1 s that grows near singularities and
    vanishes as the command goes to zero.
    """
    rows = J.shape[0]
    if J.size == 0:
        return np.zeros(J.shape[1])
    return J.T @ np.linalg.solve(J @ J.T + damping**2 * np.eye(rows), twist)


def damped(M: np.ndarray, block: str) -> np.ndarray:
    """M# = M^T (M M^T + λ² I)^-1, λ = :data:`DLS_DAMPING`: :func:`dls`'s inverse of a block
    (the ``block`` name is unused: it is finite for every M, so it raises nothing)."""
    rows, cols = M.shape
    if rows == 0 or cols == 0:
        return np.zeros((cols, rows))
    return dls(M, np.eye(rows))


def convergence_matrices(A: np.ndarray, B: np.ndarray, U: np.ndarray, W: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(G, H) = (U A^-1 B W^-1, B W^-1 U A^-1) (eq. 32, 50); pseudo-inverses for non-square blocks.

    G is k x k (angular rows), H is m x m (linear rows); they share their non-zero eigenvalues.
    """
    P = U @ inverse(A, "A")
    Q = B @ inverse(W, "W")
    return P @ Q, Q @ P


def smaller_eigenvalues(G: np.ndarray, H: np.ndarray) -> np.ndarray:
    """The eigenvalues (LAPACK) of the smaller of G and H, which share their non-zero ones
    (the Theorem); empty when that one is empty."""
    smaller = G if G.shape[0] <= H.shape[0] else H
    return np.linalg.eigvals(smaller) if smaller.size else np.zeros(0, dtype=complex)


def spectral_radius(A: np.ndarray, B: np.ndarray, U: np.ndarray, W: np.ndarray) -> float:
    """ρ, the largest ``|eigenvalue|`` of G and H (eq. 32, 50), 0.0 when there is none.

    Raises:
        SingularBlockError: A or W is square and singular.
    """
    eigenvalues = smaller_eigenvalues(*convergence_matrices(A, B, U, W))
    return float(np.max(np.abs(eigenvalues))) if eigenvalues.size else 0.0
