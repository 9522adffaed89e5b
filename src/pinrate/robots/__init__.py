"""Robots by name: the papers' robots as parametric URDFs, example-robot-data's arms, and
:func:`load` for any URDF.

``pinrate.robots.NAME(**lengths)`` builds a papers' robot (see :mod:`.parametric` for each one's
frames and conventions); ``pinrate.robots.urdf(NAME, **lengths)`` returns its URDF text.
"""

from .catalog import EXAMPLE_ROBOTS, CatalogEntry, example_robot_data_share, example_robot_path
from .loading import known_names, load
from .parametric import (
    ROBOT_NAMES,
    barker_arm,
    build,
    cartesian,
    cylindrical,
    hirata_arh300,
    parameters,
    planar_polar,
    scara,
    spherical,
    spherical_6dof,
    two_link_planar,
    urdf,
    write_urdfs,
)

__all__ = [
    "EXAMPLE_ROBOTS",
    "ROBOT_NAMES",
    "CatalogEntry",
    "barker_arm",
    "build",
    "cartesian",
    "cylindrical",
    "example_robot_data_share",
    "example_robot_path",
    "hirata_arh300",
    "known_names",
    "load",
    "parameters",
    "planar_polar",
    "scara",
    "spherical",
    "spherical_6dof",
    "two_link_planar",
    "urdf",
    "write_urdfs",
]
