"""The block algorithms for square blocks of size 1 to 3, in closed form on Python floats.

numpy pays about a microsecond per call on tiny arrays, so the MCA formulas written with
numpy cost more than one 6x6 LAPACK solve. Here the same formulas (eq. 24-25, 44-45,
51-52 and the Schur form of eq. 20, see :mod:`pinrate.solvers.reference`) run on Python
floats: Cramer's rule for 1x1, 2x2 and 3x3 solves, singular blocks decided by the one rule
of :mod:`pinrate.solvers.singular`, and rho by the one routine of
:mod:`pinrate.solvers.eigen`. The numpy versions stay the reference; the tests check the
three forms against each other and against the paper's error identities.

Blocks are nested lists (rows), vectors are lists; all quantities are in the units of the
sensor-frame Jacobian's rows (m/s and rad/s per unit joint rate).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from ..errors import SingularBlockError
from . import eigen
from .singular import invertible

Matrix = list[list[float]]
Vector = list[float]
Blocks = tuple[Matrix, Matrix, Matrix, Matrix]


def _singular(det: float, M: Matrix, block: str) -> None:
    """Raise SingularBlockError unless M passes the singularity rule."""
    scale_squared = 1.0
    for column in zip(*M, strict=True):
        scale_squared *= _dot(column, column)
    if not invertible(det, scale_squared):
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
        if not invertible(det, scale_squared):
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
    # _dot, not sum(): CPython 3.12+ sums floats with Neumaier compensation, the core left to right.
    complement = [[A[r][c] - _dot(B[r], W_inv_U_columns[c]) for c in range(len(A))] for r in range(len(A))]
    arm = solve(complement, _minus_matvec(v, B, solve(W, omega, "W")), "A - B W^-1 U")
    return arm, solve(W, _minus_matvec(omega, U, arm), "W")


Kernel = Callable[[Matrix, Matrix, Matrix, Matrix, Vector, Vector], tuple[Vector, Vector]]
"""(A, B, U, W, v, Ω) -> (arm rates, wrist rates)."""


def blocks(jacobian: np.ndarray, selectors: tuple[Any, ...]) -> Blocks:
    """(A, B, U, W) of eq. 19 as nested lists, from the sensor-frame Jacobian (6, nv) and the
    partition's selectors (``selectors`` of :class:`pinrate.kinematics.PartitionIndex`)."""
    a, b, u, w = selectors
    return jacobian[a].tolist(), jacobian[b].tolist(), jacobian[u].tolist(), jacobian[w].tolist()


def block_rates(kernel: Kernel, parts: Blocks, twist: np.ndarray) -> Vector:
    """Rates of the arm then the wrist joints from a twist in partition order (linear, angular)."""
    command = twist.tolist()
    m = len(parts[0])
    arm, wrist = kernel(*parts, command[:m], command[m:])
    return arm + wrist


def inverse(M: Matrix, block: str) -> Matrix:
    """M^-1 of a non-singular square M of size 0 to 3: the adjugate over the determinant."""
    n = len(M)
    if n == 3:
        (a, b, c), (d, e, f), (g, h, i) = M
        c0, c1, c2 = e * i - f * h, f * g - d * i, d * h - e * g
        det = a * c0 + b * c1 + c * c2
        scale_squared = (a * a + d * d + g * g) * (b * b + e * e + h * h) * (c * c + f * f + i * i)
        if not invertible(det, scale_squared):
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


def spectral_radius(parts: Blocks, inverses: tuple[Matrix, Matrix] | None = None) -> float:
    """ρ of the smaller of G = U A^-1 B W^-1 and H = B W^-1 U A^-1 (eq. 32, 50); ``inverses``
    are (A^-1, W^-1) when already at hand.

    Raises SingularBlockError when A or W is singular.
    """
    A_inv, W_inv = (inverse(parts[0], "A"), inverse(parts[3], "W")) if inverses is None else inverses
    _, B, U, _ = parts
    P = _matmul(U, A_inv)  # k x m
    Q = _matmul(B, W_inv)  # m x k
    M = _matmul(P, Q) if len(P) <= len(Q) else _matmul(Q, P)
    n = len(M)
    if n == 3:
        return float(eigen.spectral_radius_3((*M[0], *M[1], *M[2]), eigen.FLOATS))
    if n == 2:
        return float(eigen.spectral_radius_2(M[0][0], M[0][1], M[1][0], M[1][1], eigen.FLOATS))
    if n == 1:
        return abs(M[0][0])
    return 0.0
