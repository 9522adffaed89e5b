"""``pinrate list``: every robot name pinrate can load, the papers' robots first, then
example-robot-data's arms. Importing this module loads numpy and Pinocchio (the robots)."""

from __future__ import annotations

import argparse

from .. import robots
from ..robots import EXAMPLE_ROBOTS, ROBOT_NAMES, example_robot_data_share


def list_robots(_: argparse.Namespace) -> int:
    """``pinrate list``: the names, one a line, each with its one-line summary."""
    print("The papers' robots (pinrate.robots, urdf/):")
    for name in ROBOT_NAMES:
        summary_line = (getattr(robots, name).__doc__ or "").strip().splitlines()[0]
        print(f"  {name:<16} {summary_line}")
    available = example_robot_data_share() is not None
    note = "" if available else "  (example-robot-data not installed)"
    print(f"example-robot-data arms:{note}")
    for entry in EXAMPLE_ROBOTS.values():
        print(f"  {entry.name:<8} tip {entry.tip:<24} {entry.description}")
    print("Any other URDF: pass its path.")
    return 0
