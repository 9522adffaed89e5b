"""Closed-form algebra on stacks of small matrices, against numpy's LAPACK results."""

from __future__ import annotations

import numpy as np
import pytest

from pinrate.solvers import batched


def stacks(n: int, count: int = 3000, seed: int = 0) -> np.ndarray:
    rng = np.random.default_rng(seed)
    M = rng.normal(size=(count, n, n)) * rng.choice([1e-3, 1.0, 1e3], size=(count, 1, 1))
    M[::5] = M[::5] @ np.transpose(M[::5], (0, 2, 1))  # symmetric: real eigenvalues
    M[1::7] = np.eye(n) * rng.normal(size=(count // 7 + 1, 1, 1))[: M[1::7].shape[0]]  # repeated roots
    return M


@pytest.mark.parametrize("n", [1, 2, 3, 4])
def test_spectral_radius_matches_eigvals(n: int) -> None:
    M = stacks(n)
    expected = np.abs(np.linalg.eigvals(M)).max(axis=1)
    np.testing.assert_allclose(batched.matrix_spectral_radius(M), expected, rtol=1e-7, atol=1e-12)


def test_spectral_radius_of_a_rotation_is_one() -> None:
    angle = 0.7
    rotation = np.array([[np.cos(angle), -np.sin(angle), 0], [np.sin(angle), np.cos(angle), 0], [0, 0, 0.5]])
    assert batched.matrix_spectral_radius(rotation[None])[0] == pytest.approx(1.0)
    assert batched.matrix_spectral_radius(np.zeros((2, 0, 0))).tolist() == [0.0, 0.0]


@pytest.mark.parametrize("n", [1, 2, 3, 4])
def test_inverse_matches_inv_and_flags_singular(n: int) -> None:
    M = stacks(n, seed=1)
    M[::9] = 0.0
    M[2::9, :, 0] = M[2::9, :, -1] if n > 1 else 0.0  # two equal columns
    inverses, singular = batched.inverse(M)
    expected_singular = np.abs(np.linalg.det(M)) <= 1e-10 * np.prod(np.linalg.norm(M, axis=1), axis=-1)
    np.testing.assert_array_equal(singular, expected_singular)
    good = ~singular
    np.testing.assert_allclose(inverses[good] @ M[good], np.broadcast_to(np.eye(n), M[good].shape), atol=1e-6)
    assert np.all(inverses[singular] == 0.0) and np.isfinite(inverses).all()


def test_rectangular_blocks_get_pseudo_inverses() -> None:
    M = np.random.default_rng(2).normal(size=(50, 3, 4))
    inverses, singular = batched.inverse(M)
    np.testing.assert_allclose(inverses, np.linalg.pinv(M), atol=1e-12)
    assert not singular.any()
