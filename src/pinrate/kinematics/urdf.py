"""A :class:`~pinrate.kinematics.manipulator.Robot` from URDF text: parsing, SRDF homes, specs.

The common path of every way of loading (:func:`pinrate.load` picks the text; this module
turns it into a model). Parsing is Pinocchio's; the XML is read once here only to refuse a
non-URDF with a clear message.
"""

from __future__ import annotations

import codecs
import contextlib
import functools
import math
import os
import re
import sys
import tempfile
import warnings
import xml.etree.ElementTree as ET
from collections.abc import Iterator, Mapping, Sequence
from pathlib import Path

import numpy as np
import pinocchio as pin

from ..checks import check_count
from ..errors import LoadError
from .home import srdf_states
from .manipulator import Robot, RobotSpec
from .mimic import Mimic
from .urdf_meshes import confine_meshes, mesh_roots
from .urdf_structure import check_structure, max_joints_default

# ---------------------------------------------------------------------- loading
_BOMS = (
    (codecs.BOM_UTF32_LE, "utf-32"),
    (codecs.BOM_UTF32_BE, "utf-32"),
    (codecs.BOM_UTF8, "utf-8-sig"),
    (codecs.BOM_UTF16_LE, "utf-16"),
    (codecs.BOM_UTF16_BE, "utf-16"),
)
_DECLARATION = re.compile(r"""^\s*<\?xml[^>]*?encoding\s*=\s*["']([A-Za-z0-9._-]+)["'][^>]*\?>""")
_ANY_DECLARATION = re.compile(r"^\s*<\?xml[^>]*\?>")


def read_urdf(path: Path) -> tuple[str, str]:
    """The text of a URDF (or xacro) file and the encoding it was read in; LoadError naming
    the path when it is missing or a folder, or not decodable in its declared encoding."""
    try:
        if not path.exists():
            raise LoadError(f"URDF file not found: {path}")
        if not path.is_file():
            raise LoadError(f"URDF path is not a file: {path}")
        data = path.read_bytes()
    except OSError as error:  # too long a name, no permission, a device that fails
        raise LoadError(f"URDF file cannot be read: {str(path)[:200]} ({error.strerror or error})") from None
    return _decode_xml(data, str(path))


def _decode_xml(data: bytes, label: str) -> tuple[str, str]:
    """XML bytes as text, in the encoding its byte-order mark or declaration names (UTF-8
    when neither does, as XML 1.0 §4.3.3 says), and that encoding's name. The declaration
    itself is dropped, since the text no longer is in that encoding."""
    encoding = "utf-8"
    for bom, name in _BOMS:
        if data.startswith(bom):
            encoding = name
            break
    else:
        if data.startswith(b"<\x00"):
            encoding = "utf-16-le"
        elif data.startswith(b"\x00<"):
            encoding = "utf-16-be"
        else:
            declared = _DECLARATION.match(data[:256].decode("latin-1"))
            if declared:
                encoding = declared.group(1)
    try:
        text = data.decode(encoding)
    except LookupError:  # also a bytes-to-bytes codec such as base64
        raise LoadError(f"{label}: unknown XML encoding {encoding!r} in its declaration") from None
    except UnicodeDecodeError as error:
        raise LoadError(
            f"{label}: not valid {encoding} text at byte {error.start}"
            + ("" if encoding != "utf-8" else ' (declare its encoding: <?xml version="1.0" encoding="..."?>)')
        ) from None
    except (UnicodeError, ValueError) as error:  # codecs such as punycode raise other errors
        raise LoadError(f"{label}: cannot be read as {encoding!r}, the encoding it declares ({error})") from None
    try:  # UTF-7 decodes to lone surrogates, which no XML parser (nor Pinocchio) takes
        text.encode("utf-8")
    except UnicodeEncodeError as error:
        raise LoadError(f"{label}: not valid {encoding} text: a lone surrogate at character {error.start}") from None
    return _ANY_DECLARATION.sub("", text, count=1), codecs.lookup(encoding).name


_XACRO_HINT = (
    "{label}: this is a xacro file, not a URDF: name it robot.urdf.xacro (pinrate expands a .xacro file, "
    "with pinrate[xacro]), or expand it first and load the result"
)


_PREFIXED_NAME = re.compile(r"[<\s/]([A-Za-z_][\w.-]*):[A-Za-z_][\w.-]*")
_ROBOT_START = re.compile(r"<robot(?=[\s>/])")


def _parse_like_urdfdom(text: str) -> ET.Element:
    """The XML tree as urdfdom (through tinyxml2, which knows no namespaces) sees it.

    Prefixes that the file uses without declaring them (``drake:acceleration``, a common
    foreign extension) are declared for the parse, so they stay foreign elements and
    attributes instead of making the file malformed; a default namespace on ``<robot>`` is
    dropped, so ``<link>`` is a link whatever ``xmlns`` says. Raises ``ET.ParseError``.
    """
    try:
        root = ET.fromstring(text)
    except ET.ParseError as error:
        if "unbound prefix" not in str(error):
            raise
        prefixes = sorted(set(_PREFIXED_NAME.findall(text)) - {"xml", "xmlns"})
        declarations = "".join(f' xmlns:{prefix}="urn:pinrate:undeclared:{prefix}"' for prefix in prefixes)
        root = ET.fromstring(_ROBOT_START.sub(lambda match: match.group(0) + declarations, text, count=1))
    if root.tag.startswith("{"):
        default = root.tag[: root.tag.index("}") + 1]
        for element in root.iter():
            if element.tag.startswith(default):
                element.tag = element.tag[len(default) :]
    return root


def _check_urdf_text(text: str, label: str, max_joints: int) -> ET.Element:
    """The URDF's root element; LoadError naming ``label`` for malformed XML, a non-URDF, a
    xacro, or a structure Pinocchio cannot build soundly (:mod:`.urdf_structure`)."""
    try:
        root = _parse_like_urdfdom(text)
    except ET.ParseError as error:
        if "<xacro:" in text:  # xacro without its namespace declared
            raise LoadError(_XACRO_HINT.format(label=label)) from None
        raise LoadError(f"{label}: malformed XML ({error})") from None
    # Expanded files often keep xmlns:xacro on <robot>; only xacro elements mean unexpanded.
    if any(element.tag.startswith("{") and "xacro" in element.tag.split("}")[0] for element in root.iter()):
        raise LoadError(_XACRO_HINT.format(label=label))
    if root.tag != "robot":
        raise LoadError(f"{label}: not a URDF (root element is <{root.tag}>, expected <robot>)")
    check_structure(root, label, max_joints=max_joints)
    return root


@contextlib.contextmanager
def _stderr_captured() -> Iterator[list[str]]:
    """Collect what C++ code writes to file descriptor 2 (urdfdom's reasons) into a list."""
    lines: list[str] = []
    sys.stderr.flush()
    saved = os.dup(2)
    try:
        with tempfile.TemporaryFile() as sink:
            os.dup2(sink.fileno(), 2)
            try:
                yield lines
            finally:
                os.dup2(saved, 2)
                sink.seek(0)
                lines.extend(sink.read().decode("utf-8", "replace").splitlines())
    finally:
        os.close(saved)


def _build_model(text: str, label: str) -> pin.Model:
    """Pinocchio's model of the URDF; urdfdom's reasons (which it writes to the C++ stderr)
    become the LoadError's message, or a warning when it built the model anyway (a
    malformed inertial or visual element is skipped, not refused)."""
    model, failure = None, ""
    with _stderr_captured() as messages:
        try:
            model = pin.buildModelFromXML(text)
        except (ValueError, RuntimeError) as error:
            failure = " ".join(str(error).split())
    reasons = [line.strip().removeprefix("Error:").strip() for line in messages if line.strip().startswith("Error:")]
    if model is None:
        raise LoadError(f"{label}: Pinocchio could not build a model: {'; '.join(reasons) or failure}")
    if reasons:
        warnings.warn(f"{label}: urdfdom skipped parts of the file: {'; '.join(reasons)}", stacklevel=4)
    return model


def robot_from_urdf(
    text: str,
    *,
    label: str,
    tip: str | None = None,
    sensor: str | None = None,
    urdf_path: Path | None = None,
    package_dirs: Sequence[str] = (),
    srdf_path: Path | None = None,
    home: str | None = None,
    home_values: Mapping[str, float] | None = None,
    name: str | None = None,
    max_joints: int | None = None,
    search_home: bool = False,
    confine: bool = False,
) -> Robot:
    """A Robot from URDF text: the common path of every way of loading.

    ``max_joints`` bounds the moving joints (default :func:`.urdf_structure.max_joints_default`).
    ``search_home``: a URDF without a curated home gets a well-conditioned one
    (:func:`.home.find_home`: the SRDF's ``home`` group_state, else its first, else a search).
    ``confine``: every mesh is resolved now in ``package_dirs`` (in that order) and kept only
    when its file lies inside one of them (:mod:`.urdf_meshes`); the others are left out, named
    in one warning, and the robot's geometry comes from the text with the kept files' paths.
    """
    limit = max_joints_default() if max_joints is None else check_count(max_joints, "max_joints", minimum=1)
    root = _check_urdf_text(text, label, limit)
    model = _build_model(text, label)
    geometry_text = text
    if confine:
        try:
            geometry_text, skipped = confine_meshes(text, package_dirs, mesh_roots(package_dirs))
        except ValueError as error:
            raise LoadError(f"{label}: its mesh file names could not be read ({error})") from None
        urdf_path = None  # the geometry is read from the text: every mesh in it checked, by its own path
        if skipped:
            warnings.warn(
                f"{label}: {len(skipped)} mesh{'es' if len(skipped) > 1 else ''} left out (the robot loads "
                f"without {'them' if len(skipped) > 1 else 'it'}): {'; '.join(skipped)}",
                stacklevel=3,
            )
    references: dict[str, np.ndarray] = {}
    if srdf_path is not None and srdf_path.is_file():
        try:
            pin.loadReferenceConfigurations(model, str(srdf_path), False)
            references = {entry.key(): np.array(entry.data()) for entry in model.referenceConfigurations}
        except (RuntimeError, ValueError) as error:
            warnings.warn(f"{label}: reference configurations not read from {srdf_path}: {error}", stacklevel=3)
    if home is not None and home in references:
        references["home"] = references[home].copy()
    if home_values:
        configuration = references.get("home", np.array(pin.neutral(model)))
        for joint, value in home_values.items():
            if model.existJointName(joint):
                configuration[model.joints[model.getJointId(joint)].idx_q] = value
        references["home"] = configuration
    if "home" in references:
        references["home"] = _into_limits(model, references["home"])
    robot_name = name or root.get("name") or label
    named: list[tuple[str, np.ndarray]] = []
    if search_home:
        states = srdf_states(srdf_path) if srdf_path is not None and srdf_path.is_file() else []
        order = [state for state in (["home"] if "home" in states else []) + states if state in references]
        named = [
            (f"SRDF group_state {state!r}", _into_limits(model, references[state])) for state in dict.fromkeys(order)
        ]
    robot = Robot(
        model,
        tip=tip,
        sensor=sensor,
        name=robot_name,
        urdf_path=urdf_path,
        urdf_text=geometry_text,
        package_dirs=package_dirs,
        reference_configurations=references,
        mimic=_mimic_joints(root),
        srdf_path=srdf_path,
        search_home=search_home,
        home_candidates=named,
    )
    return robot


def _mimic_joints(root: ET.Element) -> dict[str, Mimic]:
    """Joint -> its :class:`~.mimic.Mimic` relation, from the URDF's ``<mimic joint=...
    multiplier=... offset=...>`` elements (multiplier 1 and offset 0 where not given; Pinocchio
    has refused a value that is not a finite number before this runs). Pinocchio models them
    as independent joints; :mod:`.mimic` keeps the relation, :func:`.frames.hand_joints` tells
    a hand's from an arm's."""
    pairs = {}
    for joint in root.findall("joint"):
        mimic = joint.find("mimic")
        if mimic is not None and joint.get("name") and mimic.get("joint"):
            multiplier, offset = float(mimic.get("multiplier", "1")), float(mimic.get("offset", "0"))
            pairs[joint.get("name", "")] = Mimic(mimic.get("joint", ""), multiplier, offset)
    return pairs


def _into_limits(model: pin.Model, q: np.ndarray) -> np.ndarray:
    """q with each 1-DOF joint brought inside its limits: revolute ones by whole turns when
    that suffices (an SRDF pose may be written in another turn), else clamped."""
    q = q.copy()
    for joint_id in range(1, model.njoints):
        joint_model = model.joints[joint_id]
        if joint_model.nq != 1:
            continue
        i = joint_model.idx_q
        lower, upper = model.lowerPositionLimit[i], model.upperPositionLimit[i]
        if lower <= q[i] <= upper:
            continue
        if joint_model.shortname().startswith("JointModelR"):
            turned = q[i] + 2 * math.pi * math.ceil((lower - q[i]) / (2 * math.pi))
            if lower <= turned <= upper:
                q[i] = turned
                continue
        q[i] = min(max(q[i], lower), upper)
    return q


@functools.lru_cache(maxsize=8)
def robot_from_spec(spec: RobotSpec) -> Robot:
    """The robot of a spec (built once per process: worker processes reuse it)."""
    return robot_from_urdf(spec.urdf_text, label=spec.name, tip=spec.tip, sensor=spec.sensor, name=spec.name)
