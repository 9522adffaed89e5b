"""Control: one step (:class:`Controller`) and the loops built on it (:func:`servo`)."""

from .commands import JointJog, PoseGoal, Uncoupled
from .controller import Controller, Observation, Step
from .recorder import Playback, Recorder
from .servo_loop import servo
from .status import Status
from .trajectory import PlantRecord, Trajectory

__all__ = [
    "Controller",
    "JointJog",
    "Observation",
    "PlantRecord",
    "Playback",
    "PoseGoal",
    "Recorder",
    "Status",
    "Step",
    "Trajectory",
    "Uncoupled",
    "servo",
]
