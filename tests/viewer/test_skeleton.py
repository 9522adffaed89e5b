"""The kinematic tree drawn for links without a visual: where it is, that it moves with q
as Pinocchio's joint placements, and that a robot with full meshes gets none.

The robot below is written for these tests: a fixed joint under the first moving one, a
branch, a fixed elbow offset, a prismatic joint, a continuous joint about an unaligned
axis and a fixed tool frame. Expected poses and points come from Pinocchio's kinematics
of that URDF and the axes written in it.
"""

from __future__ import annotations

import warnings

import numpy as np
import pinocchio as pin
import pytest
import umsgpack

import pinrate
from pinrate.viewer import Viewer

URDF = """<?xml version="1.0"?>
<robot name="bare">
  <link name="base_link"/>
  <joint name="base_fixed" type="fixed"><parent link="base_link"/><child link="pedestal"/>
    <origin xyz="0 0 0.1"/></joint>
  <link name="pedestal"/>
  <joint name="j1" type="revolute"><parent link="pedestal"/><child link="l1"/>
    <origin xyz="0 0 0.2" rpy="0 0 0.3"/><axis xyz="0 0 1"/>
    <limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
  <link name="l1"/>
  <joint name="j2" type="revolute"><parent link="l1"/><child link="l2"/>
    <origin xyz="0.05 0 0.1" rpy="0.2 0 0"/><axis xyz="0 1 0"/>
    <limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
  <link name="l2">{l2_visual}</link>
  <joint name="elbow_offset" type="fixed"><parent link="l2"/><child link="l2b"/><origin xyz="0.3 0 0"/></joint>
  <link name="l2b"/>
  <joint name="j3" type="prismatic"><parent link="l2b"/><child link="l3"/>
    <origin xyz="0 0 0.1"/><axis xyz="1 0 0"/><limit lower="0" upper="0.2" effort="1" velocity="1"/></joint>
  <link name="l3"/>
  <joint name="j4" type="continuous"><parent link="l3"/><child link="l4"/>
    <origin xyz="0.2 0 0"/><axis xyz="0.6 0 0.8"/></joint>
  <link name="l4"/>
  <joint name="tool_fixed" type="fixed"><parent link="l4"/><child link="tool0"/><origin xyz="0 0 0.08"/></joint>
  <link name="tool0"/>
  <joint name="side" type="revolute"><parent link="l1"/><child link="side_link"/>
    <origin xyz="-0.1 0 0.05"/><axis xyz="1 0 0"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
  <link name="side_link"/>
</robot>
"""

AXES = {"j1": [0, 0, 1], "j2": [0, 1, 0], "j3": [1, 0, 0], "j4": [0.6, 0, 0.8], "side": [1, 0, 0]}
"""The joints' axes as written in the URDF (their own frames)."""

LINKS = [
    ("universe", "base_fixed"),
    ("base_fixed", "j1"),
    ("j1", "j2"),
    ("j1", "side"),
    ("j2", "elbow_offset"),
    ("elbow_offset", "j3"),
    ("j3", "j4"),
    ("j4", "tool_fixed"),
]
"""Consecutive joint origins in the URDF's tree (fixed joints included): the link capsules."""

BOX = '<visual><geometry><box size="0.3 0.04 0.04"/></geometry></visual>'


def bare_robot(tmp_path, l2_visual: str = "") -> pinrate.Robot:
    path = tmp_path / "bare.urdf"
    path.write_text(URDF.format(l2_visual=l2_visual))
    return pinrate.load(path, tip="tool0")


def skeleton_meshes(viewer: Viewer) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """Meshcat path -> ((N, 3) vertices in its node's frame, (M, 3) faces) of each skeleton
    mesh the page receives."""
    meshes = {}
    for packed in viewer.scene.packed():
        command = umsgpack.unpackb(packed)
        if command["type"] == "set_object" and "/skeleton/" in command["path"]:
            data = command["object"]["geometries"][0]["data"]
            vertices = np.frombuffer(data["attributes"]["position"]["array"].data, dtype=np.float32)
            faces = np.frombuffer(data["index"]["array"].data, dtype=np.uint32)
            path = command["path"].removeprefix("/meshcat/").removesuffix("/<object>")
            meshes[path] = (vertices.reshape(-1, 3).astype(float), faces.reshape(-1, 3).astype(int))
    return meshes


def pieces(vertices: np.ndarray, faces: np.ndarray) -> list[np.ndarray]:
    """The vertices of each connected piece of a mesh (faces sharing vertices)."""
    parent = list(range(vertices.shape[0]))

    def root(i: int) -> int:
        while parent[i] != i:
            parent[i] = parent[parent[i]]
            i = parent[i]
        return i

    for a, b, c in faces:
        parent[root(b)] = root(a)
        parent[root(c)] = root(a)
    labels = np.array([root(i) for i in range(vertices.shape[0])])
    return [vertices[labels == label] for label in np.unique(labels)]


def world_points(transform: np.ndarray, points: np.ndarray) -> np.ndarray:
    return points @ transform[:3, :3].T + transform[:3, 3]


def distance_to_segment(points: np.ndarray, start: np.ndarray, end: np.ndarray) -> np.ndarray:
    along = end - start
    t = np.clip((points - start) @ along / (along @ along), 0.0, 1.0)
    return np.linalg.norm(points - (start + t[:, None] * along), axis=1)


@pytest.fixture
def bare(tmp_path):
    robot = bare_robot(tmp_path)
    assert robot.visual_model.ngeoms == 0
    return robot, Viewer(robot, offline=True)


def kinematics(robot: pinrate.Robot, q: np.ndarray) -> pin.Data:
    data = robot.model.createData()
    pin.forwardKinematics(robot.model, data, q)
    pin.updateFramePlacements(robot.model, data)
    return data


def test_every_bare_body_is_a_node_at_its_joint_placement(bare) -> None:
    robot, viewer = bare
    model = robot.model
    for seed in range(5):
        q = robot.random_configuration(seed)
        transforms = viewer.node_transforms(q)
        data = kinematics(robot, q)
        skeleton = {name for name in transforms if name.startswith("pinrate/skeleton/")}
        assert skeleton == {f"pinrate/skeleton/{name}" for name in model.names}
        for joint, name in enumerate(model.names):
            np.testing.assert_allclose(
                transforms[f"pinrate/skeleton/{name}"], data.oMi[joint].homogeneous, atol=1e-12, err_msg=name
            )


def origin(robot: pinrate.Robot, data: pin.Data, name: str, *, parent_side: bool) -> np.ndarray:
    """A joint's origin in the world: a fixed joint's frame; a moving joint's frame, or with
    ``parent_side`` its placement on the parent body (the same for a revolute joint; a
    prismatic one's slide apart, the slide being the joint, not a link)."""
    model = robot.model
    if model.existJointName(name) and name != "universe":
        joint = model.getJointId(name)
        if parent_side:
            return np.array((data.oMi[model.parents[joint]] * model.jointPlacements[joint]).translation)
        return np.array(data.oMi[joint].translation)
    return np.array(data.oMf[model.getFrameId(name)].translation)


def test_the_links_join_consecutive_joint_origins(bare) -> None:
    # Each capsule (a connected piece of a body's links mesh) has every vertex at the
    # capsule radius from one segment between consecutive joint origins, and reaches both
    # ends (its poles, one radius past them); each segment has exactly one capsule.
    robot, viewer = bare
    q = robot.random_configuration(11)
    transforms = viewer.node_transforms(q)
    data = kinematics(robot, q)
    radius = viewer.skeleton.radius
    segments = [(origin(robot, data, a, parent_side=False), origin(robot, data, b, parent_side=True)) for a, b in LINKS]
    capsules = [
        world_points(transforms[path.removesuffix("/links")], piece)
        for path, (vertices, faces) in skeleton_meshes(viewer).items()
        if path.endswith("/links")
        for piece in pieces(vertices, faces)
    ]

    def joins(capsule: np.ndarray, start: np.ndarray, end: np.ndarray) -> bool:
        on_surface = np.allclose(distance_to_segment(capsule, start, end), radius, atol=1e-5)
        reach = [np.min(np.linalg.norm(capsule - point, axis=1)) for point in (start, end)]
        return on_surface and np.allclose(reach, radius, atol=1e-5)

    matches = np.array([[joins(capsule, *segment) for segment in segments] for capsule in capsules])
    assert matches.shape == (len(LINKS), len(LINKS))
    assert (matches.sum(axis=0) == 1).all() and (matches.sum(axis=1) == 1).all(), matches


def test_the_joints_are_cylinders_along_their_axes(bare) -> None:
    robot, viewer = bare
    q = robot.random_configuration(5)
    transforms = viewer.node_transforms(q)
    data = kinematics(robot, q)
    meshes = skeleton_meshes(viewer)
    assert not any(path.startswith("pinrate/skeleton/universe/joint") for path in meshes)
    for name, axis in AXES.items():
        joint = robot.model.getJointId(name)
        world_axis = data.oMi[joint].rotation @ (np.array(axis) / np.linalg.norm(axis))
        centre = data.oMi[joint].translation
        points = world_points(transforms[f"pinrate/skeleton/{name}"], meshes[f"pinrate/skeleton/{name}/joint"][0])
        along = (points - centre) @ world_axis
        across = np.linalg.norm(points - centre - along[:, None] * world_axis, axis=1)
        # A cylinder about the axis: its vertices at +-half its length and within its radius
        # of the axis, both rims at full radius; about any other axis they would not be.
        half, radius = np.max(np.abs(along)), np.max(across)
        np.testing.assert_allclose(np.abs(along), half, atol=1e-5, err_msg=name)
        assert set(np.round(across / radius, 4)) <= {0.0, 1.0}, name
        assert half > radius > viewer.skeleton.radius, name


def test_a_robot_with_full_meshes_has_no_skeleton() -> None:
    robot = pinrate.load("ur5")
    has_visual = {geometry.parentJoint for geometry in robot.visual_model.geometryObjects}
    assert has_visual == set(range(robot.model.njoints))  # the premise: every body has a mesh
    viewer = Viewer(robot, offline=True)
    assert viewer.skeleton.bodies == []
    assert not skeleton_meshes(viewer)
    assert not [name for name in viewer.node_transforms(robot.home()) if "skeleton" in name]


def test_only_the_bare_bodies_get_a_skeleton(tmp_path) -> None:
    robot = bare_robot(tmp_path, l2_visual=BOX)
    assert [geometry.parentJoint for geometry in robot.visual_model.geometryObjects] == [robot.model.getJointId("j2")]
    viewer = Viewer(robot, offline=True)
    expected = {f"pinrate/skeleton/{name}" for name in robot.model.names if name != "j2"}
    assert {name for name in viewer.node_transforms(robot.home()) if "/skeleton/" in name} == expected


def test_a_visual_the_viewer_cannot_draw_leaves_its_body_bare(tmp_path) -> None:
    # A geometry Pinocchio's MeshcatVisualizer has no drawing for (a coal triangle): it warns
    # and sends nothing, so the body still gets its skeleton; a box beside it counts.
    coal = pytest.importorskip("coal")
    robot = bare_robot(tmp_path)
    model = robot.model
    odd = coal.TriangleP(np.zeros(3), np.ones(3), np.array([1.0, 0.0, 0.0]))
    for name, joint, shape in (("odd", "j2", odd), ("box", "j3", coal.Box(0.1, 0.1, 0.1))):
        geometry = pin.GeometryObject(name, model.getJointId(joint), pin.SE3.Identity(), shape)
        robot.visual_model.addGeometryObject(geometry)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # Pinocchio's own "not supported" warning
        viewer = Viewer(robot, offline=True)
    assert viewer._visualizer.drawn == {"box"}
    skeleton = {name for name in viewer.node_transforms(robot.home()) if "/skeleton/" in name}
    assert "pinrate/skeleton/j2" in skeleton and "pinrate/skeleton/j3" not in skeleton


def test_unloadable_meshes_leave_the_whole_tree(tmp_path) -> None:
    visual = '<visual><geometry><mesh filename="package://nowhere/missing.stl"/></geometry></visual>'
    with pytest.warns(UserWarning, match="mesh left out"):  # named as the robot loads
        robot = bare_robot(tmp_path, l2_visual=visual)
    assert robot.visual_model.ngeoms == 0
    viewer = Viewer(robot, offline=True)
    assert {body.joint for body in viewer.skeleton.bodies} == set(range(robot.model.njoints))


ONE_JOINT_URDF = """<?xml version="1.0"?>
<robot name="one">
  <link name="base_link"/>
  <joint name="j1" type="revolute"><parent link="base_link"/><child link="l1"/>
    <origin xyz="0 0 0.1"/><axis xyz="0 1 0"/><limit lower="-2" upper="2" effort="1" velocity="1"/></joint>
  <link name="l1"/>
  <joint name="tool_fixed" type="fixed"><parent link="l1"/><child link="tool0"/><origin xyz="0.3 0 0"/></joint>
  <link name="tool0"/>
</robot>
"""


def test_a_one_joint_robot_gets_its_skeleton(tmp_path) -> None:
    # Pinocchio hands a one-column Jacobian back as a vector: the skeleton read its axis as
    # a column of a matrix and raised IndexError for any one-joint robot.
    path = tmp_path / "one.urdf"
    path.write_text(ONE_JOINT_URDF)
    robot = pinrate.load(path)
    viewer = Viewer(robot, offline=True)
    q = np.array([0.7])
    points = world_points(
        viewer.node_transforms(q)["pinrate/skeleton/j1"], skeleton_meshes(viewer)["pinrate/skeleton/j1/joint"][0]
    )
    centre = kinematics(robot, q).oMi[1].translation
    # The cylinder lies along the world y axis (the joint's axis, unchanged by turning about it).
    across = np.linalg.norm((points - centre)[:, [0, 2]], axis=1)
    assert np.max(np.abs((points - centre)[:, 1])) > np.max(across)
