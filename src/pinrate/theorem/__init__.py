"""The convergence Theorem of Shoham & Koren (1987, §4): at one configuration
(:func:`convergence`) and over the work volume (:func:`sample_convergence`,
:func:`spectral_radius_at`)."""

from .pointwise import Convergence, convergence, convergence_from_blocks, coupling_along
from .sampling import ConvergenceSample, sample_convergence, spectral_radius_at, wilson_interval

__all__ = [
    "Convergence",
    "ConvergenceSample",
    "convergence",
    "convergence_from_blocks",
    "coupling_along",
    "sample_convergence",
    "spectral_radius_at",
    "wilson_interval",
]
