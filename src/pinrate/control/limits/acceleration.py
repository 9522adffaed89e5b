"""Acceleration limits (``Controller(acceleration_limits=...)``): each step's rates move from
the rates applied last toward the new ones by at most a·dt per joint, one factor for all
joints, so the change keeps its direction (``Status.RATE_LIMITED``). Joints held at a position
limit or frozen keep their rates (position limits act at once); a joint the blend would carry
past a limit stops on it."""

from __future__ import annotations

import numpy as np

from ..status import Status
from .position import PositionLimits


class AccelerationLimits:
    """Limits (nv,) in rad/s² or m/s², and the rates applied last (its state).

    Args:
        limits: one per velocity component.
        dt: the control period (s).
        velocity_of: joint name -> its velocity index.
        positions: the controller's position limits (the blend stops a joint on its limit).
    """

    def __init__(self, limits: np.ndarray, dt: float, velocity_of: dict[str, int], positions: PositionLimits) -> None:
        self.limits = limits
        self.dt = dt
        self.velocity_of = velocity_of
        self.positions = positions
        self.previous = np.zeros(limits.size)
        """The rates applied at the last step (zero at rest)."""

    def reset(self) -> None:
        """Start at rest."""
        self.previous = np.zeros(self.limits.size)

    def remember(self, rates: np.ndarray) -> None:
        """The rates this step applied in the end (after every scaling)."""
        self.previous = rates.copy()

    def apply(
        self, q: np.ndarray, rates: np.ndarray, held: tuple[str, ...], statuses: list[Status], details: list[str]
    ) -> tuple[np.ndarray, tuple[str, ...]]:
        """(rates, stopped): previous + s (rates - previous) on the joints not ``held`` (at a
        limit, frozen), s the largest factor <= 1 keeping every change within a·dt; the held
        joints keep their rates, and a joint the blend would carry past a limit stops on it
        (``stopped`` names those, said as ``Status.JOINT_LIMIT``). Between two rate vectors
        within the velocity limits, the result is within them too."""
        change = rates - self.previous
        for name in held:
            change[self.velocity_of[name]] = 0.0  # position limits act at once
        largest = np.abs(change) / (self.limits * self.dt)
        worst = float(largest.max(initial=0.0))
        if worst <= 1.0:
            return rates, ()
        blended = self.previous + change / worst
        for name in held:
            blended[self.velocity_of[name]] = rates[self.velocity_of[name]]
        statuses.append(Status.RATE_LIMITED)
        details.append(f"rates changed by {1.0 / worst:.3g} of the step's change to meet the acceleration limits")
        passing = self.positions.passing(q, blended, ())
        for limit in passing:
            blended[limit.velocity] = limit.onto_the_limit(q, blended[limit.velocity], self.dt)
        stopped = tuple(limit.joint for limit in passing)
        if stopped:
            statuses.append(Status.JOINT_LIMIT)
            details.append(f"stopped on a position limit by the acceleration limits: {', '.join(stopped)}")
        return blended, stopped


__all__ = ["AccelerationLimits"]
