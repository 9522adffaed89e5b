"""LAPACK's solve and inverse of one small square matrix, as numpy computes them, for the
control step's hot path.

``numpy.linalg.solve`` and ``numpy.linalg.inv`` check shapes and types, look up the result
type and enter an error state in Python before they call their LAPACK routine (``gesv``);
on a 6x6 matrix that costs about twice the routine itself. Here the same routine (numpy's
``_umath_linalg`` gufuncs, ``d->d`` loops) is called under the same error state, so the
results are numpy's to the bit and a singular matrix raises ``numpy.linalg.LinAlgError``
as numpy's does. The inputs must already be float arrays of the right shapes (the callers'
own: a Jacobian and a checked twist). Where a numpy release lacks those gufuncs, numpy's
public functions run instead.
"""

from __future__ import annotations

import numpy as np

try:
    from numpy.linalg._umath_linalg import inv as _inv  # private: guarded, with numpy's own below
    from numpy.linalg._umath_linalg import solve as _solve
    from numpy.linalg._umath_linalg import solve1 as _solve1
except ImportError:  # pragma: no cover  # a numpy without them
    _inv = _solve = _solve1 = None


def _singular(error: str, flag: int) -> None:
    """numpy's own reaction to LAPACK's "singular" (its error state's ``call``)."""
    raise np.linalg.LinAlgError("Singular matrix")


# The decorator form of errstate sets the state per call (thread-safe, reusable), as
# numpy.linalg does around the same gufuncs.
_NUMPY_STATE = np.errstate(call=_singular, invalid="call", over="ignore", divide="ignore", under="ignore")


@_NUMPY_STATE
def solve(M: np.ndarray, b: np.ndarray) -> np.ndarray:
    """X with M X = b, for a float (n, n) M and an (n,) or (n, r) b: ``numpy.linalg.solve(M,
    b)`` to the bit (a 1-D b is one vector, as numpy takes it). Raises
    ``numpy.linalg.LinAlgError`` where LAPACK finds M singular."""
    if _solve1 is None or _solve is None:  # pragma: no cover
        return np.linalg.solve(M, b)
    return (_solve1 if b.ndim == 1 else _solve)(M, b, signature="dd->d")  # type: ignore[no-any-return]


@_NUMPY_STATE
def inverse(M: np.ndarray) -> np.ndarray:
    """M^-1 of a float (n, n) M: ``numpy.linalg.inv(M)`` to the bit. Raises
    ``numpy.linalg.LinAlgError`` where LAPACK finds M singular."""
    if _inv is None:  # pragma: no cover
        return np.linalg.inv(M)
    return _inv(M, signature="d->d")  # type: ignore[no-any-return]


__all__ = ["inverse", "solve"]
