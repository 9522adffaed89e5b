"""The compiled core for the tests: which tests need it, and the two paths side by side.

A test that needs the core is skipped with a reason when ``pinrate_core`` is not installed
(a pure-Python install), unless PINRATE_REQUIRE_CORE=1 (CI sets it), which turns a missing
core into a failure.
"""

from __future__ import annotations

import contextlib
import importlib.util
import os
from collections.abc import Iterator

import pytest

import pinrate
from pinrate.compiled import use
from support import DATA

REQUIRED = os.environ.get("PINRATE_REQUIRE_CORE") == "1"
MISSING = "" if importlib.util.find_spec("pinrate_core") else "pinrate_core is not installed (make core)"
if MISSING and REQUIRED:
    raise RuntimeError(f"PINRATE_REQUIRE_CORE=1 but {MISSING}")
needs_core = pytest.mark.skipif(bool(MISSING), reason=MISSING or "core available")


@contextlib.contextmanager
def path(choice: str) -> Iterator[None]:
    """Run the block on one path ("python" or "compiled"), then follow PINRATE_BACKEND again."""
    use(choice)
    try:
        yield
    finally:
        use(None)


CLOSED_FORM = ("schur", "mca1", "mca2", "mca3")
ROBOTS = ("ur5", "panda", "scara", "barker_arm", "kinova", "planar_polar")
"""Six axes and a spherical wrist; seven (a 3x4 A: pseudo-inverses); four, planar (SCARA); the
paper's arm with its sensor off the tip; continuous joints; three joints, no wrist; and a
4-DOF arm from another package (a 3x1 W) left the list when its automatic partition (six
rows, rank 4) went to Python: its steps judge what the joints cannot make (test_servo.py).
The robots of every two-path equality test (the servo loop, the per-call step)."""


@contextlib.contextmanager
def core_steps_taken() -> Iterator[list[bool]]:
    """Records each call of the core's per-call step: True where it took the step, False
    where it handed it back."""
    from pinrate.control import core_step

    calls: list[bool] = []
    original = core_step.CoreStep.__call__

    def counted(self: core_step.CoreStep, *arguments: object) -> pinrate.Step | bool | None:
        step = original(self, *arguments)  # type: ignore[arg-type]
        calls.append(isinstance(step, pinrate.Step))
        return step

    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(core_step.CoreStep, "__call__", counted)
        yield calls


def load(name: str) -> pinrate.Robot:
    return pinrate.load(DATA / "third_party" / "rtb_al5d_robot.urdf" if name == "al5d" else name)


def bitwise(robot: pinrate.Robot, algorithm: str, partition: pinrate.Partition | None = None) -> bool:
    """Whether both paths make the same operations: the sensor at the tip, a closed-form kernel
    on square blocks of size <= 3."""
    small = (partition or pinrate.Partition.auto(robot)).resolve(robot).small
    return robot.sensor_id == robot.tip_id and algorithm in CLOSED_FORM and small
