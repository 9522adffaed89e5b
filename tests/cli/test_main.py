"""The command line: `pinrate list` and `pinrate demo`."""

from __future__ import annotations

import dataclasses
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import pinrate
from pinrate.cli import main
from pinrate.robots import ROBOT_NAMES


def test_list_prints_every_loadable_name(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["list"]) == 0
    out = capsys.readouterr().out
    for name in (*ROBOT_NAMES, "ur3", "ur5", "ur10", "panda", "z1", "xarm7", "so100", "so101", "kinova"):
        assert name in out


def test_demo_ur5_converges_and_summarises(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["demo", "ur5", "--no-viewer"]) == 0
    out = capsys.readouterr().out
    assert "converged  yes" in out
    for field in ("partition", "algorithm  mca1", "steps", "errors", "rho        ", "coupling   |U A^-1|"):
        assert field in out


def test_demo_with_explicit_target(capsys: pytest.CaptureFixture[str]) -> None:
    code = main(
        ["demo", "scara", "--no-viewer", "--algorithm", "mca2", "--target", "0.9", "0.3", "-0.1", "0", "0", "0.4"]
    )
    out = capsys.readouterr().out
    assert "algorithm  mca2" in out
    assert code in (0, 1)


def test_demo_bad_robot_is_a_clear_error(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["demo", "ur55"]) == 2
    err = capsys.readouterr().err
    assert "unknown robot name 'ur55'" in err and "ur5" in err


def test_console_script_runs() -> None:
    result = subprocess.run([sys.executable, "-m", "pinrate.cli", "list"], capture_output=True, text=True, check=False)
    assert result.returncode == 0 and "ur5" in result.stdout


def test_demo_reports_an_automatic_tip(capsys: pytest.CaptureFixture[str]) -> None:
    from support import DATA

    main(["demo", str(DATA / "mixed_joints.urdf"), "--no-viewer", "--max-steps", "5"])
    out = capsys.readouterr().out
    assert "tip        tool (chosen: named like a tool centre on 'pitch'" in out and "left out: finger_joint" in out


def test_demo_starts_at_q0_given_per_joint(capsys: pytest.CaptureFixture[str]) -> None:
    import pinrate
    from pinrate.kinematics.targets import nearby_target

    q0 = np.array([0.1, -1.2, 1.3, -1.4, -1.5, 0.2])
    assert main(["demo", "ur5", "--no-viewer", "--max-steps", "1", "--q0", *map(str, q0)]) in (0, 1)
    out = capsys.readouterr().out
    printed = float(out.split("errors     position ")[1].split(" ")[0])
    # The first error is measured at q0, towards the target drawn near q0 (seed 0).
    ur5 = pinrate.load("ur5")
    _, target = nearby_target(ur5, pinrate.Partition.auto(ur5), 0, start=q0)
    assert printed == pytest.approx(np.linalg.norm(target[:3, 3] - ur5.pose(q0)[:3, 3]), rel=1e-3)


def test_version_names_the_backend(monkeypatch: pytest.MonkeyPatch) -> None:
    result = subprocess.run(
        [sys.executable, "-m", "pinrate.cli", "--version"], capture_output=True, text=True, timeout=60, check=False
    )
    assert result.returncode == 0, result.stderr
    assert result.stdout.splitlines() == [f"pinrate {pinrate.__version__}", f"backend: {pinrate.backend()}"]
    monkeypatch.setenv("PINRATE_BACKEND", "python")
    result = subprocess.run(
        [sys.executable, "-m", "pinrate.cli", "--version"], capture_output=True, text=True, timeout=60, check=False
    )
    assert "backend: python (PINRATE_BACKEND=python)" in result.stdout


def test_many_targets_are_drawn_as_their_segments_start(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    # `--targets 1000000000` drew every target before the first segment: nothing printed
    # while memory grew by 1.1 MB/s. Now each is drawn when its segment starts.
    from pinrate.cli import demo

    drawn = []

    def nearby_target(*args: object, **kwargs: object) -> object:
        drawn.append(1)
        if len(drawn) == 3:
            raise KeyboardInterrupt  # Ctrl-C as the third segment starts
        return real(*args, **kwargs)

    real = demo.nearby_target
    monkeypatch.setattr(demo, "nearby_target", nearby_target)
    assert main(["demo", "ur5", "--no-viewer", "--targets", "1000000000", "--max-steps", "5"]) == 130
    out = capsys.readouterr().out
    assert "segment 2/1000000000" in out and len(drawn) == 3


@pytest.mark.skipif(not os.path.exists("/dev/full"), reason="needs Linux /dev/full")
def test_a_replay_that_cannot_be_written_is_one_error_line(capsys: pytest.CaptureFixture[str]) -> None:
    # A device is refused before the run (the replay replaces a regular file whole).
    assert main(["demo", "ur5", "--record", "/dev/full", "--max-steps", "1", "--speed", "1000"]) == 2
    captured = capsys.readouterr()
    said = "pinrate: error: --record '/dev/full' exists and is not a regular file"
    assert captured.err.strip().splitlines() == [said]
    assert "converged" not in captured.out and "segment" not in captured.out  # nothing ran


def test_python_dash_m_pinrate_is_the_command_line() -> None:
    ran = subprocess.run([sys.executable, "-m", "pinrate", "--version"], capture_output=True, text=True, timeout=60)
    assert ran.returncode == 0 and ran.stdout.startswith("pinrate ") and not ran.stderr


def test_the_demo_falls_back_to_exact_where_mca1_does_not_converge_and_says_so(
    tmp_path, capsys: pytest.CaptureFixture[str]
) -> None:
    # Shoham & Koren's spherical 6-DOF arm with a 5 m tool: the coupling B W^-1 U A^-1 grows
    # with the tool, rho nears 1 (0.95 on the way) and MCA1 does not reach the first target
    # within the demo's step budget, while the exact inverse does (checked here first, so the
    # test stands on measured behaviour).
    from pinrate.cli.parser import DEMO_MAX_STEPS
    from pinrate.kinematics.targets import nearby_target
    from pinrate.robots import parametric

    path = tmp_path / "long_tool.urdf"
    path.write_text(parametric.urdf("spherical_6dof", l=5.0), encoding="utf-8")
    robot = pinrate.load(path)
    _, target = nearby_target(robot, pinrate.Partition.auto(robot), 0)
    assert not pinrate.servo(robot, robot.home(), target, algorithm="mca1", max_steps=DEMO_MAX_STEPS).converged
    assert pinrate.servo(robot, robot.home(), target, algorithm="exact").converged

    assert main(["demo", str(path), "--no-viewer"]) == 0
    out = capsys.readouterr().out
    assert "algorithm  mca1" in out and "converged  no" in out  # the lesson is kept
    assert "fallback   mca1 did not reach it: exact from the same start" in out
    assert "algorithm  exact" in out and "converged  yes" in out
    # asked for by name, mca1 is kept to: no fallback, and the exit code says it failed
    assert main(["demo", str(path), "--no-viewer", "--algorithm", "mca1"]) == 1
    assert "fallback" not in capsys.readouterr().out


def test_a_demo_target_the_exact_motion_does_not_reach_is_drawn_again(monkeypatch: pytest.MonkeyPatch) -> None:
    # A target within reach joint by joint can lie across a joint's limit for the tip's way
    # there (a FANUC M-430iA's first target asked joint_1 for half a turn): the demo draws
    # again, from a seed of its own, when the exact dry run does not converge.
    import argparse

    from pinrate.cli import demo
    from pinrate.kinematics.targets import nearby_target

    robot = pinrate.load("ur5")
    partition = pinrate.Partition.auto(robot)
    real_servo, dry_runs = demo.servo, []

    def servo(*args: object, **kwargs: object) -> pinrate.Trajectory:
        run = real_servo(*args, **kwargs)
        dry_runs.append(run)
        if len(dry_runs) == 1:  # the first draw's dry run "fails"
            run = dataclasses.replace(run, converged=False, reason="stalled: (pretend)")
        return run

    monkeypatch.setattr(demo, "servo", servo)
    args = argparse.Namespace(dt=0.01, tol=1e-4)
    target = demo._servable_target(args, robot, partition, 7, robot.home())
    assert len(dry_runs) == 2 and all(run.algorithm == "exact" for run in dry_runs)
    np.testing.assert_array_equal(target, nearby_target(robot, partition, 7 + 1_000_003)[1])


@pytest.mark.parametrize("algorithm", [None, "exact"])
def test_demo_converges_on_a_five_dof_arm(algorithm: str | None, capsys: pytest.CaptureFixture[str]) -> None:
    """Issue 24 item 4: a yaw-pitch-pitch-pitch-roll arm (6 rows, 5 joints) with the demo's
    defaults and with exact (position first), three random reachable targets."""
    path = Path(__file__).parent.parent / "data" / "five_dof_arm.urdf"
    chosen = [] if algorithm is None else ["--algorithm", algorithm]
    assert main(["demo", str(path), "--no-viewer", "--targets", "3", *chosen]) == 0
    out = capsys.readouterr().out
    assert out.count(" converged ") == 3, out[-2000:]
    assert "position first" in out  # the partition's description says the rule
