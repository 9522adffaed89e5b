"""The package's metadata tells the truth: one version, every imported package declared,
a licence, and an sdist that carries what the README tells users to install."""

from __future__ import annotations

import ast
import contextlib
import importlib.metadata
import re
import sys
from pathlib import Path

import pytest

import pinrate
from support import ROOT

SOURCE = ROOT / "src" / "pinrate"


def declared_requirements() -> dict[str, str]:
    """Distribution name (normalised) -> requirement string, from the installed metadata."""
    requirements = importlib.metadata.requires("pinrate") or []
    declared = {}
    for requirement in requirements:
        if "extra ==" in requirement:
            continue
        name = re.split(r"[<>=!~;\[ ]", requirement, maxsplit=1)[0]
        declared[normalise(name)] = requirement
    return declared


def normalise(name: str) -> str:
    return re.sub(r"[-_.]+", "-", name).lower()


def imported_top_level_modules() -> set[str]:
    """Every absolute top-level module that pinrate's source imports, anywhere in a module."""
    modules = set()
    for path in SOURCE.rglob("*.py"):
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.Import):
                modules |= {alias.name.split(".")[0] for alias in node.names}
            elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
                modules.add(node.module.split(".")[0])
    return modules - set(sys.stdlib_module_names) - {"pinrate", "pinrate_core", "__future__"}


OPTIONAL = {"dask", "distributed", "xacro", "xacrodoc", "mujoco"}
"""Imported only behind ``pip install 'pinrate[dask]'``, ``'pinrate[xacro]'`` and
``'pinrate[mujoco]'`` (an error naming the extra otherwise)."""


def test_one_version() -> None:
    """pyproject reads pinrate.__version__; the core's pyproject states the same."""
    assert importlib.metadata.version("pinrate") == pinrate.__version__
    core = (ROOT / "core" / "pyproject.toml").read_text(encoding="utf-8")
    assert re.search(r'^version = "([^"]+)"', core, re.MULTILINE).group(1) == pinrate.__version__  # type: ignore[union-attr]
    assert 'dynamic = ["version"]' in (ROOT / "pyproject.toml").read_text(encoding="utf-8")


BROUGHT_BY = {"coal": "pin"}
"""Modules a declared dependency's own API is made of: pin's collision API is coal's (its
GeometryObject holds coal shapes), and pin 3.3 requires it as the distribution coal-library,
pin >= 3.4 as coal, one module from either: neither can be declared for every pin pinrate
supports (both at once would install two distributions of one module)."""


def test_every_imported_package_is_declared() -> None:
    """An import of a package that only arrives as another's dependency breaks the day that
    other drops it: each is declared, with the distribution that provides it."""
    providers = importlib.metadata.packages_distributions()
    for distribution in importlib.metadata.distributions():  # cmeel wheels (pin): under cmeel.prefix
        for file in distribution.files or []:
            parts = file.parts
            if "cmeel.prefix" in parts and "site-packages" in parts[:-1]:
                module = parts[parts.index("site-packages") + 1].removesuffix(".py")
                providers.setdefault(module, []).append(distribution.metadata["Name"])
    declared = declared_requirements()
    missing = []
    for module in sorted(imported_top_level_modules() - OPTIONAL):
        distributions = {normalise(name) for name in providers.get(module, [])}
        if not distributions:  # Python 3.10's packages_distributions misses some wheels (matplotlib 3.9)
            with contextlib.suppress(importlib.metadata.PackageNotFoundError):
                distributions = {normalise(importlib.metadata.distribution(module).metadata["Name"])}
        assert distributions, f"{module} is imported but no installed distribution provides it"
        if not distributions & set(declared) and BROUGHT_BY.get(module) not in declared:
            missing.append(f"{module} (from {', '.join(sorted(distributions))})")
    assert not missing, f"imported but not declared in [project] dependencies: {missing}"
    extras = importlib.metadata.metadata("pinrate").get_all("Provides-Extra") or []
    assert {"dask", "xacro", "mujoco"} <= set(extras)


def test_licence() -> None:
    metadata = importlib.metadata.metadata("pinrate")
    assert metadata["License-Expression"] == "BSD-3-Clause"
    assert "BSD 3-Clause License" in (ROOT / "LICENSE").read_text(encoding="utf-8")


@pytest.mark.parametrize("kind", ["Programming Language :: Python :: 3.10", "Programming Language :: Python :: 3.13"])
def test_classifiers_name_the_supported_pythons(kind: str) -> None:
    assert kind in (importlib.metadata.metadata("pinrate").get_all("Classifier") or [])


def test_the_sdist_carries_the_core_and_the_licence() -> None:
    """MANIFEST.in grafts core/ (``pip install ./core`` from an unpacked sdist) and LICENSE."""
    manifest = (ROOT / "MANIFEST.in").read_text(encoding="utf-8").splitlines()
    assert "graft core" in manifest and any(line.startswith("include LICENSE") for line in manifest)
    assert (ROOT / "core" / "pyproject.toml").is_file() and (ROOT / "core" / "CMakeLists.txt").is_file()


def test_third_party_test_data_is_permissively_licensed() -> None:
    """Every URDF under tests/data/third_party has its row, and every licence named there is
    one a BSD-3-Clause project may ship (Apache-2.0, BSD, MIT, zlib)."""
    folder = Path(ROOT / "tests" / "data" / "third_party")
    readme = (folder / "README.md").read_text(encoding="utf-8")
    for urdf in sorted(folder.glob("*.urdf")):
        row = next((line for line in readme.splitlines() if line.startswith(f"| `{urdf.name}`")), None)
        assert row is not None, f"{urdf.name} has no row in tests/data/third_party/README.md"
        licence = row.rstrip(" |").rsplit("|", 1)[-1]
        assert re.search(r"Apache-2\.0|BSD|MIT|zlib", licence), f"{urdf.name}: {licence}"
