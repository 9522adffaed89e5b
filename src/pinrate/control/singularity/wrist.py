"""Barker's wrist strategies (eq. 61-63): how two aligned wrist axes share a rotation
(``Controller(wrist=...)``), whatever ``singularity=`` is.

Two wrist axes are aligned when the weakest block's smallest right singular vector is carried
by two wrist joints (:func:`~pinrate.control.singular_region.wrist_pair`); the rule is a change
of the wrist's rate variables:

* ``"turn"`` (the default of ``servo`` and the command line): as ``"split"``, and the pair
  turns against itself toward the rotation the aligned axes cannot make (below), so a servo
  passes the singularity;
* ``"split"`` (the Controller's default, contract v2): the pair moves as one joint, each at
  the same rate: they share the rotation about the common axis equally (eq. 61; at exact
  alignment the Moore-Penrose solution of eq. 60);
* ``"hold_first"``: the first of the pair (nearer the base) holds still, the last takes the
  whole rotation (eq. 62);
* ``"last_then_first"``: as ``hold_first`` until the last is held at a position limit, then
  the first takes the rotation (eq. 63).

Each rule leaves out the rotation the aligned axes cannot make: about u, the block's weakest
left singular vector (at Barker's θ5 = 0 the axis normal to θ5's and the common one; his eq.
50 "is useless" there). A servo whose error lies along u would stall there for ever: no
joint rate lowers it to first order (the error is stationary in q). The pair's opposite
turning, the weakest right singular vector n (W n = σ u), makes that rotation at σ per unit
rate, and at σ = 0 moves nothing but the middle axis, which it turns toward the commanded
rotation; then the middle joint makes it. So ``"turn"`` adds (:class:`LostRotation`)

    r = b / max(σ, slow_threshold · σ_1),   b = u · (residual the rule's solve leaves),

along n: the pseudo-inverse's own rate on that direction (eq. 60 without the cut), with its
gain capped at its value at the singular region's edge, so the turn is never faster than a
step just outside the region would ask. The turn is an opposite turning of the pair, so θ4 +
θ6 stays eq. 61's; only M2*'s equal split (its minimum norm) gives way. Barker's rules
(``"split"``, ``"hold_first"``, ``"last_then_first"``) are kept as eq. 60-63 say, and can
stall there (the servo's reason then names the wrist singularity). At σ = 0 exactly the sign of the turn is
the SVD's: either way leads to one of the two wrist solutions of the target.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from ..context import StepContext
from ..singular_region import Conditioning, block_of, c_said, wrist_pair


class WristRule(NamedTuple):
    """The change of variables of a wrist rule, in partition positions."""

    dropped: frozenset[int]  # the held joint (hold_first, last_then_first)
    merged: tuple[int, int, float] | None  # (first, last, sign): the pair as one variable (split)
    released_by: tuple[int, int] | None  # (held, last): last_then_first releases held when last is blocked
    detail: str


def wrist_rule(wrist: str, context: StepContext, weakest: Conditioning, n_arm: int, q: np.ndarray) -> WristRule | None:
    """The ``wrist`` strategy's rule when the weakest motion is a wrist pair's, else None.
    Its detail names the pair and the value at q of each joint between them (the one whose
    angle brings the two axes into line: Barker's θ5, the UR5's wrist_2)."""
    pair = wrist_pair(weakest, n_arm)
    if pair is None:
        return None
    names = context.names
    first, last, _ = pair
    joints = f"{names[first]} and {names[last]}"
    between = (context.joint_said(position, q) for position in range(first + 1, last))
    said = [*filter(None, between), c_said(weakest.value, f"c({weakest.block})")]
    dropped: frozenset[int] = frozenset()
    merged = released_by = None
    if wrist in ("turn", "split"):
        merged = pair
        how = "they share the rotation about the common axis"
        if wrist == "turn":
            how += " and turn toward the rotation they cannot make"
    else:
        dropped = frozenset([first])
        released_by = (first, last) if wrist == "last_then_first" else None
        how = f"{names[first]} holds, {names[last]} takes the rotation"
    return WristRule(
        dropped,
        merged,
        released_by,
        f"wrist axes of {joints} aligned ({', '.join(said)}): {how}",
    )


class LostRotation(NamedTuple):
    """The rotation two aligned wrist axes cannot make, and the pair's turn that makes it.

    ``rows`` (m + k,): u over the partition's rows, each already multiplied by its row scale
    (u · rows-weighted residual is the block's component b, rad/s); ``motion`` (n,): the unit
    joint motion n over the partition's columns; ``gain``: 1 / max(σ, slow_threshold · σ_1)
    (rad of joint per rad of hand rotation)."""

    rows: np.ndarray
    motion: np.ndarray
    gain: float

    def turn(self, residual: np.ndarray) -> np.ndarray:
        """The partition's rates (n,) that make the lost part of ``residual`` (m + k,; m/s then
        rad/s, sensor axes): r n with r = gain · (u · residual)."""
        return (self.gain * float(self.rows @ residual)) * self.motion


def lost_rotation(context: StepContext, reduced: np.ndarray, weakest: Conditioning, n_arm: int) -> LostRotation:
    """The :class:`LostRotation` of the ``weakest`` block of ``reduced`` (the partition's J,
    m + k by n, partition order) with ``n_arm`` arm columns: its SVD's last triplet within the
    block's generic rank."""
    index = context.index
    m, n = index.m, reduced.shape[1]
    block = block_of(weakest.block, reduced, m, n_arm, context.row_scale)
    rank = min(min(block.shape), context.ranks.get(weakest.block, n))
    left, values, right_t = np.linalg.svd(block)
    rows = np.zeros(reduced.shape[0])
    motion = np.zeros(n)
    if weakest.block == "W":
        rows[m:], motion[n_arm:] = left[:, rank - 1], right_t[rank - 1]
    else:  # "J": its rows are scaled, the residual's must be too
        rows, motion = left[:, rank - 1] * context.row_scale, right_t[rank - 1]
    floor = context.slow_threshold * float(values[0])
    sigma = float(values[rank - 1])
    return LostRotation(rows, motion, 1.0 / max(sigma, floor) if max(sigma, floor) > 0.0 else 0.0)


__all__ = ["LostRotation", "WristRule", "lost_rotation", "wrist_rule"]
