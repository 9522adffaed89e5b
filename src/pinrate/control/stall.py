"""Why a servo run stalled: the condition its steps met in the stall window, said in the one
vocabulary of step statuses (:attr:`Status.word <pinrate.control.status.Status.word>`) with the
detail of the last step that met it (the wrist pair and the angle between them, the joint
held at its limit, the frozen joints, the share of the twist out of reach, ...).

The window is the steps since the error last improved by STALL_IMPROVEMENT. The statuses that
can hold a run there are those that bend or stop the motion: every status above
RATE_LIMITED. OK, a saturated twist and a rate-limited step keep the commanded direction
(one scale factor), so they slow the error's fall but do not stop it. The cause is the
status most steps of the window met (the more severe of a tie).
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Sequence

from .status import WORDS, Status

CAUSES: frozenset[str] = frozenset(status.word for status in Status if status.severity > Status.RATE_LIMITED.severity)
"""The words of the statuses that can hold a run (every one above RATE_LIMITED)."""

_RANK = {WORDS[status]: status.severity for status in Status}


def stall_cause(words: Sequence[str], details: Sequence[str]) -> str:
    """The cause of a stall in words, from the status words and details of the steps of its
    window: "wrist singularity on 628 of its 948 steps: wrist axes of ... aligned (joint_5_b =
    -0.007 rad, ...)", or, when no step of the window met one of :data:`CAUSES`, that none was
    bent (the error's own landscape or the algorithm's map held it)."""
    counts = Counter(word for word in words if word in CAUSES)
    if not counts:
        return (
            f"no step of its {len(words)} was held by a limit, a singularity or the collision monitor "
            "(the commanded motion did not lower the error)"
        )
    cause = max(counts, key=lambda word: (counts[word], _RANK[word]))
    detail = next(detail for word, detail in zip(reversed(words), reversed(details), strict=True) if word == cause)
    said = f"{cause} on {counts[cause]} of its {len(words)} steps"
    return f"{said}: {detail}" if detail else said


__all__ = ["CAUSES", "stall_cause"]
