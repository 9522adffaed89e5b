"""pinrate.solvers.lapack: numpy's solve and inverse to the bit, singular matrices refused alike."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from pinrate.solvers import lapack


@pytest.mark.parametrize("size", [1, 2, 3, 6, 7])
def test_solve_and_inverse_are_numpys_to_the_bit(size: int) -> None:
    # The same LAPACK routine on the same numbers: equal bits, no tolerance.
    rng = np.random.default_rng(size)
    for _ in range(50):
        M = rng.normal(size=(size, size))
        b = rng.normal(size=size)
        B = rng.normal(size=(size, 3))
        np.testing.assert_array_equal(lapack.solve(M, b), np.linalg.solve(M, b))
        np.testing.assert_array_equal(lapack.solve(M, B), np.linalg.solve(M, B))
        np.testing.assert_array_equal(lapack.inverse(M), np.linalg.inv(M))


def test_a_matrix_right_hand_side_is_solved_column_by_column() -> None:
    # numpy takes a 2-D b as columns (M X = B), not as a stack of vectors: the difference shows
    # for a non-symmetric M, whose X = M^-1 B differs from (M^-1 B^T)^T.
    M = np.array([[2.0, 1.0], [0.0, 4.0]])
    X = lapack.solve(M, np.eye(2))
    np.testing.assert_allclose(M @ X, np.eye(2), atol=1e-15)  # exact up to one rounding per entry


def test_a_singular_matrix_raises_numpys_error_without_a_warning() -> None:
    singular = np.array([[1.0, 2.0], [2.0, 4.0]])
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with pytest.raises(np.linalg.LinAlgError, match="Singular matrix"):
            lapack.solve(singular, np.ones(2))
        with pytest.raises(np.linalg.LinAlgError, match="Singular matrix"):
            lapack.inverse(singular)


def test_the_callers_error_state_is_kept() -> None:
    # The singular matrix raises under LAPACK's error state; the caller's is back afterwards.
    before = np.geterr()
    with np.errstate(invalid="raise"), pytest.raises(np.linalg.LinAlgError):
        lapack.inverse(np.zeros((3, 3)))
    assert np.geterr() == before
    with np.errstate(all="ignore"):
        assert np.geterr()["invalid"] == "ignore"
        with pytest.raises(np.linalg.LinAlgError):
            lapack.solve(np.zeros((3, 3)), np.ones(3))
        assert np.geterr()["invalid"] == "ignore"
