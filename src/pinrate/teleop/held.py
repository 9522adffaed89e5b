"""The operator's command as the console holds it between ticks: stick deflections turned
into speeds, a joint jog, or Barker's uncoupled command, each with the time it was given (the
dead man ages it), and what the controller's step takes for it."""

from __future__ import annotations

import math
import time
from collections.abc import Mapping
from types import MappingProxyType
from typing import NamedTuple

import numpy as np

from ..checks import check_vector
from ..control.commands import JointJog, Uncoupled
from ..control.controller import Controller
from ..control.observation import Observation
from ..errors import InputError
from ..kinematics.spatial import saturate


class Held(NamedTuple):
    """The command held (one tuple, assigned at once: a reader never sees half of it).
    ``linear`` m/s and ``angular`` rad/s (``frame`` axes; in the uncoupled mode ``angular``
    holds the wrist joints' rates, one per axis), ``stamp`` s, ``mode`` a :data:`~pinrate.teleop.session.MODES` value
    or ``"jog"``, ``jog`` {joint: rate} for a jog."""

    linear: np.ndarray
    angular: np.ndarray
    stamp: float
    mode: str = "twist"
    jog: Mapping[str, float] = MappingProxyType({})

    @property
    def moves(self) -> bool:
        """Something non-zero is commanded."""
        return bool(self.linear.any() or self.angular.any() or any(self.jog.values()))

    def command(self, controller: Controller, observation: Observation, frame: str, max_linear_speed: float) -> object:
        """What :meth:`Controller.step` takes for this held command at ``observation``: a
        :class:`~pinrate.control.commands.JointJog`, an
        :class:`~pinrate.control.commands.Uncoupled` command (the wrist centre's velocity,
        saturated at ``max_linear_speed`` m/s, and each angular axis's wrist joint rate), or
        the twist (partition rows); ``frame`` ``"base"`` turns world axes into the sensor's."""
        linear, angular = self.linear, self.angular
        if self.mode == "jog":
            return JointJog(self.jog)
        sensor_R_world = observation.world_T_sensor.rotation.T
        index = controller.index
        if self.mode == "uncoupled":
            if frame == "base":
                linear = sensor_R_world @ linear
            wrist = controller.partition.wrist
            rates = {name: float(angular[axis]) for axis, name in enumerate(wrist[:3]) if angular[axis]}
            # Each axis is a deflection up to max_linear_speed: the speed of their sum is bounded too.
            centre_velocity, _ = saturate(linear[index.rows[: index.m]], max_linear_speed)
            return Uncoupled(centre_velocity, rates)
        if frame == "base":
            linear, angular = sensor_R_world @ linear, sensor_R_world @ angular
        return np.concatenate([linear, angular])[index.rows]


STILL = Held(np.zeros(3), np.zeros(3), -math.inf)


def check_time(now: object) -> float:
    if now is None:
        return time.monotonic()
    try:
        stamp = float(now)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        raise InputError(f"now must be a time in seconds, not {now!r}") from None
    if not math.isfinite(stamp):
        raise InputError(f"now must be finite, got {stamp}")
    return stamp


def deflection(value: object, what: str) -> np.ndarray:
    """Three stick deflections, clipped to [-1, 1]; InputError for a wrong shape or NaN."""
    return np.clip(check_vector(value, 3, what), -1.0, 1.0)


__all__ = ["STILL", "Held", "check_time", "deflection"]
