"""pinrate.compiled.kinematics: the core's rebuilt model gives the Python model's Jacobian."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import pinrate
from compiled_core import needs_core, path
from pinrate.compiled import core_kinematics
from pinrate.control.controller import Controller
from support import DATA

pytestmark = needs_core

sys_path_fuzz = pytest.importorskip("fuzz.test_random_urdfs", reason="the fuzz generator")


@pytest.mark.parametrize("name", ["ur5", "panda", "scara", "kinova", "barker_arm", "z1", "planar_polar"])
def test_the_same_jacobian_as_the_python_model(name: str) -> None:
    robot = pinrate.load(name)
    with path("compiled"):
        kinematics = core_kinematics(robot)
    rng = np.random.default_rng(0)
    for q in robot.sample_configurations(30, rng):
        ours, theirs = kinematics.jacobian(q), robot.kinematics(q)[0]
        if robot.sensor_id == robot.tip_id:
            np.testing.assert_array_equal(ours, theirs)  # the same Pinocchio calls on the same numbers
        else:
            np.testing.assert_allclose(ours, theirs, rtol=0, atol=1e-15)  # numpy's rotation vs Eigen's


@pytest.mark.parametrize("seed", range(40))
def test_random_trees_every_joint_kind_any_sensor(tmp_path: Path, seed: int) -> None:
    """Revolute, prismatic, continuous and fixed joints with odd axes, branches, any sensor."""
    rng = np.random.default_rng(seed)
    urdf = tmp_path / f"random{seed}.urdf"
    urdf.write_text(sys_path_fuzz.random_urdf(rng), encoding="utf-8")
    bodies = [frame.name for frame in pinrate.load(urdf).model.frames if frame.name.startswith("link")]
    robot = pinrate.load(urdf, sensor=str(rng.choice(bodies)))
    with path("compiled"):
        kinematics = core_kinematics(robot)
    for _ in range(3):
        q = robot.random_configuration(rng)
        np.testing.assert_allclose(kinematics.jacobian(q), robot.kinematics(q)[0], rtol=0, atol=1e-14)


def test_a_joint_the_core_does_not_rebuild_runs_on_python(tmp_path: Path) -> None:
    urdf = tmp_path / "planar_base.urdf"
    urdf.write_text(
        '<robot name="planar_base"><link name="base"/><link name="a"/><link name="b"/><link name="c"/>'
        '<joint name="slide" type="planar"><parent link="base"/><child link="a"/><axis xyz="0 0 1"/></joint>'
        '<joint name="j1" type="revolute"><parent link="a"/><child link="b"/><origin xyz="0 0 0.3"/>'
        '<axis xyz="0 1 0"/><limit lower="-2" upper="2" effort="1" velocity="1"/></joint>'
        '<joint name="j2" type="revolute"><parent link="b"/><child link="c"/><origin xyz="0 0 0.3"/>'
        '<axis xyz="0 1 0"/><limit lower="-2" upper="2" effort="1" velocity="1"/></joint>'
        '<link name="d"/><joint name="tool" type="fixed"><parent link="c"/><child link="d"/>'
        '<origin xyz="0 0 0.3"/></joint></robot>',
        encoding="utf-8",
    )
    robot = pinrate.load(urdf, tip="d")
    with path("compiled"):
        with pytest.raises(pinrate.PinrateError, match="'slide' is a JointModelPlanar"):
            core_kinematics(robot)
        partition = pinrate.Partition(["j1", "j2"], [], linear="xz", angular="")
        controller = Controller(robot, partition=partition)
        assert "JointModelPlanar" in controller.compiled_reason()
        assert controller.compiled() is None
        start = robot.home()
        start[robot.model.joints[robot.joint_id("j2")].idx_q] = 0.8  # bent: straight is singular
        target = robot.pose(start)
        target[0, 3] += 0.02
        assert pinrate.servo(robot, start, target, partition=partition).converged  # on Python


def test_the_mixed_robot_of_the_tests() -> None:
    robot = pinrate.load(DATA / "mixed_joints.urdf", tip="tool", sensor="link2")
    with path("compiled"):
        kinematics = core_kinematics(robot)
    for q in robot.sample_configurations(20, np.random.default_rng(1)):
        np.testing.assert_allclose(kinematics.jacobian(q), robot.kinematics(q)[0], rtol=0, atol=1e-15)
