"""Every refused command line ends in one line ``pinrate: error: ...`` and exit code 2, before
any work starts; never a traceback (pinrate.cli.arguments, pinrate.cli.robot_arguments)."""

from __future__ import annotations

from pathlib import Path

import pytest

from pinrate.cli import main

XACRO = '<robot name="r" xmlns:xacro="http://www.ros.org/wiki/xacro"><xacro:property name="l" value="1"/></robot>'


def cases(tmp: Path) -> list[tuple[list[str], str]]:
    """(argv, a phrase the error line must contain); ``tmp`` holds the files of :func:`files`."""
    out = ["--out", str(tmp / "report")]
    return [
        (["demo", "ur5", "--seed", "-1"], "--seed: must be at least 0"),
        (["demo", "ur5", "--speed", "0"], "--speed: must be from 0.001 to 1000"),
        (["demo", "ur5", "--speed", "-2"], "--speed: must be from 0.001 to 1000"),
        (["demo", "ur5", "--speed", "1e-300"], "--speed: must be from 0.001 to 1000"),
        (["demo", "ur5", "--targets", "0"], "--targets: must be at least 1"),
        (["demo", "ur5", "--targets", "two"], "--targets: expected an integer"),
        (["demo", "ur5", "--dt", "nan"], "--dt: must be a finite number"),
        (["demo", "ur5", "--gain", "0"], "--gain: must be positive"),
        (["demo", "ur5", "--tol", "-1"], "--tol: must be positive"),
        (["demo", "ur5", "--tol", "1e-20", "--no-viewer"], "tol must be at least 1e-12"),
        (["demo", "ur5", "--max-steps", "-5"], "--max-steps: must be at least 0"),
        (["demo", "ur5", "--max-steps", "2.5"], "--max-steps: expected an integer"),
        (["demo", "ur5", "--max-steps", "1000001"], "--max-steps: must be at most 1,000,000"),
        (["demo", "ur5", "--max-steps", "99999999999999999999"], "--max-steps: must be at most 1,000,000"),
        (["demo", "ur5", "--target", "0", "0", "nan", "0", "0", "0"], "--target: must be a finite number"),
        (["demo", "ur5", "--target", "1e9", "0", "0", "0", "0", "0", "--no-viewer"], "physical bound"),
        (["demo", "ur5", "--algorithm", "bogus"], "invalid choice: 'bogus'"),
        (["demo", "ur5", "--record", str(tmp / "missing" / "run.html")], "does not exist"),
        (["demo", "ur5", "--record", str(tmp)], "is a folder"),
        (["demo", "ur5", "--record", str(tmp / "run.html"), "--no-viewer"], "drop --no-viewer"),
        (["demo", "ur5", "--record", ""], "--record must be a path, got ''"),
        (["demo", "ur5", "--record", "/proc/pinrate-run.html"], "--record '/proc/pinrate-run.html'"),
        (["demo", "ur5", "--record", "/sys/pinrate-run.html"], "--record '/sys/pinrate-run.html'"),
        (["demo", "ur5", "--tip", ""], "--tip must name a frame, got ''"),
        (["demo", "ur5", "--sensor", " "], "--sensor must name a frame, got ' '"),
        (["demo", "ur5", "--host", "8.8.8.8"], "not an address of this machine"),
        (["demo", "ur5", "--host", "256.1.1.1"], "host '256.1.1.1'"),
        (["demo", "ur5", "--tip", "nosuch"], "no frame 'nosuch'"),
        (["demo", "ur5", "--max-joints", "0"], "--max-joints: must be at least 1"),
        (["demo", "ur5", "--q0", "0", "1"], "--q0 takes 6 values"),
        (["demo", "ur5", "--q0", "0", "0", "0", "0", "0", "1e9"], "physical bound"),
        (["demo", "ur55"], "unknown robot name 'ur55'"),
        (["demo", str(tmp / "arm.urdf.xacro")], "arm.urdf.xacro: the URDF has no <link>"),  # expanded, then checked
        (["demo", str(tmp / "arm.urdf.xacro"), "--xacro-arg", "l:=2"], "xacro argument 'l' is not declared"),
        (["demo", str(tmp / "arm.urdf.xacro"), "--xacro-arg", "l=2"], "argument --xacro-arg: expected NAME:=VALUE"),
        (["demo", "ur5", "--xacro-arg", "l:=2"], "xacro_args are for a .xacro file"),
        (["demo", str(tmp / "missing.urdf")], "not found"),
        (["demo", str(tmp)], "not a file"),
        (["demo", str(tmp / "afile")], "malformed XML"),
        (["analyze", "scara", "--points", "1", *out], "--points: must be at least 2"),
        (["analyze", "scara", "--points", "0", *out], "--points: must be at least 2"),
        (["analyze", "scara", "--points", "-3", *out], "--points: must be at least 2"),
        (["analyze", "scara", "--samples", "0", *out], "--samples: must be at least 1"),
        (["analyze", "scara", "--workers", "0", *out], "--workers: must be at least 1"),
        (["analyze", "scara", "--seed", "-1", *out], "--seed: must be at least 0"),
        (["analyze", "scara", "--out", str(tmp / "afile")], "exists and is not a folder"),
        (["analyze", "scara", "--out", "/proc/pinrate-report"], "cannot be created"),
        (["analyze", "scara", "--arm", "nosuch", *out], "no moving joint 'nosuch'"),
        (["analyze", "scara", "--linear", "xq", *out], "unknown letter"),
        (["analyze", "scara", "--joints", "theta1", "theta1", "--samples", "100", *out], "two different joints"),
        (["analyze", "scara", "--sweep", "garbage", *out], "--sweep takes PARAM=LO:HI"),
        (["analyze", "scara", "--sweep", "", *out], "--sweep takes PARAM=LO:HI"),
        (["analyze", "scara", "--tip", "", *out], "--tip must name a frame, got ''"),
        (["analyze", "scara", "--out", str(tmp / "report" / "deeper"), "--arm", "nosuch"], "no moving joint"),
        (["teleop", "ur55", "--record-dir", str(tmp / "report")], "unknown robot name 'ur55'"),
        (["analyze", "ur5", "--sweep", "l1=0.1:1", *out], "--sweep needs one of the papers' parametric robots"),
        (["analyze", "scara", "--scheduler", "nonsense", "--samples", "100", *out], "scheduler address 'nonsense'"),
        (["nosuch"], "invalid choice: 'nosuch'"),
        ([], "required: command"),
    ]


def files(tmp: Path) -> None:
    (tmp / "arm.urdf.xacro").write_text(XACRO, encoding="utf-8")
    (tmp / "afile").write_text("not a folder", encoding="utf-8")


ARGVS = [argv for argv, _ in cases(Path("/nonexistent"))]  # ids only: the files are made per test


@pytest.mark.parametrize("number", range(len(ARGVS)), ids=[" ".join(argv) or "(none)" for argv in ARGVS])
def test_a_refused_command_line_is_one_error_line_and_exit_2(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], number: int
) -> None:
    files(tmp_path)
    argv, phrase = cases(tmp_path)[number]
    assert main(argv) == 2
    captured = capsys.readouterr()
    lines = captured.err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("pinrate: error: "), captured.err
    assert phrase in lines[0]
    assert "Traceback" not in captured.out + captured.err
    # A refused command leaves no folder it made (--out, --record-dir: tmp/report).
    assert not (tmp_path / "report").exists()


def test_a_refused_report_folder_is_refused_before_the_work(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    # A million samples would take minutes: the answer comes before any of them.
    (tmp_path / "afile").write_text("keep", encoding="utf-8")
    assert main(["analyze", "ur5", "--samples", "1000000", "--out", str(tmp_path / "afile")]) == 2
    assert (tmp_path / "afile").read_text(encoding="utf-8") == "keep"


def test_help_exits_zero(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["demo", "--help"]) == 0
    assert "--max-joints" in capsys.readouterr().out
