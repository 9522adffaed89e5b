"""pinrate.compiled.core: which path runs, and why."""

from __future__ import annotations

import sys
import types

import pytest

import pinrate
from compiled_core import needs_core, path
from pinrate.compiled import core, use


def test_backend_is_exported_and_names_a_path() -> None:
    report = pinrate.backend()
    assert report.name in ("compiled", "python")
    assert report.reason
    assert str(report).startswith(report.name)


@needs_core
def test_the_core_is_used_where_it_is_installed() -> None:
    with path("auto"):
        report = pinrate.backend()
    assert report.name == "compiled", report.reason
    assert "Pinocchio" in report.reason


def test_python_is_chosen_by_the_environment(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("PINRATE_BACKEND", "python")
    report = pinrate.backend()
    assert (report.name, report.choice) == ("python", "python")
    assert "PINRATE_BACKEND=python" in report.reason
    assert core.core_module() is None


def test_a_bad_choice_is_refused(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("PINRATE_BACKEND", "fortran")
    with pytest.raises(pinrate.InputError, match="PINRATE_BACKEND must be one of auto, python, compiled"):
        pinrate.backend()
    with pytest.raises(pinrate.InputError, match="backend must be one of"):
        use("gpu")


def test_a_missing_core_falls_back_and_compiled_refuses(monkeypatch: pytest.MonkeyPatch) -> None:
    """As on a machine without a compiler: the import fails, auto runs Python and says why,
    and asking for the compiled path is an error that names the reason."""
    monkeypatch.delenv("PINRATE_BACKEND", raising=False)  # auto, whatever the run's setting
    monkeypatch.setattr(core, "CORE_MODULE", "pinrate_core_that_was_never_built")
    monkeypatch.setattr(core, "_loaded", None)
    report = pinrate.backend()
    assert report.name == "python"
    assert "not installed" in report.reason and "pip install ./core" in report.reason
    with pytest.raises(pinrate.InputError, match="PINRATE_BACKEND=compiled, but the compiled core is not installed"):
        use("compiled")
    use(None)
    robot = pinrate.load("ur5")
    target = robot.pose(robot.home())
    target[:3, 3] += 0.01
    trajectory = pinrate.servo(robot, robot.home(), target)
    assert trajectory.converged  # on the Python path
    monkeypatch.setattr(core, "_loaded", None)  # the next test imports the real one afresh


def test_a_core_of_another_abi_is_not_used(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.delenv("PINRATE_BACKEND", raising=False)
    stale = types.ModuleType("pinrate_core_of_another_release")
    stale.ABI = core.CORE_ABI + 1  # type: ignore[attr-defined]
    monkeypatch.setitem(sys.modules, stale.__name__, stale)
    monkeypatch.setattr(core, "CORE_MODULE", stale.__name__)
    monkeypatch.setattr(core, "_loaded", None)
    report = pinrate.backend()
    assert report.name == "python"
    assert "ABI" in report.reason and "rebuild" in report.reason
    monkeypatch.setattr(core, "_loaded", None)


@needs_core
def test_a_controller_says_why_it_stays_on_python() -> None:
    robot = pinrate.load("ur5")
    with path("auto"):
        assert pinrate.Controller(robot).compiled_reason() is None
        assert pinrate.Controller(robot).compiled() is not None
        assert "posture" in pinrate.Controller(robot, posture="home").compiled_reason()
        assert "acceleration" in pinrate.Controller(robot, acceleration_limits=2.0).compiled_reason()
        assert "elbow" in pinrate.Controller(robot, singularity="auxiliary_elbow").compiled_reason()
    with path("python"):
        assert "PINRATE_BACKEND=python" in pinrate.Controller(robot).compiled_reason()
        assert pinrate.Controller(robot).compiled() is None
