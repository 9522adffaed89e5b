"""pinrate: resolved-rate motion control for any URDF manipulator.

Sensor-frame Jacobians (Shoham & Koren 1987, eq. 1-16), the arm/wrist partition (eq. 19),
the motion control algorithms MCA1/MCA2/MCA3 (eq. 23-54) and their convergence Theorem,
and a closed-loop servo, all on Pinocchio. The public API is listed in ``__all__``; the
subpackages, bottom to top: ``kinematics``, ``robots`` and ``solvers``, ``theorem``,
``control``, ``viewer`` and ``analysis``, ``teleop``, ``papers``, ``cli``.

The names are imported on first use (PEP 562), so ``import pinrate`` and the command line
start without loading Pinocchio until they need it.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

__version__ = "0.2.0.dev0"
"""pinrate's version (PEP 440): pyproject.toml reads it here; core/pyproject.toml repeats it."""

# Public name -> the subpackage that defines it.
_SOURCES = {
    "ALGORITHMS": "solvers",
    "Controller": "control",
    "Convergence": "theorem",
    "ConvergenceSample": "theorem",
    "FrameError": "errors",
    "InputError": "errors",
    "JointJog": "control",
    "LoadError": "errors",
    "Partition": "kinematics",
    "PinrateError": "errors",
    "PoseGoal": "control",
    "Robot": "kinematics",
    "SingularBlockError": "errors",
    "Status": "control",
    "Step": "control",
    "Teleop": "teleop",
    "Trajectory": "control",
    "Uncoupled": "control",
    "backend": "compiled",
    "convergence": "theorem",
    "joint_rates": "solvers",
    "load": "robots",
    "sample_convergence": "theorem",
    "servo": "control",
}

__all__ = [
    "ALGORITHMS",
    "Controller",
    "Convergence",
    "ConvergenceSample",
    "FrameError",
    "InputError",
    "JointJog",
    "LoadError",
    "Partition",
    "PinrateError",
    "PoseGoal",
    "Robot",
    "SingularBlockError",
    "Status",
    "Step",
    "Teleop",
    "Trajectory",
    "Uncoupled",
    "__version__",
    "backend",
    "convergence",
    "joint_rates",
    "load",
    "robots",
    "sample_convergence",
    "servo",
]

if TYPE_CHECKING:
    from . import robots
    from .compiled import backend
    from .control import Controller, JointJog, PoseGoal, Status, Step, Trajectory, Uncoupled, servo
    from .errors import FrameError, InputError, LoadError, PinrateError, SingularBlockError
    from .kinematics import Partition, Robot
    from .robots import load
    from .solvers import ALGORITHMS, joint_rates
    from .teleop import Teleop
    from .theorem import Convergence, ConvergenceSample, convergence, sample_convergence


def __getattr__(name: str) -> Any:
    source = _SOURCES.get(name)
    if source is None:
        if name == "robots":
            return importlib.import_module(".robots", __name__)
        raise AttributeError(f"module 'pinrate' has no attribute {name!r}")
    value = getattr(importlib.import_module(f".{source}", __name__), name)
    globals()[name] = value  # later lookups skip this function
    return value


def __dir__() -> list[str]:
    return sorted({*globals(), *__all__})
