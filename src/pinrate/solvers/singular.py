"""The one singularity rule of pinrate, for every square block it inverts.

A square block M is singular when::

    |det M| <= SINGULAR_RATIO * prod_j ||M[:, j]||                       (Hadamard)

Hadamard's inequality bounds ``|det M|`` by the product of the column norms, so the ratio is
in [0, 1] whatever the units of the columns (metres per radian, radians per metre): 1 for
orthogonal columns, 0 for dependent ones. The numpy reference, the closed-form kernels on
Python floats and the batched kernels on stacks all decide with :func:`invertible`.
"""

from __future__ import annotations

from typing import TypeVar

import numpy as np

from ..errors import InputError

SINGULAR_RATIO = 1e-10
"""A square block is singular when ``|det M|`` <= SINGULAR_RATIO * prod of its column norms."""

_RATIO_SQUARED = SINGULAR_RATIO * SINGULAR_RATIO

Number = TypeVar("Number", float, np.ndarray)
"""One block's number (a Python float) or a stack's (an array, elementwise)."""


def invertible(det: Number, column_norms_squared_product: Number) -> bool | np.ndarray:
    """det^2 > SINGULAR_RATIO^2 * prod_j ||M[:, j]||^2: the rule, squared to spare square roots.

    Works on Python floats (one block) and on numpy arrays (a stack, elementwise). False for
    NaN or inf, so a block with non-finite entries counts as singular.
    """
    return det * det > _RATIO_SQUARED * column_norms_squared_product


def hadamard_ratio(M: np.ndarray) -> float:
    """``|det M|`` / prod_j ||M[:, j]|| of a square block, in [0, 1] (1.0 for an empty block):
    how far from singular it is, on the scale of :data:`SINGULAR_RATIO`."""
    if M.ndim != 2 or M.shape[0] != M.shape[1]:
        raise InputError(f"the Hadamard ratio is defined for a square block, got shape {M.shape}")
    if M.shape[0] == 0:
        return 1.0
    scale = float(np.prod(np.linalg.norm(M, axis=0)))
    if scale == 0.0 or not np.isfinite(scale):
        return 0.0
    return abs(float(np.linalg.det(M))) / scale


PINV_RCOND = 1e-10
"""Relative cut-off of singular values in every pseudo-inverse (non-square blocks)."""
