"""pinrate.compiled.boundary: what crosses between pinrate and its core crosses by name, and
a core whose constants or settings' fields differ from pinrate's is refused when it loads."""

from __future__ import annotations

import dataclasses
import importlib
import sys
import types
from collections.abc import Callable
from typing import Any

import pytest

import pinrate
from compiled_core import needs_core, path
from pinrate import checks
from pinrate.compiled import boundary, core
from pinrate.compiled.boundary import KERNELS, MEASURABLE, ServoSettings, disagreements
from pinrate.compiled.kinematics import core_kinematics
from pinrate.compiled.servo import core_settings
from pinrate.control import compiled_twin
from pinrate.control.controller import Controller
from pinrate.control.singularity import measured_blocks
from pinrate.errors import UnsupportedByCoreError
from pinrate.kinematics import kinematic_model
from pinrate.solvers import eigen, singular


def real_core() -> types.ModuleType:
    """pinrate_core itself, whatever path PINRATE_BACKEND chooses (coal first: the core links
    the libcoal.so its binding loads)."""
    importlib.import_module("coal")
    return importlib.import_module("pinrate_core")


def loaded_afresh(monkeypatch: pytest.MonkeyPatch) -> pinrate.Backend:
    """pinrate.backend() after loading the core again (auto), as a new process would; the
    next test loads it afresh too."""
    monkeypatch.delenv("PINRATE_BACKEND", raising=False)
    monkeypatch.setattr(core, "_loaded", None)
    try:
        return pinrate.backend()
    finally:
        core._loaded = None


def test_the_kernels_are_algorithms_and_the_measured_blocks_measurable() -> None:
    assert set(KERNELS) <= set(pinrate.ALGORITHMS)
    for algorithm in pinrate.ALGORITHMS:
        assert set(measured_blocks(algorithm)) <= set(MEASURABLE), algorithm


@needs_core
def test_the_core_and_pinrate_agree() -> None:
    assert disagreements(real_core()) == []


@needs_core
def test_every_settings_field_is_on_the_core_and_every_core_field_in_the_settings() -> None:
    settings = real_core().Settings
    ours = {field.name for field in dataclasses.fields(ServoSettings)}
    assert set(settings.FIELDS) == ours
    assert len(settings.FIELDS) == len(ours)
    instance = settings()
    for name in ours:
        assert hasattr(instance, name), name


@needs_core
@pytest.mark.parametrize("algorithm", pinrate.ALGORITHMS)
def test_each_setting_reaches_the_core_field_of_its_name(algorithm: str) -> None:
    """A controller's settings, set by name, read back unchanged field by field (so no
    binding of one field writes another's member)."""
    robot = pinrate.load("ur5")
    settings = compiled_twin.settings(Controller(robot, algorithm=algorithm, velocity_limits=None))
    settings = dataclasses.replace(settings, pinv_rcond=1.25e-10, dls_damping=0.0125, watch_factor=3.5)
    filled = core_settings(real_core(), settings)
    for field in dataclasses.fields(settings):
        ours, theirs = getattr(settings, field.name), getattr(filled, field.name)
        if isinstance(ours, tuple):
            theirs = tuple(tuple(row) if isinstance(row, (list, tuple)) else row for row in theirs)
        assert theirs == ours, field.name


@needs_core
def test_a_servo_refuses_settings_with_a_field_unset() -> None:
    module = real_core()
    robot = pinrate.load("ur5")
    settings = compiled_twin.settings(Controller(robot))
    partial = module.Settings()
    for field in dataclasses.fields(settings):
        if field.name != "watched_step":
            setattr(partial, field.name, getattr(settings, field.name))
    with path("compiled"):
        kinematics = core_kinematics(robot)
    with pytest.raises(ValueError, match=r"pinrate_core\.Settings\.watched_step is not set"):
        module.Servo(kinematics, partial)
    partial.watched_step = settings.watched_step
    module.Servo(kinematics, partial)


@needs_core
def test_a_settings_field_the_core_lacks_is_refused_by_name() -> None:
    @dataclasses.dataclass(frozen=True)
    class Wider(ServoSettings):
        elbow_gain: float = 0.5

    settings = Wider(**dataclasses.asdict(compiled_twin.settings(Controller(pinrate.load("ur5")))))
    with pytest.raises(UnsupportedByCoreError, match=r"pinrate_core\.Settings has no field 'elbow_gain'"):
        core_settings(real_core(), settings)


def _times_ten(value: float) -> float:
    return value * 10


CHANGES: list[tuple[object, str, Callable[[Any], Any], str]] = [
    (singular, "SINGULAR_RATIO", _times_ten, "SINGULAR_RATIO"),
    (eigen, "FLAT", _times_ten, "FLAT"),
    (checks, "PHYSICAL_BOUND", _times_ten, "PHYSICAL_BOUND"),
    (kinematic_model, "UNIT_TOLERANCE", _times_ten, "UNIT_TOLERANCE"),
    (boundary, "KERNELS", lambda kernels: (kernels[1], kernels[0], *kernels[2:]), "KERNELS"),
    (boundary, "OUTCOMES", lambda outcomes: (*outcomes, "INTERRUPTED"), "OUTCOMES"),
    (boundary, "STEP_FLAGS", lambda flags: {**flags, "CLAMPED": 8}, "STEP_FLAGS"),
    (boundary, "MEASURABLE", lambda blocks: blocks[:2], "MEASURABLE"),
    (boundary, "REBUILT_JOINTS", lambda kinds: kinds - {"JointModelPX"}, "JOINT_KINDS"),
]


@needs_core
@pytest.mark.parametrize(("where", "name", "change", "named"), CHANGES, ids=[change[1] for change in CHANGES])
def test_a_constant_that_differs_refuses_the_core(
    monkeypatch: pytest.MonkeyPatch, where: object, name: str, change: Callable[[Any], Any], named: str
) -> None:
    """One of pinrate's definitions changed: the check names it with both values, the core
    is not loaded, and pinrate.backend() says so."""
    monkeypatch.setattr(where, name, change(getattr(where, name)))
    found = disagreements(real_core())
    assert len(found) == 1 and found[0].startswith(f"{named} is "), found
    report = loaded_afresh(monkeypatch)
    assert report.name == "python"
    assert "pinrate_core disagrees with this pinrate" in report.reason and f"{named} is " in report.reason
    assert "rebuild" in report.reason


@needs_core
def test_settings_fields_that_differ_refuse_the_core(monkeypatch: pytest.MonkeyPatch) -> None:
    """A field missing on either side: pinrate's settings gained one, the core's lost one."""
    module = real_core()

    @dataclasses.dataclass(frozen=True)
    class Wider(ServoSettings):
        elbow_gain: float = 0.5

    monkeypatch.setattr(boundary, "ServoSettings", Wider)
    assert disagreements(module) == ["ServoSettings.elbow_gain is no field of pinrate_core.Settings"]
    report = loaded_afresh(monkeypatch)
    assert report.name == "python" and "ServoSettings.elbow_gain is no field of pinrate_core.Settings" in report.reason
    monkeypatch.undo()

    def core_with(fields: tuple[str, ...], attributes: tuple[str, ...]) -> types.ModuleType:
        """The core with a Settings that names ``fields`` and has ``attributes``."""
        other = types.ModuleType("pinrate_core_of_other_settings")
        other.__dict__.update({key: value for key, value in vars(module).items() if not key.startswith("__")})
        other.Settings = type("Settings", (), {"FIELDS": fields, **dict.fromkeys(attributes)})  # type: ignore[attr-defined]
        return other

    ours = module.Settings.FIELDS
    changed = (*(name for name in ours if name != "dt"), "gain")
    narrower = core_with(changed, changed)
    assert disagreements(narrower) == [
        "ServoSettings.dt is no field of pinrate_core.Settings",
        "pinrate_core.Settings.gain is no field of ServoSettings",
    ]
    assert disagreements(core_with(ours, ours)) == []
    assert disagreements(core_with(ours, changed)) == ["pinrate_core.Settings names dt but has no such attribute"]
    monkeypatch.setitem(sys.modules, narrower.__name__, narrower)
    monkeypatch.setattr(core, "CORE_MODULE", narrower.__name__)
    report = loaded_afresh(monkeypatch)
    assert report.name == "python"
    assert "ServoSettings.dt is no field of pinrate_core.Settings" in report.reason
    assert "pinrate_core.Settings.gain is no field of ServoSettings" in report.reason


@needs_core
def test_the_core_is_loaded_again_after_the_checks(monkeypatch: pytest.MonkeyPatch) -> None:
    assert loaded_afresh(monkeypatch).name == "compiled"


@needs_core
def test_a_solve_is_timed_by_its_algorithms_name() -> None:
    robot = pinrate.load("ur5")
    with path("compiled"):
        servo = Controller(robot, algorithm="mca1").compiled()
    assert servo is not None
    q, twist = robot.home(), [0.01, 0.0, 0.0, 0.0, 0.0, 0.01]
    for algorithm in ("exact", "mca1", "mca2"):
        assert 0.0 < servo.solve_seconds(q, twist, algorithm, 10) < 1.0
    with pytest.raises(ValueError, match="exact, mca1 or mca2"):
        servo.solve_seconds(q, twist, "dls", 10)
    with pytest.raises(ValueError, match="no kernel sdls"):
        servo.solve_seconds(q, twist, "sdls", 10)
