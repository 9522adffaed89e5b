"""The singular region: how the blocks an algorithm inverts are measured, where the region
begins, and the changes of variables that steps in it solve for.

The blocks watched are the ones the algorithm inverts (:func:`measured_blocks`): J for exact
and dls, A and W for the MCAs, W and J for Schur's form. Each is measured by its inverse
condition number c = σ_r / σ_1 (:mod:`pinrate.solvers.conditioning`; J with its linear rows
divided by the robot's characteristic length). A step is *in the singular region* when the
least c is under ``slow_threshold``; what it does there is its strategy's
(:mod:`pinrate.control.singularity`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..errors import InputError, choices_hint
from ..kinematics.partition import split_blocks
from ..solvers.conditioning import inverse_condition

WRIST_STRATEGIES = ("turn", "split", "hold_first", "last_then_first")
"""The values of ``Controller(wrist=...)``."""

SLOW_THRESHOLD = 0.02
"""c under which the step is in the singular region (κ = 50): deceleration starts here."""

SINGULAR_THRESHOLD = 0.005
"""c treated as singular (κ = 200): a decelerating step halts before it, the generalized
inverse cuts singular values under this fraction of σ_1."""

HALT_MARGIN = 0.01
"""A decelerating step halts when its look-ahead c is within this share of the band
(slow_threshold - singular_threshold) above singular_threshold, where its scale would be
under 1 %: the approach ends in a halt in finitely many steps (:func:`halts`)."""

MAX_DAMPING = 0.02
"""λ of ``adaptive_dls`` at c = 0, relative to the block's largest singular value: the
largest rate gain along a lost direction is then 1 / (2 λ σ_1)."""

FREEZE_SHARE = 0.5
"""``freeze`` holds the joints whose entry in the weakest right singular vector is at least
this fraction of the largest entry."""

WRIST_PAIR_SHARE = 0.9
"""A near-singular W is a wrist singularity when two joints carry at least this fraction of
the square of its weakest right singular vector."""


NOISE_FLOOR = 1e-9
"""c under this is rounding, not a measure: the two paths agree on q to about 1e-12 where
their float operations differ, and c of a block at a singularity moves by as much, so its
digits under 1e-9 differ between paths and machines. Said as "c < 1e-09"."""


def c_said(value: float, name: str = "c") -> str:
    """``c = 0.013``, or ``c < 1e-09`` under :data:`NOISE_FLOOR` (``name`` for c: "c(W)")."""
    return f"{name} = {value:.2g}" if value >= NOISE_FLOOR else f"{name} < {NOISE_FLOOR:g}"


def check_strategy(value: object, valid: tuple[str, ...], what: str) -> str:
    """The strategy name, or an InputError listing the valid ones."""
    if not isinstance(value, str) or value not in valid:
        raise InputError(f"unknown {what} {value!r}.{choices_hint(str(value), valid)}")
    return value


def check_thresholds(singular: object, slow: object) -> tuple[float, float]:
    """(singular_threshold, slow_threshold) with 0 <= singular < slow <= 1, or an InputError."""
    try:
        singular_value, slow_value = float(singular), float(slow)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        raise InputError(f"singular_threshold and slow_threshold must be numbers, got {singular!r}, {slow!r}") from None
    if not (0.0 <= singular_value < slow_value <= 1.0):
        raise InputError(
            "the thresholds must satisfy 0 <= singular_threshold < slow_threshold <= 1 (inverse condition "
            f"numbers σ_min/σ_max), got singular_threshold={singular_value}, slow_threshold={slow_value}"
        )
    return singular_value, slow_value


def measured_blocks(algorithm: str) -> tuple[str, ...]:
    """The blocks ``algorithm`` inverts: ("J",) for exact and dls, ("W", "J") for schur (W
    and the complement, whose determinant is det J / det W), ("A", "W") for the MCAs."""
    if algorithm in ("exact", "dls"):
        return ("J",)
    if algorithm == "schur":
        return ("W", "J")
    return ("A", "W")


def block_of(name: str, J: np.ndarray, m: int, n_arm: int, scale: np.ndarray) -> np.ndarray:
    """Block ``name`` of J (m + k, n) in partition order: "A" or "W"
    (:func:`~pinrate.kinematics.partition.split_blocks`), or "J" with its rows scaled."""
    if name == "J":
        return J * scale[:, None]
    A, _, _, W = split_blocks(J, m, n_arm)
    return A if name == "A" else W


@dataclass(frozen=True)
class Conditioning:
    """The least inverse condition number c among the measured blocks, which block it is, and
    that block's weakest joint motion: its smallest right singular vector, spread over the
    partition's columns (n,) with 0 outside the block."""

    value: float
    block: str
    direction: np.ndarray


def conditioning(
    J: np.ndarray, m: int, n_arm: int, blocks: tuple[str, ...], scale: np.ndarray, ranks: dict[str, int]
) -> Conditioning:
    """The least c = σ_r / σ_1 over ``blocks`` of J (m + k, n) (SVDs); ``ranks`` caps r at each
    block's generic rank, so directions a block can never span do not count."""
    n = J.shape[1]
    worst = Conditioning(1.0, blocks[0], np.zeros(n))
    for name in blocks:
        M = block_of(name, J, m, n_arm, scale)
        if M.size == 0:
            continue
        rank = min(min(M.shape), ranks.get(name, n))
        if rank == 0:
            continue
        value, motion = inverse_condition(M, rank)
        if value < worst.value:
            direction = np.zeros(n)
            columns = slice(0, n_arm) if name == "A" else slice(n_arm, n) if name == "W" else slice(0, n)
            direction[columns] = motion
            worst = Conditioning(value, name, direction)
    return worst


def wrist_pair(weakest: Conditioning, n_arm: int) -> tuple[int, int, float] | None:
    """(i, j, sign) when the weakest motion is carried by two wrist joints i < j (partition
    positions; at least :data:`WRIST_PAIR_SHARE` of its square): two wrist axes aligned, whose
    opposite turning does nothing. ``sign`` = ±1 makes rate_j = sign x rate_i the motion in
    which both turn the hand the same way about the common axis. None otherwise."""
    direction = weakest.direction
    if direction.size < 2:
        return None
    order = np.argsort(-np.abs(direction))
    i, j = sorted(int(position) for position in order[:2])
    if i < n_arm or direction[i] ** 2 + direction[j] ** 2 < WRIST_PAIR_SHARE:
        return None
    return i, j, -1.0 if direction[i] * direction[j] > 0.0 else 1.0


def carrying_joints(weakest: Conditioning) -> frozenset[int]:
    """Partition positions that carry the weakest motion: at least :data:`FREEZE_SHARE` of
    the largest entry of the weakest block's smallest right singular vector."""
    magnitudes = np.abs(weakest.direction)
    if not magnitudes.any():
        return frozenset()
    return frozenset(np.flatnonzero(magnitudes >= FREEZE_SHARE * magnitudes.max()).tolist())


def adaptive_damping(value: float, slow_threshold: float) -> float:
    """λ = MAX_DAMPING · sqrt(1 - (c / slow)²) for c < slow, else 0 (relative to σ_1)."""
    if value >= slow_threshold:
        return 0.0
    return MAX_DAMPING * math.sqrt(1.0 - (value / slow_threshold) ** 2)


def deceleration(value: float, singular_threshold: float, slow_threshold: float) -> float:
    """s = (c - singular) / (slow - singular), clipped to [0, 1]: the command's scale at c."""
    return min(1.0, max(0.0, (value - singular_threshold) / (slow_threshold - singular_threshold)))


def halts(ahead: float, singular_threshold: float, slow_threshold: float) -> bool:
    """Whether a decelerating step whose look-ahead c is ``ahead`` halts: c would come within
    :data:`HALT_MARGIN` of the band (slow - singular) above ``singular_threshold``.

    Without the margin the decision never comes on its own: with the scale s linear in c,
    c falls by about s · (its unscaled drop) per step, so it nears singular_threshold
    geometrically and only rounding (a 1e-17 of another CPU or numpy) carried it under."""
    return ahead < singular_threshold + HALT_MARGIN * (slow_threshold - singular_threshold)


@dataclass(frozen=True)
class ColumnMap:
    """A change of the partition's rate variables: partition rates = matrix @ y.

    ``matrix`` is (n_partition, n_reduced); the first ``n_arm`` entries of y are arm joints
    (arm columns are only ever dropped, never merged with another)."""

    matrix: np.ndarray
    n_arm: int

    @classmethod
    def of(cls, n_arm: int, n_wrist: int, dropped: frozenset[int], merged: tuple[int, int, float] | None) -> ColumnMap:
        """Columns kept one by one, less ``dropped`` (partition positions); ``merged`` (i, j,
        sign) in partition positions moves j at sign x i's rate, as one variable."""
        n = n_arm + n_wrist
        columns: list[np.ndarray] = []
        kept_arm = 0
        pair = merged if merged and merged[0] not in dropped and merged[1] not in dropped else None
        for position in range(n):
            if position in dropped or (pair and position == pair[1]):
                continue
            column = np.zeros(n)
            column[position] = 1.0
            if pair and position == pair[0]:
                column[pair[1]] = pair[2]
            columns.append(column)
            kept_arm += position < n_arm
        matrix = np.array(columns).T if columns else np.zeros((n, 0))
        return cls(matrix, kept_arm)


__all__ = [
    "FREEZE_SHARE",
    "HALT_MARGIN",
    "MAX_DAMPING",
    "NOISE_FLOOR",
    "SINGULAR_THRESHOLD",
    "SLOW_THRESHOLD",
    "WRIST_PAIR_SHARE",
    "WRIST_STRATEGIES",
    "ColumnMap",
    "Conditioning",
    "adaptive_damping",
    "block_of",
    "c_said",
    "carrying_joints",
    "check_strategy",
    "check_thresholds",
    "conditioning",
    "deceleration",
    "halts",
    "measured_blocks",
    "wrist_pair",
]
