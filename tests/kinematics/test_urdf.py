"""Loading what Pinocchio loads: namespaced XML, foreign prefixes, extra package folders
(pinrate.kinematics.urdf, pinrate.robots.loading)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import pinrate
from support import TRIANGLE_STL

PLAIN = """<robot name="two">
<link name="a"/><link name="b"/><link name="c"/>
<joint name="j1" type="revolute"><parent link="a"/><child link="b"/><axis xyz="0 0 1"/>
<limit lower="-2" upper="2" effort="1" velocity="1"/></joint>
<joint name="j2" type="revolute"><parent link="b"/><child link="c"/><origin xyz="0.4 0 0"/><axis xyz="0 1 0"/>
<limit lower="-2" upper="2" effort="1" velocity="1"/></joint>
</robot>"""


@pytest.mark.parametrize(
    "dialect",
    [
        # a default namespace on <robot> (urdfdom's tinyxml2 ignores namespaces)
        lambda text: text.replace('<robot name="two">', '<robot name="two" xmlns="http://www.ros.org">'),
        # Drake's extension elements and attributes, with their prefix declared
        lambda text: (
            text.replace('<robot name="two">', '<robot name="two" xmlns:drake="http://drake.mit.edu">')
            .replace('<link name="a"/>', '<link name="a" drake:colour="red"/>')
            .replace("</robot>", '<drake:collision_filter_group name="g"/></robot>')
        ),
        # the same prefix never declared: malformed for a namespace-aware parser, fine for urdfdom
        lambda text: text.replace('<link name="a"/>', '<link name="a" drake:colour="red"/>').replace(
            '<axis xyz="0 0 1"/>', '<axis xyz="0 0 1"/><drake:acceleration lower="-1" upper="1"/>'
        ),
    ],
    ids=["default namespace", "declared drake prefix", "undeclared drake prefix"],
)
def test_namespaced_and_foreign_xml_loads_as_pinocchio_reads_it(tmp_path: Path, dialect) -> None:
    plain_path, dialect_path = tmp_path / "plain.urdf", tmp_path / "dialect.urdf"
    plain_path.write_text(PLAIN, encoding="utf-8")
    dialect_path.write_text(dialect(PLAIN), encoding="utf-8")
    plain, other = pinrate.load(plain_path), pinrate.load(dialect_path)
    assert other.joint_names == ("j1", "j2") and other.tip == plain.tip == "c"
    q = np.array([0.3, -0.7])
    np.testing.assert_array_equal(other.jacobian(q), plain.jacobian(q))


def test_structure_checks_still_see_a_namespaced_file(tmp_path: Path) -> None:
    broken = PLAIN.replace('<robot name="two">', '<robot name="two" xmlns="http://www.ros.org">').replace(
        '<child link="c"/>', '<child link="zz"/>'
    )
    path = tmp_path / "broken.urdf"
    path.write_text(broken, encoding="utf-8")
    with pytest.raises(pinrate.LoadError, match="child link 'zz' is not defined"):
        pinrate.load(path)


def test_package_dirs_resolve_package_uris_outside_the_urdfs_folders(tmp_path: Path) -> None:
    meshes = tmp_path / "elsewhere" / "mypkg" / "meshes"
    meshes.mkdir(parents=True)
    (meshes / "tri.stl").write_text(TRIANGLE_STL, encoding="ascii")
    (tmp_path / "robot").mkdir()
    path = tmp_path / "robot" / "arm.urdf"
    path.write_text(
        PLAIN.replace(
            '<link name="c"/>',
            '<link name="c"><visual><geometry><mesh filename="package://mypkg/meshes/tri.stl"/></geometry></visual></link>',
        ),
        encoding="utf-8",
    )
    assert pinrate.load(path, package_dirs=[tmp_path / "elsewhere"]).visual_model.ngeoms == 1
    with pytest.warns(UserWarning, match=r"package://mypkg/meshes/tri.stl \(not found\)"):
        assert pinrate.load(path).visual_model.ngeoms == 0
    with pytest.raises(pinrate.InputError, match="is not a folder"):
        pinrate.load(path, package_dirs=[tmp_path / "missing"])
