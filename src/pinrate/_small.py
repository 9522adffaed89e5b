"""Closed-form kernels of the block algorithms for square blocks of size 1 to 3.

numpy pays about a microsecond per call on tiny arrays, so the MCA formulas written with
numpy cost more than one 6x6 LAPACK solve. Here the same formulas (eq. 24-25, 44-45,
51-52 and the Schur form of eq. 20, see :mod:`pinrate.algorithms`) run on Python floats:
Cramer's rule for 1x1, 2x2 and 3x3 solves, with the same scale-free singularity test
(|det M| <= SINGULAR_RATIO * prod of column norms). The numpy versions in
:mod:`pinrate.algorithms` stay the reference; the tests check both against the paper's
error identities.
"""

from __future__ import annotations

import cmath
import math
from collections.abc import Callable
from typing import Any

import numpy as np

from .errors import SingularBlockError

Matrix = list[list[float]]
Vector = list[float]

SINGULAR_RATIO = 1e-10
"""A square block M is singular when |det M| <= SINGULAR_RATIO * prod of its column norms
(the one threshold of pinrate: algorithms and batched import it from here)."""
_RATIO_SQUARED = SINGULAR_RATIO * SINGULAR_RATIO


def _singular(det: float, M: Matrix, block: str) -> None:
    """Raise unless |det M| > SINGULAR_RATIO * prod_j ||M[:, j]|| (squared to spare roots)."""
    scale_squared = 1.0
    for column in zip(*M, strict=True):
        scale_squared *= _dot(column, column)
    if not det * det > _RATIO_SQUARED * scale_squared:
        raise SingularBlockError(f"block {block} ({len(M)}x{len(M)}) is singular", block=block)


def _dot(a: tuple[float, ...] | list[float], b: tuple[float, ...] | list[float]) -> float:
    if len(a) == 3:
        return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
    if len(a) == 2:
        return a[0] * b[0] + a[1] * b[1]
    return a[0] * b[0] if a else 0.0


def solve(M: Matrix, b: Vector, block: str) -> Vector:
    """x with M x = b for a non-singular square M of size 0 to 3 (Cramer's rule).

    The 3x3 case repeats :func:`inverse`'s cofactors on purpose: fused with the product it
    skips building M^-1, which is what keeps an MCA step under 0.8x the exact one
    (``_matvec(inverse(M), b)`` measured 0.79-0.81x in benchmarks/step.py).
    """
    n = len(M)
    if n == 3:
        (a, b_, c), (d, e, f), (g, h, i) = M
        c0, c1, c2 = e * i - f * h, f * g - d * i, d * h - e * g
        det = a * c0 + b_ * c1 + c * c2
        scale_squared = (a * a + d * d + g * g) * (b_ * b_ + e * e + h * h) * (c * c + f * f + i * i)
        if not det * det > _RATIO_SQUARED * scale_squared:
            _singular(det, M, block)
        x, y, z = b
        inv = 1.0 / det
        return [
            (c0 * x + (c * h - b_ * i) * y + (b_ * f - c * e) * z) * inv,
            (c1 * x + (a * i - c * g) * y + (c * d - a * f) * z) * inv,
            (c2 * x + (b_ * g - a * h) * y + (a * e - b_ * d) * z) * inv,
        ]
    if n == 2:
        (a, b_), (c, d) = M
        det = a * d - b_ * c
        _singular(det, M, block)
        x, y = b
        return [(d * x - b_ * y) / det, (a * y - c * x) / det]
    if n == 1:
        _singular(M[0][0], M, block)
        return [b[0] / M[0][0]]
    return []


def _matvec(M: Matrix, x: Vector) -> Vector:
    return [_dot(row, x) for row in M]


def _minus_matvec(a: Vector, M: Matrix, x: Vector) -> Vector:
    """a - M x."""
    return [value - _dot(row, x) for value, row in zip(a, M, strict=True)]


def mca1(A: Matrix, B: Matrix, U: Matrix, W: Matrix, v: Vector, omega: Vector) -> tuple[Vector, Vector]:
    """Eq. 24-25: qdot_wrist = W^-1 Ω, qdot_arm = A^-1 (v - B qdot_wrist)."""
    wrist = solve(W, omega, "W")
    return solve(A, _minus_matvec(v, B, wrist), "A"), wrist


def mca2(A: Matrix, B: Matrix, U: Matrix, W: Matrix, v: Vector, omega: Vector) -> tuple[Vector, Vector]:
    """Eq. 44-45: qdot_arm = A^-1 v, qdot_wrist = W^-1 (Ω - U qdot_arm)."""
    arm = solve(A, v, "A")
    return arm, solve(W, _minus_matvec(omega, U, arm), "W")


def mca3(A: Matrix, B: Matrix, U: Matrix, W: Matrix, v: Vector, omega: Vector) -> tuple[Vector, Vector]:
    """Eq. 51-52: qdot_arm = A^-1 (v - B W^-1 Ω), qdot_wrist = W^-1 (Ω - U A^-1 v)."""
    A_inv, W_inv = inverse(A, "A"), inverse(W, "W")
    wrist_only = _matvec(W_inv, omega)  # W^-1 Ω
    arm_only = _matvec(A_inv, v)  # A^-1 v
    return (
        _matvec(A_inv, _minus_matvec(v, B, wrist_only)),
        _matvec(W_inv, _minus_matvec(omega, U, arm_only)),
    )


def schur(A: Matrix, B: Matrix, U: Matrix, W: Matrix, v: Vector, omega: Vector) -> tuple[Vector, Vector]:
    """Eq. 20 by the complement of W: qdot_arm = K (v - B W^-1 Ω), qdot_wrist = W^-1 (Ω - U qdot_arm)."""
    k = len(W)
    # W^-1 U column by column, then the complement A - B W^-1 U.
    W_inv_U_columns = [solve(W, [U[r][c] for r in range(k)], "W") for c in range(len(A))]
    complement = [
        [A[r][c] - sum(B[r][j] * W_inv_U_columns[c][j] for j in range(k)) for c in range(len(A))] for r in range(len(A))
    ]
    arm = solve(complement, _minus_matvec(v, B, solve(W, omega, "W")), "A - B W^-1 U")
    return arm, solve(W, _minus_matvec(omega, U, arm), "W")


KERNELS: dict[str, Callable[..., tuple[Vector, Vector]]] = {
    "mca1": mca1,
    "mca2": mca2,
    "mca3": mca3,
    "schur": schur,
}


def eligible(m: int, n_arm: int, k: int, n_wrist: int) -> bool:
    """Square blocks of size at most 3 (an empty wrist included)."""
    return m == n_arm and k == n_wrist and 0 < m <= 3 and k <= 3


Selector = tuple[Any, Any]  # two slices, or np.ix_ index arrays


def selector(rows: list[int], columns: list[int]) -> Selector:
    """Index of J[rows, columns]: two slices when both are contiguous (one cheap view)."""

    def as_slice(indices: list[int]) -> slice | None:
        if not indices:
            return slice(0, 0)
        if indices == list(range(indices[0], indices[-1] + 1)):
            return slice(indices[0], indices[-1] + 1)
        return None

    row_slice, column_slice = as_slice(rows), as_slice(columns)
    if row_slice is not None and column_slice is not None:
        return (row_slice, column_slice)
    row_index, column_index = np.ix_(rows, columns)
    return (row_index, column_index)


Blocks = tuple[Matrix, Matrix, Matrix, Matrix]


def blocks(jacobian: np.ndarray, selectors: tuple[Selector, ...]) -> Blocks:
    """(A, B, U, W) of eq. 19 as nested lists, from the sensor-frame Jacobian (6, nv)."""
    a, b, u, w = selectors
    return jacobian[a].tolist(), jacobian[b].tolist(), jacobian[u].tolist(), jacobian[w].tolist()


def block_rates(algorithm: str, parts: Blocks, twist: np.ndarray) -> Vector:
    """Rates of the arm then wrist joints for a twist in partition order."""
    command = twist.tolist()
    m = len(parts[0])
    arm, wrist = KERNELS[algorithm](*parts, command[:m], command[m:])
    return arm + wrist


def inverse(M: Matrix, block: str) -> Matrix:
    """M^-1 of a non-singular square M of size 0 to 3: the adjugate over the determinant."""
    n = len(M)
    if n == 3:
        (a, b, c), (d, e, f), (g, h, i) = M
        c0, c1, c2 = e * i - f * h, f * g - d * i, d * h - e * g
        det = a * c0 + b * c1 + c * c2
        scale_squared = (a * a + d * d + g * g) * (b * b + e * e + h * h) * (c * c + f * f + i * i)
        if not det * det > _RATIO_SQUARED * scale_squared:
            _singular(det, M, block)
        s = 1.0 / det
        return [
            [c0 * s, (c * h - b * i) * s, (b * f - c * e) * s],
            [c1 * s, (a * i - c * g) * s, (c * d - a * f) * s],
            [c2 * s, (b * g - a * h) * s, (a * e - b * d) * s],
        ]
    if n == 2:
        (a, b), (c, d) = M
        det = a * d - b * c
        _singular(det, M, block)
        return [[d / det, -b / det], [-c / det, a / det]]
    if n == 1:
        _singular(M[0][0], M, block)
        return [[1.0 / M[0][0]]]
    return []


def _matmul(X: Matrix, Y: Matrix) -> Matrix:
    if len(X) == 3 and len(Y) == 3 and len(Y[0]) == 3 and len(X[0]) == 3:
        (a, b, c), (d, e, f), (g, h, i) = X
        (p, q, r), (s, t, u), (v, w, x) = Y
        return [
            [a * p + b * s + c * v, a * q + b * t + c * w, a * r + b * u + c * x],
            [d * p + e * s + f * v, d * q + e * t + f * w, d * r + e * u + f * x],
            [g * p + h * s + i * v, g * q + h * t + i * w, g * r + h * u + i * x],
        ]
    columns = list(zip(*Y, strict=True)) if Y else []
    return [[_dot(row, column) for column in columns] for row in X]


def spectral_radius(parts: Blocks) -> float:
    """ρ of the smaller of G = U A^-1 B W^-1 and H = B W^-1 U A^-1 (eq. 32, 50).

    Eigenvalues in closed form: |g| for 1x1, the quadratic formula for 2x2, and Cardano's
    (one real root) or Viète's trigonometric (three real roots) formula for 3x3.
    Raises SingularBlockError when A or W is singular.
    """
    A, B, U, W = parts
    P = _matmul(U, inverse(A, "A"))  # k x m
    Q = _matmul(B, inverse(W, "W"))  # m x k
    smaller = _matmul(P, Q) if len(P) <= len(Q) else _matmul(Q, P)
    return max((abs(root) for root in eigenvalues(smaller)), default=0.0)


def eigenvalues(M: Matrix) -> list[complex]:
    """The eigenvalues of a real square matrix of size 0 to 3, in closed form."""
    n = len(M)
    if n == 0:
        return []
    if n == 1:
        return [complex(M[0][0])]
    if n == 2:
        (a, b), (c, d) = M
        half_trace = (a + d) / 2
        root = cmath.sqrt(half_trace * half_trace - (a * d - b * c))
        return [half_trace + root, half_trace - root]
    (a, b, c), (d, e, f), (g, h, i) = M
    # λ³ + p2 λ² + p1 λ + p0 = 0
    p2 = -(a + e + i)
    p1 = (a * e - b * d) + (a * i - c * g) + (e * i - f * h)
    p0 = -(a * (e * i - f * h) - b * (d * i - f * g) + c * (d * h - e * g))
    shift = -p2 / 3  # λ = t + shift: t³ + p t + q = 0
    p = p1 - p2 * p2 / 3
    q = 2 * p2**3 / 27 - p2 * p1 / 3 + p0
    discriminant = (q / 2) ** 2 + (p / 3) ** 3
    if discriminant > 0:
        root = math.sqrt(discriminant)
        u = math.copysign(abs(-q / 2 + root) ** (1 / 3), -q / 2 + root)
        v = math.copysign(abs(-q / 2 - root) ** (1 / 3), -q / 2 - root)
        real = -(u + v) / 2 + shift
        imaginary = math.sqrt(3) / 2 * (u - v)
        return [complex(u + v + shift), complex(real, imaginary), complex(real, -imaginary)]
    if p == 0:
        return [complex(shift)] * 3
    radius = 2 * math.sqrt(-p / 3)
    angle = math.acos(max(-1.0, min(1.0, 3 * q / (p * radius))))
    return [complex(radius * math.cos((angle - 2 * math.pi * k) / 3) + shift) for k in range(3)]
