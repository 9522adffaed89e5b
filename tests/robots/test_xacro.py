"""``.xacro`` files: expanded by xacrodoc, their packages found in pinrate's one search list,
their meshes confined like any URDF's; the CLI's ``--xacro-arg``.

The description is tests/data/xacro/mypkg (our own): a three-joint arm whose link lengths are
xacro:args, a macro included through ``$(find mypkg)``, a file included by a relative path, a
mesh by ``package://mypkg`` and by ``$(find mypkg)``, and an SRDF by the file's stem.
"""

from __future__ import annotations

import builtins
import shutil
import subprocess
import sys
import warnings
from pathlib import Path

import numpy as np
import pytest

import pinrate
from support import ROOT

pytest.importorskip("xacrodoc")

PACKAGE = ROOT / "tests" / "data" / "xacro" / "mypkg"
ARM = PACKAGE / "urdf" / "arm.urdf.xacro"
MESH = PACKAGE / "meshes" / "x.stl"


def test_loads_with_its_defaults_the_srdf_by_its_stem_and_the_meshes_inside_the_package() -> None:
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no mesh left out
        robot = pinrate.load(ARM)
    assert robot.name == "xacro_arm"
    assert robot.joint_names == ("shoulder_joint", "upper_arm_joint", "forearm_joint")
    assert robot.srdf_path == PACKAGE / "urdf" / "arm.srdf"  # arm.urdf.xacro -> arm.srdf
    assert robot.home_choice == "SRDF group_state 'home'"
    # base 0.1 + shoulder 0.05 + upper arm 0.4 + forearm 0.3 (the xacro:arg defaults), straight up
    np.testing.assert_allclose(robot.pose(np.zeros(3))[:3, 3], [0, 0, 0.85], atol=1e-12)
    files = {geometry.meshPath for geometry in robot.collision_model.geometryObjects}
    files |= {geometry.meshPath for geometry in robot.visual_model.geometryObjects if geometry.meshPath}
    assert str(MESH.resolve()) in files  # package://mypkg/... and $(find mypkg)/... both, read from the package


def test_an_argument_changes_the_pose_by_exactly_that_length() -> None:
    q = np.array([0.0, 0.3, 0.0])  # upper arm pitched by 0.3 rad about y: its length moves the tip along that line
    default = pinrate.load(ARM).pose(q)[:3, 3]
    longer = pinrate.load(ARM, xacro_args={"upper_length": "0.55"}).pose(q)[:3, 3]
    # by hand: 0.15 m more along the upper arm's z axis, rotated by 0.3 rad about y
    np.testing.assert_allclose(longer - default, 0.15 * np.array([np.sin(0.3), 0, np.cos(0.3)]), atol=1e-12)


def test_an_undeclared_argument_is_a_load_error_naming_it() -> None:
    with pytest.raises(pinrate.LoadError, match=r"arm\.urdf\.xacro: xacro argument 'upper_lenght' is not declared"):
        pinrate.load(ARM, xacro_args={"upper_lenght": "0.5"})
    with pytest.raises(pinrate.InputError, match=r"xacro_args are for a \.xacro file"):
        pinrate.load("ur5", xacro_args={"a": "1"})


def test_a_missing_package_is_a_load_error_naming_it(tmp_path: Path) -> None:
    path = tmp_path / "robot.xacro"
    path.write_text(ARM.read_text(encoding="utf-8").replace("$(find mypkg)", "$(find nopkg)"), encoding="utf-8")
    with pytest.raises(pinrate.LoadError, match=r"robot\.xacro: xacro could not expand it: package 'nopkg' not found"):
        pinrate.load(path)


def test_an_undefined_substitution_and_malformed_xml_are_load_errors(tmp_path: Path) -> None:
    undefined = tmp_path / "undefined.urdf.xacro"
    undefined.write_text(
        '<robot name="r" xmlns:xacro="http://www.ros.org/wiki/xacro"><link name="$(arg nothing)"/></robot>', "utf-8"
    )
    with pytest.raises(pinrate.LoadError, match=r"undefined\.urdf\.xacro: xacro could not expand it: .*nothing"):
        pinrate.load(undefined)
    malformed = tmp_path / "malformed.xacro"
    malformed.write_text('<robot name="r" xmlns:xacro="http://www.ros.org/wiki/xacro"><link name="a">', "utf-8")
    with pytest.raises(pinrate.LoadError, match=r"malformed\.xacro: xacro could not expand it: malformed XML"):
        pinrate.load(malformed)


def test_a_package_uri_out_of_the_package_stays_refused() -> None:
    uri = "package://../../etc/passwd"  # no package is named '..'
    with pytest.warns(UserWarning, match="1 mesh left out") as caught:
        robot = pinrate.load(ARM, xacro_args={"tool_mesh": uri})
    assert uri in str(caught[0].message)
    assert "etc/passwd" not in robot.spec().urdf_text


def test_the_escape_through_the_package_is_refused_as_outside() -> None:
    escape = "package://mypkg/" + "../" * 30 + "etc/passwd"
    with pytest.warns(UserWarning, match=r"etc/passwd \(outside the URDF's folder and the package folders\)"):
        pinrate.load(ARM, xacro_args={"tool_mesh": escape})


def test_a_package_folder_named_otherwise_is_found_by_its_package_xml(tmp_path: Path) -> None:
    shutil.copytree(PACKAGE, tmp_path / "mypkg_checkout")  # the folder's name is not the package's
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        robot = pinrate.load(tmp_path / "mypkg_checkout" / "urdf" / "arm.urdf.xacro")
    mesh = str((tmp_path / "mypkg_checkout" / "meshes" / "x.stl").resolve())
    assert mesh in {geometry.meshPath for geometry in robot.visual_model.geometryObjects}


def test_without_xacrodoc_the_error_names_what_to_install(monkeypatch: pytest.MonkeyPatch) -> None:
    real_import = builtins.__import__

    def without_xacrodoc(name: str, *args: object, **kwargs: object) -> object:
        if name.split(".")[0] == "xacrodoc":
            raise ImportError("No module named 'xacrodoc'")
        return real_import(name, *args, **kwargs)  # type: ignore[arg-type]

    monkeypatch.setattr(builtins, "__import__", without_xacrodoc)
    with pytest.raises(pinrate.LoadError, match=r"pip install 'pinrate\[xacro\]'"):
        pinrate.load(ARM)


def run_cli(*arguments: str) -> subprocess.CompletedProcess[str]:
    command = [sys.executable, "-m", "pinrate.cli", *arguments]
    return subprocess.run(command, capture_output=True, text=True, timeout=600, check=False)


def test_the_cli_demo_converges_on_a_xacro_with_an_argument() -> None:
    result = run_cli(
        "demo", str(ARM), "--xacro-arg", "upper_length:=0.5", "--xacro-arg", "forearm_length:=0.35", "--no-viewer"
    )
    assert result.returncode == 0, result.stderr
    assert "converged  yes" in result.stdout


def test_the_cli_refuses_a_malformed_xacro_arg_naming_the_option() -> None:
    result = run_cli("demo", str(ARM), "--xacro-arg", "upper_length=0.5", "--no-viewer")
    assert result.returncode == 2
    assert result.stderr.count("\n") == 1
    assert "argument --xacro-arg: expected NAME:=VALUE" in result.stderr
    undeclared = run_cli("demo", str(ARM), "--xacro-arg", "nothing:=1", "--no-viewer")
    assert undeclared.returncode != 0
    assert "xacro argument 'nothing' is not declared" in undeclared.stderr
    assert "Traceback" not in undeclared.stderr
