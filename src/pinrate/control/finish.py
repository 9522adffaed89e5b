"""The end of every control step (:mod:`pinrate.control.controller`'s stages 6 to 8, after the
position limits' hold and the decelerating strategies' look-ahead), twist or joint command
alike: the mimic joints driven by their leaders (rate = multiplier x the leader's, so q keeps
q_mimic = m q_leader + o: :mod:`pinrate.kinematics.mimic`), velocity limits (one scale
factor), acceleration limits (a blend from the last rates),
self-collision, integration over dt, the clamp to the position limits, the status; and the
halt, which a step ends with instead where it must not move."""

from __future__ import annotations

import numpy as np

from ..kinematics.manipulator import Robot
from .collision import CollisionMonitor
from .limits import AccelerationLimits, PositionLimits, VelocityLimits
from .observation import Observation, Step
from .singularity.auxiliary_elbow import AuxiliaryElbow
from .status import Status, ranked


class Finish:
    """A controller's end of the step, over the stages it built (shared with it, not copied).

    Args:
        robot: the robot; dt: the control period (s).
        positions: the position limits' stage (its ``enabled`` says whether q is clamped).
        rate_limits: the velocity limits' stage.
        accelerations: the acceleration limits' stage, or None.
        collision: the self-collision monitor, or None.
        auxiliary: Barker's auxiliary elbow control, or None (it follows the elbow's bend).
    """

    def __init__(
        self,
        robot: Robot,
        dt: float,
        positions: PositionLimits,
        rate_limits: VelocityLimits,
        accelerations: AccelerationLimits | None,
        collision: CollisionMonitor | None,
        auxiliary: AuxiliaryElbow | None,
    ) -> None:
        self.robot = robot
        self.dt = dt
        self.positions = positions
        self.rate_limits = rate_limits
        self.accelerations = accelerations
        self.collision = collision
        self.auxiliary = auxiliary
        self.mimics = robot.mimics if robot.mimics else None
        """The robot's mimic coupling when it has mimic joints, else None (a step skips it)."""

    def __call__(
        self,
        observation: Observation,
        twist: np.ndarray,
        rates: np.ndarray,
        statuses: list[Status],
        details: list[str],
        frozen: tuple[str, ...],
    ) -> Step:
        """The end of every step: the mimic joints driven by their leaders, velocity limits
        (one scale factor), acceleration limits, self-collision, integration over dt, the clamp
        to the position limits, the status."""
        mimics = self.mimics
        # rate(mimic) = m rate(leader) before any limit sees the rates, and again after a stage
        # that changes joints one by one: q keeps q_mimic = m q_leader + o (the rates said are applied).
        if mimics is not None:
            rates = mimics.drive(rates.copy())
        rates = self.rate_limits.apply(rates, statuses, details)
        if self.accelerations is not None:
            rates, stopped = self.accelerations.apply(observation.q, rates, frozen, statuses, details)
            frozen = frozen + tuple(name for name in stopped if name not in frozen)
            if mimics is not None:
                mimics.drive(rates)
        if self.collision is not None:
            verdict = self.collision.limit(observation.q, rates, self.dt)
            if verdict.status is Status.HALT_FOR_COLLISION:
                return self.halt(observation, twist, verdict.detail, Status.HALT_FOR_COLLISION)
            if verdict.scale < 1.0:
                rates = rates * verdict.scale
                statuses.append(verdict.status)
                details.append(verdict.detail)
        next_q = self.robot.integrate(observation.q, rates, self.dt)
        if self.auxiliary is not None:
            self.auxiliary.reach_extension(observation.q, next_q)
        if self.positions.enabled:
            hit = self.positions.clamp(next_q, observation.q, rates)
            if mimics is not None:
                if hit:
                    mimics.carry(observation.q, next_q, rates, self.dt)
                mimics.settle(next_q)
            if hit and Status.JOINT_LIMIT not in statuses:
                statuses.append(Status.JOINT_LIMIT)
                details.append(hit)
        if self.accelerations is not None:
            self.accelerations.remember(rates)  # the rates applied, after every scaling and the clamp
        if not statuses:  # the common step: nothing to rank
            return Step(next_q, rates, Status.OK, frozen, twist, observation, "; ".join(details), ())
        conditions = ranked(statuses)
        return Step(next_q, rates, conditions[-1], frozen, twist, observation, "; ".join(details), conditions)

    def halt(
        self, observation: Observation, twist: np.ndarray, detail: str, status: Status = Status.HALT_FOR_SINGULARITY
    ) -> Step:
        """The step that does not move: q kept, rates 0, ``status`` with ``detail``; the
        acceleration limits forget the last rates (the next motion starts at rest)."""
        if self.accelerations is not None:
            self.accelerations.reset()
        return Step(observation.q.copy(), np.zeros(self.robot.nv), status, (), twist, observation, detail, (status,))


__all__ = ["Finish"]
