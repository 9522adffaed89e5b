"""The kinematic plant: the joints do exactly what they are told. The next configuration is
the commanded rates integrated over the duration on the configuration space,

    q(t + T) = q(t) ⊕ q̇ T                    (``pin.integrate``; rad, m)

which is what pinrate's loops do without a plant (a step's own ``q``, up to the last bit of
a joint the step clamped onto its limit)."""

from __future__ import annotations

import numpy as np

from ..kinematics.manipulator import Robot
from .abstract_plant import Measurement, Plant


class KinematicPlant(Plant):
    """Joints that follow their commanded rates exactly (see the module docstring)."""

    def __init__(self, robot: Robot) -> None:
        self.robot = robot
        self.name = "kinematic"
        self.limit_tolerance = np.zeros(robot.nv)  # the integrated rates end on the limit
        self._q = robot.home()
        self._time = 0.0

    def reset(self, q: np.ndarray) -> Measurement:
        self._q = self.robot.check_q(q).copy()
        self._time = 0.0
        return Measurement(self._q.copy(), np.zeros(self.robot.nv), 0.0)

    def advance(self, joint_rates: np.ndarray, duration: float) -> Measurement:
        rates, seconds = self.check_command(joint_rates, duration)
        self._q = self.robot.integrate(self._q, rates, seconds)
        self._time += seconds
        return Measurement(self._q.copy(), rates.copy(), self._time)


__all__ = ["KinematicPlant"]
