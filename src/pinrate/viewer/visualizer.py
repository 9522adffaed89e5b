"""Pinocchio's MeshcatVisualizer as pinrate's viewer uses it: Collada meshes every part of
which three.js draws, and a record of the geometries actually sent."""

from __future__ import annotations

import warnings

import meshcat
import pinocchio as pin
from pinocchio.visualize import MeshcatVisualizer

from ..errors import InputError
from .collada import one_material_per_mesh, outside_textures


class _SendCount:
    """A meshcat window that passes every command on to ``window``, counting them."""

    def __init__(self, window: object) -> None:
        self.window = window
        self.count = 0

    def send(self, command: object) -> None:
        self.count += 1
        self.window.send(command)  # type: ignore[attr-defined]


class RobotVisualizer(MeshcatVisualizer):
    """Pinocchio's MeshcatVisualizer, with two changes.

    * Collada meshes are sent as :func:`~.collada.one_material_per_mesh` rewrites them:
      meshcat 0.3.2's viewer skips the parts of a multi-material ``<mesh>`` (the module's
      docstring says why). One whose textures lie outside its folder is not drawn
      (:func:`~.collada.outside_textures`; a warning names them): Pinocchio would read them
      into the scene. The mesh files themselves are confined when the robot loads
      (:mod:`pinrate.kinematics.urdf_meshes`).
    * The names of the geometries it actually sent are kept in :attr:`drawn` (Pinocchio
      only warns about the others), so the viewer can draw the skeleton where a link has none.

    Attributes:
        drawn: the names of the geometries sent to the viewer.
    """

    viewer: meshcat.Visualizer  # set by initViewer

    def __init__(self, *args: object, **kwargs: object) -> None:
        super().__init__(*args, **kwargs)
        self.drawn: set[str] = set()

    def loadMeshFromFile(self, geometry_object: pin.GeometryObject) -> object:
        path = geometry_object.meshPath
        if path.lower().endswith(".dae"):
            outside = outside_textures(path)
            if outside:  # Pinocchio reports it as a geometry it could not load, and goes on
                raise InputError(f"{path}: not drawn: its textures lie outside its folder: {', '.join(outside)}")
        mesh = super().loadMeshFromFile(geometry_object)
        text = getattr(mesh, "dae_raw", None)  # Pinocchio's DaeMeshGeometry: the file's text
        if isinstance(text, str):
            try:
                mesh.dae_raw = one_material_per_mesh(text)
            except InputError as error:
                warnings.warn(
                    f"{geometry_object.meshPath}: sent unchanged, its multi-material parts may not be drawn ({error})",
                    stacklevel=2,
                )
        return mesh

    def loadViewerGeometryObject(
        self, geometry_object: pin.GeometryObject, geometry_type: pin.GeometryType, color: object = None
    ) -> None:
        viewer, counter = self.viewer, _SendCount(self.viewer.window)
        self.viewer = meshcat.Visualizer(window=counter)  # the same /meshcat root, through the counter
        try:
            super().loadViewerGeometryObject(geometry_object, geometry_type, color)
        finally:
            self.viewer = viewer
        if counter.count:
            self.drawn.add(geometry_object.name)


__all__ = ["RobotVisualizer"]
