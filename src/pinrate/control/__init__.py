"""Control: one step (:class:`Controller`) and the loops built on it (:func:`servo`)."""

from .controller import Controller, Observation, PoseGoal, Step
from .servo_loop import servo
from .status import Status
from .trajectory import Trajectory

__all__ = ["Controller", "Observation", "PoseGoal", "Status", "Step", "Trajectory", "servo"]
