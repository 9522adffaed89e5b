"""Collada visuals as the browser's three.js draws them: every material group of every mesh.

meshcat 0.3.2's viewer merges the three.js Meshes ColladaLoader builds from a
``_meshfile_object`` Collada file into one geometry (``merge_geometries``): group i draws
with entry i of the merged material list, which is the i-th Mesh's material. A Collada
``<mesh>`` with several primitives (``<triangles>`` elements, one per material) gives its
Mesh a material *list*, so entry i is a list, and three.js's renderer skips a group whose
entry is not a Material (``groupMaterial.visible`` is undefined). The rule checked on what
pinrate sends: a Collada file that makes more than one Mesh makes each with one primitive,
and every triangle of the file is still there with its material. The reference reading of
the files below is written here, from the Collada format, not from pinrate's rewrite.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from collections import defaultdict
from pathlib import Path

import numpy as np
import pytest
import umsgpack

import pinrate
from pinrate.robots import example_robot_path
from pinrate.viewer import Viewer
from pinrate.viewer.collada import one_material_per_mesh

MESH_PRIMITIVES = ("triangles", "polylist")
"""The primitives ColladaLoader turns into a Mesh, one Mesh per kind and ``<mesh>``."""


def parse(text: str) -> tuple[ET.Element, dict[str, ET.Element]]:
    """The document with namespaces dropped from tags, and its elements by id."""
    root = ET.fromstring(text)
    for element in root.iter():
        element.tag = element.tag.rsplit("}", 1)[-1]
    return root, {element.get("id"): element for element in root.iter() if element.get("id")}


def instances(root: ET.Element) -> list[tuple[ET.Element, ET.Element]]:
    """(node, instance_geometry) for every geometry instanced in the file."""
    return [(node, instance) for node in root.iter("node") for instance in node.findall("instance_geometry")]


def rows(source: ET.Element, ids: dict[str, ET.Element]) -> np.ndarray:
    """A <source>'s elements as an (count, stride) array."""
    accessor = source.find("technique_common/accessor")
    array = ids[accessor.get("source")[1:]]
    values = np.array(array.text.split(), dtype=float)
    count, stride, offset = (
        int(accessor.get(key, default)) for key, default in (("count", 0), ("stride", 1), ("offset", 0))
    )
    return values[offset : offset + count * stride].reshape(count, stride)


def corner_triangles(primitive: ET.Element, ids: dict[str, ET.Element]) -> np.ndarray:
    """(triangles, 3 * attributes) of a triangles or polylist primitive: each corner's
    position, normal, ... (inputs sorted by semantic), polygons fanned from their first corner."""
    inputs = sorted(primitive.findall("input"), key=lambda element: (element.get("semantic"), element.get("set", "")))
    stride = 1 + max(int(element.get("offset")) for element in inputs)
    indices = np.array(primitive.find("p").text.split(), dtype=int).reshape(-1, stride)
    columns = []
    for element in inputs:
        offset, source = int(element.get("offset")), ids[element.get("source")[1:]]
        if source.tag == "vertices":
            for vertex_input in sorted(source.findall("input"), key=lambda item: item.get("semantic")):
                columns.append(rows(ids[vertex_input.get("source")[1:]], ids)[indices[:, offset]])
        else:
            columns.append(rows(source, ids)[indices[:, offset]])
    corners = np.hstack(columns)
    if primitive.tag == "polylist":
        counts = np.array(primitive.find("vcount").text.split(), dtype=int)
        starts = np.concatenate([[0], np.cumsum(counts)[:-1]])
        fans = [
            (start, start + k, start + k + 1) for start, n in zip(starts, counts, strict=True) for k in range(1, n - 1)
        ]
        corners = corners[np.array(fans).ravel()]
    return corners.reshape(-1, 3 * corners.shape[1])


def triangles_by_material(text: str) -> dict[tuple[str, str], np.ndarray]:
    """(node id, bound material) -> every triangle of the geometries that node instances,
    rows sorted (the order of primitives and vertices is free, their content is not)."""
    root, ids = parse(text)
    found = defaultdict(list)
    for node, instance in instances(root):
        bindings = {bound.get("symbol"): bound.get("target") for bound in instance.iter("instance_material")}
        mesh = ids[instance.get("url")[1:]].find("mesh")
        for primitive in mesh:
            if primitive.tag in MESH_PRIMITIVES:
                material = bindings.get(primitive.get("material"), primitive.get("material"))
                found[node.get("id") or node.get("name"), material].append(corner_triangles(primitive, ids))
    result = {}
    for key, parts in found.items():
        triangles = np.vstack(parts)
        result[key] = triangles[np.lexsort(triangles.T[::-1])]
    return result


def three_js_meshes(text: str) -> list[int]:
    """The number of primitives (materials) of each Mesh ColladaLoader builds from the file."""
    root, ids = parse(text)
    meshes = []
    for _, instance in instances(root):
        mesh = ids[instance.get("url")[1:]].find("mesh")
        for kind in MESH_PRIMITIVES:
            count = sum(1 for primitive in mesh if primitive.tag == kind)
            if count:
                meshes.append(count)
    return meshes


def every_group_is_drawn(text: str) -> bool:
    """merge_geometries' material list is flat: one Mesh, or every Mesh with one material."""
    meshes = three_js_meshes(text)
    return len(meshes) <= 1 or all(count == 1 for count in meshes)


def sent_objects(viewer: Viewer) -> dict[str, dict]:
    """Meshcat path -> the ``object`` of its set_object command, as the page receives it."""
    commands = [umsgpack.unpackb(packed) for packed in viewer.scene.packed()]
    return {command["path"]: command["object"] for command in commands if command["type"] == "set_object"}


def ur5_meshes() -> list[Path]:
    return [Path(geometry.meshPath) for geometry in pinrate.load("ur5").visual_model.geometryObjects]


@pytest.fixture(scope="module")
def ur5_scene():
    robot = pinrate.load("ur5")
    return robot, sent_objects(Viewer(robot, offline=True))


def test_the_ur5_files_are_what_the_bug_needs() -> None:
    # The premise: several UR5 visuals hold a multi-material mesh beside others (the
    # shoulder, the upper arm, both wrists), which three.js drew without their housings.
    assert sum(not every_group_is_drawn(path.read_text()) for path in ur5_meshes()) >= 3


def test_every_mesh_pinrate_sends_for_the_ur5_is_drawn_whole(ur5_scene) -> None:
    robot, objects = ur5_scene
    for geometry in robot.visual_model.geometryObjects:
        sent = objects[f"/meshcat/pinrate/visuals/{geometry.name}"]["object"]
        assert (sent["type"], sent["format"]) == ("_meshfile_object", "dae")
        assert every_group_is_drawn(sent["data"]), f"{geometry.name}: a group would reference a material list"
        original = triangles_by_material(Path(geometry.meshPath).read_text())
        rewritten = triangles_by_material(sent["data"])
        assert rewritten.keys() == original.keys(), geometry.name
        for key, triangles in original.items():
            np.testing.assert_array_equal(rewritten[key], triangles, err_msg=f"{geometry.name} {key}")


def test_every_other_object_names_one_material(ur5_scene) -> None:
    # Markers, paths, the hand axes: a three.js Mesh or Line with one material by uuid.
    _, objects = ur5_scene
    for path, sent in objects.items():
        if sent["object"]["type"] == "_meshfile_object":
            continue
        materials = {material["uuid"] for material in sent["materials"]}
        assert isinstance(sent["object"]["material"], str) and sent["object"]["material"] in materials, path


@pytest.mark.parametrize(
    "path",
    [
        *ur5_meshes(),
        example_robot_path("panda_description/meshes/visual/link6.dae"),
        example_robot_path("hector_description/meshes/quadrotor/quadrotor_base.dae"),  # polylists
        example_robot_path("icub_description/meshes/upmc/visual/icub_l_hand.dae"),
    ],
    ids=lambda path: path.name,
)
def test_the_rewrite_keeps_every_triangle_with_its_material(path: Path) -> None:
    text = path.read_text()
    rewritten = one_material_per_mesh(text)
    assert every_group_is_drawn(rewritten)
    assert all(count == 1 for count in three_js_meshes(rewritten))
    original, kept = triangles_by_material(text), triangles_by_material(rewritten)
    assert kept.keys() == original.keys()
    for key, triangles in original.items():
        np.testing.assert_array_equal(kept[key], triangles, err_msg=str(key))
    _, ids = parse(rewritten)
    assert len(ids) == len({element.get("id") for element in ET.fromstring(rewritten).iter() if element.get("id")})


def test_a_file_with_nothing_to_split_is_sent_as_it_is() -> None:
    text = example_robot_path("ur_description/meshes/ur5/visual/forearm.dae").read_text()
    assert all(count == 1 for count in three_js_meshes(text))  # four meshes, one material each
    assert one_material_per_mesh(text) == text


@pytest.mark.parametrize(
    "text",
    ["not xml", "<robot/>", '<COLLADA><library_geometries><geometry id="g"><mesh>'],
    ids=["not-xml", "not-collada", "truncated"],
)
def test_what_is_not_collada_is_refused(text: str) -> None:
    with pytest.raises(pinrate.PinrateError, match="Collada"):
        one_material_per_mesh(text)


def test_a_mesh_referring_to_a_missing_source_is_refused() -> None:
    text = """<COLLADA xmlns="http://www.collada.org/2005/11/COLLADASchema" version="1.4.1">
      <library_geometries><geometry id="g"><mesh>
        <vertices id="v"><input semantic="POSITION" source="#nowhere"/></vertices>
        <triangles material="a" count="1"><input semantic="VERTEX" source="#v" offset="0"/><p>0 0 0</p></triangles>
        <triangles material="b" count="1"><input semantic="VERTEX" source="#v" offset="0"/><p>0 0 0</p></triangles>
      </mesh></geometry></library_geometries></COLLADA>"""
    with pytest.raises(pinrate.errors.InputError, match="nowhere"):
        one_material_per_mesh(text)
