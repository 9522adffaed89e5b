"""Sphinx configuration of pinrate's API reference, built from the docstrings.

``make api`` builds it to build/api with ``-W --keep-going -n`` (warnings are errors, every
cross-reference must resolve); tests/test_api_docs.py does the same in a temporary folder.
No intersphinx: CI reaches only the package registries, so the names of other projects
(numpy, Pinocchio, the standard library's classes) are listed in ``nitpick_ignore_regex``,
and no name of pinrate's own is.

Each object is documented once, in the module that defines it (``automodule`` with
``:members:`` and ``:ignore-module-all:``, so a module's re-exports are not documented again);
a package's page lists its ``__all__`` with links to those homes (``pinrate-exports``), and
the build fails if a module of pinrate is on no page.
"""

from __future__ import annotations

import ast
import importlib
import importlib.util
import inspect
import pkgutil
import re
import typing
from pathlib import Path
from types import ModuleType
from typing import Any

from docutils import nodes
from docutils.statemachine import StringList
from sphinx.addnodes import pending_xref
from sphinx.application import Sphinx
from sphinx.ext.napoleon import Config as NapoleonConfig
from sphinx.ext.napoleon.docstring import GoogleDocstring
from sphinx.util import logging
from sphinx.util.docutils import SphinxDirective

import pinrate

project = "pinrate"
author = "pinrate developers"
copyright = "pinrate developers"
release = version = pinrate.__version__

extensions = ["sphinx.ext.autodoc"]
root_doc = "index"
html_theme = "alabaster"

# The docstrings are Google style ("Args:", "Returns:", "Raises:", "Attributes:"): read by
# napoleon's GoogleDocstring (see google_sections), not by the napoleon extension itself,
# which would read the first line of a constant's docstring, "The URL to open: ...", as a type.
NAPOLEON = NapoleonConfig(napoleon_google_docstring=True, napoleon_numpy_docstring=False)

autodoc_default_options = {"members": True, "ignore-module-all": True}
autodoc_member_order = "bysource"
autodoc_inherit_docstrings = False  # each object's own docstring (none for argparse's error())

nitpicky = True
# Other projects' names (no intersphinx: see above). Never one of pinrate's own.
nitpick_ignore_regex = [
    (r"py:.*", r"(np|numpy)\..*"),  # np.ndarray, numpy.typing.NDArray, ...
    (r"py:.*", r"(pin|pinocchio)\..*"),  # pin.SE3, pinocchio.Model, ...
    (r"py:.*", r"(meshcat|tornado|matplotlib|dask|distributed)\..*"),
    # The standard library's classes (its builtins and typing's names resolve without this).
    (r"py:.*", r"(collections\.abc|pathlib|os|argparse|types|threading|zipfile|xml\.etree\.ElementTree)\.\w+"),
]

logger = logging.getLogger(__name__)

PENDING: set[tuple[str, str]] = set()
"""(module, target) of unresolved references waiting for a docstring of their own (none now)."""


def home(module: str, name: str) -> str | None:
    """Where the object that ``name`` is bound to in ``module`` is documented: a class's or a
    function's own module, a module itself, or for data (and names imported only for type
    checking) the module whose top level assigns it, found by following the chain of
    ``from ... import name``. None when ``module`` binds no such name."""
    value = getattr(importlib.import_module(module), name, None)
    if isinstance(value, ModuleType):
        return value.__name__
    # typing.get_origin: a type alias (tuple[...], Callable[...]) counts as a class on Python
    # 3.10 but is data, documented where it is assigned.
    if (inspect.isclass(value) or inspect.isfunction(value)) and typing.get_origin(value) is None:
        return f"{value.__module__}.{value.__qualname__}"
    while True:
        tree = ast.parse(inspect.getsource(importlib.import_module(module)))
        source = next(
            (
                importlib.util.resolve_name("." * node.level + (node.module or ""), package_of(module))
                for node in ast.walk(tree)
                if isinstance(node, ast.ImportFrom) and any((a.asname or a.name) == name for a in node.names)
            ),
            None,
        )
        if source is None:
            return f"{module}.{name}" if defines(tree, name) else None
        if is_package(source) and importlib.util.find_spec(f"{source}.{name}") is not None:
            return f"{source}.{name}"  # from . import module, for type checking only
        module = source


def defines(tree: ast.Module, name: str) -> bool:
    """Whether a module's top level assigns ``name`` or defines a class or function of that name."""
    for node in tree.body:
        if isinstance(node, ast.ClassDef | ast.FunctionDef) and node.name == name:
            return True
        targets = (
            node.targets if isinstance(node, ast.Assign) else [node.target] if isinstance(node, ast.AnnAssign) else []
        )
        if any(isinstance(t, ast.Name) and t.id == name for target in targets for t in ast.walk(target)):
            return True
    return False


def is_module(name: str) -> bool:
    if name.endswith("__main__"):  # importing it runs the command line
        return False
    try:
        importlib.import_module(name)
    except ImportError:
        return False
    return True


def is_package(module: str) -> bool:
    return hasattr(importlib.import_module(module), "__path__")


def package_of(module: str) -> str:
    """The package a relative import in ``module`` is resolved against."""
    return module if is_package(module) else module.rpartition(".")[0]


class Exports(SphinxDirective):
    """``.. pinrate-exports:: pinrate.control``: the package's ``__all__``, each name linked to
    its one description (an unresolved link fails the build: every export is documented)."""

    required_arguments = 1

    def run(self) -> list[nodes.Node]:
        package = self.arguments[0]
        lines = []
        for name in importlib.import_module(package).__all__:
            target = home(package, name)
            where = target if is_module(target) else target.rpartition(".")[0]
            lines.append(f"* :py:obj:`{name} <{target}>`, in :py:mod:`{where}`")
        container = nodes.container()
        self.state.nested_parse(StringList(lines, source=self.get_source_info()[0]), self.content_offset, container)
        return container.children


def bound_name(app: Sphinx, env: Any, node: pending_xref, contnode: nodes.TextElement) -> nodes.reference | None:
    """A reference to a name as Python binds it: ``pinrate.Robot`` (a package's re-export), or
    in a module's docstring ``Controller`` where that module imports it, links to the one
    description of the object, in its home module. A name no module binds stays unresolved."""
    if node.get("refdomain") != "py":
        return None
    target = node["reftarget"]
    module = node.get("py:module")
    for dotted in [target] if module is None else [f"{module}.{target}", target]:
        parts = dotted.split(".")
        for split in range(len(parts) - 1, 0, -1):  # the longest prefix that is a module of pinrate
            prefix = ".".join(parts[:split])
            if not (prefix == "pinrate" or prefix.startswith("pinrate.")) or not is_module(prefix):
                continue
            found = home(prefix, parts[split])
            if found is not None and found != ".".join(parts[: split + 1]):
                resolved = ".".join([found, *parts[split + 1 :]])
                retry = node.deepcopy()
                retry["reftarget"] = resolved
                retry.attributes.pop("refspecific", None)
                domain = env.get_domain("py")
                # A type alias (Axis, Inverter) is data, not a class: an annotation's
                # :class: link to one resolves as any object (Sphinx 8.1 links them so).
                for role in (node["reftype"], "obj"):
                    reference = domain.resolve_xref(env, node["refdoc"], app.builder, role, resolved, retry, contnode)
                    if reference is not None:
                        return reference
            break
    return None


def pending(app: Sphinx, domain: Any, node: pending_xref) -> bool | None:
    """True (no warning) for the unresolved references listed in ``PENDING``."""
    return True if (node.get("py:module"), node.get("reftarget")) in PENDING else None


def google_sections(app: Sphinx, what: str, name: str, obj: Any, options: Any, lines: list[str]) -> None:
    """The Google-style sections of a module's, class's or function's docstring, as napoleon
    reads them; a constant's or an attribute's docstring is prose (no sections, no type)."""
    if what not in ("data", "attribute", "property"):
        lines[:] = GoogleDocstring(lines, NAPOLEON, app, what, name, obj, options).lines()


def skip_tuple_fields(app: Sphinx, what: str, name: str, obj: Any, skip: bool, options: Any) -> bool | None:
    """A NamedTuple's fields are described by its own docstring, not as "Alias for field number 0"."""
    if what == "class" and re.fullmatch(r"Alias for field number \d+", getattr(obj, "__doc__", None) or ""):
        return True
    return None


def every_module_has_a_page(app: Sphinx, env: Any) -> None:
    """The build fails when a module of pinrate is documented on no page."""
    package = Path(pinrate.__file__).parent
    modules = {"pinrate"} | {
        info.name
        for info in pkgutil.walk_packages([str(package)], prefix="pinrate.")
        if not info.name.endswith("__main__")  # importing it runs the command line
    }
    documented = set(env.get_domain("py").modules)
    for name in sorted(modules - documented):
        logger.warning("pinrate's module %s is on no page of the API reference", name)


def setup(app: Sphinx) -> dict[str, Any]:
    app.add_directive("pinrate-exports", Exports)
    app.connect("autodoc-process-docstring", google_sections)
    app.connect("missing-reference", bound_name)
    app.connect("warn-missing-reference", pending)
    app.connect("autodoc-skip-member", skip_tuple_fields)
    app.connect("env-check-consistency", every_module_has_a_page)
    return {"parallel_read_safe": True}
