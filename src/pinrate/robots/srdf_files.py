"""The SRDF that goes with a robot description: beside it by stem, or in a MoveIt config
package next to its package.

Searched, in this order (the first that exists wins):

1. ``robot.srdf`` beside ``robot.urdf``, ``robot.urdf.xacro`` or ``robot.xacro`` (its stem);
2. when the file is in a ROS package (a ``package.xml`` at most four folders above it), a
   MoveIt config package near it: ``config/*.srdf`` of every folder named
   ``*moveit_config*`` beside that package or one folder further down beside it (ROS-Industrial
   keeps them in ``moveit_cfgs/``), taking only an SRDF whose ``<robot name>`` is the URDF's
   robot name; ``<name>.srdf`` first among several.

Nothing else is read: a robot whose SRDF lives elsewhere passes its home as ``q0``.
"""

from __future__ import annotations

import re
from pathlib import Path

from .xacro_files import is_xacro

_ROBOT_NAME = re.compile(rb"<robot\b[^>]*?\bname\s*=\s*[\"']([^\"']+)[\"']")
_HEAD_BYTES = 65536  # the <robot> tag sits near the top; a large file is not read whole
_MAX_CANDIDATES = 200  # a folder of thousands of packages costs a bounded number of reads
_PACKAGE_DEPTH = 4  # pkg/urdf/robot.urdf, pkg/urdf/<variant>/robot.xacro, ...: package.xml this close


def srdf_beside(path: Path) -> Path:
    """The SRDF whose stem is the description's: ``robot.srdf`` beside ``robot.urdf``,
    ``robot.urdf.xacro`` or ``robot.xacro``."""
    if is_xacro(path):
        return path.with_name(path.name.removesuffix(".xacro").removesuffix(".urdf") + ".srdf")
    return path.with_suffix(".srdf")


def robot_name(text: str | bytes) -> str | None:
    """The ``name`` of the first ``<robot>`` element of URDF or SRDF text (None: none)."""
    head = (text.encode("utf-8", "replace") if isinstance(text, str) else text)[:_HEAD_BYTES]
    match = _ROBOT_NAME.search(head)
    return match.group(1).decode("utf-8", "replace") if match else None


def find_srdf(path: Path, name: str | None) -> Path | None:
    """The SRDF of the description at ``path`` whose robot is called ``name`` (see the module
    for the search list), or None."""
    beside = srdf_beside(path)
    if beside.is_file():
        return beside
    if not name:
        return None
    matches = [candidate for candidate in _moveit_srdfs(path) if _srdf_robot_name(candidate) == name]
    matches.sort(key=lambda candidate: (candidate.stem != name, str(candidate)))
    return matches[0] if matches else None


def _package_root(path: Path) -> Path | None:
    for folder in list(path.parents)[:_PACKAGE_DEPTH]:
        if (folder / "package.xml").is_file():
            return folder
    return None


def _moveit_srdfs(path: Path) -> list[Path]:
    root = _package_root(path)
    if root is None or root.parent == root:
        return []  # not in a ROS package: its neighbours are not its MoveIt configs
    around = root.parent
    candidates: list[Path] = []
    try:
        for pattern in ("*moveit_config*/config/*.srdf", "*/*moveit_config*/config/*.srdf"):
            for candidate in sorted(around.glob(pattern)):
                if len(candidates) >= _MAX_CANDIDATES:
                    return candidates
                if candidate.is_file():
                    candidates.append(candidate)
    except OSError:  # an unreadable folder on the way: what was found so far
        pass
    return candidates


def _srdf_robot_name(path: Path) -> str | None:
    try:
        with path.open("rb") as handle:
            return robot_name(handle.read(_HEAD_BYTES))
    except OSError:
        return None
