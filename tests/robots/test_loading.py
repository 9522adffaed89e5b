"""``pinrate.load`` (pinrate.robots.loading): the frames it is asked for, and the mesh files
it reads, only from the URDF's folders (pinrate.kinematics.urdf_meshes)."""

from __future__ import annotations

import os
import sys
import warnings
from pathlib import Path

import pytest

import pinrate
from pinrate.viewer import Viewer
from support import TRIANGLE_STL, files_opened_in, python_opens

pytestmark = pytest.mark.skipif(not sys.platform.startswith("linux"), reason="inotify: Linux")


URDF = """<robot name="r">
<link name="base"><visual><geometry><mesh filename="meshes/base.stl"/></geometry></visual></link>
<link name="arm">
  <visual><geometry><mesh filename="{absolute}"/></geometry></visual>
  <collision><geometry><mesh filename="meshes/link.stl"/></geometry></collision>
  <visual><geometry><mesh filename="{passwd}"/></geometry></visual>
  <collision><geometry><mesh filename="file:///etc/shadow"/></geometry></collision>
  <visual><geometry><mesh filename="package://pkg/meshes/arm.stl"/></geometry></visual>
  <collision><geometry><mesh scale="1 1 1" filename="package://pkg/meshes/arm.stl"/></geometry></collision>
</link>
<link name="hand"/>
<joint name="j" type="revolute"><parent link="base"/><child link="arm"/><axis xyz="0 0 1"/>
  <limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
<joint name="k" type="revolute"><parent link="arm"/><child link="hand"/><origin xyz="0.3 0 0"/><axis xyz="0 0 1"/>
  <limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
</robot>
"""


def test_meshes_are_read_only_inside_the_urdfs_folders(tmp_path: Path) -> None:
    # The URDF in ws/pkg/urdf: its folder and three ancestors (up to tmp/a) are the roots; a
    # secret beside them, /etc/passwd and /etc/shadow are outside.
    secret = tmp_path / "secret"
    secret.mkdir()
    (secret / "secret.stl").write_text(TRIANGLE_STL, encoding="ascii")
    package = tmp_path / "a" / "ws" / "pkg"
    (package / "urdf" / "meshes").mkdir(parents=True)
    (package / "meshes").mkdir()
    (package / "urdf" / "meshes" / "base.stl").write_text(TRIANGLE_STL, encoding="ascii")
    (package / "meshes" / "arm.stl").write_text(TRIANGLE_STL, encoding="ascii")
    os.symlink(secret / "secret.stl", package / "urdf" / "meshes" / "link.stl")  # inside, pointing out
    passwd = "package://" + "../" * 40 + "etc/passwd"
    absolute = str(secret / "secret.stl")
    urdf = package / "urdf" / "r.urdf"
    urdf.write_text(URDF.format(passwd=passwd, absolute=absolute), encoding="utf-8")

    with files_opened_in(secret) as opened, python_opens() as by_python, warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        robot = pinrate.load(urdf)
        visuals = [geometry.meshPath for geometry in robot.visual_model.geometryObjects]
        collisions = [geometry.meshPath for geometry in robot.collision_model.geometryObjects]
        Viewer(robot, offline=True)  # the viewer reads the mesh files again, in Python
    assert opened == [], "a file outside the URDF's folders was opened"
    assert not {"/etc/passwd", "/etc/shadow", absolute} & {os.path.realpath(path) for path in by_python}
    # The robot loads with the meshes inside, each by its own real path.
    inside = str(package / "meshes" / "arm.stl")
    assert visuals == [str(package / "urdf" / "meshes" / "base.stl"), inside] and collisions == [inside]
    # One warning names every mesh left out.
    messages = [str(warning.message) for warning in caught if "left out" in str(warning.message)]
    assert len(messages) == 1, [str(warning.message) for warning in caught]
    for uri in (passwd, "file:///etc/shadow", absolute, "meshes/link.stl"):
        assert f"{uri} (outside the URDF's folder and the package folders)" in messages[0]
    assert "4 meshes left out" in messages[0]


def test_an_empty_frame_name_is_refused_not_read_as_the_default() -> None:
    with pytest.raises(pinrate.InputError, match="tip must name a frame"):
        pinrate.load("ur5", tip="")
    with pytest.raises(pinrate.InputError, match="sensor must name a frame"):
        pinrate.load("scara", sensor=" ")
