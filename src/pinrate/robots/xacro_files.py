"""``.xacro`` files expanded to URDF text, by xacrodoc (xacro without ROS): ``pip install 'pinrate[xacro]'``.

xacro's ``$(find pkg)`` is answered by :func:`pinrate.kinematics.urdf_meshes.find_package` over
the same folders ``package://`` meshes are looked up in (the loader's one search list): xacrodoc's
own package finder is replaced while a file expands, and put back after. ``package://`` URIs are
left in the text; the expanded text is then loaded like any URDF, every mesh resolved and
confined to those folders (:mod:`pinrate.kinematics.urdf_meshes`).
"""

from __future__ import annotations

import threading
import xml.parsers.expat
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

from ..errors import InputError, LoadError, choices_hint
from ..kinematics.urdf_meshes import find_package

INSTALL = "pip install 'pinrate[xacro]'"
"""What a ``.xacro`` file needs (xacrodoc, and xacro, rospkg under it)."""

_EXPANDING = threading.Lock()  # xacro and xacrodoc keep their state in module globals


def is_xacro(path: Path) -> bool:
    """Whether ``path`` names a xacro file (``robot.urdf.xacro``, ``robot.xacro``)."""
    return path.name.endswith(".xacro")


def checked_arguments(arguments: object) -> dict[str, str]:
    """``xacro_args`` as a dict of names to strings; InputError otherwise."""
    if not isinstance(arguments, Mapping):
        raise InputError(f"xacro_args must be a mapping of names to values, got {arguments!r}")
    checked = {}
    for name, value in arguments.items():
        if not (isinstance(name, str) and name.strip()):
            raise InputError(f"xacro_args: an argument's name must be a non-empty string, got {name!r}")
        if not isinstance(value, str | int | float) or isinstance(value, bool):
            raise InputError(f"xacro_args[{name!r}] must be a string or a number, got {value!r}")
        checked[name] = str(value)
    return checked


def expand_xacro(path: Path, text: str, arguments: Mapping[str, str], search_dirs: Sequence[str]) -> str:
    """The URDF text of the xacro file at ``path`` (its text ``text``) with ``arguments`` as its
    ``xacro:arg`` values; packages found in ``search_dirs``. LoadError naming the file and the
    cause: xacrodoc not installed, an argument the file does not declare, a package not found,
    malformed XML, any error of the expansion."""
    xacro, xacrodoc, packages = _expander(path)

    def lookup(name: str) -> str:
        folder = find_package(name, search_dirs)
        if folder is None:
            raise packages.PackageNotFoundError(name)
        return folder

    given = _Arguments(arguments)
    finder = packages.PackageFinder()
    finder.finder_funcs = [(lookup, packages.PackageNotFoundError)]
    with _EXPANDING:
        saved = packages._finder
        packages._finder = finder
        xacro.init_stacks(str(path))  # includes by relative path: from the file's folder
        try:
            urdf: str = xacrodoc.XacroDoc.from_string(text, subargs=given, resolve_packages=False).to_urdf_string()
        except Exception as error:  # the expander's errors are of many kinds: each one becomes a LoadError
            raise LoadError(f"{path}: xacro could not expand it: {_cause(error, packages, search_dirs)}") from None
        finally:
            packages._finder = saved
            xacro.init_stacks(None)
    unknown = [name for name in arguments if name not in given.declared]
    if unknown:
        declared = sorted(given.declared)
        raise LoadError(
            f"{path}: xacro argument {unknown[0]!r} is not declared by the file (no <xacro:arg> of that name)."
            + (choices_hint(unknown[0], declared) if declared else " It declares no xacro:arg.")
        )
    return urdf


def _expander(path: Path) -> tuple[Any, Any, Any]:
    try:
        import xacro
        import xacrodoc
        from xacrodoc import packages
    except ImportError as error:
        raise LoadError(
            f"{path}: a .xacro file is expanded by xacrodoc, which is not installed ({error}): {INSTALL}"
        ) from None
    return xacro, xacrodoc, packages


class _Arguments(dict[str, str]):
    """The arguments given, recording the names the file declares: xacro asks ``name in
    arguments`` for each ``<xacro:arg name=...>`` before it sets the default."""

    def __init__(self, given: Mapping[str, str]) -> None:
        super().__init__(given)
        self.declared: set[str] = set()

    def __contains__(self, name: object) -> bool:
        if isinstance(name, str):
            self.declared.add(name)
        return super().__contains__(name)


def _cause(error: BaseException, packages: Any, search_dirs: Sequence[str]) -> str:
    """What went wrong, in one line: the innermost cause xacro wraps (its ``exc``)."""
    inner: BaseException = error
    while isinstance(getattr(inner, "exc", None), BaseException):
        inner = inner.exc  # type: ignore[attr-defined]
    if isinstance(inner, packages.PackageNotFoundError):
        return (
            f"package {inner.args[0]!r} not found (searched for a package.xml naming it, or a folder of that name, "
            f"in: {', '.join(search_dirs)})"
        )
    if isinstance(inner, xml.parsers.expat.ExpatError):
        return f"malformed XML ({inner})"
    message = " ".join(str(error).split()) or type(error).__name__
    return message if len(message) <= 400 else message[:400] + "..."
