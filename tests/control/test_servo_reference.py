"""The servo on the Controller seam reproduces the previous release's runs.

``tests/data/servo_reference.npz`` holds servo runs of release 0.1.0 (written by
``tests/data/make_servo_reference.py`` on the flat layout): the demo's runs on UR5 with every
algorithm, panda, SCARA and Barker's arm, and the papers' simulations (Fig. 6 and 9).
"""

from __future__ import annotations

import math
from collections.abc import Iterator

import numpy as np
import pytest

import pinrate
from pinrate.compiled import use
from support import DATA

REFERENCE = np.load(DATA / "servo_reference.npz")
RUNS = sorted({key.split("/")[0] for key in REFERENCE.files})

# Where every operation of the step is Pinocchio or Python floats (the closed-form kernels)
# the run is deterministic to the bit on any machine; numpy's LAPACK (exact, dls, the
# pseudo-inverse of panda's 3x4 arm block) may pick other kernels on another CPU.
LAPACK_RUNS = {"demo-ur5-exact-0", "demo-ur5-dls-0", "demo-panda-mca1-0"}


@pytest.fixture(autouse=True)
def python_path() -> Iterator[None]:
    """The release's runs were made on Python: the Python path must reproduce them to the bit
    (the compiled path is held to the Python one in tests/compiled/test_servo.py)."""
    use("python")
    yield
    use(None)


def run(name: str) -> pinrate.Trajectory:
    robot = pinrate.load(str(REFERENCE[f"{name}/robot"]))
    settings = eval(str(REFERENCE[f"{name}/settings"]), {"inf": math.inf})  # a dict literal we wrote
    return pinrate.servo(
        robot,
        REFERENCE[f"{name}/q0"],
        REFERENCE[f"{name}/target"],
        algorithm=str(REFERENCE[f"{name}/algorithm"]),
        **settings,
    )


def test_the_reference_covers_the_demo_and_the_papers() -> None:
    assert {"demo-ur5-mca1-0", "fig6a", "fig6b", "fig9a", "fig9b"} <= set(RUNS)
    assert {str(REFERENCE[f"{name}/algorithm"]) for name in RUNS} == set(pinrate.ALGORITHMS)


@pytest.mark.parametrize("name", RUNS)
def test_servo_reproduces_the_previous_release(name: str) -> None:
    trajectory = run(name)
    assert trajectory.reason == str(REFERENCE[f"{name}/reason"])
    assert trajectory.status == [str(s) for s in REFERENCE[f"{name}/status"]]
    for field in ("q", "joint_rates", "position_error", "orientation_error"):
        expected = REFERENCE[f"{name}/{field}"]
        if name in LAPACK_RUNS:
            np.testing.assert_allclose(getattr(trajectory, field), expected, rtol=1e-12, atol=1e-12, err_msg=field)
        elif field.endswith("_error"):
            # The recorded error norms are numpy reductions, not fed back: numpy 2.4's norm
            # rounds some of them one ulp away from the release's (q and rates stay bit-identical).
            np.testing.assert_allclose(getattr(trajectory, field), expected, rtol=4.5e-16, atol=0, err_msg=field)
        else:
            np.testing.assert_array_equal(getattr(trajectory, field), expected, err_msg=f"{field} not bit-identical")
    # rho is recorded, not fed back: the unified eigenvalue routine may move its last digits.
    np.testing.assert_allclose(trajectory.spectral_radius, REFERENCE[f"{name}/spectral_radius"], rtol=1e-9, atol=1e-15)
