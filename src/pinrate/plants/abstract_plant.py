"""The plant seam: what a controller drives. A plant takes joint rates, advances its time and
reports the configuration it measured; the controller reads that measurement at its next step
(the closed loop of Shoham & Koren's Fig. 3), never its own integrated q.

Two plants: :class:`~.kinematic_plant.KinematicPlant` (the next q is the integrated rates,
exactly: pinrate's behaviour without a plant) and :class:`~.mujoco_plant.MujocoPlant` (a
MuJoCo simulation of the same robot, ``pip install "pinrate[mujoco]"``).
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from dataclasses import dataclass, field

import numpy as np

from ..checks import check_positive, check_vector
from ..kinematics.manipulator import Robot


@dataclass(frozen=True)
class Measurement:
    """What a plant measured at the end of an advance (or at a reset).

    Attributes:
        q: the configuration (nq,), Pinocchio's layout (rad, m).
        joint_rates: the joints' velocities (nv,), rad/s or m/s.
        time: s since the last reset, on the plant's clock.
        saturated: the joints whose actuator reached its force (effort) limit during the
            advance, in velocity order; () for a plant without actuators.
    """

    q: np.ndarray
    joint_rates: np.ndarray
    time: float
    saturated: tuple[str, ...] = field(default=())


class Plant(ABC):
    """A robot that joint rates drive: :meth:`reset` it to a configuration at rest, then
    :meth:`advance` it by a command held for a duration; each returns a :class:`Measurement`.

    Attributes:
        robot: the robot the plant simulates (the controller's: one model of the joints).
        name: what the plant is, in words (for summaries and records).
        limit_tolerance: per joint (nv,), rad or m: how far past a position limit the plant
            may measure a joint that its commands brought onto the limit (its lag and its
            limits' softness; :mod:`pinrate.control.measured`).
    """

    robot: Robot
    name: str
    limit_tolerance: np.ndarray

    @abstractmethod
    def reset(self, q: np.ndarray) -> Measurement:
        """Put the plant at ``q`` (nq,), at rest, its clock at 0."""

    @abstractmethod
    def advance(self, joint_rates: np.ndarray, duration: float) -> Measurement:
        """Command ``joint_rates`` (nv,, rad/s or m/s, velocity order) for ``duration`` s,
        then measure."""

    def check_command(self, joint_rates: object, duration: object) -> tuple[np.ndarray, float]:
        """``joint_rates`` as a float vector (nv,) of finite, physical numbers and
        ``duration`` as a positive number of seconds; InputError naming the argument otherwise."""
        rates = check_vector(joint_rates, self.robot.nv, "joint_rates", names=self.robot.joint_names)
        return rates, check_positive(duration, "duration")


__all__ = ["Measurement", "Plant"]
