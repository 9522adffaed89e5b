"""The compiled core installs the way the README says: ``pip install ./core``, build isolation on.

Under pip's build isolation the build requirements (libpinocchio, libcoal, cmeel-eigen,
cmeel-boost, nanobind) live in a throwaway build environment, not in the target environment; the core's
CMakeLists.txt finds the headers through the build's own Python (importlib.metadata, then
cmeel.prefix/include on sys.path). Issue 20: it once looked only in the target environment's
site-packages, so the documented install failed in a fresh venv.

- The quick tests (a CMake configure, a few seconds, no compile) check the header search
  with the interpreter running the tests (the --no-build-isolation path of ``make core``) and
  the error message where Eigen cannot be imported. They need cmake, a C++ compiler and
  nanobind, and skip with a reason where one is missing.
- ``test_pip_install_core_in_a_fresh_venv`` builds the core for real in a fresh venv: about
  2 minutes of CPU and 3.2 GB of memory, so it runs only with PINRATE_TEST_INSTALL=1 (CI runs
  it as a step of its own). It uses the package registries as pip is configured (pip.conf,
  PIP_* variables and pip's cache), nothing else.
"""

from __future__ import annotations

import importlib.util
import os
import re
import shutil
import subprocess
import sys
import time
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
CORE = ROOT / "core"
GATE = "PINRATE_TEST_INSTALL"

# What the build must not inherit from the test run: another interpreter's paths, a request
# for --no-build-isolation, a forced backend.
_SCRUBBED = (
    "PYTHONPATH",
    "PYTHONHOME",
    "PYTHONSTARTUP",
    "VIRTUAL_ENV",
    "PIP_NO_BUILD_ISOLATION",
    "PIP_USER",
    "PIP_TARGET",
    "PIP_PREFIX",
    "PINRATE_BACKEND",
    "CMAKE_ARGS",
    "SKBUILD_CMAKE_ARGS",
)


def _environment(**extra: str) -> dict[str, str]:
    environment = {key: value for key, value in os.environ.items() if key not in _SCRUBBED}
    environment.update(extra)
    return environment


def _configure_tools() -> str:
    """Why the configure tests cannot run here, or '' when they can."""
    if shutil.which("cmake") is None:
        return "no cmake on PATH"
    if shutil.which(os.environ.get("CXX", "c++")) is None:
        return "no C++ compiler"
    if importlib.util.find_spec("nanobind") is None:
        return "nanobind is not installed here (pip install ./core builds in an isolated env)"
    return ""


needs_configure_tools = pytest.mark.skipif(bool(_configure_tools()), reason=_configure_tools() or "tools present")


def _configure(python: str, build: Path, **environment: str) -> subprocess.CompletedProcess[str]:
    command = ["cmake", "-S", str(CORE), "-B", str(build), f"-DPython_EXECUTABLE={python}"]
    if shutil.which("ninja"):
        command += ["-G", "Ninja"]
    return subprocess.run(command, capture_output=True, text=True, timeout=300, env=_environment(**environment))


@needs_configure_tools
def test_configure_finds_the_headers_of_the_running_interpreter(tmp_path: Path) -> None:
    """The --no-build-isolation path: the headers of this environment's wheels, each named."""
    if importlib.util.find_spec("cmeel") is None or not any(
        (Path(entry) / "cmeel.prefix" / "include" / "eigen3" / "Eigen" / "Core").is_file() for entry in sys.path
    ):
        pytest.skip("cmeel-eigen is not installed here (pip install cmeel-eigen libpinocchio to run this)")
    result = _configure(sys.executable, tmp_path / "build")
    assert result.returncode == 0, result.stdout + result.stderr
    headers = re.search(r"-- Headers: (.*)", result.stdout)
    assert headers, result.stdout
    for what in ("Pinocchio", "Eigen", "Boost", "coal"):
        assert what in headers.group(1)
    assert "(libpinocchio " in headers.group(1) and "(cmeel-eigen " in headers.group(1)
    library = re.search(r"-- libcoal: (.*)", result.stdout)  # the collision monitor links it
    assert library and Path(library.group(1)).name == "libcoal.so" and Path(library.group(1)).is_file()


@needs_configure_tools
def test_configure_says_what_it_searched_and_how_to_fix_it(tmp_path: Path) -> None:
    """An interpreter that imports nanobind but no header wheel: the error names each step."""
    bare = tmp_path / "bare"
    subprocess.run([sys.executable, "-m", "venv", "--without-pip", str(bare)], check=True, timeout=120)
    only = tmp_path / "only-nanobind"
    only.mkdir()
    spec = importlib.util.find_spec("nanobind")
    assert spec is not None and spec.origin is not None
    (only / "nanobind").symlink_to(Path(spec.origin).parent, target_is_directory=True)
    result = _configure(str(bare / "bin" / "python"), tmp_path / "build", PYTHONPATH=str(only))
    assert result.returncode != 0
    message = " ".join(result.stderr.split())  # CMake wraps its messages
    assert "not found: Pinocchio" in message and "Eigen" in message and "Boost" in message
    assert "libpinocchio: not installed" in message and "cmeel-eigen: not installed" in message
    assert "searched cmeel.prefix/include under every sys.path entry" in message
    assert str(only) in message
    assert "pip install ./core" in message and "--no-build-isolation" in message


def _run(command: list[str], cwd: Path, log: Path, timeout: float) -> float:
    """Run a step of the install, its output appended to log; its wall time in seconds."""
    start = time.perf_counter()
    with log.open("a") as out:
        out.write(f"$ {' '.join(command)}\n")
        out.flush()
        result = subprocess.run(
            command,
            cwd=cwd,
            stdout=out,
            stderr=subprocess.STDOUT,
            timeout=timeout,
            env=_environment(PINRATE_BACKEND="auto"),
        )
    if result.returncode != 0:
        tail = "\n".join(log.read_text().splitlines()[-40:])
        pytest.fail(f"{' '.join(command)} exited with {result.returncode}:\n{tail}")
    return time.perf_counter() - start


@pytest.mark.skipif(
    os.environ.get(GATE) != "1",
    reason=(f"builds the compiled core in a fresh venv (about 2 minutes of CPU, 3.2 GB of memory): {GATE}=1 runs it"),
)
def test_pip_install_core_in_a_fresh_venv(tmp_path: Path) -> None:
    """``pip install .`` then ``pip install ./core``, with build isolation, in a fresh venv.

    pinrate itself is installed with --no-deps plus pin and numpy (all ``import pinrate``
    needs), which saves half a minute of matplotlib, meshcat and Dask; the core gets exactly
    the README's command, on a copy of core/ without its build/ directory (a clean clone's
    tree, and no clash with the working tree's ``make core``).
    """
    log = tmp_path / "install.log"
    venv = tmp_path / "venv"
    python = str(venv / "bin" / "python")
    core = tmp_path / "core"
    shutil.copytree(CORE, core, ignore=shutil.ignore_patterns("build", "*.egg-info", "__pycache__"))
    pin = next(requirement for requirement in _dependencies() if re.match(r"pin\b", requirement))
    numpy = next(requirement for requirement in _dependencies() if re.match(r"numpy\b", requirement))

    times = {"venv": _run([sys.executable, "-m", "venv", str(venv)], tmp_path, log, 300)}
    times["pinrate"] = _run([python, "-m", "pip", "install", "--no-deps", str(ROOT), pin, numpy], tmp_path, log, 900)
    times["core"] = _run([python, "-m", "pip", "install", str(core)], tmp_path, log, 2400)
    probe = (
        "import importlib.metadata as m, pinocchio, pinrate, pinrate_core\n"
        "b = pinrate.backend()\n"
        "print(b.name); print(b.reason); print(pinocchio.__version__); print(pinrate_core.PINOCCHIO_VERSION)\n"
        "print(m.version('pinrate-core')); print(pinrate_core.__file__)\n"
        "import coal; print(coal.__version__); print(pinrate_core.COAL_VERSION)\n"
    )
    result = subprocess.run(
        [python, "-c", probe],
        cwd=tmp_path,
        capture_output=True,
        text=True,
        timeout=300,
        env=_environment(PINRATE_BACKEND="auto"),
    )
    assert result.returncode == 0, result.stderr
    name, reason, runtime_pin, header_pin, version, library, runtime_coal, header_coal = result.stdout.split("\n")[:8]
    assert name == "compiled", reason
    # The collision monitor runs in the core only on the coal it was built on: the README's
    # install gives the same release to both.
    assert runtime_coal == header_coal
    assert version == _core_version()
    assert library.startswith(str(venv)), library
    # The core links no libpinocchio (the headers' release and the runtime's may differ), only
    # libcoal.so (the collision monitor).
    readelf = shutil.which("readelf")
    if readelf:
        needed = subprocess.run([readelf, "-d", library], capture_output=True, text=True, check=True).stdout
        assert "pinocchio" not in needed and "libcoal.so" in needed, needed
    print(
        f"\nfresh-venv install: {', '.join(f'{step} {seconds:.0f} s' for step, seconds in times.items())}; "
        f"core on Pinocchio {header_pin}'s headers beside pin {runtime_pin}"
    )


def _dependencies() -> list[str]:
    """pinrate's [project] dependencies (a regular expression: tomllib is Python 3.11's)."""
    text = (ROOT / "pyproject.toml").read_text()
    block = re.search(r"^dependencies = \[(.*?)^\]", text, re.MULTILINE | re.DOTALL)
    assert block, "no dependencies in pyproject.toml"
    return re.findall(r'"([^"]+)"', block.group(1))


def _core_version() -> str:
    version = re.search(r'^version = "([^"]+)"', (CORE / "pyproject.toml").read_text(), re.MULTILINE)
    assert version, "no version in core/pyproject.toml"
    return version.group(1)
