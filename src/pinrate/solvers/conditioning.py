"""How far a block is from singular, and the generalized inverse that stays finite there.

The measure of a block M (m x n) is its inverse condition number

    c(M) = σ_r(M) / σ_1(M),   r = the block's rank where it is generic (usually min(m, n)),

in [0, 1]: 1 for orthogonal columns of equal norm, 0 when M has lost rank. It is the measure
the controller decelerates by and the cut-off of the generalized inverse (Barker eq. 38, 60):
directions with σ_i < threshold · σ_1 are the ones treated as lost.

J mixes m/s and rad/s rows, so its c depends on the unit of length. J is measured with its
linear rows divided by the robot's characteristic length L (:func:`characteristic_length`,
metres): the rows then carry like units and c does not change when the robot is scaled. The
blocks A (linear rows only) and W (angular rows only) are measured as they are.

c needs an SVD (some µs in numpy). A control step first takes the cheap lower bound

    c(M) >= 1 / (||M||_F ||M^-1||_F)                  (square M, its inverse at hand)

(since ||M||_2 <= ||M||_F and ||M^-1||_2 <= ||M^-1||_F), and pays for the SVD only when the
bound falls under its threshold.
"""

from __future__ import annotations

import math

import numpy as np

from ..errors import InputError


def _sum_of_squares(rows: np.ndarray | list[list[float]]) -> float:
    """Σ value², left to right on Python floats, as the compiled core sums (not ``sum()``:
    CPython 3.12+ sums floats with Neumaier compensation, which rounds differently)."""
    total = 0.0
    for row in rows:
        for value in row:
            total += value * value
    return total


def inverse_condition_bound(M: np.ndarray | list[list[float]], M_inverse: np.ndarray | list[list[float]]) -> float:
    """1 / (||M||_F ||M^-1||_F), a lower bound of :func:`inverse_condition` for a square M.

    Works on numpy arrays and on nested lists (the closed-form kernels' blocks).
    """
    if isinstance(M, np.ndarray):
        matrix_norm2 = float(np.vdot(M, M))
        inverse = np.asarray(M_inverse)
        inverse_norm2 = float(np.vdot(inverse, inverse))
    else:
        matrix_norm2 = _sum_of_squares(M)
        inverse_norm2 = _sum_of_squares(M_inverse)
    product = matrix_norm2 * inverse_norm2
    if not product > 0.0 or not math.isfinite(product):
        return 0.0
    return 1.0 / math.sqrt(product)


def characteristic_length(J: np.ndarray, m: int) -> float:
    """L = ||J_linear||_F / ||J_angular||_F (metres): the rms lever arm of J's columns.

    J is (m + k, n) in partition order, linear rows first. 1.0 when either part is empty or
    zero (a robot with only linear or only angular rows needs no scale).
    """
    linear = float(np.linalg.norm(J[:m]))
    angular = float(np.linalg.norm(J[m:]))
    if linear == 0.0 or angular == 0.0 or not math.isfinite(linear / angular):
        return 1.0
    return linear / angular


def row_scale(m: int, k: int, length: float) -> np.ndarray:
    """The row weights (m + k,) that put J's rows in like units: 1/L on linear rows, 1 on angular."""
    return np.concatenate([np.full(m, 1.0 / length), np.ones(k)])


def truncated_pinv(M: np.ndarray, threshold: float) -> np.ndarray:
    """The Moore-Penrose inverse of M with every σ_i < threshold · σ_1 treated as 0 (n x m).

    Finite for every finite M, the zero matrix included (its inverse is 0). Barker's
    generalized inverse M* (eq. 38, 44, 60) with the near-singular directions cut.
    """
    if not 0.0 <= threshold < 1.0:
        raise InputError(f"the pseudo-inverse threshold must be in [0, 1), got {threshold}")
    rows, cols = M.shape
    if M.size == 0 or not np.isfinite(M).all():
        return np.zeros((cols, rows))
    left, singular_values, right_t = np.linalg.svd(M, full_matrices=False)
    if singular_values[0] == 0.0:
        return np.zeros((cols, rows))
    kept = singular_values >= threshold * singular_values[0]
    inverted = np.where(kept, 1.0 / np.where(kept, singular_values, 1.0), 0.0)
    return (right_t.T * inverted) @ left.T


def inverse_condition(M: np.ndarray, rank: int) -> tuple[float, np.ndarray]:
    """(c, v): c = σ_rank / σ_1 of a non-empty M (dimensionless, in [0, 1]; 0.0 for a zero M),
    and v, its right singular vector number ``rank``: the joint motion M produces least,
    unit, over M's columns."""
    _, singular_values, right_t = np.linalg.svd(M)
    value = float(singular_values[rank - 1] / singular_values[0]) if singular_values[0] > 0.0 else 0.0
    return value, right_t[rank - 1]


__all__ = [
    "characteristic_length",
    "inverse_condition",
    "inverse_condition_bound",
    "row_scale",
    "truncated_pinv",
]
