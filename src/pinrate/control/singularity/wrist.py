"""Barker's wrist strategies (eq. 61-63): how two aligned wrist axes share a rotation
(``Controller(wrist=...)``), whatever ``singularity=`` is.

Two wrist axes are aligned when the weakest block's smallest right singular vector is carried
by two wrist joints (:func:`~pinrate.control.singular_region.wrist_pair`); the rule is a change
of the wrist's rate variables:

* ``"split"``: the pair moves as one joint, each at the same rate: they share the rotation
  about the common axis equally (eq. 61; at exact alignment the Moore-Penrose solution of
  eq. 60);
* ``"hold_first"``: the first of the pair (nearer the base) holds still, the last takes the
  whole rotation (eq. 62);
* ``"last_then_first"``: as ``hold_first`` until the last is held at a position limit, then
  the first takes the rotation (eq. 63).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from ..context import StepContext
from ..singular_region import Conditioning, c_said, wrist_pair


class WristRule(NamedTuple):
    """The change of variables of a wrist rule, in partition positions."""

    dropped: frozenset[int]  # the held joint (hold_first, last_then_first)
    merged: tuple[int, int, float] | None  # (first, last, sign): the pair as one variable (split)
    released_by: tuple[int, int] | None  # (held, last): last_then_first releases held when last is blocked
    detail: str


def wrist_rule(
    wrist: str, context: StepContext, weakest: Conditioning, n_arm: int, q: np.ndarray
) -> WristRule | None:
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
    if wrist == "split":
        merged = pair
        how = "they share the rotation about the common axis"
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


__all__ = ["WristRule", "wrist_rule"]
