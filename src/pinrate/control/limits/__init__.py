"""The limits a control step meets after its rates are solved, each a module: position
limits (joints held at a limit while the others serve the command, then the clamp),
velocity limits (one scale factor), acceleration limits (a blend from the last rates). The
self-collision monitor (:mod:`pinrate.control.collision`) comes after them in the step."""

from .acceleration import AccelerationLimits
from .position import PositionLimits
from .velocity import VelocityLimits, per_joint

__all__ = ["AccelerationLimits", "PositionLimits", "VelocityLimits", "per_joint"]
