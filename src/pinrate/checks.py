"""Every check of user input in one place: vectors, positive numbers, counts, seeds, poses.

Each check returns the value in the form pinrate computes with, or raises
:class:`~pinrate.errors.InputError` naming the offending argument.
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Sequence

import numpy as np
import pinocchio as pin

from .errors import InputError

RngLike = np.random.Generator | int | None


def check_vector(value: object, length: int, what: str, *, names: Sequence[str] | None = None) -> np.ndarray:
    """A float vector of the given length; InputError naming ``what`` otherwise.

    ``names`` labels the entries (joint names for q) in the message about NaN or inf.
    """
    try:
        array = np.asarray(value, dtype=float)
    except (TypeError, ValueError) as error:
        raise InputError(f"{what} must be a vector of {length} numbers: {error}") from None
    if array.shape != (length,):
        raise InputError(f"{what} must have shape ({length},), got shape {array.shape}")
    # A finite sum proves every entry finite (the cheap test on the hot path); an overflowing
    # sum of finite entries falls through to the entry-wise test.
    if not math.isfinite(array.sum()) and not np.isfinite(array).all():
        bad = np.flatnonzero(~np.isfinite(array))
        where = ", ".join(f"{what}[{i}]" + (f" ({names[int(i)]})" if names and names[int(i)] else "") for i in bad)
        raise InputError(f"{what} contains NaN or inf at {where}")
    return array


def check_positive(value: object, name: str, *, allow_inf: bool = False) -> float:
    """``value`` as a float > 0 (finite unless ``allow_inf``); InputError naming ``name`` otherwise."""
    if (
        isinstance(value, bool)
        or not isinstance(value, numbers.Real)
        or math.isnan(value)
        or value <= 0
        or (value == math.inf and not allow_inf)
    ):
        bound = "a positive number (or inf)" if allow_inf else "a positive finite number"
        raise InputError(f"{name} must be {bound}, got {value!r}")
    return float(value)


def check_count(value: object, name: str, *, minimum: int = 0) -> int:
    """``value`` as an int >= ``minimum`` (bools refused); InputError naming ``name`` otherwise."""
    if isinstance(value, bool) or not isinstance(value, int | np.integer) or value < minimum:
        kind = "a positive integer" if minimum == 1 else f"an integer >= {minimum}"
        raise InputError(f"{name} must be {kind}, got {value!r}")
    return int(value)


def as_rng(rng: RngLike) -> np.random.Generator:
    """A numpy Generator from a Generator, an int seed, or None (fresh entropy)."""
    if isinstance(rng, np.random.Generator):
        return rng
    if rng is None or isinstance(rng, int | np.integer):
        return np.random.default_rng(rng)
    raise InputError(f"rng must be a numpy Generator, an int seed or None, not {type(rng).__name__}")


def as_pose(target: object) -> pin.SE3:
    """A pose from a 4x4 homogeneous matrix or a pinocchio SE3; InputError otherwise."""
    if isinstance(target, pin.SE3):
        matrix = np.array(target.homogeneous)
    else:
        try:
            matrix = np.asarray(target, dtype=float)
        except (TypeError, ValueError):
            raise InputError("target must be a 4x4 homogeneous matrix or a pinocchio.SE3") from None
    if matrix.shape != (4, 4):
        raise InputError(f"target must be a 4x4 homogeneous matrix, got shape {matrix.shape}")
    if not np.isfinite(matrix).all():
        raise InputError("target contains NaN or inf")
    rotation = matrix[:3, :3]
    if not np.allclose(rotation.T @ rotation, np.eye(3), atol=1e-6) or np.linalg.det(rotation) < 0:
        raise InputError("target's upper-left 3x3 block is not a rotation matrix")
    if not np.allclose(matrix[3], [0.0, 0.0, 0.0, 1.0]):
        raise InputError("target's last row must be [0, 0, 0, 1]")
    return pin.SE3(rotation, matrix[:3, 3])
