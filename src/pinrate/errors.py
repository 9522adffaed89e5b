"""The exceptions pinrate raises on purpose.

Every error derives from :class:`PinrateError`, so ``except pinrate.PinrateError`` catches
anything pinrate refuses to do. Messages name the offending thing (file, frame, joint,
robot name) and, where there is a list of valid choices, list them.
"""

from __future__ import annotations

import difflib
from collections.abc import Iterable

import numpy as np


class PinrateError(Exception):
    """Root of every error pinrate raises on purpose."""


class InputError(PinrateError, ValueError):
    """Wrong shapes or lengths, NaN/inf in inputs, unknown axis letters, bad partitions."""


class LoadError(PinrateError):
    """A robot could not be loaded: missing file, malformed XML, not a URDF, unknown name."""


class FrameError(PinrateError, KeyError):
    """A frame name (tip or sensor) that the model does not have."""

    def __str__(self) -> str:  # KeyError would quote the message
        return str(self.args[0]) if self.args else ""


class SingularBlockError(PinrateError):
    """A Jacobian block that must be inverted is singular at the given configuration."""

    def __init__(self, message: str, *, block: str = "", q: object = None) -> None:
        super().__init__(message)
        self.block = block
        self.q = q

    def at(self, robot_name: str, q: object, detail: str = "") -> SingularBlockError:
        """The same error, its message completed with the robot and the configuration."""
        where = np.array2string(np.asarray(q), precision=4)
        return SingularBlockError(f"{self} for robot {robot_name!r}{detail} at q = {where}", block=self.block, q=q)


class ViewerError(PinrateError):
    """The Meshcat server could not be started or reached."""


class SchedulerError(PinrateError):
    """A Dask scheduler could not be reached."""


class PlantError(PinrateError):
    """A simulated plant could not be built or run: what the robot's model lacks for the
    simulator (an inertia, a joint kind), or the simulator is not installed; the message says
    which and how to repair it."""


class UnsupportedByCoreError(PinrateError):
    """The compiled core does not cover a robot or configuration; the message says why. The
    loops catch it and run on the Python path, which covers everything."""


def choices_hint(name: str, valid: Iterable[str], *, limit: int = 40) -> str:
    """A ' Did you mean …? Known: …' suffix listing the closest or all valid names."""
    valid = list(valid)
    close = difflib.get_close_matches(str(name), valid, n=5, cutoff=0.5)
    hint = f" Did you mean {', '.join(repr(c) for c in close)}?" if close else ""
    shown = valid if len(valid) <= limit else [*valid[:limit], f"... ({len(valid) - limit} more)"]
    return f"{hint} Known: {', '.join(shown)}."
