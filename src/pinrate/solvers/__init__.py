"""Twist -> joint rates, and the Theorem's block algebra: pure functions over matrices.

Three forms of the same mathematics, checked against each other by the tests:
:mod:`.reference` (numpy, any block shape), :mod:`.closed_form` (Python floats, square
blocks of size 1 to 3: the control loop's hot path) and :mod:`.batched` (numpy stacks: the
work-volume maps). One singularity rule (:mod:`.singular`), one eigenvalue routine
(:mod:`.eigen`), one algorithm table (:mod:`.registry`).
"""

from .rates import joint_rates, partition_rates, partition_spectral_radius
from .registry import ALGORITHMS, REGISTRY, Algorithm, check_algorithm
from .singular import SINGULAR_RATIO, hadamard_ratio

__all__ = [
    "ALGORITHMS",
    "REGISTRY",
    "SINGULAR_RATIO",
    "Algorithm",
    "check_algorithm",
    "hadamard_ratio",
    "joint_rates",
    "partition_rates",
    "partition_spectral_radius",
]
