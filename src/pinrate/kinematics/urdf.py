"""A :class:`~pinrate.kinematics.manipulator.Robot` from URDF text: parsing, SRDF homes, specs.

The common path of every way of loading (:func:`pinrate.load` picks the text; this module
turns it into a model). Parsing is Pinocchio's; the XML is read once here only to refuse a
non-URDF with a clear message.
"""

from __future__ import annotations

import functools
import math
import warnings
import xml.etree.ElementTree as ET
from collections.abc import Mapping, Sequence
from pathlib import Path

import numpy as np
import pinocchio as pin

from ..errors import LoadError
from .manipulator import Robot, RobotSpec


# ---------------------------------------------------------------------- loading
def read_urdf(path: Path) -> str:
    """The text of a URDF file; LoadError naming the path when it is missing or a folder."""
    if not path.exists():
        raise LoadError(f"URDF file not found: {path}")
    if not path.is_file():
        raise LoadError(f"URDF path is not a file: {path}")
    return path.read_text(encoding="utf-8", errors="replace")


def _check_urdf_text(text: str, label: str) -> ET.Element:
    """The URDF's root element; LoadError naming ``label`` for malformed XML or a non-URDF."""
    try:
        root = ET.fromstring(text)
    except ET.ParseError as error:
        raise LoadError(f"{label}: malformed XML ({error})") from None
    if root.tag != "robot":
        raise LoadError(f"{label}: not a URDF (root element is <{root.tag}>, expected <robot>)")
    return root


def _build_model(text: str, label: str) -> pin.Model:
    try:
        return pin.buildModelFromXML(text)
    except (ValueError, RuntimeError) as error:
        detail = " ".join(str(error).split())
        raise LoadError(f"{label}: Pinocchio could not build a model: {detail}") from None


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
) -> Robot:
    """A Robot from URDF text: the common path of every way of loading."""
    root = _check_urdf_text(text, label)
    model = _build_model(text, label)
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
        references["home"] = into_limits(model, references["home"])
    robot_name = name or root.get("name") or label
    return Robot(
        model,
        tip=tip,
        sensor=sensor,
        name=robot_name,
        urdf_path=urdf_path,
        urdf_text=text,
        package_dirs=package_dirs,
        reference_configurations=references,
    )


def into_limits(model: pin.Model, q: np.ndarray) -> np.ndarray:
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
