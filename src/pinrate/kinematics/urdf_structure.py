"""What a URDF must be before Pinocchio sees it: one tree of named links and joints, finite
numbers, and a size Pinocchio can hold.

urdfdom (Pinocchio's parser) reports most of these faults only as "does not contain a valid
URDF model", with the reason on the C++ stderr; a few it accepts and builds a corrupt model
from (a link with two parent joints), and a deep enough chain crashes it. These checks run
on the parsed XML first, so every refusal is a :class:`~pinrate.errors.LoadError` that names
the joint or link.

Size: Pinocchio's ``Data`` holds several nv x nv and 6 x nv x nv arrays, so its memory grows
with the cube of the joint count (measured with pin 4.1: 100 joints 0.15 GB, 200 joints
0.6 GB, 300 joints 1.8 GB, 500 joints 8 GB), and urdfdom's recursive tree walk overflows the
stack past about 3000 links in one chain. :data:`MAX_JOINTS` bounds the moving joints
(override with ``load(..., max_joints=N)``, ``--max-joints N`` or ``PINRATE_MAX_JOINTS``);
:data:`MAX_DEPTH` bounds the links in one chain and is not overridable.
"""

from __future__ import annotations

import math
import os
import xml.etree.ElementTree as ET
from collections.abc import Iterable

from ..checks import PHYSICAL_BOUND
from ..errors import LoadError

MAX_JOINTS = 100
"""Default limit on a URDF's moving joints (Pinocchio's data for 100 joints: about 0.15 GB)."""

MAX_DEPTH = 1000
"""Most links in one chain from the root (urdfdom crashes past about 3000)."""

JOINT_TYPES = ("revolute", "continuous", "prismatic", "fixed", "floating", "planar")
"""The joint types of the URDF specification."""

_NEEDS_LIMIT = ("revolute", "prismatic")


def max_joints_default() -> int:
    """:data:`MAX_JOINTS`, or the ``PINRATE_MAX_JOINTS`` environment variable when set."""
    text = os.environ.get("PINRATE_MAX_JOINTS")
    if text is None:
        return MAX_JOINTS
    try:
        value = int(text)
    except ValueError:
        value = 0
    if value < 1:
        raise LoadError(f"PINRATE_MAX_JOINTS must be a positive integer, got {text!r}")
    return value


def check_structure(root: ET.Element, label: str, *, max_joints: int) -> None:
    """Refuse a URDF whose tree, numbers or size Pinocchio cannot turn into a sound model.

    Checks, naming the joint or link: every link and joint is named, once; joint types are
    the specification's; each joint's parent and child links exist; no link has two parent
    joints; exactly one root and no cycle; revolute and prismatic joints carry a
    ``<limit>``; a ``<limit>`` has effort and velocity, lower <= upper and velocity >= 0;
    origins, axes and limits are finite numbers, origins and axes within
    :data:`~pinrate.checks.PHYSICAL_BOUND`; an axis is not zero; at most ``max_joints``
    moving joints and :data:`MAX_DEPTH` links in a chain.
    """
    links = _unique_names(root.findall("link"), "link", label)
    joints = root.findall("joint")
    _unique_names(joints, "joint", label)

    moving = sum(1 for joint in joints if joint.get("type") != "fixed")
    if moving > max_joints:
        raise LoadError(
            f"{label}: {moving} moving joints, more than pinrate's limit of {max_joints} (Pinocchio's data "
            "grows with the cube of the joint count); to load it anyway pass max_joints= to pinrate.load, "
            "--max-joints to the command line, or set PINRATE_MAX_JOINTS"
        )

    parent_of: dict[str, str] = {}  # child link -> parent link
    joint_of: dict[str, str] = {}  # child link -> joint
    for joint in joints:
        name = joint.get("name", "")
        where = f"{label}: joint {name!r}"
        kind = joint.get("type")
        if kind not in JOINT_TYPES:
            shown = "no type" if kind is None else f"unknown type {kind!r}"
            raise LoadError(f"{where} has {shown} (URDF joint types: {', '.join(JOINT_TYPES)})")
        parent, child = (_link_reference(joint, role, links, where) for role in ("parent", "child"))
        if child in joint_of:
            raise LoadError(
                f"{where}: link {child!r} already has the parent joint {joint_of[child]!r}; "
                "a link has at most one parent joint"
            )
        if parent == child:
            raise LoadError(f"{where} connects link {child!r} to itself")
        parent_of[child], joint_of[child] = parent, name
        _check_origins(joint, where)
        _check_axis(joint, where, kind)
        _check_limit(joint, where, kind)
    for link in root.findall("link"):
        _check_origins(link, f"{label}: link {link.get('name')!r}")

    roots = [link for link in links if link not in parent_of]
    if not links:
        raise LoadError(f"{label}: the URDF has no <link>")
    if len(roots) > 1:
        shown = ", ".join(repr(link) for link in roots[:5]) + (" ..." if len(roots) > 5 else "")
        raise LoadError(
            f"{label}: {len(roots)} root links ({shown}); a URDF is one tree, so every link but one "
            "must be the child of a joint"
        )
    _check_depths(parent_of, roots, label)


def _unique_names(elements: Iterable[ET.Element], kind: str, label: str) -> list[str]:
    names: list[str] = []
    seen: set[str] = set()
    for element in elements:
        name = element.get("name")
        if not name:
            raise LoadError(f"{label}: a <{kind}> has no name")
        if name in seen:
            raise LoadError(f"{label}: two {kind}s are named {name!r}; {kind} names must be unique")
        seen.add(name)
        names.append(name)
    return names


def _link_reference(joint: ET.Element, role: str, links: list[str], where: str) -> str:
    element = joint.find(role)
    link = None if element is None else element.get("link")
    if not link:
        raise LoadError(f"{where} has no <{role} link=...>")
    if link not in links:
        raise LoadError(f"{where}: its {role} link {link!r} is not defined (no <link name={link!r}>)")
    return link


def _numbers(
    element: ET.Element, attribute: str, count: int, where: str, bound: float = math.inf
) -> list[float] | None:
    """The ``count`` finite numbers (within ±``bound``) of an attribute (None when absent)."""
    text = element.get(attribute)
    if text is None:
        return None
    parts = text.split()
    try:
        values = [float(part) for part in parts]
    except ValueError:
        values = []
    if len(parts) != count or len(values) != count or not all(abs(value) <= bound for value in values):
        expected = "a finite number" if count == 1 else f"{count} finite numbers"
        expected += f" within ±{bound:g}" if math.isfinite(bound) else ""
        raise LoadError(f"{where}: <{element.tag} {attribute}={text!r}> must be {expected}")
    return values


def _check_origins(owner: ET.Element, where: str) -> None:
    for origin in owner.iter("origin"):
        _numbers(origin, "xyz", 3, where, PHYSICAL_BOUND)
        _numbers(origin, "rpy", 3, where, PHYSICAL_BOUND)


def _check_axis(joint: ET.Element, where: str, kind: str) -> None:
    axis = joint.find("axis")
    if axis is None:
        return
    values = _numbers(axis, "xyz", 3, where, PHYSICAL_BOUND)
    if values is not None and kind != "fixed" and math.hypot(*values) < 1e-9:
        raise LoadError(f"{where}: its axis is zero ({axis.get('xyz')!r}); give a direction such as '0 0 1'")


def _check_limit(joint: ET.Element, where: str, kind: str) -> None:
    limit = joint.find("limit")
    if limit is None:
        if kind in _NEEDS_LIMIT:
            raise LoadError(f"{where} is {kind} but has no <limit> (URDF requires lower, upper, effort and velocity)")
        return
    values = {name: _numbers(limit, name, 1, where) for name in ("lower", "upper", "effort", "velocity")}
    missing = [name for name in ("effort", "velocity") if values[name] is None]
    if missing:  # urdfdom refuses a <limit> without both, whatever the joint type
        raise LoadError(f"{where}: its <limit> has no {' and no '.join(missing)} (URDF requires both)")
    # urdfdom reads an absent lower or upper as 0.
    lower, upper = ((values[name] or [0.0])[0] for name in ("lower", "upper"))
    if lower > upper:
        missing_note = "" if values["lower"] and values["upper"] else " (an absent lower or upper limit is 0)"
        raise LoadError(f"{where}: its lower limit {lower:g} is above its upper limit {upper:g}{missing_note}")
    velocity = values["velocity"]
    if velocity is not None and velocity[0] < 0:
        raise LoadError(f"{where}: its velocity limit {velocity[0]:g} is negative")


def _check_depths(parent_of: dict[str, str], roots: list[str], label: str) -> None:
    """Every link reaches the root in at most MAX_DEPTH joints; a link that never does sits on
    a cycle."""
    depth: dict[str, int] = dict.fromkeys(roots, 0)
    for start in parent_of:
        path: list[str] = []
        link = start
        while link not in depth:
            if link in path:
                raise LoadError(f"{label}: the joints form a cycle through link {link!r}")
            path.append(link)
            link = parent_of[link]
        base = depth[link]
        for offset, on_path in enumerate(reversed(path), start=1):
            depth[on_path] = base + offset
        if depth[start] > MAX_DEPTH:
            raise LoadError(
                f"{label}: link {start!r} is {depth[start]} joints from the root, more than pinrate's "
                f"limit of {MAX_DEPTH} links in one chain (urdfdom's parser crashes on such chains)"
            )
