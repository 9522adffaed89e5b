"""``pinrate.load``: a robot from a URDF path, a papers' robot name or an example-robot-data name."""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence
from pathlib import Path

from ..checks import check_count
from ..errors import InputError, LoadError, choices_hint
from ..kinematics.manipulator import Robot
from ..kinematics.urdf import read_urdf, robot_from_urdf
from ..kinematics.urdf_meshes import ros_package_dirs
from . import parametric
from .catalog import EXAMPLE_ROBOTS, CatalogEntry, example_robot_data_share, example_robot_path
from .srdf_files import find_srdf, robot_name
from .xacro_files import checked_arguments, expand_xacro, is_xacro


def known_names() -> list[str]:
    """Every name :func:`load` accepts: the papers' robots, then example-robot-data's."""
    return [*parametric.ROBOT_NAMES, *EXAMPLE_ROBOTS]


def load(
    source: str | os.PathLike[str],
    *,
    tip: str | None = None,
    sensor: str | None = None,
    max_joints: int | None = None,
    package_dirs: Sequence[str | os.PathLike[str]] = (),
    xacro_args: Mapping[str, str] | None = None,
) -> Robot:
    """Load a robot from a URDF or xacro path, a papers'-robot name or an example-robot-data name.

    Args:
        source: a path to a ``.urdf`` file, or to a ``.xacro`` file (``robot.urdf.xacro``,
            ``robot.xacro``), expanded first by xacrodoc (``pip install 'pinrate[xacro]'``);
            or a name from :func:`known_names` (the papers' robots such as ``"scara"``, and
            ``"ur5"``, ``"panda"``, ...). A URDF's home comes from the SRDF beside it with the
            same stem (``robot.srdf`` for ``robot.urdf``, ``robot.urdf.xacro`` and ``robot.xacro``),
            else from a MoveIt config package next to its package whose SRDF names the same
            robot (:mod:`pinrate.robots.srdf_files`).
        tip: the frame whose origin is the TCP (a link, joint or fixed frame; a name that is
            both a link and a joint means the link). Default: the name table's tip; for any
            other URDF, the tool frame of the main arm, gripper and hand joints left out
            (:func:`pinrate.kinematics.frames.default_tip_frame`; ``robot.tip_choice`` says why).
        sensor: the frame whose axes twists are expressed in. Default: the tip.
        max_joints: refuse URDFs with more moving joints (default
            :data:`pinrate.kinematics.urdf_structure.MAX_JOINTS`, 100, or the
            ``PINRATE_MAX_JOINTS`` environment variable): Pinocchio's data grows with the
            cube of the joint count.
        package_dirs: more folders for ``package://`` mesh URIs, searched before the
            defaults (the URDF's folder and three of its ancestors, example-robot-data, then
            ROS_PACKAGE_PATH's and AMENT_PREFIX_PATH's, as Pinocchio adds them). A mesh is read
            only from inside these folders (the filesystem's root excepted), once ``..`` and
            symbolic links are resolved; any other mesh is left out with a warning naming it
            (:mod:`pinrate.kinematics.urdf_meshes`). The same folders answer a xacro file's
            ``$(find pkg)``: the first that is the package (its ``package.xml`` names it, or
            without one its name is ``pkg``) or holds a folder ``pkg``.
        xacro_args: a ``.xacro`` file's ``xacro:arg`` values, ``{"name": "value"}`` (as
            ``xacro robot.urdf.xacro name:=value``); each must be declared by the file.

    Raises:
        LoadError: missing file, malformed XML, not a URDF, a xacro file that cannot be
            expanded (xacrodoc not installed, an undeclared argument, a package not found:
            the message says which), a structure fault (named joint or link), too many
            joints, no moving joint, unknown robot name.
        FrameError: unknown tip or sensor frame (the message lists the frames).
        InputError: a tip or sensor that is not a name ("" is not the default: None is);
            ``xacro_args`` for a source that is not a ``.xacro`` file.
    """
    if max_joints is not None:
        check_count(max_joints, "max_joints", minimum=1)
    for role, frame in (("tip", tip), ("sensor", sensor)):
        if frame is not None and not (isinstance(frame, str) and frame.strip()):
            raise InputError(f"{role} must name a frame (or be None for the default), got {frame!r}")
    if isinstance(source, os.PathLike) or (isinstance(source, str) and _looks_like_path(source)):
        try:
            path = Path(source).expanduser().resolve()
        except (OSError, RuntimeError, ValueError) as error:  # a NUL byte, ~unknownuser, a loop
            raise LoadError(f"URDF path {str(source)[:200]!r} cannot be resolved: {error}") from None
        search_dirs = [*_checked_dirs(package_dirs), *_package_dirs_for(path), *ros_package_dirs()]
        arguments = checked_arguments({} if xacro_args is None else xacro_args)
        if arguments and not is_xacro(path):
            raise InputError(f"xacro_args are for a .xacro file, and {path.name!r} is not one")
        text, encoding = read_urdf(path)
        if is_xacro(path):
            text, encoding = expand_xacro(path, text, arguments, search_dirs), "xacro"
        return robot_from_urdf(
            text,
            label=str(path),
            tip=tip,
            sensor=sensor,
            # urdfdom reads files as UTF-8: the visuals of a file in another encoding come from the text
            urdf_path=path if encoding in ("utf-8", "ascii") else None,
            package_dirs=search_dirs,
            max_joints=max_joints,
            srdf_path=find_srdf(path, robot_name(text)),
            search_home=True,
            confine=True,
        )
    if xacro_args:
        raise InputError(f"xacro_args are for a .xacro file, and {source!r} is a robot name")
    if not isinstance(source, str):
        raise InputError(f"source must be a URDF path or a robot name, not {type(source).__name__}")
    if source in parametric.ROBOT_NAMES:
        return parametric.build(source, tip=tip, sensor=sensor)
    entry = EXAMPLE_ROBOTS.get(source)
    if entry is None:
        raise LoadError(f"unknown robot name {source!r}." + choices_hint(source, known_names()))
    return _load_example_robot(entry, tip=tip, sensor=sensor)


def _looks_like_path(source: str) -> bool:
    return source.endswith((".urdf", ".xml", ".xacro")) or os.sep in source or "/" in source


def _checked_dirs(package_dirs: object) -> list[str]:
    if isinstance(package_dirs, str | os.PathLike):
        package_dirs = [package_dirs]
    try:
        folders = [Path(folder).expanduser() for folder in package_dirs]  # type: ignore[attr-defined]
    except TypeError:
        raise InputError(f"package_dirs must be a list of folders, got {package_dirs!r}") from None
    for folder in folders:
        if not folder.is_dir():
            raise InputError(f"package_dirs: {str(folder)!r} is not a folder")
    return [str(folder) for folder in folders]


def _package_dirs_for(path: Path) -> list[str]:
    """Folders ``package://`` URIs may resolve against: the file's ancestors, example-robot-data."""
    dirs = [str(parent) for parent in list(path.parents)[:4]]
    share = example_robot_data_share()
    if share is not None:
        dirs.append(str(share))
    return dirs


def _load_example_robot(entry: CatalogEntry, *, tip: str | None, sensor: str | None) -> Robot:
    path = example_robot_path(entry.urdf)
    srdf = example_robot_path(entry.srdf) if entry.srdf else None
    share = example_robot_data_share()
    return robot_from_urdf(
        read_urdf(path)[0],
        label=entry.name,
        tip=tip or entry.tip,
        sensor=sensor,
        urdf_path=path,
        package_dirs=[*([str(share)] if share else []), *ros_package_dirs()],
        srdf_path=srdf,
        home=entry.home,
        home_values=entry.home_values,
        name=entry.name,
        confine=True,
    )
