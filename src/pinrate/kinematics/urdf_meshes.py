"""The mesh files a URDF names, confined to the folders it may take them from.

A ``<mesh filename="...">`` is a path Pinocchio opens (through coal and assimp for the
geometry, and the viewer again to send the file to the browser), wherever it points:
``package://../../../../etc/passwd``, ``file:///etc/shadow``, an absolute path, a symbolic link
in the URDF's folder. :func:`confine_meshes` resolves each one now, the way Pinocchio would,
and checks the file it finds, ``..`` and symbolic links resolved, against the *roots*: the
folders pinrate looks meshes up in (the URDF's folder and the ancestors searched for
``package://``, the ``package_dirs`` given, example-robot-data's share, ROS_PACKAGE_PATH's and
AMENT_PREFIX_PATH's), never the filesystem's root itself. A mesh inside them is written into the
text as that file's own path, so Pinocchio opens exactly the file checked and searches for
nothing; any other (outside the roots, not found, or a scheme Pinocchio does not read) is
taken out with its whole ``<visual>`` or ``<collision>`` element, and named in one warning.
The robot loads without those meshes, with its others.

The text is edited in place (by the byte ranges the XML parser reports), never rewritten by
an XML library: the kinematics Pinocchio reads from it stay exactly as they were.
"""

from __future__ import annotations

import os
import re
import xml.etree.ElementTree as ET
import xml.parsers.expat
from collections.abc import Sequence
from dataclasses import dataclass
from xml.sax.saxutils import quoteattr

_ATTRIBUTE = re.compile(rb"""\s+([^\s=/>]+)\s*=\s*("[^"]*"|'[^']*')""")
"""One attribute of a start tag, from its leading space to its closing quote (a value never
holds its own quote character, so this reads a tag exactly as an XML parser does)."""


def ros_package_dirs() -> list[str]:
    """The folders Pinocchio adds to the ``package://`` search: ROS_PACKAGE_PATH's, then
    AMENT_PREFIX_PATH's ``share`` folders."""
    ros = [folder for folder in os.environ.get("ROS_PACKAGE_PATH", "").split(os.pathsep) if folder]
    ament = [f"{folder}/share" for folder in os.environ.get("AMENT_PREFIX_PATH", "").split(os.pathsep) if folder]
    return ros + ament


_PACKAGE_NAME = re.compile(r"[A-Za-z0-9_][A-Za-z0-9_.-]*")


def find_package(name: str, search_dirs: Sequence[str]) -> str | None:
    """The folder of ROS package ``name`` (``package://name/...``, xacro's ``$(find name)``), or
    None: the first of ``search_dirs`` that is the package (its ``package.xml`` names it; without
    one, the folder's own name is ``name``) or holds a folder ``name`` (``ROS_PACKAGE_PATH/name``,
    ``AMENT_PREFIX_PATH/share/name``). ``.``, ``..`` and names with a separator are no package."""
    if not _PACKAGE_NAME.fullmatch(name) or name in (".", ".."):
        return None
    for folder in search_dirs:
        if os.path.isdir(folder) and _package_name(folder) == name:
            return folder
        if os.path.isdir(os.path.join(folder, name)):
            return os.path.join(folder, name)
    return None


def _package_name(folder: str) -> str:
    """The ``<name>`` of the folder's ``package.xml``; the folder's name without a readable one."""
    try:
        name = ET.parse(os.path.join(folder, "package.xml")).getroot().findtext("name")
    except (OSError, ET.ParseError):
        name = None
    return name.strip() if name else os.path.basename(os.path.normpath(folder))


def mesh_roots(search_dirs: Sequence[str]) -> list[str]:
    """The real paths of ``search_dirs`` that exist and are not the filesystem's root."""
    roots = []
    for folder in search_dirs:
        real = os.path.realpath(folder)
        if os.path.isdir(real) and os.path.dirname(real) != real and real not in roots:
            roots.append(real)
    return roots


_MESH_PATHS = {("robot", "link", kind, "geometry", "mesh") for kind in ("visual", "collision")}


@dataclass(frozen=True)
class _Mesh:
    uri: str
    value: tuple[int, int]  # byte range of its filename attribute's quoted value
    element: tuple[int, int]  # byte range of its <visual> or <collision> element


def confine_meshes(text: str, search_dirs: Sequence[str], roots: Sequence[str]) -> tuple[str, list[str]]:
    """``text`` with each mesh resolved and confined to ``roots`` (see the module docstring), and
    the skipped ones as "URI (reason)". ``search_dirs`` are the ``package://`` folders in the
    order Pinocchio searches them; ``roots`` come from :func:`mesh_roots`. ValueError when the
    text cannot be read to the byte (the loader has parsed it before: that is not expected, and
    the robot is then refused rather than its meshes read unchecked)."""
    data = text.encode("utf-8")
    try:
        meshes = _meshes(data)
    except xml.parsers.expat.ExpatError as error:
        raise ValueError(str(error)) from None
    edits: list[tuple[int, int, bytes]] = []  # (start, end, replacement)
    skipped: list[str] = []
    for mesh in meshes:
        resolved, reason = _resolve(mesh.uri, search_dirs, roots)
        if resolved is None:
            skipped.append(f"{mesh.uri} ({reason})")
            edits.append((*mesh.element, b""))
        else:
            edits.append((*mesh.value, quoteattr(resolved).encode("utf-8")))
    if not edits:
        return text, skipped
    pieces, position = [], 0
    for start, end, replacement in sorted(edits):  # an element taken out comes before its mesh's value
        if start < position:  # inside an element already taken out
            continue
        pieces += [data[position:start], replacement]
        position = end
    pieces.append(data[position:])
    return b"".join(pieces).decode("utf-8"), skipped


def _meshes(data: bytes) -> list[_Mesh]:
    """Every mesh urdfdom reads, with its byte positions (expat, no namespace processing: the
    element names as urdfdom's tinyxml2 sees them)."""
    parser = xml.parsers.expat.ParserCreate()
    stack: list[tuple[str, int]] = []
    pending: list[tuple[str, tuple[int, int]]] = []  # the meshes of the open <visual> or <collision>
    meshes: list[_Mesh] = []

    def start(name: str, attributes: dict[str, str]) -> None:
        offset = parser.CurrentByteIndex
        stack.append((name, offset))
        names = tuple(entry[0] for entry in stack)  # urdfdom's mesh: robot/link/visual|collision/geometry/mesh
        if names in _MESH_PATHS and "filename" in attributes:
            pending.append((attributes["filename"], _value_of(data, offset, "filename")))

    def end(name: str) -> None:
        _, begin = stack.pop()
        if len(stack) == 2 and pending:  # a <visual> or <collision> holding meshes closes: </visual>
            close = data.index(b">", parser.CurrentByteIndex) + 1
            meshes.extend(_Mesh(uri, value, (begin, close)) for uri, value in pending)
            pending.clear()

    parser.StartElementHandler = start
    parser.EndElementHandler = end
    parser.Parse(data, True)
    return meshes


def _value_of(data: bytes, tag_start: int, name: str) -> tuple[int, int]:
    """The byte range of attribute ``name``'s quoted value in the start tag at ``tag_start``."""
    position = data.index(b"<", tag_start) + 1
    while data[position : position + 1] not in b" \t\r\n/>":  # the element's name
        position += 1
    while True:
        attribute = _ATTRIBUTE.match(data, position)
        if attribute is None:
            raise xml.parsers.expat.ExpatError(f"unreadable start tag at byte {tag_start}")
        if attribute.group(1) == name.encode():
            return attribute.span(2)
        position = attribute.end()


def _resolve(uri: str, search_dirs: Sequence[str], roots: Sequence[str]) -> tuple[str | None, str]:
    """The real path of the file ``uri`` names inside ``roots``, or None and why not."""
    scheme, separator, rest = uri.partition("://")
    if separator and scheme in ("package", "model"):
        package, _, inside = rest.partition("/")
        found = find_package(package, search_dirs)
        candidates = [f"{folder}/{rest}" for folder in search_dirs]
        if found is not None:  # the package whose package.xml names it, first
            candidates.insert(0, f"{found}/{inside}")
    elif separator and scheme == "file":
        candidates = [rest]
    elif separator:
        return None, f"scheme {scheme!r} is not read"
    elif os.path.isabs(uri):
        candidates = [uri]
    else:
        candidates = [f"{folder}/{uri}" for folder in search_dirs]
    reason = "not found"
    for candidate in candidates:
        if not os.path.exists(candidate):
            continue
        real = os.path.realpath(candidate)
        if not any(real.startswith(root + os.sep) for root in roots):
            reason = "outside the URDF's folder and the package folders"
        elif os.path.isfile(real):
            return real, ""
        elif reason == "not found":
            reason = "not a file"
    return None, reason
