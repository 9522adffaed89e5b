"""Position limits (step 6 of :mod:`pinrate.control.controller`, the first limit): a joint whose commanded rate
would carry it past a limit within dt is *blocked*: the rates are solved again without it (the
others serve the command as well as they can), and it moves at most onto the limit. A joint
on its limit whose command points away is not blocked: motion away is always executed. The
test is on the commanded rate, never on a measured one, so a joint held at a limit does not
cycle between stop and go (MoveIt Servo issue #2898). After integration q is clamped to the
limits (a guard against rounding)."""

from __future__ import annotations

from collections.abc import Callable, Collection

import numpy as np

from ...errors import InputError, SingularBlockError
from ..observation import Observation
from ..robot_facts import Limit
from ..status import Status


def reached_detail(limit: Limit, value: float) -> str:
    """A step's detail when ``limit``'s joint was clamped onto it at ``value`` (its lower or
    upper bound; the one wording, whichever path took the step)."""
    side, bound = ("lower", limit.lower) if value == limit.lower else ("upper", limit.upper)
    return f"{limit.joint} reached its {side} limit {bound:.4g}"


class PositionLimits:
    """The 1-DOF joints' position limits of a controller.

    Args:
        limits: every 1-DOF joint with finite limits (rad or m).
        dt: the control period (s).
        enabled: ``Controller(position_limits=...)``: False keeps nothing (but :meth:`passing`,
            which the acceleration blend uses whatever this says).
    """

    def __init__(self, limits: tuple[Limit, ...], dt: float, enabled: bool) -> None:
        self.limits = limits
        self.dt = dt
        self.enabled = enabled

    def passing(self, q: np.ndarray, rates: np.ndarray, skipped: Collection[Limit]) -> list[Limit]:
        """The limits, less ``skipped``, that the commanded rates carry their joints past
        within dt. On Python floats: numpy's per-call cost exceeds the arithmetic for a
        handful of joints, and this runs every step."""
        q_values, rate_values, dt = q.tolist(), rates.tolist(), self.dt
        passing = []
        for limit in self.limits:
            _, q_index, velocity, lower, upper = limit  # unpacked: a NamedTuple's fields are slower
            rate = rate_values[velocity]
            value = q_values[q_index] + rate * dt
            # Moving outward past a bound: a joint already outside (a controller without
            # position limits) and standing still passes nothing.
            if ((value > upper and rate > 0.0) or (value < lower and rate < 0.0)) and limit not in skipped:
                passing.append(limit)
        return passing

    def check_inside(self, q: np.ndarray) -> None:
        """InputError naming every joint that ``q`` puts outside its limits, when the limits
        are kept: a step from there would have to snap the joint onto its limit (a jump no
        velocity limit allows) or leave q outside them. Nothing when they are not kept."""
        if not self.enabled:
            return
        q_values = q.tolist()
        for _, q_index, _, lower, upper in self.limits:
            if not lower <= q_values[q_index] <= upper:
                break
        else:
            return  # inside: the common case, no words made
        outside = [
            f"{limit.joint} at {q_values[limit.q_index]:.6g} (limits [{limit.lower:.6g}, {limit.upper:.6g}])"
            for limit in self.limits
            if not limit.lower <= q_values[limit.q_index] <= limit.upper
        ]
        raise InputError(
            f"q is outside the position limits: {'; '.join(outside)}. Start inside them (robot.home() is), "
            "or bring the joint back with a controller built with position_limits=False"
        )

    def hold(
        self,
        observation: Observation,
        rates: np.ndarray,
        solve: Callable[[frozenset[str]], np.ndarray],
        statuses: list[Status],
        details: list[str],
        frozen: tuple[str, ...],
    ) -> tuple[np.ndarray, tuple[str, ...]]:
        """(rates, frozen): joints that ``rates`` would carry past a position limit are held at
        it and ``solve`` runs without them; the condition is appended to ``statuses`` and
        ``details``. Raises SingularBlockError as ``solve`` does."""
        passing = self.passing(observation.q, rates, ()) if self.enabled else []
        if not passing:
            return rates, frozen
        try:
            rates, blocked = self._respect(observation, rates, passing, solve)
        except SingularBlockError as singular:
            raise SingularBlockError(f"{singular}, with the joints at their limits left out") from None
        if blocked:
            statuses.append(Status.JOINT_LIMIT)
            details.append(f"held at a position limit: {', '.join(blocked)}")
            frozen = frozen + tuple(name for name in blocked if name not in frozen)
        return rates, frozen

    def _respect(
        self,
        observation: Observation,
        rates: np.ndarray,
        passing: list[Limit],
        solve: Callable[[frozenset[str]], np.ndarray],
    ) -> tuple[np.ndarray, tuple[str, ...]]:
        """(rates, blocked joints), from the limits ``passing`` at ``rates``: those joints are
        left out and the rates solved again by ``solve``, until no remaining joint passes a
        limit; each blocked joint goes on at its commanded rate up to its limit, and stops there."""
        q = observation.q
        blocked: dict[Limit, float] = {}  # each blocked joint's rate when it was blocked
        while passing:
            blocked.update((limit, float(rates[limit.velocity])) for limit in passing)
            rates = solve(frozenset(limit.joint for limit in blocked))
            passing = self.passing(q, rates, blocked)
        for limit, commanded in blocked.items():
            rates[limit.velocity] = limit.onto_the_limit(q, commanded, self.dt)
        return rates, tuple(limit.joint for limit in blocked)

    def clamp(self, next_q: np.ndarray, q: np.ndarray, rates: np.ndarray) -> str:
        """Clamp ``next_q`` in place to the limits, and each clamped joint's entry of ``rates``
        (in place) to the rate that reaches its limit from ``q`` in dt, (bound - q) / dt, so the
        rates said are the rates applied (the clamp only takes up rounding after the hold, which
        already brings a joint onto its limit at most); describe the first joint that was past
        one ('' if none). The compiled core clamps with the same operations."""
        hit = ""
        next_values = next_q.tolist()  # the test on Python floats; the rare clamp writes the arrays
        for limit in self.limits:
            _, q_index, velocity, lower, upper = limit
            value = next_values[q_index]
            if value < lower or value > upper:
                bound = lower if value < lower else upper
                next_q[q_index] = bound
                rates[velocity] = (bound - q[q_index]) / self.dt
                hit = hit or reached_detail(limit, bound)
        return hit


__all__ = ["PositionLimits"]
