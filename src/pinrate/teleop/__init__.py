"""Teleoperation, Barker's operator: stick deflections -> a twist in the hand frame -> one
controller step per tick, with a dead man and the way back (:class:`Teleop`); keyboard and
gamepad mappings (:mod:`.mapping`); recorded runs (:class:`Recording`).

The browser console on top (``pinrate teleop``) is :mod:`pinrate.teleop.server`, imported
only when asked for: it is the part that needs meshcat and tornado.
"""

from .recording import Recording
from .session import FRAMES, Teleop

__all__ = ["FRAMES", "Recording", "Teleop"]
