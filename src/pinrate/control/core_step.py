"""The control step in the compiled core, per call, and the words of a step the core took.

:meth:`Controller.step <pinrate.control.controller.Controller.step>` hands a twist step to
:class:`CoreStep` where the core covers the controller (:mod:`.compiled_twin`'s allow-list):
the core runs the step's common path (saturation, the conditioning bound, the algorithm, the
position-limit test, the decelerate look-ahead, the velocity scale, integration over dt, the
clamp; ``core/src/servo.hpp``'s ``Servo::advance``, the servo loop's own) on the J of the
caller's observation, and hands back, to the Python stages, any step that needs more (the
singular region, a joint passing a limit, a singular block, a big step near the region).

A step the core took is said by its flags (SATURATED, RATE_LIMITED, CLAMPED), its velocity
scale and the first limit it clamped: :data:`CONDITIONS` and :func:`core_detail` turn them
into the statuses and the detail :class:`~.finish.Finish` gives the same step, for this
per-call step and the servo loop's log alike (the one mapping).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from ..compiled import CoreServo, chosen, core_module
from ..compiled.boundary import CLAMPED, RATE_LIMITED, SATURATED, STEP_FLAGS
from .limits.position import reached_detail
from .limits.velocity import scaled_detail
from .observation import Observation, Step
from .robot_facts import Limit
from .status import Status, ranked


def _conditions(flags: int) -> tuple[Status, ...]:
    """The conditions :class:`~.finish.Finish` ranks for a step with these core flags."""
    statuses = [Status.TWIST_SATURATED] if flags & SATURATED else []
    if flags & RATE_LIMITED:
        statuses.append(Status.RATE_LIMITED)
    if flags & CLAMPED:
        statuses.append(Status.JOINT_LIMIT)
    return ranked(statuses)


CONDITIONS: tuple[tuple[Status, ...], ...] = tuple(_conditions(flags) for flags in range(2 * max(STEP_FLAGS.values())))
"""Every condition a step the core took met, least severe first, indexed by its flags."""

STATUSES: tuple[Status, ...] = tuple(conditions[-1] if conditions else Status.OK for conditions in CONDITIONS)
"""The status (the most severe condition) of a step the core took, indexed by its flags."""

DETAILED = RATE_LIMITED | CLAMPED
"""The flags whose conditions carry a detail (a saturated twist has none)."""


def core_detail(flags: int, scale: float, limit: Callable[[], Limit], next_q: np.ndarray) -> str:
    """The detail of a step the core took: the velocity scale's words, then the clamped
    limit's (``limit()`` gives the first one clamped; ``next_q`` (nq,) the clamped q), joined
    as :class:`~.finish.Finish` joins them."""
    parts = []
    if flags & RATE_LIMITED:
        parts.append(scaled_detail(scale))
    if flags & CLAMPED:
        clamped = limit()
        parts.append(reached_detail(clamped, float(next_q[clamped.q_index])))
    return "; ".join(parts)


class CoreStep:
    """A controller's step in the compiled core (``twin``, its :class:`~pinrate.compiled.CoreServo`).

    Args:
        twin: the controller's compiled twin.
        limits: the position limits the controller keeps (the core names a clamped one by its
            number in this tuple).
    """

    def __init__(self, twin: CoreServo, limits: tuple[Limit, ...]) -> None:
        self._step = twin.step_function()
        self._limits = limits
        self._nq, self._nv = twin.nq, twin.nv

    def __call__(self, observation: Observation, twist: np.ndarray) -> Step | None:
        """The step from ``observation`` (its q and J are the core's input) with ``twist``
        (m + k,; partition order, sensor axes, m/s and rad/s; a float array of the caller's
        own, saturated in place): the :class:`~.observation.Step`, or None where the step is
        Python's."""
        rates, next_q = np.empty(self._nv), np.empty(self._nq)
        taken, flags, scale, hit = self._step(
            q=observation.q, jacobian=observation.jacobian, twist=twist, rates=rates, next=next_q
        )
        if not taken:
            return None
        detail = core_detail(flags, scale, lambda: self._limits[hit], next_q) if flags & DETAILED else ""
        return Step(next_q, rates, STATUSES[flags], (), twist, observation, detail, CONDITIONS[flags])


class CorePath:
    """A controller's :class:`CoreStep`, or None where the Python path runs it: found once per
    :func:`pinrate.compiled.use` choice (``PINRATE_BACKEND`` is read then, not per step:
    reading the environment costs more than the step's own checks).

    Args:
        twin: the controller's :meth:`~.controller.Controller.compiled`.
        limits: the position limits the controller keeps.
    """

    def __init__(self, twin: Callable[[], CoreServo | None], limits: tuple[Limit, ...]) -> None:
        self._twin = twin
        self._limits = limits
        self._steps: dict[str | None, CoreStep | None] = {}

    def __call__(self) -> CoreStep | None:
        choice = chosen()
        steps = self._steps
        if choice not in steps:
            twin = None if core_module() is None else self._twin()
            steps[choice] = None if twin is None else CoreStep(twin, self._limits)
        return steps[choice]


__all__ = ["CONDITIONS", "STATUSES", "CorePath", "CoreStep", "core_detail"]
