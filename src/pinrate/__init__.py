"""pinrate: resolved-rate motion control for any URDF manipulator.

Sensor-frame Jacobians (Shoham & Koren 1987, eq. 1-16), the arm/wrist partition (eq. 19),
the motion control algorithms MCA1/MCA2/MCA3 (eq. 23-54) and their convergence Theorem,
and a closed-loop servo, all on Pinocchio. The public API is listed in ``__all__``.
"""

from . import robots
from .algorithms import ALGORITHMS, joint_rates
from .convergence import Convergence, ConvergenceSample, convergence, sample_convergence
from .errors import FrameError, InputError, LoadError, PinrateError, SingularBlockError
from .partition import Partition
from .robot import Robot, load
from .servo import Trajectory, servo

__version__ = "0.1.0"

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
