"""One block mathematics in three forms: the numpy reference, the closed-form kernels on
Python floats and the batched kernels on stacks must agree on the same blocks, and rho
must match an independent 60-digit computation (mpmath) where it decides the Theorem."""

from __future__ import annotations

import math

import mpmath
import numpy as np
import pytest

import pinrate
from pinrate.solvers import batched, closed_form, eigen, reference
from pinrate.solvers.singular import SINGULAR_RATIO, hadamard_ratio

SIZES = [(m, k) for m in (1, 2, 3) for k in (1, 2, 3)]


def random_blocks(rng: np.random.Generator, m: int, k: int) -> tuple[np.ndarray, ...]:
    """Square A (m x m) and W (k x k), couplings B (m x k) and U (k x m), mixed scales."""
    scale = rng.choice([1e-2, 1.0, 1e2])
    return (
        rng.normal(size=(m, m)) * scale,
        rng.normal(size=(m, k)),
        rng.normal(size=(k, m)) * scale,
        rng.normal(size=(k, k)),
    )


def reference_rho(blocks: tuple[np.ndarray, ...]) -> float:
    return reference.spectral_radius(*blocks)


def closed_form_rho(blocks: tuple[np.ndarray, ...]) -> float:
    return closed_form.spectral_radius(tuple(block.tolist() for block in blocks))  # type: ignore[arg-type]


def batched_rho(blocks: tuple[np.ndarray, ...]) -> float:
    return float(batched.spectral_radius(*(block[None] for block in blocks))[0])


def exact_rho(blocks: tuple[np.ndarray, ...]) -> float:
    """max |λ| of U A^-1 B W^-1 in 60-digit arithmetic, from the same double blocks."""
    with mpmath.workdps(60):
        A, B, U, W = (mpmath.matrix(block.tolist()) for block in blocks)
        G = U * mpmath.inverse(A) * B * mpmath.inverse(W)
        return float(max(abs(value) for value in mpmath.eig(G, left=False, right=False)))


FORMS = {"reference": reference_rho, "closed_form": closed_form_rho, "batched": batched_rho}


@pytest.mark.parametrize(("m", "k"), SIZES)
def test_random_blocks_agree(m: int, k: int) -> None:
    rng = np.random.default_rng(100 * m + k)
    for _ in range(200):
        blocks = random_blocks(rng, m, k)
        truth = exact_rho(blocks)
        for name, form in FORMS.items():
            assert form(blocks) == pytest.approx(truth, rel=1e-8, abs=1e-300), name


@pytest.mark.parametrize(("m", "k"), SIZES)
def test_rho_near_one_is_right_to_1e_9(m: int, k: int) -> None:
    """Blocks scaled so that ρ = 1 ± 1e-6: every form within 1e-9 (relative) of 60 digits,
    so the Theorem's verdict ρ < 1 is the same in every form."""
    rng = np.random.default_rng(7 * m + k)
    for trial in range(60):
        A, B, U, W = random_blocks(rng, m, k)
        offset = 1e-6 * (1 if trial % 2 else -1)
        B = B * (1 + offset) / exact_rho((A, B, U, W))
        truth = exact_rho((A, B, U, W))
        for name, form in FORMS.items():
            value = form((A, B, U, W))
            assert value == pytest.approx(truth, rel=1e-9), name
            assert (value < 1) == (truth < 1), name


@pytest.mark.parametrize(("m", "k"), SIZES)
@pytest.mark.parametrize("c", [1.0 - 1e-7, -0.999, 2.5, 1e-3])
def test_c_times_identity(m: int, k: int, c: float) -> None:
    """G = c I (k <= m) or H = c I (k > m): every eigenvalue is c, a multiple root."""
    rng = np.random.default_rng(m + 10 * k)
    A, B, U, W = random_blocks(rng, m, k)
    if k <= m:  # B = c A U^T (U U^T)^-1 W gives U A^-1 B W^-1 = c I_k
        B = c * A @ U.T @ np.linalg.solve(U @ U.T, W)
    else:  # U = c W B^T (B B^T)^-1 A gives B W^-1 U A^-1 = c I_m
        U = c * W @ B.T @ np.linalg.solve(B @ B.T, A)
    truth = exact_rho((A, B, U, W))
    assert truth == pytest.approx(abs(c), rel=1e-10)
    for name, form in FORMS.items():
        assert form((A, B, U, W)) == pytest.approx(truth, rel=1e-9), name


@pytest.mark.parametrize(("m", "k"), SIZES)
def test_rank_deficient_blocks_are_singular_in_every_form(m: int, k: int) -> None:
    rng = np.random.default_rng(3 * m + k)
    for singular_block in ("A", "W"):
        A, B, U, W = random_blocks(rng, m, k)
        if singular_block == "A":
            A[:, -1] = A[:, 0] * 2.0 if m > 1 else 0.0
        else:
            W[:, -1] = W[:, 0] * -3.0 if k > 1 else 0.0
        with pytest.raises(pinrate.SingularBlockError, match=f"block {singular_block}"):
            reference_rho((A, B, U, W))
        with pytest.raises(pinrate.SingularBlockError, match=f"block {singular_block}"):
            closed_form_rho((A, B, U, W))
        assert batched_rho((A, B, U, W)) == math.inf


@pytest.mark.parametrize(("m", "k"), SIZES)
def test_near_singular_blocks_agree_within_their_conditioning(m: int, k: int) -> None:
    """W just above the singularity rule (Hadamard ratio 1e-9 .. 1e-6): the forms agree with
    60 digits to eps over the ratio (the data's own conditioning), and decide alike."""
    rng = np.random.default_rng(11 * m + k)
    for exponent in (-6, -7, -8, -9):
        A, B, U, W = random_blocks(rng, m, k)
        if k > 1:
            W[:, -1] = W[:, 0] + 10.0**exponent * rng.normal(size=k)
        else:
            W[0, 0] = 10.0**exponent
        ratio = hadamard_ratio(W)
        assert ratio > SINGULAR_RATIO
        truth = exact_rho((A, B, U, W))
        tolerance = max(1e-9, 1e3 * np.finfo(float).eps / ratio)
        for name, form in FORMS.items():
            assert form((A, B, U, W)) == pytest.approx(truth, rel=tolerance), (name, ratio)


def test_the_one_eigenvalue_routine_matches_lapack_on_floats_and_stacks() -> None:
    rng = np.random.default_rng(5)
    matrices = rng.normal(size=(500, 3, 3)) * rng.choice([1e-3, 1.0, 1e3], size=(500, 1, 1))
    matrices[::7] = np.eye(3) * rng.normal(size=(72, 1, 1))  # triple roots
    matrices[1::7] = np.diag([1.0, 1.0, 0.25])  # a double dominant root
    expected = np.abs(np.linalg.eigvals(matrices)).max(axis=1)
    stacked = eigen.spectral_radius_3(tuple(matrices[:, r, c] for r in range(3) for c in range(3)), eigen.ARRAYS)
    singles = [eigen.spectral_radius_3(tuple(matrix.ravel().tolist()), eigen.FLOATS) for matrix in matrices]
    np.testing.assert_allclose(stacked, expected, rtol=1e-9)
    np.testing.assert_allclose(singles, expected, rtol=1e-9)
    np.testing.assert_allclose(singles, stacked, rtol=1e-12)
