"""Convergence analysis of any robot: what a designer asks of the Theorem (S&K §4-5).

Block structure, independent joints, the converging share of the work volume, region maps,
design sweeps and parameter limits, and the ``pinrate analyze`` report with its PNGs.
"""

from .design import (
    GridCheck,
    grid_check,
    independent_joints,
    largest_parameter,
    smallest_parameter,
    worst_spectral_radius,
)
from .regions import RegionMap, default_map_joints, joint_sensitivity, region_map, tcp_positions
from .report import Report, analyze, write_report
from .structure import BlockStructure, block_structure
from .sweeps import Sweep, parse_sweep, sweep

__all__ = [
    "BlockStructure",
    "GridCheck",
    "RegionMap",
    "Report",
    "Sweep",
    "analyze",
    "block_structure",
    "default_map_joints",
    "grid_check",
    "independent_joints",
    "joint_sensitivity",
    "largest_parameter",
    "parse_sweep",
    "region_map",
    "smallest_parameter",
    "sweep",
    "tcp_positions",
    "worst_spectral_radius",
    "write_report",
]
