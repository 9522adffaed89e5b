"""The SRDF found for a description: beside it by stem, or in a MoveIt config package next to
its package (the layout of ROS description and ``*_moveit_config`` packages), for the robot
the URDF names."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import pinrate
from pinrate.robots.srdf_files import find_srdf, robot_name

PLANAR = """<?xml version="1.0"?>
<robot name="{name}">
  <link name="base"/>
  <joint name="shoulder" type="revolute"><parent link="base"/><child link="l1"/><axis xyz="0 0 1"/>
    <limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
  <link name="l1"/>
  <joint name="elbow" type="revolute"><parent link="l1"/><child link="l2"/><origin xyz="0.5 0 0"/><axis xyz="0 0 1"/>
    <limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
  <link name="l2"/>
  <joint name="tool" type="fixed"><parent link="l2"/><child link="tcp"/><origin xyz="0.4 0 0"/></joint>
  <link name="tcp"/>
</robot>
"""


def srdf(name: str, elbow: float) -> str:
    return (
        f'<?xml version="1.0"?>\n<robot name="{name}">'
        '<group name="arm"><chain base_link="base" tip_link="tcp"/></group><group_state name="home" group="arm">'
        f'<joint name="shoulder" value="0.2"/><joint name="elbow" value="{elbow}"/>'
        "</group_state></robot>"
    )


def ros_tree(root: Path, name: str = "planar") -> Path:
    """root/planar_description/{package.xml, urdf/planar.urdf}: the description package."""
    package = root / "planar_description"
    (package / "urdf").mkdir(parents=True)
    (package / "package.xml").write_text("<package><name>planar_description</name></package>", encoding="utf-8")
    urdf = package / "urdf" / "planar.urdf"
    urdf.write_text(PLANAR.format(name=name), encoding="utf-8")
    return urdf


def moveit_srdf(folder: Path, file_name: str, robot: str, elbow: float) -> Path:
    (folder / "config").mkdir(parents=True, exist_ok=True)
    path = folder / "config" / file_name
    path.write_text(srdf(robot, elbow), encoding="utf-8")
    return path


def test_the_moveit_config_beside_the_package_gives_the_home(tmp_path: Path) -> None:
    urdf = ros_tree(tmp_path)
    expected = moveit_srdf(tmp_path / "planar_moveit_config", "planar.srdf", "planar", 1.2)
    robot = pinrate.load(urdf)
    assert robot.srdf_path == expected
    assert robot.home_choice == "SRDF group_state 'home'"
    np.testing.assert_allclose(robot.home(), [0.2, 1.2])


def test_an_srdf_of_another_robot_is_passed_over(tmp_path: Path) -> None:
    urdf = ros_tree(tmp_path)
    moveit_srdf(tmp_path / "other_moveit_config", "other.srdf", "other_robot", 1.2)
    robot = pinrate.load(urdf)
    assert robot.srdf_path is None
    assert not robot.home_choice.startswith("SRDF")


def test_one_folder_down_and_the_robot_s_own_name_first(tmp_path: Path) -> None:
    urdf = ros_tree(tmp_path)
    # ROS-Industrial's layout: moveit_cfgs/<robot>_moveit_config; two SRDFs naming the robot.
    moveit_srdf(tmp_path / "moveit_cfgs" / "planar_moveit_config", "a_variant.srdf", "planar", 0.7)
    own = moveit_srdf(tmp_path / "moveit_cfgs" / "planar_moveit_config", "planar.srdf", "planar", 1.1)
    assert find_srdf(urdf, "planar") == own


def test_the_srdf_by_the_stem_wins(tmp_path: Path) -> None:
    urdf = ros_tree(tmp_path)
    moveit_srdf(tmp_path / "planar_moveit_config", "planar.srdf", "planar", 1.2)
    beside = urdf.with_suffix(".srdf")
    beside.write_text(srdf("planar", 0.9), encoding="utf-8")
    robot = pinrate.load(urdf)
    assert robot.srdf_path == beside
    np.testing.assert_allclose(robot.home(), [0.2, 0.9])


@pytest.mark.parametrize(
    ("text", "name"),
    [
        ('<?xml version="1.0"?>\n<!-- <robot name="comment"> -->\n<robot name="r1">', "comment"),
        ("<robot xmlns:xacro='http://www.ros.org/wiki/xacro' name='r2'>", "r2"),
        ("<robotx name='no'/>", None),
        ("", None),
    ],
)
def test_the_robot_name_is_read_from_the_first_robot_tag(text: str, name: str | None) -> None:
    # A commented-out tag counts (a cheap reader, no XML parse): the name then simply matches
    # no SRDF, and the search finds nothing, as for a file without a name.
    assert robot_name(text) == name


def test_outside_a_ros_package_no_neighbour_is_searched(tmp_path: Path) -> None:
    # A URDF in a plain folder: the MoveIt config of a package beside that folder is not its own.
    (tmp_path / "plain").mkdir()
    urdf = tmp_path / "plain" / "planar.urdf"
    urdf.write_text(PLANAR.format(name="planar"), encoding="utf-8")
    moveit_srdf(tmp_path / "planar_moveit_config", "planar.srdf", "planar", 1.2)
    moveit_srdf(tmp_path / "x" / "planar_moveit_config", "planar.srdf", "planar", 1.2)
    assert find_srdf(urdf, "planar") is None
