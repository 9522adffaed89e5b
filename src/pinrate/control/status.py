"""What happened in one control step, as a ranked word."""

from __future__ import annotations

from enum import Enum


class Status(str, Enum):
    """The most severe condition met in a control step (contract v2), ranked by :data:`SEVERITY`.

    Two members are pinrate's own: ``TWIST_SATURATED``, the commanded twist was scaled down
    to the controller's TCP speed limits (direction kept) before any joint rate was solved;
    ``NEAR_SINGULARITY``, a block the algorithm inverts is in the singular region and the
    motion goes on: solved by the generalized or damped inverse
    (``singularity="generalized_inverse"`` or ``"adaptive_dls"``), or, with ``"decelerate"``,
    a step that raises the conditioning and is executed unscaled.
    """

    OK = "ok"
    TWIST_SATURATED = "twist_saturated"
    RATE_LIMITED = "rate_limited"
    JOINT_LIMIT = "joint_limit"
    WRIST_SINGULARITY = "wrist_singularity"
    NEAR_SINGULARITY = "near_singularity"
    DECELERATE_FOR_SINGULARITY = "decelerate_for_singularity"
    AUXILIARY_ELBOW = "auxiliary_elbow"
    FROZEN = "frozen"
    HALT_FOR_SINGULARITY = "halt_for_singularity"

    @property
    def severity(self) -> int:
        """Rank of the status: higher is more severe (OK is 0)."""
        return SEVERITY.index(self)


SEVERITY: tuple[Status, ...] = tuple(Status)
"""Statuses from the least to the most severe: OK < TWIST_SATURATED < RATE_LIMITED <
JOINT_LIMIT < WRIST_SINGULARITY < NEAR_SINGULARITY < DECELERATE_FOR_SINGULARITY < AUXILIARY_ELBOW < FROZEN <
HALT_FOR_SINGULARITY."""


def most_severe(*statuses: Status) -> Status:
    """The most severe of ``statuses`` (OK for none)."""
    return max(statuses, key=SEVERITY.index, default=Status.OK)


def ranked(statuses: list[Status]) -> tuple[Status, ...]:
    """The distinct ``statuses``, least severe first."""
    return tuple(sorted(set(statuses), key=SEVERITY.index))
