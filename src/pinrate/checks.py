"""Every check of user input in one place: vectors, positive numbers, counts, seeds, poses.

Each check returns the value in the form pinrate computes with, or raises
:class:`~pinrate.errors.InputError` naming the offending argument.
"""

from __future__ import annotations

import math
import numbers
import os
from collections.abc import Sequence
from pathlib import Path

import numpy as np
import pinocchio as pin

from .errors import InputError

RngLike = np.random.Generator | int | None


PHYSICAL_BOUND = 1e6
"""Largest magnitude pinrate accepts in a joint coordinate (rad or m), a twist component
(m/s or rad/s), a target position (m), a gain (1/s) or a time (s). Nothing physical comes
near it, and below it the algebra cannot overflow (squares stay under 1e12 per entry)."""


def check_vector(
    value: object,
    length: int,
    what: str,
    *,
    names: Sequence[str] | None = None,
    bound: float = PHYSICAL_BOUND,
) -> np.ndarray:
    """A float vector of the given length, each entry finite and within ±``bound``;
    InputError naming ``what`` (and the entry) otherwise.

    ``names`` labels the entries (joint names for q) in the message.
    """
    try:
        array = np.asarray(value, dtype=float)
    except (TypeError, ValueError) as error:
        raise InputError(f"{what} must be a vector of {length} numbers: {error}") from None
    if array.shape != (length,):
        raise InputError(f"{what} must have shape ({length},), got shape {array.shape}")
    # The Euclidean norm proves every entry finite and within the bound (|x_i| <= ||x|| <=
    # bound; NaN and inf compare false): math.hypot scales, so it never overflows, and costs a
    # sixth of max(|x|)'s numpy reduction per call. A vector it does not prove falls through
    # to max(|x|), then to the entry-wise tests, which refuse only what is out of bounds.
    if not math.hypot(*array.tolist()) <= bound and not float(np.abs(array).max(initial=0.0)) <= bound:
        _refuse_entries(array, what, names, bound)
    return array


def _refuse_entries(array: np.ndarray, what: str, names: Sequence[str] | None, bound: float) -> None:
    def label(i: int) -> str:
        return f"{what}[{i}]" + (f" ({names[i]})" if names and names[i] else "")

    bad = np.flatnonzero(~np.isfinite(array))
    if bad.size:
        raise InputError(f"{what} contains NaN or inf at {', '.join(label(int(i)) for i in bad)}")
    large = np.flatnonzero(np.abs(array) > bound)
    if large.size:
        shown = ", ".join(f"{label(int(i))} = {array[i]:.3g}" for i in large)
        raise InputError(f"{what} is beyond the physical bound ±{bound:g}: {shown}")


def check_positive(value: object, name: str, *, allow_inf: bool = False, maximum: float = PHYSICAL_BOUND) -> float:
    """``value`` as a float in (0, ``maximum``] (or inf when ``allow_inf``); InputError
    naming ``name`` otherwise."""
    number = float(value) if isinstance(value, numbers.Real) and not isinstance(value, bool) else math.nan
    if math.isnan(number) or number <= 0 or (number > maximum and not (number == math.inf and allow_inf)):
        bound = f"a positive number up to {maximum:g}" + (" (or inf)" if allow_inf else "")
        raise InputError(f"{name} must be {bound}, got {value!r}")
    return number


MAX_SAMPLES = 10_000_000
"""Most configurations one call draws or evaluates (10 M: about 0.5 GB of q for a 6-joint arm
and half a minute of work on one core); split bigger studies, or use ``workers``."""

MAX_GRID_POINTS = 1001
"""Most grid points per joint of a region map or grid check (1001² ≈ 1 M configurations)."""


def check_count(value: object, name: str, *, minimum: int = 0, maximum: int | None = None) -> int:
    """``value`` as an int in [``minimum``, ``maximum``] (bools refused); InputError naming
    ``name`` otherwise."""
    if isinstance(value, bool) or not isinstance(value, int | np.integer) or value < minimum:
        kind = "a positive integer" if minimum == 1 else f"an integer >= {minimum}"
        raise InputError(f"{name} must be {kind}, got {value!r}")
    if maximum is not None and value > maximum:
        raise InputError(f"{name} must be at most {maximum:,}, got {value:,}")
    return int(value)


def check_name(value: object, what: str) -> str:
    """``value`` if it is a string; InputError naming ``what`` otherwise."""
    if not isinstance(value, str):
        raise InputError(f"{what} must be a name (str), got {value!r}")
    return value


def as_rng(rng: RngLike) -> np.random.Generator:
    """A numpy Generator from a Generator, a non-negative int seed, or None (fresh entropy)."""
    if isinstance(rng, np.random.Generator):
        return rng
    if rng is None:
        return np.random.default_rng()
    if isinstance(rng, int | np.integer) and not isinstance(rng, bool):
        if rng < 0:
            raise InputError(f"rng seed must be a non-negative integer, got {rng}")
        return np.random.default_rng(rng)
    raise InputError(f"rng must be a numpy Generator, a non-negative int seed or None, not {rng!r}")


def as_pose(target: object) -> pin.SE3:
    """A pose from a 4x4 homogeneous matrix or a pinocchio SE3; InputError otherwise.

    The rotation must be orthonormal to 1e-6 (``|R^T R - I|`` <= 1e-6 + 1e-5 ``|I|`` entrywise, as
    ``np.allclose`` would judge) with det R > 0, and the last row [0, 0, 0, 1] (to 1e-8 +
    1e-5 ``|b|``). On Python floats: a servo call checks its target, and numpy's per-call cost
    on a 4x4 was most of the call's set-up.
    """
    if isinstance(target, pin.SE3):
        matrix = np.array(target.homogeneous)
    else:
        try:
            matrix = np.asarray(target, dtype=float)
        except (TypeError, ValueError):
            raise InputError("target must be a 4x4 homogeneous matrix or a pinocchio.SE3") from None
    if matrix.shape != (4, 4):
        raise InputError(f"target must be a 4x4 homogeneous matrix, got shape {matrix.shape}")
    values = matrix.ravel().tolist()
    if not all(math.isfinite(value) for value in values):
        raise InputError("target contains NaN or inf")
    position = (values[3], values[7], values[11])
    if max(abs(value) for value in position) > PHYSICAL_BOUND:
        raise InputError(f"target's position is beyond the physical bound ±{PHYSICAL_BOUND:g} m: {matrix[:3, 3]}")
    columns = [(values[c], values[4 + c], values[8 + c]) for c in range(3)]
    for i in range(3):
        for j in range(3):
            gram = columns[i][0] * columns[j][0] + columns[i][1] * columns[j][1] + columns[i][2] * columns[j][2]
            if abs(gram - (1.0 if i == j else 0.0)) > 1e-6 + (1e-5 if i == j else 0.0):
                raise InputError("target's upper-left 3x3 block is not a rotation matrix")
    (a, d, g), (b, e, h), (c, f, i) = columns
    if a * (e * i - f * h) - b * (d * i - f * g) + c * (d * h - e * g) < 0:
        raise InputError("target's upper-left 3x3 block is not a rotation matrix")
    last_row = zip(values[12:], (0.0, 0.0, 0.0, 1.0), strict=True)
    if any(abs(value - wanted) > 1e-8 + 1e-5 * abs(wanted) for value, wanted in last_row):
        raise InputError("target's last row must be [0, 0, 0, 1]")
    return pin.SE3(matrix[:3, :3], matrix[:3, 3])


def check_output_folder(path: str | os.PathLike[str], what: str) -> Path:
    """A folder to write into, created if missing; InputError naming ``what`` when the path
    is a file, cannot be created or is not writable."""
    folder = as_path(path, what)
    if folder.exists() and not folder.is_dir():
        raise InputError(f"{what} {str(folder)!r} exists and is not a folder")
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError as error:
        raise InputError(f"{what} {str(folder)!r} cannot be created: {error.strerror or error}") from None
    if not os.access(folder, os.W_OK | os.X_OK):
        raise InputError(f"{what} {str(folder)!r} is not writable")
    return folder


def check_output_file(path: str | os.PathLike[str], what: str) -> Path:
    """A file path to write (an existing file is replaced); InputError naming ``what`` when it
    is a folder, its folder is missing, or either is not writable."""
    target = as_path(path, what)
    if target.is_dir():
        raise InputError(f"{what} {str(target)!r} is a folder; give a file name")
    folder = target.parent
    if not folder.is_dir():
        raise InputError(f"{what} {str(target)!r}: the folder {str(folder)!r} does not exist")
    if not os.access(folder, os.W_OK | os.X_OK) or (target.exists() and not os.access(target, os.W_OK)):
        raise InputError(f"{what} {str(target)!r} is not writable")
    return target


def as_path(path: object, what: str) -> Path:
    """``path`` as a :class:`~pathlib.Path` (``~`` expanded); InputError naming ``what`` when it
    is not a path (not a string or an os.PathLike, or empty)."""
    if not isinstance(path, str | os.PathLike) or str(path) == "":
        raise InputError(f"{what} must be a path, got {path!r}")
    try:
        return Path(path).expanduser()
    except RuntimeError as error:  # ~unknownuser
        raise InputError(f"{what} {str(path)!r}: {error}") from None
