"""LAPACK's solve and inverse of one small square matrix, as numpy computes them, for the
control step's hot path.

``numpy.linalg.solve`` and ``numpy.linalg.inv`` check shapes and types, look up the result
type and build an error state in Python before they call their LAPACK routine (``gesv``);
on a 6x6 matrix that costs about three times the routine itself. Here the same routine
(numpy's ``_umath_linalg`` gufuncs, ``d->d`` loops) runs under the same error state, built
once: the results are numpy's to the bit, and a singular matrix raises
``numpy.linalg.LinAlgError`` as numpy's does (no warning, whatever the caller's error state).
The inputs must already be float arrays of the right shapes (the callers' own: a Jacobian,
a checked twist). numpy keeps the gufuncs and its error state's variable private: they are
reached as attributes and checked once, on import, against numpy.linalg's functions (the
same bits, LinAlgError on a singular matrix); where a numpy release lacks them or they
differ, numpy's public functions run instead.
"""

from __future__ import annotations

from typing import Any

import numpy as np


def _singular(error: str, flag: int) -> None:
    """numpy's own reaction to LAPACK's "singular" (its error state's ``call``)."""
    raise np.linalg.LinAlgError("Singular matrix")


def _internals() -> tuple[Any, Any, Any, Any, Any] | None:
    """(solve1, solve, inv, the error-state variable, numpy.linalg's error state): numpy's
    own, reached as attributes (numpy keeps them private), or None where this numpy lacks
    them or they do not behave as numpy.linalg's functions (checked once, here)."""
    try:
        gufuncs = np.linalg._umath_linalg
        state = np._core._ufunc_config._extobj_contextvar  # type: ignore[attr-defined]
        linalg_state = np._core._multiarray_umath._make_extobj(  # type: ignore[attr-defined]
            call=_singular, invalid="call", over="ignore", divide="ignore", under="ignore"
        )
        found = (gufuncs.solve1, gufuncs.solve, gufuncs.inv, state, linalg_state)
    except (AttributeError, TypeError):  # pragma: no cover  # another numpy
        return None
    return found if _behaves(*found) else None


def _behaves(solve1: Any, solve: Any, inv: Any, state: Any, linalg_state: object) -> bool:
    """Whether the internals give numpy.linalg's bits and raise on a singular matrix."""
    M = np.array([[4.0, 1.0, 2.0], [0.5, 3.0, 1.0], [2.0, 1.0, 5.0]])
    b = np.array([1.0, -2.0, 0.5])
    token = state.set(linalg_state)
    try:
        same = (
            np.array_equal(solve1(M, b, signature="dd->d"), np.linalg.solve(M, b))
            and np.array_equal(solve(M, M, signature="dd->d"), np.linalg.solve(M, M))
            and np.array_equal(inv(M, signature="d->d"), np.linalg.inv(M))
        )
        inv(np.zeros((2, 2)), signature="d->d")
    except np.linalg.LinAlgError:
        return bool(same)
    except Exception:  # pragma: no cover  # anything else: numpy's public functions
        return False
    finally:
        state.reset(token)
    return False  # pragma: no cover  # a singular matrix went through


_INTERNALS = _internals()


if _INTERNALS is not None:
    _solve1, _solve, _inv, _extobj_contextvar, _NUMPY_LINALG_STATE = _INTERNALS

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
