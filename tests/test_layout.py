"""The package's shape: no name traps, no private module used across subpackages.

The layers themselves (imports only go down) are import-linter's contract in
pyproject.toml, which ``make test`` runs.
"""

from __future__ import annotations

import ast
import importlib
import itertools
import pkgutil
from pathlib import Path

import pytest

import pinrate

PACKAGE = Path(pinrate.__file__).parent
MODULES = sorted(
    info.name
    for info in pkgutil.walk_packages([str(PACKAGE)], prefix="pinrate.")
    if not info.name.endswith("__main__")  # running it would run the CLI
)


def one_edit_apart(a: str, b: str) -> bool:
    """Whether b is a with one letter inserted, deleted or replaced (or the same)."""
    if abs(len(a) - len(b)) > 1:
        return False
    if len(a) == len(b):
        return sum(x != y for x, y in zip(a, b, strict=True)) <= 1
    short, long = sorted((a, b), key=len)
    return any(long[:i] + long[i + 1 :] == short for i in range(len(long)))


def test_no_two_modules_are_named_alike() -> None:
    names = sorted({name.rsplit(".", 1)[-1] for name in MODULES} - {"__init__"})
    assert len(names) == len({name.rsplit(".", 1)[-1] for name in MODULES}), "two modules share a name"
    alike = [(a, b) for a, b in itertools.combinations(names, 2) if one_edit_apart(a, b)]
    assert not alike, f"module names one letter apart: {alike}"


@pytest.mark.parametrize("name", MODULES)
def test_importing_a_module_yields_the_module(name: str) -> None:
    """``import pinrate.x.y`` must give the module y, never a function its package exports."""
    module = importlib.import_module(name)
    parent, _, leaf = name.rpartition(".")
    assert getattr(importlib.import_module(parent), leaf) is module


def test_no_private_module_exists_or_is_imported_across_subpackages() -> None:
    private = [name for name in MODULES if name.rsplit(".", 1)[-1].startswith("_")]
    assert not private, f"private modules: {private}"
    for path in PACKAGE.rglob("*.py"):
        tree = ast.parse(path.read_text(encoding="utf-8"))
        for node in ast.walk(tree):
            if isinstance(node, ast.ImportFrom) and node.module:
                assert not any(part.startswith("_") for part in node.module.split(".") if part != "__future__"), (
                    f"{path.relative_to(PACKAGE)} imports from {node.module}"
                )


def test_no_import_inside_a_function_except_optional_dependencies() -> None:
    """Deferred imports only for what not every run needs (Dask, the browser viewer, the
    teleop console's server: meshcat and tornado; xacrodoc, the ``pinrate[xacro]`` extra;
    MuJoCo, the ``pinrate[mujoco]`` extra; matplotlib's plots for ``demo --plot``),
    and in the CLI's entry point, once the arguments are parsed and inside its Ctrl-C guard,
    the subcommand's module and the error it catches, and for ``--version`` the compiled
    core's bridge (so ``--help`` loads none); the CLI's package and its console script load
    the entry point itself only when called."""
    allowed = {
        "distributed",
        "pinrate.viewer",
        "viewer",
        "teleop.server",
        "xacro",
        "xacrodoc",
        "mujoco",
        "analysis.plots",
    }
    entry = {"robot_list", "demo", "analyze", "paper_results", "teleop", "errors", "compiled"}
    for path in PACKAGE.rglob("*.py"):
        tree = ast.parse(path.read_text(encoding="utf-8"))
        permitted = allowed | entry if path == PACKAGE / "cli" / "entry.py" else allowed
        if path in (PACKAGE / "cli" / "__init__.py", PACKAGE / "cli" / "console.py"):
            permitted = allowed | {"entry"}  # main on first use; the console script's, once it owns the signals
        for function in (n for n in ast.walk(tree) if isinstance(n, ast.FunctionDef | ast.AsyncFunctionDef)):
            for node in ast.walk(function):
                if isinstance(node, ast.Import | ast.ImportFrom):
                    module = node.module if isinstance(node, ast.ImportFrom) else node.names[0].name
                    assert (module or "").lstrip(".") in permitted, (
                        f"{path.relative_to(PACKAGE)}:{node.lineno} imports {module} inside {function.name}"
                    )


def test_every_public_name_resolves_lazily() -> None:
    # __init__ imports on first use: every name of __all__ must come back, and nothing heavy
    # may load with the bare package (the CLI's Ctrl-C guard relies on it).
    import subprocess
    import sys

    code = (
        "import sys, pinrate\n"
        "assert 'pinocchio' not in sys.modules, 'import pinrate loaded pinocchio'\n"
        "missing = [n for n in pinrate.__all__ if getattr(pinrate, n, None) is None]\n"
        "assert not missing, missing\n"
        "assert set(pinrate.__all__) <= set(dir(pinrate))\n"
    )
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=False)
    assert result.returncode == 0, result.stderr
