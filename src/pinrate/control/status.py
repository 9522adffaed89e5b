"""What happened in one control step, as a ranked word."""

from __future__ import annotations

from collections.abc import Mapping
from enum import Enum
from types import MappingProxyType


class Status(str, Enum):
    """The most severe condition met in a control step (contract v2), ranked by :data:`SEVERITY`.

    Two members are pinrate's own: ``TWIST_SATURATED``, the commanded twist was scaled down
    to the controller's TCP speed limits (direction kept) before any joint rate was solved;
    ``NEAR_SINGULARITY``, a block the algorithm inverts is in the singular region and the
    motion goes on: solved by the generalized or damped inverse
    (``singularity="generalized_inverse"`` or ``"adaptive_dls"``), or, with ``"decelerate"``,
    a step that raises the conditioning and is executed unscaled.

    ``UNACHIEVABLE_TWIST`` (contract v2.1, the honest step; just above RATE_LIMITED): the
    partition's joints cannot make the commanded twist at q, whatever the limits (fewer joints
    than controlled components, or a J whose rank is below their number at almost every
    configuration): the step moves by the least-squares part of it and ``Step.detail`` gives
    the residual. A step whose motion a limit or a singularity strategy bent says so with that
    member instead; so no step reports OK or TWIST_SATURATED while it departs from the twist
    its algorithm makes of the command.

    Two more rank the self-collision monitor's verdicts (:mod:`pinrate.control.collision`):
    ``DECELERATE_FOR_COLLISION``, the nearest pair of links is closer than the safety distance
    and the step, which brings them closer, is scaled down (just above
    DECELERATE_FOR_SINGULARITY); ``HALT_FOR_COLLISION``, the step would bring a pair within
    the stop distance and is not executed (the most severe: a halt that protects hardware).
    """

    OK = "ok"
    TWIST_SATURATED = "twist_saturated"
    RATE_LIMITED = "rate_limited"
    UNACHIEVABLE_TWIST = "unachievable_twist"
    JOINT_LIMIT = "joint_limit"
    WRIST_SINGULARITY = "wrist_singularity"
    NEAR_SINGULARITY = "near_singularity"
    DECELERATE_FOR_SINGULARITY = "decelerate_for_singularity"
    DECELERATE_FOR_COLLISION = "decelerate_for_collision"
    AUXILIARY_ELBOW = "auxiliary_elbow"
    FROZEN = "frozen"
    HALT_FOR_SINGULARITY = "halt_for_singularity"
    HALT_FOR_COLLISION = "halt_for_collision"

    @property
    def severity(self) -> int:
        """Rank of the status: higher is more severe (OK is 0)."""
        return SEVERITY.index(self)

    @property
    def word(self) -> str:
        """The status in words (:data:`WORDS`): what the console shows, and what a
        :class:`~pinrate.control.trajectory.Trajectory` and a teleop recording keep per step."""
        return WORDS[self]


SEVERITY: tuple[Status, ...] = tuple(Status)
"""Statuses from the least to the most severe: OK < TWIST_SATURATED < RATE_LIMITED <
UNACHIEVABLE_TWIST < JOINT_LIMIT < WRIST_SINGULARITY < NEAR_SINGULARITY < DECELERATE_FOR_SINGULARITY <
DECELERATE_FOR_COLLISION < AUXILIARY_ELBOW < FROZEN < HALT_FOR_SINGULARITY < HALT_FOR_COLLISION."""


WORDS: Mapping[Status, str] = MappingProxyType(
    {
        Status.OK: "moving",
        Status.TWIST_SATURATED: "speed limited",
        Status.RATE_LIMITED: "rate limited",
        Status.UNACHIEVABLE_TWIST: "twist out of reach",
        Status.JOINT_LIMIT: "at a joint limit",
        Status.WRIST_SINGULARITY: "wrist singularity",
        Status.NEAR_SINGULARITY: "near singularity",
        Status.DECELERATE_FOR_SINGULARITY: "near singularity: decelerating",
        Status.DECELERATE_FOR_COLLISION: "near self-collision: decelerating",
        Status.AUXILIARY_ELBOW: "auxiliary elbow active",
        Status.FROZEN: "frozen joints",
        Status.HALT_FOR_SINGULARITY: "near singularity: halted",
        Status.HALT_FOR_COLLISION: "near self-collision: halted",
    }
)
"""Each status in words: the one vocabulary of the console, servo trajectories and teleop
recordings (a step's status is never said any other way)."""


def most_severe(*statuses: Status) -> Status:
    """The most severe of ``statuses`` (OK for none)."""
    return max(statuses, key=SEVERITY.index, default=Status.OK)


def ranked(statuses: list[Status]) -> tuple[Status, ...]:
    """The distinct ``statuses``, least severe first."""
    return tuple(sorted(set(statuses), key=SEVERITY.index))
