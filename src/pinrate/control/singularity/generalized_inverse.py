"""``singularity="generalized_inverse"``: Barker's M* (eq. 38, 44, 60) — each inversion by
the Moore-Penrose inverse with singular values under ``singular_threshold`` · σ_1 cut. On
Barker's arm this equals the 2x2 reduction (eq. 39-44) at θ3 = 0 for a command in M's range
(M's null vector leaves θ1 alone), not for a command with an outward part, nor at
S2 ES + F5 = 0, where the null vector moves θ1 (:mod:`pinrate.papers.barker_arm_rates`)."""

from __future__ import annotations

import numpy as np

from ..context import StepContext
from ..observation import Observation
from ..singular_region import Conditioning
from ..status import Status
from .plan import Plan, where

decelerates = False


def near(context: StepContext, observation: Observation, twist: np.ndarray, weakest: Conditioning, plan: Plan) -> Plan:
    """The generalized inverse's plan, said (``Status.NEAR_SINGULARITY``)."""
    cut = "directions cut" if weakest.value < context.singular_threshold else "no direction cut"
    return plan._replace(
        statuses=(*plan.statuses, Status.NEAR_SINGULARITY),
        details=(*plan.details, f"{where(weakest, context.slow_threshold)}: generalized inverse, {cut}"),
    )


__all__ = ["decelerates", "near"]
