"""Collada (``.dae``) meshes rewritten so that meshcat 0.3.2's browser viewer draws all of them.

Pinocchio's MeshcatVisualizer sends a Collada visual as a ``_meshfile_object`` (the file's text
in ``object.object.data``, no materials of its own). meshcat's viewer parses it with three.js's
ColladaLoader, which builds one ``THREE.Mesh`` per ``<mesh>`` (per primitive type) and, when a
``<mesh>`` holds several primitives (one ``<triangles>`` per material), gives that Mesh a
material *list* with one geometry group per primitive. meshcat's ``merge_geometries`` then
merges every Mesh of the file into one BufferGeometry: one group per Mesh, ``materialIndex``
i, and the Mesh's material as entry i of the merged material list. A multi-material Mesh
makes entry i a list itself; three.js's renderer draws a group only when
``material[group.materialIndex].visible`` is true, which a list is not, so it silently skips
those groups (the UR5's grey joint housings: only the blue caps are drawn). meshcat PR #170
fixes the viewer; meshcat-python 0.3.2 ships without it.

:func:`one_material_per_mesh` rewrites the file instead: every ``<mesh>`` with more than one
primitive becomes one ``<geometry>`` per primitive, each holding only the source rows (the
positions, normals, ... its indices use, their text copied unchanged) and instanced wherever
the original was, with the same material bindings. Every Mesh then has a single material,
the merged list is flat, and every group names a material three.js draws.
"""

from __future__ import annotations

import copy
import functools
import os
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np

from ..errors import InputError

PRIMITIVES = ("triangles", "polylist", "lines", "linestrips")
"""The primitive elements three.js's ColladaLoader (r129, meshcat 0.3.2) builds meshes from."""


COLLADA_1_4 = "http://www.collada.org/2005/11/COLLADASchema"
"""The namespace in which Pinocchio's DaeMeshGeometry looks for a file's textures."""


def outside_textures(path: str) -> list[str]:
    """The textures of the Collada file at ``path`` that Pinocchio's DaeMeshGeometry would read
    (the ``init_from`` paths of its first Collada 1.4 ``<library_images>``, relative to the
    file's folder) and that lie outside that folder once ``..`` and symbolic links are
    resolved: the viewer draws such a file not at all rather than read them (their bytes would
    go into the scene, and into every replay written from it)."""
    data = Path(path).read_bytes()
    if b"library_images" not in data:
        return []
    try:
        images = ET.fromstring(data).find(f"{{{COLLADA_1_4}}}library_images")
    except ET.ParseError:  # DaeMeshGeometry's own parse fails first: it reads nothing more
        return []
    if images is None:
        return []
    folder = os.path.dirname(path)
    real_folder = os.path.realpath(folder)
    names = [element.text for element in images.iter() if "init_from" in element.tag and element.text]
    return [
        name
        for name in names
        if not os.path.realpath(os.path.join(folder, name)).startswith(
            real_folder + os.sep
        )  # join keeps an absolute name
    ]


def _namespace(root: ET.Element) -> str:
    return root.tag[1:].split("}", 1)[0] if root.tag.startswith("{") else ""


class _Document:
    """A parsed Collada file, its namespace and its ids (for fresh unique ones)."""

    def __init__(self, text: str) -> None:
        try:
            self.root = ET.fromstring(text)
        except ET.ParseError as error:
            raise InputError(f"not a Collada file: {error}") from None
        self.namespace = _namespace(self.root)
        qualified = f"{{{self.namespace}}}" if self.namespace else ""
        for element in self.root.iter():  # Collada's own elements by their local names, as the viewer reads them
            if isinstance(element.tag, str) and qualified and element.tag.startswith(qualified):
                element.tag = element.tag[len(qualified) :]
        if self.root.tag != "COLLADA":
            raise InputError(f"not a Collada file: the root element is {self.root.tag!r}")
        self.ids = {element.get("id") for element in self.root.iter() if element.get("id")}

    def fresh_id(self, stem: str) -> str:
        candidate, suffix = stem, 1
        while candidate in self.ids:
            candidate, suffix = f"{stem}-{suffix}", suffix + 1
        self.ids.add(candidate)
        return candidate

    def text(self) -> str:
        """The document, Collada's namespace the default one again (ElementTree's own
        ``default_namespace`` refuses unqualified attributes, which Collada is full of)."""
        if self.namespace:
            self.root.set("xmlns", self.namespace)
        return ET.tostring(self.root, encoding="unicode")


def _local_id(reference: str | None, what: str) -> str:
    if not reference or not reference.startswith("#"):
        raise InputError(f"Collada {what} refers to {reference!r}, not to an element of the same file")
    return reference[1:]


class _Rows:
    """Subsets of a ``<source>``'s rows (its accessor's elements), as new ``<source>`` elements."""

    def __init__(self, document: _Document, source: ET.Element) -> None:
        self.document, self.source = document, source
        accessor = source.find("technique_common/accessor")
        if accessor is None:
            raise InputError(f"Collada source {source.get('id')!r} has no accessor")
        array_id = _local_id(accessor.get("source"), f"accessor of source {source.get('id')!r}")
        array = next((child for child in source if child.get("id") == array_id), None)
        if array is None:
            raise InputError(f"Collada source {source.get('id')!r}: no array {array_id!r} inside it")
        self.accessor, self.array = accessor, array
        self.tokens = (array.text or "").split()
        self.count = int(accessor.get("count", "0"))
        self.stride = int(accessor.get("stride", "1"))
        self.offset = int(accessor.get("offset", "0"))
        if self.offset + self.count * self.stride > len(self.tokens):
            raise InputError(f"Collada source {source.get('id')!r}: its accessor reads past its array")

    def subset(self, rows: np.ndarray, stem: str) -> ET.Element:
        """A copy of the source holding ``rows`` (sorted indices into its elements), in order."""
        if rows.size and (rows[0] < 0 or rows[-1] >= self.count):
            raise InputError(f"Collada source {self.source.get('id')!r}: an index outside its {self.count} elements")
        source = copy.deepcopy(self.source)
        source.set("id", self.document.fresh_id(stem))
        array = next(child for child in source if child.get("id") == self.array.get("id"))
        accessor = source.find("technique_common/accessor")
        assert accessor is not None  # copied from self.source, which has one
        array.set("id", self.document.fresh_id(f"{source.get('id')}-array"))
        starts = self.offset + rows * self.stride
        array.text = " ".join(self.tokens[start + k] for start in starts.tolist() for k in range(self.stride))
        array.set("count", str(rows.size * self.stride))
        accessor.set("source", f"#{array.get('id')}")
        accessor.set("count", str(rows.size))
        accessor.attrib.pop("offset", None)
        return source


def _indices(primitive: ET.Element, stride: int) -> list[np.ndarray]:
    """The primitive's ``<p>`` lists, each as (corners, stride) ints."""
    lists = []
    for p in primitive.findall("p"):
        try:
            values = np.array((p.text or "").split(), dtype=np.int64)
        except ValueError:
            raise InputError(
                f"Collada primitive with material {primitive.get('material')!r}: non-integer index"
            ) from None
        if values.size % stride:
            raise InputError(f"Collada primitive with material {primitive.get('material')!r}: ragged <p>")
        lists.append(values.reshape(-1, stride))
    return lists


class _Part:
    """One primitive of a ``<mesh>`` as a ``<mesh>`` of its own, with the source rows it indexes."""

    def __init__(self, document: _Document, sources: dict[str, _Rows], stem: str, rows: dict[int, np.ndarray]) -> None:
        self.document, self.sources, self.stem, self.rows = document, sources, stem, rows
        self.mesh = ET.Element("mesh")
        self.made: dict[tuple[str, int], str] = {}  # (source id, offset) -> the new source's id

    def source(self, source_id: str, offset: int, geometry_id: str) -> str:
        """The id of a new source: ``source_id``'s rows indexed at ``offset``, in sorted order."""
        if (source_id, offset) not in self.made:
            if source_id not in self.sources:
                raise InputError(f"Collada geometry {geometry_id!r}: no source {source_id!r} in its mesh")
            element = self.sources[source_id].subset(self.rows[offset], f"{self.stem}-{source_id}")
            self.mesh.append(element)
            self.made[source_id, offset] = str(element.get("id"))
        return self.made[source_id, offset]


def _split_mesh(document: _Document, geometry: ET.Element, mesh: ET.Element) -> list[ET.Element]:
    """One ``<geometry>`` per primitive of ``mesh``, each with the source rows it indexes."""
    sources = {str(source.get("id")): _Rows(document, source) for source in mesh.findall("source")}
    vertices = mesh.find("vertices")
    geometry_id = str(geometry.get("id"))
    parts = []
    for number, primitive in enumerate(_primitives(mesh)):
        stem = f"{geometry_id}-part{number}"
        inputs = primitive.findall("input")
        stride = 1 + max((int(element.get("offset", "0")) for element in inputs), default=0)
        lists = _indices(primitive, stride)
        corners = np.vstack(lists) if lists else np.zeros((0, stride), dtype=np.int64)
        part = _Part(document, sources, stem, {offset: np.unique(corners[:, offset]) for offset in range(stride)})
        part_primitive = copy.deepcopy(primitive)
        part_vertices = None
        for element in part_primitive.findall("input"):
            offset = int(element.get("offset", "0"))
            reference = _local_id(element.get("source"), f"input of geometry {geometry_id!r}")
            if element.get("semantic") == "VERTEX":
                if vertices is None or reference != vertices.get("id"):
                    raise InputError(f"Collada geometry {geometry_id!r}: its VERTEX input names no <vertices>")
                part_vertices = copy.deepcopy(vertices)
                part_vertices.set("id", document.fresh_id(f"{stem}-vertices"))
                for vertex_input in part_vertices.findall("input"):
                    vertex_source = _local_id(vertex_input.get("source"), f"vertices of geometry {geometry_id!r}")
                    vertex_input.set("source", f"#{part.source(vertex_source, offset, geometry_id)}")
                element.set("source", f"#{part_vertices.get('id')}")
            else:
                element.set("source", f"#{part.source(reference, offset, geometry_id)}")
        if part_vertices is not None:
            part.mesh.append(part_vertices)
        for p, original in zip(part_primitive.findall("p"), lists, strict=True):
            renumbered = [np.searchsorted(part.rows[offset], original[:, offset]) for offset in range(stride)]
            p.text = " ".join(map(str, np.column_stack(renumbered).ravel().tolist()))
        part.mesh.append(part_primitive)
        element = ET.Element("geometry", {**geometry.attrib, "id": document.fresh_id(stem)})
        element.append(part.mesh)
        parts.append(element)
    return parts


def _primitives(mesh: ET.Element) -> list[ET.Element]:
    """The primitives of ``mesh`` that three.js's ColladaLoader builds meshes from."""
    return [child for child in mesh if child.tag in PRIMITIVES]


def _split_instances(document: _Document, parts: dict[str, list[ET.Element]]) -> None:
    """Each ``<instance_geometry>`` of a split geometry becomes one per part, same bindings."""
    parents = [parent for parent in document.root.iter() if any(child.tag == "instance_geometry" for child in parent)]
    for parent in parents:
        rewritten = []
        for child in parent:
            url = child.get("url", "")
            if child.tag == "instance_geometry" and url.startswith("#") and url[1:] in parts:
                for part in parts[url[1:]]:
                    copied = copy.deepcopy(child)
                    copied.set("url", f"#{part.get('id')}")
                    rewritten.append(copied)
            else:
                rewritten.append(child)
        parent[:] = rewritten


@functools.lru_cache(maxsize=16)
def one_material_per_mesh(text: str) -> str:
    """The Collada file ``text`` with every multi-primitive ``<mesh>`` split, one geometry per
    primitive (see the module's docstring); ``text`` itself when no mesh needs splitting.

    The vertex data are unchanged (the numbers' text is copied, not reformatted), and so are
    the nodes, their transforms (metres, the file's own unit and up axis) and the materials.
    Geometries a skin or a morph controller uses are left whole.

    Raises:
        InputError: ``text`` is not a Collada file, or a mesh to split refers to something
            it does not hold (the caller may send the file unchanged).
    """
    document = _Document(text)
    controlled = {
        reference[1:]
        for element in document.root.iter()
        if element.tag in ("skin", "morph")
        for reference in [element.get("source", "")]
        if reference.startswith("#")
    }
    parts: dict[str, list[ET.Element]] = {}
    for library in document.root.findall("library_geometries"):
        rebuilt = []
        for geometry in library:
            mesh = geometry.find("mesh") if geometry.tag == "geometry" else None
            geometry_id = geometry.get("id")
            if mesh is None or not geometry_id or geometry_id in controlled or len(_primitives(mesh)) < 2:
                rebuilt.append(geometry)
                continue
            parts[geometry_id] = _split_mesh(document, geometry, mesh)
            rebuilt.extend(parts[geometry_id])
        library[:] = rebuilt
    if not parts:
        return text
    _split_instances(document, parts)
    return document.text()


__all__ = ["PRIMITIVES", "one_material_per_mesh"]
