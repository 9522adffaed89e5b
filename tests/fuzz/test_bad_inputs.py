"""Every bad input to the public API is a PinrateError (InputError is also a ValueError) whose
message names the argument; never another exception type, NaN or a hang."""

from __future__ import annotations

import math
import time
from collections.abc import Callable

import numpy as np
import pytest

import pinrate
from pinrate import Partition
from pinrate.control import Controller, PoseGoal
from pinrate.theorem.sampling import spectral_radius_at


@pytest.fixture(scope="module")
def ur5() -> pinrate.Robot:
    return pinrate.load("ur5")


def cases(ur5: pinrate.Robot) -> list[tuple[str, Callable[[], object], type[Exception], str]]:
    """(case, the call, the error class, a phrase of its message)."""
    q = ur5.home()
    auto = Partition.auto(ur5)
    twist = np.zeros(6)
    target = ur5.pose(q)
    far = target.copy()
    far[0, 3] = 1e305
    huge_twist = np.full(6, 1e305)
    return [
        ("load a number", lambda: pinrate.load(123), pinrate.InputError, "source"),
        ("load None", lambda: pinrate.load(None), pinrate.InputError, "source"),
        ("load an empty name", lambda: pinrate.load(""), pinrate.LoadError, "unknown robot name"),
        ("load max_joints=0", lambda: pinrate.load("ur5", max_joints=0), pinrate.InputError, "max_joints"),
        ("rng=-1 (configuration)", lambda: ur5.random_configuration(rng=-1), pinrate.InputError, "rng"),
        ("rng='x'", lambda: ur5.random_configuration(rng="x"), pinrate.InputError, "rng"),
        ("rng=1.5", lambda: ur5.random_configuration(rng=1.5), pinrate.InputError, "rng"),
        ("count=-1", lambda: ur5.sample_configurations(-1), pinrate.InputError, "count"),
        ("count=2.5", lambda: ur5.sample_configurations(2.5), pinrate.InputError, "count"),
        ("q=1e305", lambda: ur5.jacobian(np.full(6, 1e305)), pinrate.InputError, "physical bound"),
        ("q a string", lambda: ur5.pose("home"), pinrate.InputError, "q"),
        ("samples=-1", lambda: pinrate.sample_convergence(ur5, -1), pinrate.InputError, "samples"),
        ("samples=2.5", lambda: pinrate.sample_convergence(ur5, 2.5), pinrate.InputError, "samples"),
        ("samples=True", lambda: pinrate.sample_convergence(ur5, True), pinrate.InputError, "samples"),
        ("sample rng=-1", lambda: pinrate.sample_convergence(ur5, 10, rng=-1), pinrate.InputError, "rng"),
        (
            "partition='auto'",
            lambda: pinrate.sample_convergence(ur5, 10, partition="auto"),
            pinrate.InputError,
            "partition",
        ),
        ("robot a name", lambda: pinrate.sample_convergence("ur5", 10), pinrate.InputError, "pinrate.load"),
        ("Partition.auto(None)", lambda: Partition.auto(None), pinrate.InputError, "robot"),
        ("Partition.auto('ur5')", lambda: Partition.auto("ur5"), pinrate.InputError, "robot"),
        ("blocks(r, 'J')", lambda: auto.blocks(ur5, "J"), pinrate.InputError, "J"),
        ("blocks of a 5x6 J", lambda: auto.blocks(ur5, np.zeros((5, 6))), pinrate.InputError, "shape"),
        ("blocks of a NaN J", lambda: auto.blocks(ur5, np.full((6, 6), np.nan)), pinrate.InputError, "NaN"),
        ("Partition of numbers", lambda: Partition([1, 2], []), pinrate.InputError, "joint names"),
        ("Partition linear=None", lambda: Partition([], [], linear=None), pinrate.InputError, "linear"),
        ("Partition unknown joint", lambda: Partition(["nope"], []).resolve(ur5), pinrate.InputError, "nope"),
        ("joint_rates robot None", lambda: pinrate.joint_rates(None, q, twist), pinrate.InputError, "robot"),
        (
            "joint_rates partition 'auto'",
            lambda: pinrate.joint_rates(ur5, q, twist, partition="auto"),
            pinrate.InputError,
            "partition",
        ),
        (
            "joint_rates algorithm 3",
            lambda: pinrate.joint_rates(ur5, q, twist, algorithm=3),
            pinrate.InputError,
            "algorithm",
        ),
        (
            "joint_rates twist 1e305",
            lambda: pinrate.joint_rates(ur5, q, huge_twist),
            pinrate.InputError,
            "physical bound",
        ),
        ("joint_rates twist of 5", lambda: pinrate.joint_rates(ur5, q, np.zeros(5)), pinrate.InputError, "twist"),
        ("convergence q a string", lambda: pinrate.convergence(ur5, "x"), pinrate.InputError, "q"),
        (
            "convergence partition 'auto'",
            lambda: pinrate.convergence(ur5, q, partition="auto"),
            pinrate.InputError,
            "partition",
        ),
        (
            "servo partition 'auto'",
            lambda: pinrate.servo(ur5, q, target, partition="auto"),
            pinrate.InputError,
            "partition",
        ),
        (
            "servo algorithm None",
            lambda: pinrate.servo(ur5, q, target, algorithm=None),
            pinrate.InputError,
            "algorithm",
        ),
        ("servo target 1e305 m away", lambda: pinrate.servo(ur5, q, far), pinrate.InputError, "physical bound"),
        ("servo gain 1e300", lambda: pinrate.servo(ur5, q, target, gain=1e300), pinrate.InputError, "gain"),
        ("servo tol 0", lambda: pinrate.servo(ur5, q, target, tol=0.0), pinrate.InputError, "tol"),
        ("servo max_steps -1", lambda: pinrate.servo(ur5, q, target, max_steps=-1), pinrate.InputError, "max_steps"),
        ("Controller robot a name", lambda: Controller("ur5"), pinrate.InputError, "pinrate.load"),
        ("Controller dt nan", lambda: Controller(ur5, dt=math.nan), pinrate.InputError, "dt"),
        ("step twist 1e305", lambda: Controller(ur5).step(q, huge_twist), pinrate.InputError, "physical bound"),
        ("PoseGoal of a 3x3", lambda: PoseGoal.of(np.eye(3)), pinrate.InputError, "4x4"),
        ("spectral_radius_at NaN", lambda: spectral_radius_at(ur5, np.full((2, 6), np.nan)), pinrate.InputError, "NaN"),
        ("robots.scara(l1=1e300)", lambda: pinrate.robots.scara(l1=1e300), pinrate.InputError, "l1"),
        ("robots.scara(l1=-1)", lambda: pinrate.robots.scara(l1=-1.0), pinrate.InputError, "l1"),
        ("robots.scara(l9=1)", lambda: pinrate.robots.scara(l9=1.0), pinrate.InputError, "l9"),
        ("robots.urdf('nope')", lambda: pinrate.robots.urdf("nope"), pinrate.InputError, "nope"),
        ("frame_pose of frame 5", lambda: ur5.frame_pose(q, 5), pinrate.InputError, "frame"),
    ]


CASE_NAMES = [case for case, *_ in cases(pinrate.load("ur5"))]


@pytest.mark.parametrize("number", range(len(CASE_NAMES)), ids=CASE_NAMES)
def test_a_bad_input_is_a_pinrate_error_naming_it(ur5: pinrate.Robot, number: int) -> None:
    case, call, kind, phrase = cases(ur5)[number]
    with pytest.raises(kind) as caught:
        call()
    assert phrase in str(caught.value), (case, str(caught.value))


def test_an_unreachable_dask_scheduler_is_refused_within_seconds(ur5: pinrate.Robot) -> None:
    pytest.importorskip("distributed")
    started = time.monotonic()
    with pytest.raises(pinrate.PinrateError, match=r"no Dask scheduler reachable at 'tcp://127\.0\.0\.1:9'"):
        pinrate.sample_convergence(ur5, 100, scheduler="tcp://127.0.0.1:9")
    assert time.monotonic() - started < 20  # was 30 s and an OSError
    with pytest.raises(pinrate.InputError, match="scheduler address 'nonsense'"):
        pinrate.sample_convergence(ur5, 100, scheduler="nonsense")
    with pytest.raises(pinrate.InputError, match="scheduler must be"):
        pinrate.sample_convergence(ur5, 100, scheduler=42)
