"""The kinematic tree, drawn for the links that have no visual (or none the viewer could load).

A robot whose URDF has no ``<visual>`` elements, or meshes that cannot be read, would show
nothing. For every Pinocchio joint whose body (the links it carries, fixed joints merged)
has no drawn visual, the skeleton draws:

* its links: capsules between consecutive joint origins on the body, the body's incoming
  joint origin to the fixed joints' origins and to the child joints' origins, following the
  URDF's tree (Pinocchio's ``Frame.parentFrame``);
* its joint: a short cylinder along the joint's axis (revolute: the rotation axis,
  prismatic: the sliding direction), centred on the joint's origin; a ball for a joint
  with several degrees of freedom.

Each body is one node, ``<root>/skeleton/<joint name>``, placed at the joint's world pose
``data.oMi[joint]`` exactly like the visuals (:meth:`Skeleton.transforms`), with the mesh
vertices in the joint's frame (metres), so the skeleton moves with q as the meshes do.
"""

from __future__ import annotations

import itertools
from collections.abc import Iterable
from dataclasses import dataclass, field

import meshcat
import meshcat.geometry as g
import numpy as np
import pinocchio as pin

LINK_COLOUR = 0xA8A8A8
"""Light grey: the links' capsules."""

JOINT_COLOUR = 0x5F5F5F
"""Dark grey: the joints' cylinders and balls."""

RADIUS_SHARE = 0.012
"""A link capsule's radius as a share of the robot's reach (the farthest frame origin from
the base at the neutral configuration), at least MIN_RADIUS."""

MIN_RADIUS = 0.002
"""Metres."""

JOINT_RADIUS = 2.0
"""A joint cylinder's (or ball's) radius, in link radii."""

JOINT_LENGTH = 5.0
"""A joint cylinder's length, in link radii."""

SIDES = 16
"""Facets around a capsule or cylinder."""


def _basis(direction: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Two unit vectors that make a right-handed orthonormal basis with unit ``direction``."""
    helper = np.array([1.0, 0.0, 0.0]) if abs(direction[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    u = np.cross(direction, helper)
    u /= np.linalg.norm(u)
    return u, np.cross(direction, u)


def _lathe(
    start: np.ndarray, direction: np.ndarray, profile: list[tuple[float, float]]
) -> tuple[np.ndarray, np.ndarray]:
    """A surface of revolution about the line ``start + s * direction`` (unit direction).

    ``profile`` lists (s, r): distance along the line and radius, both metres, from one end
    to the other; an end with r = 0 closes the surface there. Returns (vertices (N, 3),
    faces (M, 3) of vertex indices, counter-clockwise seen from outside), in the frame of
    ``start`` and ``direction``.
    """
    u, v = _basis(direction)
    angles = np.linspace(0.0, 2.0 * np.pi, SIDES, endpoint=False)
    around = np.cos(angles)[:, None] * u + np.sin(angles)[:, None] * v  # (SIDES, 3)
    vertices: list[np.ndarray] = []
    rows: list[list[int]] = []  # the vertex indices of each profile point
    for s, r in profile:
        centre = start + s * direction
        if r == 0.0:
            rows.append([len(vertices)] * SIDES)
            vertices.append(centre)
        else:
            rows.append(list(range(len(vertices), len(vertices) + SIDES)))
            vertices.extend(centre + r * around)
    faces = []
    for lower, upper in itertools.pairwise(rows):
        for k in range(SIDES):
            a, b, c, d = lower[k], lower[(k + 1) % SIDES], upper[(k + 1) % SIDES], upper[k]
            if a != b:
                faces.append((a, b, c))
            if c != d:
                faces.append((a, c, d))
    return np.array(vertices, dtype=float), np.array(faces, dtype=np.int64)


def capsule(start: np.ndarray, end: np.ndarray, radius: float) -> tuple[np.ndarray, np.ndarray]:
    """A capsule around the segment ``start`` -> ``end`` (same frame, metres)."""
    axis = end - start
    length = float(np.linalg.norm(axis))
    direction = axis / length
    quarter = np.linspace(0.0, np.pi / 2, 5)
    cap_start = [(-radius * np.cos(t), radius * np.sin(t)) for t in quarter]
    cap_end = [(length + radius * np.sin(t), radius * np.cos(t)) for t in quarter]
    profile = [*cap_start, *cap_end]
    profile[0], profile[-1] = (profile[0][0], 0.0), (profile[-1][0], 0.0)
    return _lathe(start, direction, profile)


def cylinder(centre: np.ndarray, axis: np.ndarray, length: float, radius: float) -> tuple[np.ndarray, np.ndarray]:
    """A closed cylinder centred on ``centre`` along unit ``axis`` (same frame, metres)."""
    half = length / 2
    return _lathe(centre - half * axis, axis, [(0.0, 0.0), (0.0, radius), (length, radius), (length, 0.0)])


def ball(centre: np.ndarray, radius: float) -> tuple[np.ndarray, np.ndarray]:
    """A sphere of ``radius`` around ``centre`` (metres)."""
    angles = np.linspace(0.0, np.pi, 9)
    profile = [(radius * (1 - np.cos(t)), radius * np.sin(t)) for t in angles]
    profile[0], profile[-1] = (0.0, 0.0), (2 * radius, 0.0)
    return _lathe(centre - np.array([0.0, 0.0, radius]), np.array([0.0, 0.0, 1.0]), profile)


def merged(parts: Iterable[tuple[np.ndarray, np.ndarray]]) -> tuple[np.ndarray, np.ndarray]:
    """One (vertices, faces) mesh made of several."""
    vertices, faces, offset = [], [], 0
    for part_vertices, part_faces in parts:
        vertices.append(part_vertices)
        faces.append(part_faces + offset)
        offset += part_vertices.shape[0]
    return np.vstack(vertices), np.vstack(faces)


@dataclass
class Body:
    """What the skeleton draws of one Pinocchio joint's body, in that joint's frame (metres)."""

    joint: int
    """Pinocchio's joint index (0: the universe, the links fixed to the world)."""

    name: str
    """The body's meshcat node name (the joint's name, slashes replaced)."""

    segments: list[tuple[np.ndarray, np.ndarray]] = field(default_factory=list)
    """(start, end) of each link capsule: consecutive joint origins."""

    axis: np.ndarray | None = None
    """Unit axis of a one-degree-of-freedom joint, in its frame; None for the universe and for
    joints with several degrees of freedom or none (drawn as a ball)."""


def _origin_frame(model: pin.Model, frame: int) -> int:
    """The joint frame (moving or fixed joint, or the universe) that ``frame``'s link hangs
    from: up the parentFrame chain from ``frame``'s parent, past the links' BODY frames."""
    current = model.frames[frame].parentFrame
    for _ in range(len(model.frames)):
        kind = model.frames[current].type
        if current == 0 or kind in (pin.FrameType.JOINT, pin.FrameType.FIXED_JOINT):
            return int(current)
        current = model.frames[current].parentFrame
    return 0


def _joint_frames(model: pin.Model) -> dict[int, int]:
    """Joint index -> its JOINT frame's index (joints added without a frame are missing)."""
    frames: dict[int, int] = {}
    for index, frame in enumerate(model.frames):
        if frame.type == pin.FrameType.JOINT and frame.parentJoint not in frames:
            frames[frame.parentJoint] = index
    return frames


def _axes(model: pin.Model) -> list[np.ndarray | None]:
    """Each joint's unit axis in its own frame: the rotation axis of a revolute joint, the
    direction of a prismatic one (from the joint's motion subspace at the neutral q, read as
    the joint's LOCAL Jacobian column); None for the universe and other joints."""
    data = model.createData()
    pin.computeJointJacobians(model, data, pin.neutral(model))
    axes: list[np.ndarray | None] = [None]
    for joint in range(1, model.njoints):
        nv, index = model.joints[joint].nv, model.joints[joint].idx_v
        if nv != 1:
            axes.append(None)
            continue
        # eigenpy hands a one-column matrix back as a vector: keep (6, nv).
        column = np.asarray(pin.getJointJacobian(model, data, joint, pin.LOCAL)).reshape(6, model.nv)[:, index]
        angular, linear = column[3:], column[:3]
        vector = angular if np.linalg.norm(angular) > 1e-12 else linear
        norm = float(np.linalg.norm(vector))
        axes.append(vector / norm if norm > 1e-12 else None)
    return axes


def bodies(model: pin.Model, joints: Iterable[int]) -> list[Body]:
    """The skeleton's parts for the bodies of ``joints`` (Pinocchio joint indices).

    A joint frame's placement is relative to its parent joint, so the origin of every segment
    end (the universe, a moving joint's own frame, a fixed joint on the body) in the body's
    joint frame is the frame's ``placement.translation``; a moving child's origin is its
    ``jointPlacements`` translation.
    """
    joint_frames = _joint_frames(model)
    axes = _axes(model)
    result: list[Body] = []
    names: set[str] = set()
    for joint in sorted(set(joints)):
        name = str(model.names[joint]).replace("/", "_") or "joint"
        name = f"{name}_{joint}" if name in names else name
        names.add(name)
        body = Body(joint=joint, name=name, axis=axes[joint])
        ends: list[tuple[np.ndarray, np.ndarray]] = []  # (start, end) in the joint's frame
        for index, frame in enumerate(model.frames):
            if index and frame.type == pin.FrameType.FIXED_JOINT and frame.parentJoint == joint:
                start = model.frames[_origin_frame(model, index)].placement.translation
                ends.append((np.array(start), np.array(frame.placement.translation)))
        for child in range(1, model.njoints):
            if model.parents[child] == joint:
                start = np.zeros(3)  # a joint added without a frame: from the body's joint origin
                if child in joint_frames:
                    start = np.array(model.frames[_origin_frame(model, joint_frames[child])].placement.translation)
                ends.append((start, np.array(model.jointPlacements[child].translation)))
        body.segments = [(start, end) for start, end in ends if np.linalg.norm(end - start) > 1e-9]
        result.append(body)
    return result


def reach(model: pin.Model) -> float:
    """The farthest frame or joint origin from the world origin at the neutral q (metres)."""
    data = model.createData()
    pin.framesForwardKinematics(model, data, pin.neutral(model))
    points = [np.asarray(placement.translation) for placement in [*data.oMi, *data.oMf]]
    return float(max(np.linalg.norm(point) for point in points))


class Skeleton:
    """The kinematic tree of a robot's bare bodies in a meshcat scene.

    Args:
        model: the robot's Pinocchio model.
        joints: the joints whose bodies get a skeleton (those without a drawn visual).
        root: the meshcat path the ``skeleton`` node goes under (the viewer's robot root).
    """

    def __init__(self, model: pin.Model, joints: Iterable[int], root: str) -> None:
        self.bodies = bodies(model, joints)
        self.radius = max(MIN_RADIUS, RADIUS_SHARE * reach(model))
        self.root = f"{root}/skeleton"

    def path(self, body: Body) -> str:
        """The meshcat path of ``body``'s node (placed at the joint's world pose)."""
        return f"{self.root}/{body.name}"

    def meshes(self, body: Body) -> dict[str, tuple[np.ndarray, np.ndarray, int]]:
        """Part name ("links", "joint") -> (vertices (N, 3) in the joint's frame, metres;
        faces (M, 3); colour) of what is drawn for ``body``; empty parts left out."""
        parts: dict[str, tuple[np.ndarray, np.ndarray, int]] = {}
        if body.segments:
            vertices, faces = merged(capsule(start, end, self.radius) for start, end in body.segments)
            parts["links"] = (vertices, faces, LINK_COLOUR)
        origin = np.zeros(3)
        if body.axis is not None:
            length, radius = JOINT_LENGTH * self.radius, JOINT_RADIUS * self.radius
            parts["joint"] = (*cylinder(origin, body.axis, length, radius), JOINT_COLOUR)
        elif body.joint > 0:
            parts["joint"] = (*ball(origin, JOINT_RADIUS * self.radius), JOINT_COLOUR)
        return parts

    def draw(self, viewer: meshcat.Visualizer) -> None:
        """Send every body's meshes under its node."""
        for body in self.bodies:
            for part, (vertices, faces, colour) in self.meshes(body).items():
                viewer[f"{self.path(body)}/{part}"].set_object(
                    g.TriangularMeshGeometry(vertices, faces), g.MeshLambertMaterial(color=colour)
                )

    def transforms(self, data: pin.Data) -> dict[str, np.ndarray]:
        """Meshcat path -> 4x4 world pose of each body's node: ``data.oMi[joint]`` (the
        forward kinematics must be fresh in ``data``)."""
        return {self.path(body): np.array(data.oMi[body.joint].homogeneous) for body in self.bodies}


__all__ = ["JOINT_COLOUR", "LINK_COLOUR", "Body", "Skeleton", "bodies"]
