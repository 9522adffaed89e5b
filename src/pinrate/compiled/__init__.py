"""The optional compiled core (``pinrate_core``, built from ``core/``): which path runs, and
the bridges from pinrate's objects to the core's.

:func:`backend` says which path runs and why. The core is used automatically where it is
importable and supports the configuration; ``PINRATE_BACKEND=python`` (or :func:`use`)
keeps everything on the pure-Python path.
"""

from __future__ import annotations

from .core import Backend, backend, chosen, core_module, use
from .kinematics import core_kinematics
from .servo import CoreServo, ServoSettings, core_servo, rho_map

__all__ = [
    "Backend",
    "CoreServo",
    "ServoSettings",
    "backend",
    "chosen",
    "core_kinematics",
    "core_module",
    "core_servo",
    "rho_map",
    "use",
]
