"""The algorithms with every inversion made finite: the generalized inverse (Barker eq. 38, 44,
60) and the adaptive damped inverse, for any algorithm of the registry.

Each algorithm inverts J (exact, dls) or the blocks A, W (and Schur's complement) of eq. 19.
Here each of those inversions goes through the singular value decomposition of the block
M = Σ σ_i u_i v_i^T, with a filter on 1/σ_i:

    generalized inverse:  M* = Σ_{σ_i >= t σ_1} v_i u_i^T / σ_i          (t: the threshold)
    damped inverse:       M# = Σ σ_i / (σ_i² + λ² σ_1²) v_i u_i^T        (λ: relative damping)

M* is the Moore-Penrose inverse with the directions under t σ_1 cut (M* = M^-1 when M is
square and c(M) >= t); M# is damped least squares with the damping relative to the block's
own scale, so it means the same for a block in m/rad and one in rad/rad. J is inverted with
its rows put in like units first (:func:`pinrate.solvers.conditioning.row_scale`):
J* = (S J)* S, so the least-squares split between a missing metre and a missing radian is
made at the robot's characteristic length.
"""

from __future__ import annotations

import numpy as np

from ..kinematics.partition import split_blocks
from .conditioning import truncated_pinv
from .rates import position_first_rates, position_first_solves
from .reference import Inverter
from .registry import REGISTRY


def generalized_inverter(threshold: float) -> Inverter:
    """Blocks inverted by :func:`~pinrate.solvers.conditioning.truncated_pinv` at ``threshold``."""
    return lambda M, _block: truncated_pinv(M, threshold)


def _damped_inverse(M: np.ndarray, damping: float) -> np.ndarray:
    """M# = Σ σ_i / (σ_i² + λ² σ_1²) v_i u_i^T with λ = ``damping`` (relative, >= 0): M^T (M M^T
    + λ² σ_1² I)^-1 without forming it. Finite for every finite M; M^+ when λ = 0."""
    rows, cols = M.shape
    if M.size == 0 or not np.isfinite(M).all():
        return np.zeros((cols, rows))
    left, singular_values, right_t = np.linalg.svd(M, full_matrices=False)
    if singular_values[0] == 0.0:
        return np.zeros((cols, rows))
    squared = singular_values * singular_values + (damping * singular_values[0]) ** 2
    return (right_t.T * (singular_values / squared)) @ left.T


def damped_inverter(damping: float) -> Inverter:
    """Blocks inverted by ``_damped_inverse`` at relative damping ``damping``."""
    return lambda M, _block: _damped_inverse(M, damping)


def filtered_rates(
    J: np.ndarray,
    m: int,
    n_arm: int,
    twist: np.ndarray,
    algorithm: str,
    invert: Inverter,
    scale: np.ndarray,
    position_first: bool = False,
) -> np.ndarray:
    """Rates (n,) of J's columns for ``twist`` (m + k,), the algorithm's inversions done by ``invert``.

    J is (m + k, n) in partition order (linear rows, angular rows; arm columns, wrist
    columns; ``n_arm`` arm columns). ``scale`` (m + k,) weights the rows of J where the
    algorithm inverts J itself (exact, dls): rates = (S J)^inv (S twist). ``position_first``:
    the partition puts position first (its own blocks, before columns were merged or
    dropped); where these blocks still have a square A and a tall W, exact, schur and dls
    then solve by :func:`~.rates.position_first_rates`, A and the complement inverted by
    ``invert``. (A 6-DOF partition whose wrist pair was merged keeps its least squares.)
    """
    entry = REGISTRY[algorithm]
    m_k, n = J.shape
    if position_first and position_first_solves(algorithm, m, n_arm, m_k - m, n - n_arm):
        return position_first_rates(J, m, n_arm, twist, algorithm, invert)
    if entry.whole is not None:
        return invert(J * scale[:, None], "J") @ (scale * twist)
    assert entry.blocks is not None
    arm, wrist = entry.blocks(*split_blocks(J, m, n_arm), twist[:m], twist[m:], invert=invert)
    return np.concatenate([arm, wrist])


__all__ = ["damped_inverter", "filtered_rates", "generalized_inverter"]
