"""A step's solve (:data:`Solve`): its joint rates with some joints left out, which the
position limits call again without the joints they hold (:mod:`.limits`); and the solve of a
twist step (:class:`TwistSolver`, stage 5 of :mod:`pinrate.control.controller`): Barker's
auxiliary elbow's, a singular-region plan's (:mod:`.singularity`), or the algorithm's, with
the posture task's null-space motion (:mod:`.posture`) outside the singular region."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from .context import StepContext
from .limits import VelocityLimits
from .observation import Observation
from .posture import PostureTask
from .singularity import Plan
from .singularity.auxiliary_elbow import Auxiliary, AuxiliaryElbow
from .singularity.plan import solve_planned
from .status import Status

Solve = Callable[[frozenset[str]], np.ndarray]
"""A step's solve: rates (nv,) with the given joints left out (held at a position limit)."""


class TwistSolver:
    """A controller's choice of the solve of a twist step, over the stages it built.

    Args:
        context: what the step's stages read.
        elbow: Barker's auxiliary elbow control, or None.
        posture: the secondary task, or None.
        rate_limits: the velocity limits' stage (the posture task's motion fits in their room).
    """

    def __init__(
        self,
        context: StepContext,
        elbow: AuxiliaryElbow | None,
        posture: PostureTask | None,
        rate_limits: VelocityLimits,
    ) -> None:
        self.context = context
        self.elbow = elbow
        self.posture = posture
        self.rate_limits = rate_limits

    def __call__(
        self,
        observation: Observation,
        twist: np.ndarray,
        auxiliary: Auxiliary | None,
        plan: Plan | None,
        statuses: list[Status],
        details: list[str],
    ) -> tuple[Solve, tuple[str, ...]]:
        """(solve, frozen): the step's solve for the auxiliary elbow, a plan or the algorithm
        (with the posture task's null-space motion outside the singular region), the plan's
        conditions appended to ``statuses`` and ``details``."""
        context = self.context
        if auxiliary is not None:
            elbow = self.elbow
            assert elbow is not None
            statuses.extend(auxiliary.statuses)
            details.extend(auxiliary.details)
            return (lambda left_out: elbow.solve(observation, twist, auxiliary, left_out)), ()
        if plan is not None:
            statuses.extend(plan.statuses)
            details.extend(plan.details)
            return (lambda left_out: solve_planned(context, observation, twist, plan, left_out)), plan.frozen
        posture = self.posture
        if posture is None:
            return (lambda left_out: context.solve_without(observation, twist, left_out)), ()

        def with_posture(left_out: frozenset[str]) -> np.ndarray:
            rates = context.solve_without(observation, twist, left_out)
            null = posture.null_motion(observation, left_out)
            return rates + self.rate_limits.room(rates, null) * null

        return with_posture, ()


__all__ = ["Solve", "TwistSolver"]
