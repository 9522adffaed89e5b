"""LAPACK's solve and inverse of one small square matrix, as numpy computes them, for the
control step's hot path.

``numpy.linalg.solve`` and ``numpy.linalg.inv`` check shapes and types, look up the result
type and build an error state in Python before they call their LAPACK routine (``gesv``);
on a 6x6 matrix that costs about three times the routine itself. Here the same routine
(numpy's ``_umath_linalg`` gufuncs, ``d->d`` loops) runs under the same error state, built
once: the results are numpy's to the bit, and a singular matrix raises
``numpy.linalg.LinAlgError`` as numpy's does (no warning, whatever the caller's error state).
The inputs must already be float arrays of the right shapes (the callers' own: a Jacobian,
a checked twist). Where a numpy release lacks those internals, numpy's public functions run.
"""

from __future__ import annotations

import numpy as np


def _singular(error: str, flag: int) -> None:
    """numpy's own reaction to LAPACK's "singular" (its error state's ``call``)."""
    raise np.linalg.LinAlgError("Singular matrix")


try:  # numpy's private internals, guarded: numpy's public functions below where they differ
    from numpy._core._multiarray_umath import _make_extobj
    from numpy._core._ufunc_config import _extobj_contextvar  # type: ignore[attr-defined]
    from numpy.linalg._umath_linalg import inv as _inv
    from numpy.linalg._umath_linalg import solve as _solve
    from numpy.linalg._umath_linalg import solve1 as _solve1

    # numpy.linalg's error state around these gufuncs: "invalid" (LAPACK's singular) raises.
    _NUMPY_LINALG_STATE = _make_extobj(call=_singular, invalid="call", over="ignore", divide="ignore", under="ignore")
    _INTERNALS = True
except (ImportError, AttributeError, TypeError):  # pragma: no cover  # another numpy: its own functions
    _INTERNALS = False


if _INTERNALS:

    def solve(M: np.ndarray, b: np.ndarray) -> np.ndarray:
        """X with M X = b, for a float (n, n) M and an (n,) or (n, r) b: ``numpy.linalg.solve(M,
        b)`` to the bit (a 1-D b is one vector, as numpy takes it). Raises
        ``numpy.linalg.LinAlgError`` where LAPACK finds M singular."""
        token = _extobj_contextvar.set(_NUMPY_LINALG_STATE)
        try:
            return (_solve1 if b.ndim == 1 else _solve)(M, b, signature="dd->d")
        finally:
            _extobj_contextvar.reset(token)

    def inverse(M: np.ndarray) -> np.ndarray:
        """M^-1 of a float (n, n) M: ``numpy.linalg.inv(M)`` to the bit. Raises
        ``numpy.linalg.LinAlgError`` where LAPACK finds M singular."""
        token = _extobj_contextvar.set(_NUMPY_LINALG_STATE)
        try:
            return _inv(M, signature="d->d")
        finally:
            _extobj_contextvar.reset(token)

else:  # pragma: no cover

    def solve(M: np.ndarray, b: np.ndarray) -> np.ndarray:
        """``numpy.linalg.solve(M, b)``."""
        return np.linalg.solve(M, b)

    def inverse(M: np.ndarray) -> np.ndarray:
        """``numpy.linalg.inv(M)``."""
        return np.linalg.inv(M)


__all__ = ["inverse", "solve"]
