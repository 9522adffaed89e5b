"""Mesh file names resolved and confined to the URDF's folders (pinrate.kinematics.urdf_meshes):
the file name rewritten is the one urdfdom reads, and nothing else of the text changes."""

from __future__ import annotations

import os
from pathlib import Path

from pinrate.kinematics.urdf_meshes import confine_meshes, mesh_roots


def test_the_name_rewritten_is_the_one_urdfdom_reads_and_the_rest_is_kept(tmp_path: Path) -> None:
    (tmp_path / "ok.stl").write_text("solid t\nendsolid t\n", encoding="ascii")
    real = os.path.realpath(tmp_path / "ok.stl")
    # A decoy attribute holding ` filename='...'` in its value, an entity, a comment that looks
    # like a mesh, and a <mesh> where urdfdom reads none (under <robot>'s <material>).
    text = (
        '<robot name="r &amp; co">\n  <!-- <mesh filename="/etc/passwd"/> -->\n'
        '  <material name="m"><mesh filename="/etc/group"/></material>\n'
        '  <link name="a"><visual><geometry><mesh decoy=" filename=\'/etc/hosts\'"\n'
        '     filename = "ok.stl" scale="1 1 1"/></geometry></visual>\n'
        '  <collision><geometry><mesh filename="/etc/hosts"/></geometry></collision></link>\n</robot>'
    )
    confined, skipped = confine_meshes(text, [str(tmp_path)], mesh_roots([str(tmp_path), "/"]))
    assert skipped == ["/etc/hosts (outside the URDF's folder and the package folders)"]
    expected = text.replace('filename = "ok.stl"', f'filename = "{real}"').replace(
        '  <collision><geometry><mesh filename="/etc/hosts"/></geometry></collision>', "  "
    )
    assert confined == expected
