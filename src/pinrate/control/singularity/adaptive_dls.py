"""``singularity="adaptive_dls"``: damped least squares with the damping raised as c falls,
λ = :data:`~pinrate.control.singular_region.MAX_DAMPING` · sqrt(1 - (c / slow_threshold)²),
relative to each block's σ_1 (Nakamura & Hanafusa 1986; Chiaverini 1997): the robust
baseline."""

from __future__ import annotations

import numpy as np

from ...solvers.generalized import damped_inverter
from ..context import StepContext
from ..observation import Observation
from ..singular_region import Conditioning, adaptive_damping
from ..status import Status
from .plan import Plan, where

decelerates = False


def near(context: StepContext, observation: Observation, twist: np.ndarray, weakest: Conditioning, plan: Plan) -> Plan:
    """The plan with every inversion damped by λ(c)."""
    damping = adaptive_damping(weakest.value, context.slow_threshold)
    return plan._replace(
        invert=damped_inverter(damping),
        statuses=(*plan.statuses, Status.NEAR_SINGULARITY),
        details=(
            *plan.details,
            f"{where(weakest, context.slow_threshold)}: damped least squares, λ = {damping:.2g} σ_1",
        ),
    )


__all__ = ["decelerates", "near"]
