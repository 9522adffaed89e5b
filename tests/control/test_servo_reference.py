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
from pinrate.control.trajectory import RENAMED_WORDS
from support import DATA, EPS, partition_rows_and_columns, spectral_radius_tolerance

REFERENCE = np.load(DATA / "servo_reference.npz")
RUNS = sorted({key.split("/")[0] for key in REFERENCE.files})


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


def rounding_tolerance(robot: pinrate.Robot, q: np.ndarray, values: np.ndarray) -> float:
    """How far a run on another machine or numpy may honestly stray from the recorded one.

    numpy's reductions and LAPACK's kernels may round in another order on another CPU or
    release (numpy 2.5's norm moves some of these runs' rates by one ulp, 2.8e-17), and the
    loop feeds each step's rounding back. To first order a relative perturbation of size ε in
    a step's operands changes its rates by at most κ(J) ε relatively, κ the condition number
    of the partition's sensor-frame Jacobian along the run (recomputed here from the recorded
    configurations); 64 ε covers the operations of a step that may each contribute one. The
    bound is taken relative to the largest value of the field over the run."""
    rows, columns = partition_rows_and_columns(robot, pinrate.Partition.auto(robot))
    conditioning = max(np.linalg.cond(robot.jacobian(x)[np.ix_(rows, columns)]) for x in q)
    return 64 * EPS * conditioning * float(np.max(np.abs(values)))


@pytest.mark.parametrize("name", RUNS)
def test_servo_reproduces_the_previous_release(name: str) -> None:
    """The words exactly; the numbers within rounding_tolerance (bit identity across
    machines and numpy releases is not promised where numpy computes)."""
    trajectory = run(name)
    robot = pinrate.load(str(REFERENCE[f"{name}/robot"]))
    assert trajectory.reason == str(REFERENCE[f"{name}/reason"])
    # 0.1.0's step words, renamed as the one vocabulary renamed them (Status.word)
    assert trajectory.status == [RENAMED_WORDS.get(str(s), str(s)) for s in REFERENCE[f"{name}/status"]]
    recorded_q = REFERENCE[f"{name}/q"]
    for field in ("q", "joint_rates", "position_error", "orientation_error", "spectral_radius"):
        expected = REFERENCE[f"{name}/{field}"]
        tolerance = rounding_tolerance(robot, recorded_q, expected)
        if field == "spectral_radius":  # not fed back; an eigenvalue moves by a root of rounding
            tolerance = spectral_radius_tolerance(robot, trajectory.partition, recorded_q)
        actual = getattr(trajectory, field)
        np.testing.assert_array_equal(np.isinf(actual), np.isinf(expected), err_msg=field)
        finite = np.isfinite(expected)
        excess = np.abs(actual[finite] - expected[finite]) - np.broadcast_to(tolerance, expected.shape)[finite]
        assert not np.any(excess > 0), f"{field}: beyond the rounding bound by up to {excess.max():.3g}"
