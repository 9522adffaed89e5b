"""The viewer's mesh loading (pinrate.viewer.visualizer, pinrate.viewer.collada): a Collada
file whose textures lie outside its folder is not drawn, and those textures are not read
(Pinocchio's DaeMeshGeometry would put their bytes into the scene and every replay)."""

from __future__ import annotations

import base64
import sys
import warnings
from pathlib import Path

import pytest

import pinrate
from pinrate.viewer import Viewer
from support import files_opened_in

pytestmark = pytest.mark.skipif(not sys.platform.startswith("linux"), reason="inotify: Linux")

COLLADA = """<?xml version="1.0" encoding="utf-8"?>
<COLLADA xmlns="http://www.collada.org/2005/11/COLLADASchema" version="1.4.1">
  <library_images>{images}</library_images>
  <library_geometries><geometry id="g" name="g"><mesh>
    <source id="g-positions"><float_array id="g-positions-array" count="9">0 0 0 0.1 0 0 0 0.1 0</float_array>
      <technique_common><accessor source="#g-positions-array" count="3" stride="3">
        <param name="X" type="float"/><param name="Y" type="float"/><param name="Z" type="float"/>
      </accessor></technique_common></source>
    <vertices id="g-vertices"><input semantic="POSITION" source="#g-positions"/></vertices>
    <triangles count="1"><input semantic="VERTEX" source="#g-vertices" offset="0"/><p>0 1 2</p></triangles>
  </mesh></geometry></library_geometries>
  <library_visual_scenes><visual_scene id="s"><node id="n"><instance_geometry url="#g"/></node></visual_scene>
  </library_visual_scenes>
  <scene><instance_visual_scene url="#s"/></scene>
</COLLADA>
"""

URDF = """<robot name="r">
<link name="base"><visual><geometry><mesh filename="meshes/inside.dae"/></geometry></visual></link>
<link name="arm"><visual><geometry><mesh filename="meshes/outside.dae"/></geometry></visual></link>
<link name="hand"/>
<joint name="j" type="revolute"><parent link="base"/><child link="arm"/><axis xyz="0 0 1"/>
  <limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
<joint name="k" type="revolute"><parent link="arm"/><child link="hand"/><origin xyz="0.3 0 0"/><axis xyz="0 0 1"/>
  <limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
</robot>
"""


def image(name: str) -> str:
    return f'<image id="{name}-id"><init_from>{name}</init_from></image>'


def test_a_collada_mesh_with_textures_outside_its_folder_is_not_drawn(tmp_path: Path) -> None:
    secret = tmp_path / "secret"
    secret.mkdir()
    (secret / "texture.png").write_bytes(b"pinrate's secret texture")
    meshes = tmp_path / "robot" / "meshes"
    meshes.mkdir(parents=True)
    (meshes / "skin.png").write_bytes(b"pinrate's own texture")
    (meshes / "inside.dae").write_text(COLLADA.format(images=image("skin.png")), encoding="utf-8")
    outside = ["../../secret/texture.png", str(secret / "texture.png")]
    (meshes / "outside.dae").write_text(COLLADA.format(images="".join(map(image, outside))), encoding="utf-8")
    (tmp_path / "robot" / "r.urdf").write_text(URDF, encoding="utf-8")

    with files_opened_in(secret) as opened, warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        robot = pinrate.load(tmp_path / "robot" / "r.urdf")
        viewer = Viewer(robot, offline=True)
    assert opened == [], "a texture outside the mesh's folder was read"
    scene = b"".join(viewer.scene.packed())  # a texture is sent as a base64 data URL
    assert base64.b64encode(b"pinrate's secret texture") not in scene
    assert base64.b64encode(b"pinrate's own texture") in scene
    messages = [str(warning.message) for warning in caught if "not drawn" in str(warning.message)]
    assert len(messages) == 1 and "outside.dae" in messages[0]
    assert f"its textures lie outside its folder: {', '.join(outside)}" in messages[0]
    # The other file and its own texture are drawn; the link without a drawn mesh gets its skeleton.
    drawn = {geometry.name for geometry in robot.visual_model.geometryObjects} & viewer._visualizer.drawn
    assert drawn == {robot.visual_model.geometryObjects[0].name}
