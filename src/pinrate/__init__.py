"""pinrate: resolved-rate motion control for any URDF manipulator.

Sensor-frame Jacobians (Shoham & Koren 1987, eq. 1-16), the arm/wrist partition (eq. 19),
the motion control algorithms MCA1/MCA2/MCA3 (eq. 23-54) and their convergence Theorem,
and a closed-loop servo, all on Pinocchio. The public API is listed in ``__all__``; the
subpackages, bottom to top: ``kinematics``, ``robots`` and ``solvers``, ``theorem``,
``control``, ``viewer`` and ``analysis``, ``papers``, ``cli``.
"""

from . import robots
from .control import Trajectory, servo
from .errors import FrameError, InputError, LoadError, PinrateError, SingularBlockError
from .kinematics import Partition, Robot
from .robots import load
from .solvers import ALGORITHMS, joint_rates
from .theorem import Convergence, ConvergenceSample, convergence, sample_convergence

__version__ = "0.2.0.dev0"

__all__ = [
    "ALGORITHMS",
    "Convergence",
    "ConvergenceSample",
    "FrameError",
    "InputError",
    "LoadError",
    "Partition",
    "PinrateError",
    "Robot",
    "SingularBlockError",
    "Trajectory",
    "__version__",
    "convergence",
    "joint_rates",
    "load",
    "robots",
    "sample_convergence",
    "servo",
]
