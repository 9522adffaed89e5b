"""The Theorem's block algebra on stacks of blocks (N, r, c), in closed form for n <= 3.

numpy's ``inv`` and ``eigvals`` loop over a stack in C but pay LAPACK's set-up per matrix;
for the 1x1 to 3x3 blocks of the Theorem (A, W, G, H of a 6-DOF arm) the closed forms
written as elementwise operations on length-N arrays are several times faster. Larger
matrices fall back to numpy. Singular blocks follow the one rule of
:mod:`pinrate.solvers.singular`; eigenvalues come from the one routine of
:mod:`pinrate.solvers.eigen`.
"""

from __future__ import annotations

import numpy as np

from ..errors import SingularBlockError
from ..kinematics.partition import pseudo_g_is_exact
from . import eigen
from .error_map import error_map
from .singular import PINV_RCOND, invertible


def inverse(M: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(inverses, singular mask) of a stack (N, r, c): pseudo-inverses when r != c (never
    singular), adjugate / det for square n <= 3, numpy's inv above; singular ones set to 0."""
    count, rows, cols = M.shape
    if rows == 0 or cols == 0:
        return np.zeros((count, cols, rows)), np.zeros(count, dtype=bool)
    if rows != cols:
        return np.linalg.pinv(M, rcond=PINV_RCOND), np.zeros(count, dtype=bool)
    column_norms_squared = np.einsum("nij,nij->nj", M, M)
    scale_squared = np.prod(column_norms_squared, axis=-1)
    if rows == 1:
        det = M[:, 0, 0]
        adjugate = np.ones_like(M)
    elif rows == 2:
        a, b, c, d = M[:, 0, 0], M[:, 0, 1], M[:, 1, 0], M[:, 1, 1]
        det = a * d - b * c
        adjugate = np.stack([np.stack([d, -b], -1), np.stack([-c, a], -1)], 1)
    elif rows == 3:
        m = M
        c00 = m[:, 1, 1] * m[:, 2, 2] - m[:, 1, 2] * m[:, 2, 1]
        c01 = m[:, 1, 2] * m[:, 2, 0] - m[:, 1, 0] * m[:, 2, 2]
        c02 = m[:, 1, 0] * m[:, 2, 1] - m[:, 1, 1] * m[:, 2, 0]
        c10 = m[:, 0, 2] * m[:, 2, 1] - m[:, 0, 1] * m[:, 2, 2]
        c11 = m[:, 0, 0] * m[:, 2, 2] - m[:, 0, 2] * m[:, 2, 0]
        c12 = m[:, 0, 1] * m[:, 2, 0] - m[:, 0, 0] * m[:, 2, 1]
        c20 = m[:, 0, 1] * m[:, 1, 2] - m[:, 0, 2] * m[:, 1, 1]
        c21 = m[:, 0, 2] * m[:, 1, 0] - m[:, 0, 0] * m[:, 1, 2]
        c22 = m[:, 0, 0] * m[:, 1, 1] - m[:, 0, 1] * m[:, 1, 0]
        det = m[:, 0, 0] * c00 + m[:, 0, 1] * c01 + m[:, 0, 2] * c02
        adjugate = np.stack(
            [np.stack([c00, c10, c20], -1), np.stack([c01, c11, c21], -1), np.stack([c02, c12, c22], -1)], 1
        )
    else:
        det = np.linalg.det(M)
        singular = np.logical_not(invertible(det, scale_squared))
        inverses = np.linalg.inv(np.where(singular[:, None, None], np.eye(rows), M))
        inverses[singular] = 0.0
        return inverses, singular
    singular = np.logical_not(invertible(det, scale_squared))
    inverses = adjugate / np.where(singular, 1.0, det)[:, None, None]
    inverses[singular] = 0.0
    return inverses, singular


def matrix_spectral_radius(M: np.ndarray) -> np.ndarray:
    """max ``|eigenvalue|`` of each matrix of a stack (N, n, n); 0 for n = 0 (numpy above 3)."""
    count, n, _ = M.shape
    if n == 0:
        return np.zeros(count)
    if n == 1:
        return np.abs(M[:, 0, 0])
    if n == 2:
        return eigen.spectral_radius_2(M[:, 0, 0], M[:, 0, 1], M[:, 1, 0], M[:, 1, 1], eigen.ARRAYS)
    if n == 3:
        return eigen.spectral_radius_3(tuple(M[:, r, c] for r in range(3) for c in range(3)), eigen.ARRAYS)
    return np.abs(np.linalg.eigvals(M)).max(axis=1)


def spectral_radius(A: np.ndarray, B: np.ndarray, U: np.ndarray, W: np.ndarray) -> np.ndarray:
    """ρ of the smaller of G = U A^-1 B W^-1 and H = B W^-1 U A^-1 (eq. 32, 50) for stacks of
    blocks (N, ., .); inf where A or W is singular.

    Where A is tall or W wide, pseudo-inverses no longer give the error map's spectrum
    (A A^+ or W^+ W is not the identity), so each configuration gets ρ of MCA1's error map
    (:mod:`pinrate.solvers.error_map`; a loop, not batched: user partitions only). A wide A or a
    tall W of full rank (a 7-DOF arm, a 5-DOF arm) keeps the batched G, which equals it.
    """
    if not pseudo_g_is_exact(A.shape[1], A.shape[2], W.shape[1], W.shape[2]):
        m, arm = A.shape[1], A.shape[2]
        per_configuration: list[float] = []
        for blocks in zip(A, B, U, W, strict=True):
            try:
                per_configuration.append(
                    error_map(
                        np.block([[blocks[0], blocks[1]], [blocks[2], blocks[3]]]), m, arm, "mca1"
                    ).spectral_radius
                )
            except SingularBlockError:
                per_configuration.append(np.inf)
        return np.array(per_configuration)
    A_inv, singular_A = inverse(A)
    W_inv, singular_W = inverse(W)
    P = U @ A_inv
    Q = B @ W_inv
    radii = matrix_spectral_radius(P @ Q if P.shape[1] <= Q.shape[1] else Q @ P)
    radii[singular_A | singular_W] = np.inf
    return radii
