"""The browser view: a robot, its frames and its servo path in Meshcat.

This package is the only one that imports meshcat; the rest of pinrate works without a
display. The viewer keeps its own ``pin.Data``, so drawing never disturbs a control loop
that runs on the robot's.

    viewer = Viewer(robot)            # starts a Meshcat server on 127.0.0.1, prints nothing
    print(viewer.url)                 # open it in a browser
    viewer.show(q)
    viewer.play(trajectory, target=pose)
    viewer.save_html("run.html")      # a standalone page that replays the whole run offline

Scene layout (paths under Meshcat's ``/meshcat`` root, Z up):
``pinrate/visuals/<geometry>`` the robot's visual geometries (Pinocchio's MeshcatVisualizer,
Collada files rewritten by :func:`~.collada.one_material_per_mesh` so every part is drawn),
``pinrate/skeleton/<joint>`` the kinematic tree of the links without a drawn visual
(:mod:`~.skeleton`),
``markers/target``, ``markers/tcp``, ``markers/sensor`` triads, ``paths/<k>`` the TCP paths,
coloured by the spectral radius of G along the way (green ρ < 1, red ρ >= 1).
"""

from __future__ import annotations

import contextlib
import io
import math
import os
import time
import webbrowser
from collections.abc import Sequence
from pathlib import Path

import meshcat
import meshcat.geometry as g
import numpy as np
import pinocchio as pin

from ..checks import as_pose, check_output_file, check_positive, check_vector
from ..control.trajectory import Trajectory
from ..errors import InputError
from ..files import replace_file
from ..kinematics.manipulator import Robot, check_robot
from .markers import AXIS_COLOURS, TARGET_COLOUR, arrow_parts, path_colours, triad
from .offline import Animation, SceneCommands
from .server import MeshcatServer, check_reachable
from .skeleton import Skeleton
from .visualizer import RobotVisualizer

ROOT = "pinrate"
"""The Meshcat path under which a Viewer draws the robot."""
CAMERA_DIRECTION = np.array([1.0, -1.25, 0.85]) / np.linalg.norm([1.0, -1.25, 0.85])
"""From the scene's centre towards the camera: an elevated three-quarter view (world axes)."""

CAMERA_FOV_DEGREES = 75.0
"""meshcat's default vertical field of view."""

CAMERA_FILL = 0.9
"""Every framed point stays within this share of the half field of view from the view axis."""

MESH_PADDING = 0.08
"""Metres added around frame origins for the link meshes' thickness."""


class Viewer:
    """A robot in Meshcat, with markers, paths and a recorder for a standalone HTML replay.

    Args:
        robot: what to draw: its visual meshes, and its kinematic tree (:attr:`skeleton`)
            for the links without one.
        host: address the server binds to (127.0.0.1: this machine only).
        zmq_url: connect to a running Meshcat server instead of starting one.
        open_browser: open the URL in the default browser.
        offline: no server: the scene is kept in this process (:attr:`scene`, a
            :class:`~.offline.SceneCommands`) for a page that builds it itself (the teleop
            console) or for :meth:`save_html`; :attr:`url` is "".
        record: keep every frame :meth:`show` draws, for :meth:`save_html`'s replay (False:
            a long session's memory stays flat, and the replay is the scene alone).

    Attributes:
        url: the page to open ("" when offline).
        scene: the scene kept in this process when offline, None otherwise.
        skeleton: the kinematic tree drawn for the links without a visual mesh.
    """

    def __init__(
        self,
        robot: Robot,
        *,
        host: str = "127.0.0.1",
        zmq_url: str | None = None,
        open_browser: bool = False,
        offline: bool = False,
        record: bool = True,
    ) -> None:
        self.robot = check_robot(robot)
        self.recording = bool(record)
        self.data = robot.model.createData()  # the viewer's own: a control loop keeps robot.data
        if zmq_url is not None:
            if offline:
                raise InputError("an offline viewer has no server: drop zmq_url or offline")
            check_reachable(zmq_url)
        self.server = MeshcatServer(host) if zmq_url is None and not offline else None
        self.scene = SceneCommands() if offline else None
        with contextlib.redirect_stdout(io.StringIO()):  # meshcat prints the URL itself; we report it
            if self.scene is not None:
                self.meshcat = meshcat.Visualizer(window=self.scene)
                self.url = ""
            else:
                self.meshcat = meshcat.Visualizer(zmq_url=self.server.zmq_url if self.server else zmq_url)
                self.url = self.server.web_url if self.server else self.meshcat.url()
            self._visualizer = RobotVisualizer(robot.model, pin.GeometryModel(), robot.visual_model)
            self._visualizer.initViewer(viewer=self.meshcat)
            self._visualizer.loadViewerModel(rootNodeName=ROOT)
        self._geometry_data = robot.visual_model.createData()
        dressed = {
            geometry.parentJoint
            for geometry in robot.visual_model.geometryObjects
            if geometry.name in self._visualizer.drawn
        }
        self.skeleton = Skeleton(robot.model, [j for j in range(robot.model.njoints) if j not in dressed], ROOT)
        self.skeleton.draw(self.meshcat)
        self._frames: list[dict[str, np.ndarray]] = []  # recorded transforms, for save_html
        self._hand_axes = False
        self._paths = 0
        self.meshcat["markers/tcp"].set_object(*triad(0.08))
        self.meshcat["markers/sensor"].set_object(*triad(0.05, opacity=0.6))
        self.frame(robot.home())
        if open_browser and self.url:
            webbrowser.open(self.url, new=2)

    # ------------------------------------------------------------------ drawing
    def frame(self, q: np.ndarray, points: Sequence[Sequence[float]] | np.ndarray = ()) -> None:
        """Frame the robot at q (every frame's origin, padded for the link meshes) and
        ``points`` (world, metres; the targets) from an elevated three-quarter view.

        meshcat 0.3.2's orbit controls always look at the world origin (it has no command to
        move their target), so the scene moves instead: ``/meshcat`` (everything pinrate
        draws), the grid and the axes are shifted by minus the bounding box's centre, and the
        camera sits along CAMERA_DIRECTION far enough for the box's sphere to fit
        CAMERA_FILL of meshcat's 75° field of view. Poses relative to ``/meshcat`` are
        unchanged.
        """
        model, data = self.robot.model, self.data
        pin.framesForwardKinematics(model, data, self.robot.check_q(q))
        origins = [np.asarray(placement.translation) for placement in data.oMf]
        cloud = np.vstack([*origins, *np.asarray(points, dtype=float).reshape(-1, 3)])
        low, high = cloud.min(axis=0) - MESH_PADDING, cloud.max(axis=0) + MESH_PADDING
        shift = np.eye(4)
        shift[:3, 3] = -(low + high) / 2
        for path in ("/meshcat", "/Grid", "/Axes"):
            self.meshcat[path].set_transform(shift)
        radius = float(np.linalg.norm(high - low)) / 2
        distance = radius / math.sin(CAMERA_FILL * math.radians(CAMERA_FOV_DEGREES) / 2)
        self.set_camera(CAMERA_DIRECTION * distance)

    def set_camera(self, position: Sequence[float] | np.ndarray) -> None:
        """Put the camera at ``position`` (world frame, Z up), looking at the origin.

        meshcat 0.3.2's camera helpers in Pinocchio fail (no ``set_cam_pos``), so this sets
        the ``position`` of ``/Cameras/default/rotated/<object>``, whose frame is Y up.
        """
        x, y, z = check_vector(position, 3, "camera position")
        self.meshcat["/Cameras/default"].set_transform(np.eye(4))
        self.meshcat["/Cameras/default/rotated/<object>"].set_property("position", [x, z, -y])

    def node_transforms(self, q: np.ndarray) -> dict[str, np.ndarray]:
        """Meshcat path -> 4x4 transform (relative to ``/meshcat``: the world frame, metres) of
        every visual geometry, every skeleton body and the tip/sensor markers at q."""
        return self._node_transforms(self.robot.check_q(q), self.data, self._geometry_data)

    def _node_transforms(self, q: np.ndarray, data: pin.Data, geometry_data: pin.GeometryData) -> dict[str, np.ndarray]:
        """:meth:`node_transforms` on the given Pinocchio data (one per thread)."""
        model = self.robot.model
        pin.forwardKinematics(model, data, q)
        pin.updateGeometryPlacements(model, data, self.robot.visual_model, geometry_data)
        transforms = {}
        for index, geometry in enumerate(self.robot.visual_model.geometryObjects):
            scale = np.diag(np.concatenate([np.asarray(geometry.meshScale).ravel(), [1.0]]))
            name = self._visualizer.getViewerNodeName(geometry, pin.GeometryType.VISUAL)
            transforms[name] = geometry_data.oMg[index].homogeneous @ scale
        transforms.update(self.skeleton.transforms(data))
        transforms["markers/tcp"] = np.array(pin.updateFramePlacement(model, data, self.robot.tip_id).homogeneous)
        world_T_sensor = np.array(pin.updateFramePlacement(model, data, self.robot.sensor_id).homogeneous)
        transforms["markers/sensor"] = world_T_sensor
        if self._hand_axes:
            transforms["markers/hand"] = world_T_sensor
        return transforms

    def draw_hand_axes(self, length: float = 0.12) -> None:
        """Arrows along the sensor frame's x, y, z (red, green, blue) under ``markers/hand``,
        moved with the robot by :meth:`show` (Barker: "keeping track of the positive hand
        axes"). ``length`` in metres."""
        length = check_positive(length, "length")
        for axis, colour in enumerate(AXIS_COLOURS):
            material = g.MeshLambertMaterial(color=colour)
            for part, geometry, transform in arrow_parts(axis, length, length / 30):
                node = self.meshcat[f"markers/hand/{'xyz'[axis]}/{part}"]
                node.set_object(geometry, material)
                node.set_transform(transform)
        self._hand_axes = True

    def tip_position(self, q: np.ndarray) -> np.ndarray:
        """The TCP position (3,) in the world at q (metres), on the viewer's own data."""
        pin.forwardKinematics(self.robot.model, self.data, q)
        return np.array(pin.updateFramePlacement(self.robot.model, self.data, self.robot.tip_id).translation)

    def show(self, q: np.ndarray, *, record: bool = True) -> None:
        """Draw the robot at q (and remember the frame for :meth:`save_html` when the viewer
        records and ``record`` is True)."""
        transforms = self.node_transforms(q)
        for name, transform in transforms.items():
            self.meshcat[name].set_transform(transform)
        if record and self.recording:
            self._frames.append(transforms)

    def set_frame(self, name: str, pose: object, *, length: float = 0.1) -> None:
        """A triad at ``pose`` (4x4 or SE3, world frame) under ``markers/<name>``."""
        self.meshcat[f"markers/{name}"].set_object(*triad(length, width=4.0))
        self.meshcat[f"markers/{name}"].set_transform(np.array(as_pose(pose).homogeneous))

    def set_target(self, pose: object) -> None:
        """The target: a triad and a small sphere at the target pose."""
        self.set_frame("target", pose, length=0.12)
        self.meshcat["markers/target/ball"].set_object(g.Sphere(0.012), g.MeshLambertMaterial(color=TARGET_COLOUR))

    def add_path(self, points: np.ndarray, spectral_radius: Sequence[float] | np.ndarray) -> str:
        """A polyline through ``points`` (N, 3), each segment coloured by ρ at its start."""
        points = np.asarray(points, dtype=np.float32)
        radius = np.asarray(spectral_radius, dtype=float)
        if points.ndim != 2 or points.shape[1] != 3 or radius.shape != (points.shape[0],):
            raise InputError(
                f"points must be (N, 3) with one spectral radius per point, got {points.shape} and {radius.shape}"
            )
        name = f"paths/{self._paths}"
        self._paths += 1
        if points.shape[0] >= 2:
            starts, ends = points[:-1], points[1:]
            vertices = np.empty((2 * starts.shape[0], 3), dtype=np.float32)
            vertices[0::2], vertices[1::2] = starts, ends
            colours = np.repeat(path_colours(radius[:-1]), 2, axis=1)
            self.meshcat[name].set_object(
                g.LineSegments(
                    g.PointsGeometry(vertices.T, colours), g.LineBasicMaterial(vertexColors=True, linewidth=4)
                )
            )
        return name

    def play(
        self,
        trajectory: Trajectory,
        *,
        target: object | None = None,
        speed: float = 1.0,
        realtime: bool = True,
        fps: float = 30.0,
    ) -> None:
        """Animate a servo run: the path coloured by ρ, then the robot along it at ``speed`` times real time."""
        if not isinstance(trajectory, Trajectory):
            raise InputError(f"play takes a Trajectory (what servo() returns), not {type(trajectory).__name__}")
        speed = check_positive(speed, "speed")
        fps = check_positive(fps, "fps")
        if target is not None:
            self.set_target(target)
        tips = np.array([self.tip_position(q) for q in trajectory.q])
        self.add_path(tips, trajectory.spectral_radius)
        stride = max(1, round(1.0 / (fps * trajectory.dt)))
        indices = list(range(0, trajectory.q.shape[0], stride))
        if indices[-1] != trajectory.q.shape[0] - 1:
            indices.append(trajectory.q.shape[0] - 1)
        period = stride * trajectory.dt / speed
        for index in indices:
            started = time.monotonic()
            self.show(trajectory.q[index])
            if realtime:
                time.sleep(max(0.0, period - (time.monotonic() - started)))

    # ------------------------------------------------------------------ recording
    @property
    def recorded_frames(self) -> int:
        return len(self._frames)

    def animation(self, fps: float = 30.0, *, loop: bool = True) -> Animation:
        """The recorded frames (one per :meth:`show`) as meshcat's ``set_animation`` command."""
        return self._animation(self._frames, check_positive(fps, "fps"), loop)

    def _animation(self, frames: Sequence[dict[str, np.ndarray]], fps: float, loop: bool) -> Animation:
        """Each node's position and quaternion in each frame; a transform's scale (a mesh's
        units) stays in the scene's own transform, which the animation leaves alone."""
        # The nodes of every frame (one drawn after the recording began has no whole track).
        names = [name for name in frames[0] if all(name in transforms for transforms in frames)] if frames else []
        poses = np.empty((len(frames), len(names), 7))
        for index, transforms in enumerate(frames):
            for column, name in enumerate(names):
                transform = transforms[name]
                rotation = transform[:3, :3] / np.linalg.norm(transform[:3, :3], axis=0)
                poses[index, column, :3] = transform[:3, 3]
                poses[index, column, 3:] = pin.Quaternion(rotation).coeffs()  # x y z w, as three.js
        paths = [self.meshcat[name].path.lower() for name in names]
        return Animation(paths, poses, fps, repetitions=10**9 if loop else 1)

    def save_html(self, path: str | os.PathLike[str], *, fps: float = 30.0, loop: bool = True) -> Path:
        """A standalone HTML page of the scene that replays every recorded frame, offline.
        Written whole or not at all (:func:`~pinrate.files.replace_file`): a save that fails
        leaves the file it was replacing as it was, and is an InputError naming the file."""
        fps = check_positive(fps, "fps")
        target = check_output_file(path, "replay file")
        animation = self._animation(self._frames, fps, loop) if self._frames else None
        if self.scene is not None:
            return self.scene.write_html(target, extra=[animation.packed()] if animation else [])
        if animation is not None:
            self.meshcat.set_animation(animation, play=True, repetitions=animation.repetitions)
        page = self.meshcat.static_html()
        return replace_file(target, "replay file", lambda stream: stream.write(page), encoding="utf-8")

    def save_replay(
        self, path: str | os.PathLike[str], configurations: np.ndarray, *, fps: float = 30.0, loop: bool = True
    ) -> Path:
        """A standalone HTML page of this offline viewer's scene that replays
        ``configurations`` (F, nq) at ``fps``; the scene itself is left as it is.

        Safe beside a thread that draws with this viewer (the teleop console's render thread):
        the poses come from a Pinocchio data of this call's own, and the scene's commands,
        already encoded, are reused rather than the meshes read and encoded again. Written
        whole or not at all, as :meth:`save_html`.
        """
        if self.scene is None:
            raise InputError("save_replay needs an offline viewer (Viewer(robot, offline=True))")
        fps = check_positive(fps, "fps")
        target = check_output_file(path, "replay file")
        data, geometry_data = self.robot.model.createData(), self.robot.visual_model.createData()
        frames = [self._node_transforms(self.robot.check_q(q), data, geometry_data) for q in configurations]
        extra = [self._animation(frames, fps, loop).packed()] if frames else []
        return self.scene.write_html(target, extra=extra)

    def close(self) -> None:
        """Stop the Meshcat server this viewer started."""
        if self.server is not None:
            self.server.close()

    def __enter__(self) -> Viewer:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


__all__ = ["ROOT", "Viewer"]
