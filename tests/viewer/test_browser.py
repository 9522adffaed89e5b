"""The Meshcat view in a real headless Chromium (tests/browser.py: skipped with a reason when
Chromium is missing, a failure in CI)."""

from __future__ import annotations

import io
import socket
import time
import xml.etree.ElementTree as ET
from pathlib import Path
from urllib.parse import urlparse

import numpy as np
import pinocchio as pin
import pytest

import pinrate
from browser import chromium, needs_browser
from pinrate.kinematics.targets import nearby_target

pytestmark = needs_browser

# JavaScript run in the page: walk viewer.scene_tree by .children only (find() creates nodes).
WALK = """
(path) => {
  let node = window.viewer.scene_tree;
  for (const name of path) {
    if (!node || !node.children || !(name in node.children)) return null;
    node = node.children[name];
  }
  return node;
}
"""
MESH_VERTICES = f"""
(path) => {{
  const node = ({WALK})(path);
  if (!node || !node.object) return -1;
  let count = 0;
  node.object.traverse((o) => {{
    if (o.isMesh && o.geometry && o.geometry.attributes.position) count += o.geometry.attributes.position.count;
  }});
  return count;
}}
"""
# The node's world matrix relative to the /meshcat node (the three.js root is Z-up -> Y-up).
RELATIVE_MATRIX = f"""
(path) => {{
  const walk = {WALK};
  const root = walk(["meshcat"]);
  const node = walk(path);
  if (!root || !node) return null;
  window.viewer.scene.updateMatrixWorld(true);
  const inverse = root.object.matrixWorld.clone().invert();
  return inverse.multiply(node.object.matrixWorld).elements;  // column-major
}}
"""


@pytest.fixture(scope="module")
def browser():
    with chromium() as context:
        yield context


def served_robot(name: str):
    """A viewer with a short servo played and recorded; yields (viewer, trajectory, target)."""
    robot = pinrate.load(name)
    partition = pinrate.Partition.auto(robot)
    _, target = nearby_target(robot, partition, seed=3)
    trajectory = pinrate.servo(robot, robot.home(), target, max_steps=400)
    viewer = pinrate.viewer.Viewer(robot)
    viewer.show(robot.home())
    viewer.play(trajectory, target=target, realtime=False, fps=10)
    return viewer, trajectory, target


@pytest.fixture(scope="module", params=["ur5", "scara"])
def scene(request):
    import pinrate.viewer  # noqa: F401  (the only module importing meshcat)

    viewer, trajectory, target = served_robot(request.param)
    yield viewer, trajectory, target
    viewer.close()


def open_page(browser, url: str):
    page = browser.new_page()
    page.goto(url)
    page.wait_for_function("() => window.viewer !== undefined && window.viewer.scene_tree !== undefined")
    return page


def wait_for_meshes(page, viewer) -> None:
    names = [
        viewer._visualizer.getViewerNodeName(geometry, pin.GeometryType.VISUAL)
        for geometry in viewer.robot.visual_model.geometryObjects
    ]
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline:
        counts = [page.evaluate(MESH_VERTICES, ["meshcat", *name.split("/"), "<object>"]) for name in names]
        if all(count > 0 for count in counts):
            return
        page.wait_for_timeout(250)
    raise AssertionError(f"meshes without vertices after 60 s: {dict(zip(names, counts, strict=True))}")


def expected_transforms(viewer, q) -> dict[str, np.ndarray]:
    return {
        name: transform for name, transform in viewer.node_transforms(q).items() if name.startswith(pinrate.viewer.ROOT)
    }


def page_matrix(page, name: str) -> np.ndarray:
    elements = page.evaluate(RELATIVE_MATRIX, ["meshcat", *name.split("/")])
    assert elements is not None, f"no node {name}"
    return np.array(elements).reshape(4, 4).T


def test_every_visual_is_a_mesh_with_vertices(browser, scene) -> None:
    viewer, _, _ = scene
    assert viewer.robot.visual_model.ngeoms > 0
    page = open_page(browser, viewer.url)
    wait_for_meshes(page, viewer)
    page.close()


def test_drawn_link_poses_match_pinocchio(browser, scene) -> None:
    viewer, trajectory, _ = scene
    page = open_page(browser, viewer.url)
    wait_for_meshes(page, viewer)
    for name, transform in expected_transforms(viewer, trajectory.q[-1]).items():
        np.testing.assert_allclose(page_matrix(page, name), transform, atol=1e-5, err_msg=name)
    page.close()


def test_target_and_path_exist(browser, scene) -> None:
    viewer, _, target = scene
    page = open_page(browser, viewer.url)
    wait_for_meshes(page, viewer)
    for path in (["markers", "target", "<object>"], ["paths", "0", "<object>"], ["markers", "tcp", "<object>"]):
        assert page.evaluate(f"(p) => ({WALK})(p) !== null", ["meshcat", *path]), path
    np.testing.assert_allclose(page_matrix(page, "markers/target"), target, atol=1e-6)
    page.close()


def robot_pixels(page, viewer):
    """The pixels the robot covers: a screenshot with it shown against one with its root node
    hidden, thresholded (a black-and-white PIL image the size of the page)."""
    from PIL import Image, ImageChops

    wait_for_meshes(page, viewer)
    page.wait_for_timeout(500)
    shown = Image.open(io.BytesIO(page.screenshot())).convert("RGB")
    page.evaluate(f"""() => {{
        const node = ({WALK})(["meshcat", "{pinrate.viewer.ROOT}"]);
        node.object.visible = false;
        window.viewer.set_dirty();
    }}""")
    page.wait_for_timeout(500)
    hidden = Image.open(io.BytesIO(page.screenshot())).convert("RGB")
    return ImageChops.difference(shown, hidden).convert("L").point(lambda v: 255 if v > 16 else 0)


def test_screenshot_changes_when_the_robot_is_hidden(browser, scene) -> None:
    viewer, _, _ = scene
    page = open_page(browser, viewer.url)
    changed = robot_pixels(page, viewer)
    assert changed.getbbox() is not None
    assert sum(changed.histogram()[255:]) > 500  # hundreds of pixels, not noise
    page.close()


def test_recorded_html_replays_offline(browser, scene, tmp_path) -> None:
    viewer, trajectory, _ = scene
    html = viewer.save_html(tmp_path / "run.html")
    viewer.close()  # the server is gone: the page must stand alone
    host, port = urlparse(viewer.url).hostname, urlparse(viewer.url).port
    with socket.socket() as probe:
        assert probe.connect_ex((host, port)) != 0, "the Meshcat server still listens"
    page = open_page(browser, html.as_uri())
    wait_for_meshes(page, viewer)
    page.evaluate(
        "() => { window.viewer.animator.pause(); window.viewer.animator.seek(window.viewer.animator.duration); }"
    )
    assert page.evaluate("() => window.viewer.animator.duration") > 0
    for name, transform in expected_transforms(viewer, trajectory.q[-1]).items():
        np.testing.assert_allclose(page_matrix(page, name), transform, atol=1e-4, err_msg=name)
    page.close()


@pytest.mark.parametrize("name", ["ur5", "scara", "panda"])
def test_the_view_frames_the_robot_and_its_targets(browser, name: str) -> None:
    # Three sizes (a 0.5 m SCARA, a 0.9 m UR5, a 1.1 m panda): the robot's pixels (shown minus
    # hidden) lie inside the picture with a margin on every side, and fill a fair part of it.
    import pinrate.viewer

    robot = pinrate.load(name)
    partition = pinrate.Partition.auto(robot)
    targets = [nearby_target(robot, partition, seed)[1] for seed in range(3)]
    viewer = pinrate.viewer.Viewer(robot)
    try:
        viewer.frame(robot.home(), [target[:3, 3] for target in targets])
        viewer.show(robot.home())
        for index, target in enumerate(targets):
            viewer.set_frame(f"target{index}", target)
        page = open_page(browser, viewer.url)
        changed = robot_pixels(page, viewer)
        page.close()
    finally:
        viewer.close()
    box = changed.getbbox()
    assert box is not None
    left, top, right, bottom = box
    width, height = changed.size
    margin = 0.03
    assert left >= margin * width and right <= (1 - margin) * width, (box, changed.size)
    assert top >= margin * height and bottom <= (1 - margin) * height, (box, changed.size)
    assert max((right - left) / width, (bottom - top) / height) >= 0.3, box  # not a speck in the distance


# Every three.js Mesh under the node: the groups whose material entry is not a Material
# (three.js skips those), and the triangles the renderer draws for it alone (a copy in a
# scene of its own, never culled: renderer.info counts what each draw call drew).
DRAWN_TRIANGLES = f"""
(path) => {{
  const node = ({WALK})(path);
  if (!node || !node.object) return null;
  const renderer = window.viewer.renderer;
  let triangles = 0, skipped = 0, meshes = 0;
  node.object.traverse((o) => {{
    if (!o.isMesh) return;
    meshes += 1;
    if (Array.isArray(o.material)) {{
      for (const group of o.geometry.groups) {{
        const entry = o.material[group.materialIndex];
        if (!(entry && entry.isMaterial)) skipped += 1;
      }}
    }}
    const scene = new MeshCat.THREE.Scene();
    const copy = o.clone();
    copy.frustumCulled = false;
    scene.add(copy);
    renderer.render(scene, window.viewer.camera);
    triangles += renderer.info.render.triangles;
  }});
  window.viewer.set_dirty();
  return {{triangles, skipped, meshes}};
}}
"""


def collada_triangles(path: Path) -> int:
    """The triangles of every geometry the Collada file instances (polygons fanned)."""
    root = ET.parse(path).getroot()
    for element in root.iter():
        element.tag = element.tag.rsplit("}", 1)[-1]
    ids = {element.get("id"): element for element in root.iter() if element.get("id")}
    total = 0
    for instance in root.iter("instance_geometry"):
        for primitive in ids[instance.get("url")[1:]].find("mesh"):
            if primitive.tag == "triangles":
                total += int(primitive.get("count"))
            elif primitive.tag == "polylist":
                total += sum(int(count) - 2 for count in primitive.find("vcount").text.split())
    return total


@pytest.mark.parametrize("where", ["offline", "server"])
def test_every_material_group_of_the_ur5_is_drawn(browser, tmp_path, where: str) -> None:
    # The offline page of a UR5 (and the live one, from the Meshcat server): each link's
    # mesh draws all the triangles of its Collada file, no group pointing at a material
    # list (before the fix the shoulder drew 9302 of its 13492 triangles, the grey housing
    # missing).
    import pinrate.viewer

    robot = pinrate.load("ur5")
    viewer = pinrate.viewer.Viewer(robot, offline=where == "offline")
    try:
        viewer.show(robot.home())
        page = open_page(browser, viewer.save_html(tmp_path / "ur5.html").as_uri() if viewer.scene else viewer.url)
        wait_for_meshes(page, viewer)
        drawn = {}
        for geometry in robot.visual_model.geometryObjects:
            name = viewer._visualizer.getViewerNodeName(geometry, pin.GeometryType.VISUAL)
            drawn[geometry.name] = page.evaluate(DRAWN_TRIANGLES, ["meshcat", *name.split("/"), "<object>"])
        page.close()
    finally:
        viewer.close()
    expected = {
        geometry.name: {"triangles": collada_triangles(Path(geometry.meshPath)), "skipped": 0, "meshes": 1}
        for geometry in robot.visual_model.geometryObjects
    }
    assert drawn == expected


BARE_URDF = """<?xml version="1.0"?>
<robot name="bare">
  <link name="base"/>
  <joint name="j1" type="revolute"><parent link="base"/><child link="l1"/><origin xyz="0 0 0.3"/>
    <axis xyz="0 0 1"/><limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
  <link name="l1"/>
  <joint name="j2" type="revolute"><parent link="l1"/><child link="l2"/><origin xyz="0 0 0.1"/>
    <axis xyz="0 1 0"/><limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
  <link name="l2"/>
  <joint name="j3" type="revolute"><parent link="l2"/><child link="l3"/><origin xyz="0.4 0 0"/>
    <axis xyz="0 1 0"/><limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
  <link name="l3"/>
  <joint name="tool_joint" type="fixed"><parent link="l3"/><child link="tool"/><origin xyz="0.3 0 0"/></joint>
  <link name="tool"/>
</robot>
"""


def test_a_meshless_robot_shows_its_skeleton(browser, tmp_path) -> None:
    # No <visual> at all: the offline replay holds one skeleton node per body, meshes with
    # vertices, at Pinocchio's joint placements at the last frame, and the robot is seen.
    import pinrate.viewer

    path = tmp_path / "bare.urdf"
    path.write_text(BARE_URDF)
    robot = pinrate.load(path, tip="tool")
    assert robot.visual_model.ngeoms == 0
    viewer = pinrate.viewer.Viewer(robot, offline=True)
    configurations = [robot.random_configuration(seed) for seed in range(4)]
    viewer.frame(configurations[-1])
    for q in configurations:
        viewer.show(q)
    page = open_page(browser, viewer.save_html(tmp_path / "bare.html").as_uri())
    page.evaluate(
        "() => { window.viewer.animator.pause(); window.viewer.animator.seek(window.viewer.animator.duration); }"
    )
    data = robot.model.createData()
    pin.forwardKinematics(robot.model, data, configurations[-1])
    for joint, name in enumerate(robot.model.names):
        node = f"{pinrate.viewer.ROOT}/skeleton/{name}"
        parts = ["links"] if joint == 0 else ["links", "joint"]
        for part in parts:
            vertices = page.evaluate(MESH_VERTICES, ["meshcat", *node.split("/"), part, "<object>"])
            assert vertices > 0, (node, part)
        np.testing.assert_allclose(page_matrix(page, node), data.oMi[joint].homogeneous, atol=1e-5, err_msg=name)
    changed = robot_pixels(page, viewer)
    page.close()
    assert sum(changed.histogram()[255:]) > 500  # the skeleton covers hundreds of pixels
