"""The step of a command that names joint rates instead of a twist
(:mod:`pinrate.control.commands`): a :class:`~pinrate.control.commands.JointJog` (the named
joints at their rates, the others still) or an :class:`~pinrate.control.commands.Uncoupled`
command (Barker's arm/wrist mode, :mod:`.uncoupled`); then the limits, as every step
(:mod:`.finish`). No strategy of the singular region acts: the rates are the command's."""

from __future__ import annotations

import numpy as np

from .commands import JointJog, Uncoupled, joint_rate_vector
from .context import StepContext
from .finish import Finish
from .limits import PositionLimits
from .observation import Observation, Step
from .robot_facts import Facts
from .solve import Solve
from .status import Status
from .uncoupled import WristCentre


class JointSpace:
    """A controller's joint-space steps, over the stages it built.

    Args:
        context: what the step's stages read.
        facts: the robot's facts (the joints that can be jogged, the wrist's axes and body).
        positions: the position limits' stage.
        finish: the end of the step.
    """

    def __init__(self, context: StepContext, facts: Facts, positions: PositionLimits, finish: Finish) -> None:
        self.context = context
        self.joggable = facts.joggable
        self.positions = positions
        self.finish = finish
        self._wrist_axes, self._wrist_body = facts.wrist_axes, facts.wrist_body
        self._wrist_centre: WristCentre | None = None  # Uncoupled commands' own, made on first use

    def step(self, observation: Observation, command: JointJog | Uncoupled) -> Step:
        """A joint jog (the named joints at their rates, the others still) or an uncoupled
        command (:mod:`.uncoupled`); then the limits. ``Step.twist`` is the twist the rates
        produce at q (partition rows, sensor axes)."""
        context = self.context
        statuses: list[Status] = []
        details: list[str] = []
        if isinstance(command, JointJog):
            velocity_of = context.velocity_of
            requested = joint_rate_vector(command.rates, self.joggable, velocity_of, context.robot.nv, "JointJog")

            def jog(left_out: frozenset[str]) -> np.ndarray:
                rates = requested.copy()
                for name in left_out:
                    rates[velocity_of[name]] = 0.0
                return rates

            solve: Solve = jog
            rates = requested.copy()
        else:
            if self._wrist_centre is None:
                self._wrist_centre = WristCentre(context, self._wrist_axes, self._wrist_body)
            solve = self._wrist_centre.solver(observation, command, statuses, details)
            rates = solve(frozenset())
        rates, frozen = self.positions.hold(observation, rates, solve, statuses, details, ())
        step = self.finish(observation, np.zeros(context.index.rows.size), rates, statuses, details, frozen)
        step.twist = context.reduced_rows(observation.jacobian) @ step.joint_rates
        return step


__all__ = ["JointSpace"]
