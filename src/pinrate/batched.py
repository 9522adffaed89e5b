"""Linear algebra on stacks of small matrices (N, n, n), n <= 3, in closed form.

numpy's ``inv`` and ``eigvals`` loop over a stack in C but pay LAPACK's set-up per matrix;
for the 1x1 to 3x3 blocks of the Theorem (A, W, G, H of a 6-DOF arm) the closed forms
written as elementwise operations on length-N arrays are several times faster. Larger
matrices fall back to numpy. Singular matrices follow pinrate's scale-free test:
|det M| <= SINGULAR_RATIO * prod of column norms.
"""

from __future__ import annotations

import numpy as np

from ._small import SINGULAR_RATIO


def inverse(M: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(inverses, singular mask) of a stack (N, r, c): pseudo-inverses when r != c (never
    singular), adjugate / det for square n <= 3, numpy's inv above; singular ones set to 0."""
    count, rows, cols = M.shape
    if rows == 0 or cols == 0:
        return np.zeros((count, cols, rows)), np.zeros(count, dtype=bool)
    if rows != cols:
        return np.linalg.pinv(M, rcond=1e-10), np.zeros(count, dtype=bool)
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
        singular = ~(det * det > SINGULAR_RATIO**2 * scale_squared)
        inverses = np.linalg.inv(np.where(singular[:, None, None], np.eye(rows), M))
        inverses[singular] = 0.0
        return inverses, singular
    singular = ~(det * det > SINGULAR_RATIO**2 * scale_squared)
    inverses = adjugate / np.where(singular, 1.0, det)[:, None, None]
    inverses[singular] = 0.0
    return inverses, singular


def spectral_radius(M: np.ndarray) -> np.ndarray:
    """max |eigenvalue| of each matrix of a stack (N, n, n); 0 for n = 0.

    n = 1: |m|; n = 2: the quadratic formula; n = 3: the characteristic cubic, by Cardano's
    formula where it has one real root and Viète's trigonometric form where it has three.
    """
    count, n, _ = M.shape
    if n == 0:
        return np.zeros(count)
    if n == 1:
        return np.abs(M[:, 0, 0])
    if n == 2:
        half_trace = (M[:, 0, 0] + M[:, 1, 1]) / 2
        det = M[:, 0, 0] * M[:, 1, 1] - M[:, 0, 1] * M[:, 1, 0]
        root = np.sqrt((half_trace * half_trace - det).astype(complex))
        return np.maximum(np.abs(half_trace + root), np.abs(half_trace - root))
    if n > 3:
        return np.abs(np.linalg.eigvals(M)).max(axis=1)
    a, b, c = M[:, 0, 0], M[:, 0, 1], M[:, 0, 2]
    d, e, f = M[:, 1, 0], M[:, 1, 1], M[:, 1, 2]
    g, h, i = M[:, 2, 0], M[:, 2, 1], M[:, 2, 2]
    p2 = -(a + e + i)  # λ³ + p2 λ² + p1 λ + p0
    p1 = (a * e - b * d) + (a * i - c * g) + (e * i - f * h)
    p0 = -(a * (e * i - f * h) - b * (d * i - f * g) + c * (d * h - e * g))
    shift = -p2 / 3  # λ = t + shift: t³ + p t + q = 0
    p = p1 - p2 * p2 / 3
    q = 2 * p2**3 / 27 - p2 * p1 / 3 + p0
    # Cancellation leaves rounding noise where p or q is exactly 0 (a triple root, c I):
    # snap it, or the cube roots of the noise cost ~eps^(1/3) of accuracy.
    p = np.where(np.abs(p) <= 1e-12 * (p2 * p2 / 3 + np.abs(p1)), 0.0, p)
    q = np.where(np.abs(q) <= 1e-12 * (np.abs(2 * p2**3 / 27) + np.abs(p2 * p1 / 3) + np.abs(p0)), 0.0, q)
    discriminant = (q / 2) ** 2 + (p / 3) ** 3
    one_real = discriminant > 0
    # Cardano (one real root, a complex pair).
    root = np.sqrt(np.where(one_real, discriminant, 0.0))
    u, v = np.cbrt(-q / 2 + root), np.cbrt(-q / 2 - root)
    real = -(u + v) / 2 + shift
    imaginary = np.sqrt(3) / 2 * (u - v)
    cardano = np.maximum(np.abs(u + v + shift), np.hypot(real, imaginary))
    # Viète (three real roots); p <= 0 here, p = 0 only for a triple root.
    safe_p = np.where(one_real | (p >= 0), -1.0, p)
    radius = 2 * np.sqrt(-safe_p / 3)
    angle = np.arccos(np.clip(3 * q / (safe_p * radius), -1.0, 1.0))
    roots = radius[:, None] * np.cos((angle[:, None] - 2 * np.pi * np.arange(3)) / 3) + shift[:, None]
    viete = np.where(p >= 0, np.abs(shift), np.abs(roots).max(axis=1))
    return np.where(one_real, cardano, viete)
