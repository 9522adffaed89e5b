"""Every bad input to the public API is a PinrateError (InputError is also a ValueError) whose
message names the argument; never another exception type, NaN or a hang."""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest

import pinrate
import pinrate.papers
from pinrate import Partition, analysis
from pinrate.control import Controller, PoseGoal
from pinrate.errors import SchedulerError
from pinrate.solvers.singular import hadamard_ratio
from pinrate.theorem import parallel
from pinrate.theorem.pointwise import convergence_from_blocks
from pinrate.theorem.sampling import spectral_radius_at, wilson_interval
from pinrate.viewer.markers import path_colours


@pytest.fixture(scope="module")
def ur5() -> pinrate.Robot:
    return pinrate.load("ur5")


def scara_l3(value: float) -> pinrate.Robot:
    return pinrate.robots.scara(l3=value)


def small_report(robot: pinrate.Robot) -> analysis.Report:
    return analysis.analyze(robot, samples=10, points=2, rng=0)


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
        ("Robot of a name", lambda: pinrate.Robot("ur5"), pinrate.InputError, "pinocchio.Model"),
        ("Robot of None", lambda: pinrate.Robot(None), pinrate.InputError, "pinocchio.Model"),
        ("joint_id(123)", lambda: ur5.joint_id(123), pinrate.InputError, "joint"),
        ("joint_limits(['x'])", lambda: ur5.joint_limits(["elbow_joint"]), pinrate.InputError, "joint"),
        (
            "set_joint_values wrong width",
            lambda: ur5.set_joint_values(np.zeros((3, 2)), "elbow_joint", np.zeros(3)),
            pinrate.InputError,
            "configurations",
        ),
        (
            "set_joint_values wrong count",
            lambda: ur5.set_joint_values(np.zeros((3, 6)), "elbow_joint", np.zeros(5)),
            pinrate.InputError,
            "values",
        ),
        ("samples=10**12", lambda: pinrate.sample_convergence(ur5, 10**12), pinrate.InputError, "at most"),
        ("samples=2**63", lambda: pinrate.sample_convergence(ur5, 2**63), pinrate.InputError, "at most"),
        ("count=10**12", lambda: ur5.sample_configurations(10**12), pinrate.InputError, "at most"),
        ("observe a NaN q", lambda: Controller(ur5).observe(np.full(6, np.nan)), pinrate.InputError, "NaN"),
        ("observe with a 4x4 goal", lambda: Controller(ur5).observe(q, target), pinrate.InputError, "PoseGoal"),
        ("region_map points=0", lambda: analysis.region_map(ur5, points=0), pinrate.InputError, "points"),
        ("region_map points=10**6", lambda: analysis.region_map(ur5, points=10**6), pinrate.InputError, "at most"),
        ("region_map points=1.5", lambda: analysis.region_map(ur5, points=1.5), pinrate.InputError, "points"),
        ("grid_check points=None", lambda: analysis.grid_check(ur5, points=None), pinrate.InputError, "points"),
        ("grid_check joints of numbers", lambda: analysis.grid_check(ur5, joints=[1, 2]), pinrate.InputError, "joint"),
        ("independent_joints rng=-1", lambda: analysis.independent_joints(ur5, rng=-1), pinrate.InputError, "rng"),
        (
            "independent_joints samples=0",
            lambda: analysis.independent_joints(ur5, samples=0),
            pinrate.InputError,
            "samples",
        ),
        ("joint_sensitivity rng=-1", lambda: analysis.joint_sensitivity(ur5, rng=-1), pinrate.InputError, "rng"),
        (
            "largest_parameter tolerance=0",
            lambda: analysis.largest_parameter(scara_l3, 0.01, 0.2, tolerance=0.0),
            pinrate.InputError,
            "tolerance",
        ),
        ("sweep steps=0", lambda: analysis.sweep(scara_l3, "l3", 0.01, 0.2, steps=0), pinrate.InputError, "steps"),
        ("sweep low='a'", lambda: analysis.sweep(scara_l3, "l3", "a", 0.2), pinrate.InputError, "two numbers"),
        ("parse_sweep(None)", lambda: analysis.parse_sweep(None), pinrate.InputError, "sweep"),
        ("parse_sweep('l3=nan:1')", lambda: analysis.parse_sweep("l3=nan:1"), pinrate.InputError, "finite"),
        ("write_report(None)", lambda: analysis.write_report(None, "x"), pinrate.InputError, "Report"),
        ("robots.build(123)", lambda: pinrate.robots.build(123), pinrate.InputError, "robot name"),
        ("robots.urdf(['scara'])", lambda: pinrate.robots.urdf(["scara"]), pinrate.InputError, "robot name"),
        ("robots.parameters(None)", lambda: pinrate.robots.parameters(None), pinrate.InputError, "robot name"),
        ("robots.write_urdfs(None)", lambda: pinrate.robots.write_urdfs(None), pinrate.InputError, "path"),
        ("write_report into ''", lambda: analysis.write_report(small_report(ur5), ""), pinrate.InputError, "path"),
        (
            "robots.write_urdfs onto a file",
            lambda: pinrate.robots.write_urdfs("/etc/hostname"),
            pinrate.InputError,
            "not a folder",
        ),
        ("example_robot_path(None)", lambda: pinrate.robots.example_robot_path(None), pinrate.InputError, "file"),
        ("wilson_interval(5, 3)", lambda: wilson_interval(5, 3), pinrate.InputError, "successes"),
        ("hadamard_ratio of 2x3", lambda: hadamard_ratio(np.ones((2, 3))), pinrate.InputError, "square"),
        (
            "convergence_from_blocks mismatched",
            lambda: convergence_from_blocks(np.eye(3), np.eye(2), np.eye(3), np.eye(3)),
            pinrate.InputError,
            "blocks",
        ),
        ("path_colours('abc')", lambda: path_colours("abc"), pinrate.InputError, "spectral_radius"),
        ("papers.markdown(None)", lambda: pinrate.papers.markdown(None), pinrate.InputError, "Result"),
        ("load a NUL byte path", lambda: pinrate.load("/tmp/a\x00b.urdf"), pinrate.LoadError, "cannot be resolved"),
        (
            "load ~nosuchuser",
            lambda: pinrate.load(Path("~nosuchuser-pinrate/x.urdf")),
            pinrate.LoadError,
            "cannot be resolved",
        ),
        (
            "load a 300-char name",
            lambda: pinrate.load("/tmp/" + "a" * 300 + ".urdf"),
            pinrate.LoadError,
            "cannot be read",
        ),
    ]


CASE_NAMES = [case for case, *_ in cases(pinrate.load("ur5"))]


@pytest.mark.parametrize("number", range(len(CASE_NAMES)), ids=CASE_NAMES)
def test_a_bad_input_is_a_pinrate_error_naming_it(ur5: pinrate.Robot, number: int) -> None:
    case, call, kind, phrase = cases(ur5)[number]
    with pytest.raises(kind) as caught:
        call()
    assert phrase in str(caught.value), (case, str(caught.value))


def test_an_unreachable_dask_scheduler_is_refused_within_seconds(
    ur5: pinrate.Robot, monkeypatch: pytest.MonkeyPatch
) -> None:
    pytest.importorskip("distributed")
    monkeypatch.setattr(parallel, "SCHEDULER_TIMEOUT", 1.0)
    started = time.monotonic()
    with pytest.raises(pinrate.PinrateError, match=r"no Dask scheduler reachable at 'tcp://127\.0\.0\.1:9'"):
        pinrate.sample_convergence(ur5, 100, scheduler="tcp://127.0.0.1:9")
    assert time.monotonic() - started < 10  # was 30 s and an OSError
    with pytest.raises(pinrate.InputError, match="scheduler address 'nonsense'"):
        pinrate.sample_convergence(ur5, 100, scheduler="nonsense")
    with pytest.raises(pinrate.InputError, match="scheduler must be"):
        pinrate.sample_convergence(ur5, 100, scheduler=42)


def test_exotic_encodings_are_load_errors(tmp_path: Path) -> None:
    for encoding in ("punycode", "base64", "rot13"):
        path = tmp_path / f"{encoding}.urdf"
        path.write_bytes(f'<?xml version="1.0" encoding="{encoding}"?><robot name="r"/>'.encode())
        with pytest.raises(pinrate.LoadError, match=encoding):
            pinrate.load(path)


def test_dask_peers_that_are_not_schedulers_are_refused_in_seconds(
    ur5: pinrate.Robot, monkeypatch: pytest.MonkeyPatch
) -> None:
    pytest.importorskip("distributed")
    monkeypatch.setattr(parallel, "SCHEDULER_TIMEOUT", 1.0)
    import socket
    import threading

    def serve(listener: socket.socket, banner: bytes) -> None:
        connections = []
        while True:
            try:
                connection, _ = listener.accept()
            except OSError:
                return
            connections.append(connection)  # held open, silent, unless there is a banner
            if banner:
                connection.sendall(banner)

    # The HTTP reply parses as a frame of exabytes (MemoryError inside distributed); the silent
    # peer never completes the handshake. Either way: a SchedulerError, in seconds.
    for banner in (b"HTTP/1.1 400 Bad Request\r\n\r\n" * 40, b""):
        listener = socket.create_server(("127.0.0.1", 0))
        threading.Thread(target=serve, args=(listener, banner), daemon=True).start()
        started = time.monotonic()
        with pytest.raises(SchedulerError, match="Dask scheduler"):
            pinrate.sample_convergence(ur5, 10, scheduler=f"tcp://127.0.0.1:{listener.getsockname()[1]}")
        assert time.monotonic() - started < 20
        listener.close()
