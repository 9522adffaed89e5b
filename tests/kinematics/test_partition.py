"""The arm/wrist partition (eq. 17-19) and the contract's automatic rule."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import pinrate
from mimic_urdfs import parallelogram_arm
from pinrate import Partition


def test_ur5_auto_is_three_plus_three(ur5: pinrate.Robot) -> None:
    partition = Partition.auto(ur5)
    assert partition.arm == ("shoulder_pan_joint", "shoulder_lift_joint", "elbow_joint")
    assert partition.wrist == ("wrist_1_joint", "wrist_2_joint", "wrist_3_joint")
    assert (partition.linear, partition.angular) == ("xyz", "xyz")


def test_panda_auto_is_four_plus_three_without_fingers(panda: pinrate.Robot) -> None:
    partition = Partition.auto(panda)
    assert partition.arm == tuple(f"panda_joint{i}" for i in range(1, 5))
    assert partition.wrist == tuple(f"panda_joint{i}" for i in range(5, 8))


def test_planar_robots_drop_the_zero_rows() -> None:
    scara = Partition.auto(pinrate.robots.scara())
    assert (scara.linear, scara.angular) == ("xyz", "z")
    assert (scara.arm, scara.wrist) == (("theta1", "theta2", "d"), ("theta3",))
    polar = Partition.auto(pinrate.robots.planar_polar())
    assert (polar.linear, polar.angular) == ("xy", "z")
    assert (polar.arm, polar.wrist) == (("theta1", "d2"), ("theta3",))


def test_fewer_joints_than_components() -> None:
    # SO-100: five arm joints for six twist components: a 3 + 2 split, W is 3x2.
    robot = pinrate.load("so100")
    partition = Partition.auto(robot)
    assert len(partition.arm) == 3 and len(partition.wrist) == 2
    _A, B, _U, W = partition.blocks(robot, robot.jacobian(robot.home()))
    assert W.shape == (3, 2) and B.shape == (3, 2)


def test_blocks_are_the_rows_and_columns_named(mixed: pinrate.Robot) -> None:
    partition = Partition(["slide", "yaw"], ["pitch"], linear="zx", angular="y")
    q = mixed.random_configuration(2)
    jacobian = mixed.jacobian(q)
    A, B, U, W = partition.blocks(mixed, jacobian)
    yaw, slide, _roll, pitch = (mixed.velocity_indices(j)[0] for j in ("yaw", "slide", "roll", "pitch"))
    expected_A = [[jacobian[2, slide], jacobian[2, yaw]], [jacobian[0, slide], jacobian[0, yaw]]]
    np.testing.assert_array_equal(A, expected_A)
    np.testing.assert_array_equal(B, [[jacobian[2, pitch]], [jacobian[0, pitch]]])
    np.testing.assert_array_equal(U, [[jacobian[4, slide], jacobian[4, yaw]]])
    np.testing.assert_array_equal(W, [[jacobian[4, pitch]]])


def test_empty_groups_are_allowed(ur5: pinrate.Robot) -> None:
    partition = Partition(list(ur5.joint_names), [], linear="xyz", angular="")
    A, B, U, W = partition.blocks(ur5, ur5.jacobian(ur5.home()))
    assert A.shape == (3, 6) and B.shape == (3, 0) and U.shape == (0, 6) and W.shape == (0, 0)


def test_str_explains_the_split(ur5: pinrate.Robot) -> None:
    text = str(Partition.auto(ur5))
    assert "arm" in text and "wrist" in text and "elbow_joint" in text and "3x3" in text


def test_overlapping_joints() -> None:
    with pytest.raises(pinrate.InputError, match=r"overlap.*elbow"):
        Partition(["shoulder", "elbow"], ["elbow", "wrist"])


def test_repeated_joint() -> None:
    with pytest.raises(pinrate.InputError, match="more than once"):
        Partition(["a", "a"], ["b"])


def test_unknown_joint_lists_the_joints(ur5: pinrate.Robot) -> None:
    partition = Partition(["shoulder_pan_joint", "elbow"], ["wrist_1_joint"])
    with pytest.raises(pinrate.InputError) as error:
        partition.blocks(ur5, ur5.jacobian(ur5.home()))
    assert "'elbow'" in str(error.value) and "elbow_joint" in str(error.value)


@pytest.mark.parametrize(("linear", "angular"), [("xw", "z"), ("xx", "z"), ("x", "zz"), ("x", "q")])
def test_bad_axis_letters(linear: str, angular: str) -> None:
    with pytest.raises(pinrate.InputError, match="axes"):
        Partition(["a"], ["b"], linear=linear, angular=angular)


def test_jacobian_of_the_wrong_shape(ur5: pinrate.Robot) -> None:
    with pytest.raises(pinrate.InputError, match="shape"):
        Partition.auto(ur5).blocks(ur5, np.zeros((6, 5)))


def test_block_shapes_count_velocity_components(tmp_path) -> None:
    # A planar base joint has 3 velocity components: with j1, A is 3x4, not "3x2".
    limit = '<limit lower="-2" upper="2" effort="1" velocity="1"/>'
    text = (
        '<robot name="mobile"><link name="world"/><link name="base"/><link name="l1"/><link name="l2"/>'
        '<joint name="floor" type="planar"><parent link="world"/><child link="base"/><axis xyz="0 0 1"/></joint>'
        f'<joint name="j1" type="revolute"><parent link="base"/><child link="l1"/><axis xyz="0 1 0"/>{limit}</joint>'
        f'<joint name="j2" type="revolute"><parent link="l1"/><child link="l2"/><origin xyz="0 0 0.5"/>'
        f'<axis xyz="0 1 0"/>{limit}</joint></robot>'
    )
    path = tmp_path / "mobile.urdf"
    path.write_text(text, encoding="utf-8")
    robot = pinrate.load(path)
    partition = pinrate.Partition(("floor", "j1"), (), linear="xyz", angular="")
    assert "A is 3x4, W is 0x0" in partition.describe(robot)
    assert "A is 3x2" in str(partition)  # without the robot: joints, as before


PLANAR_BASE = """<?xml version="1.0"?>
<robot name="planar_base_arm">
  <link name="world"/><link name="base"/>
  <joint name="base_planar" type="planar"><parent link="world"/><child link="base"/><axis xyz="0 0 1"/>
    <limit effort="1" velocity="1" lower="-1" upper="1"/></joint>
  <link name="l1"/><link name="l2"/><link name="l3"/><link name="tool0"/>
  <joint name="j1" type="revolute"><parent link="base"/><child link="l1"/><origin xyz="0 0 0.3"/>
    <axis xyz="0 0 1"/><limit effort="1" velocity="1" lower="-2" upper="2"/></joint>
  <joint name="j2" type="revolute"><parent link="l1"/><child link="l2"/><origin xyz="0 0 0.4"/>
    <axis xyz="0 1 0"/><limit effort="1" velocity="1" lower="-2" upper="2"/></joint>
  <joint name="j3" type="revolute"><parent link="l2"/><child link="l3"/><origin xyz="0 0 0.3"/>
    <axis xyz="0 1 0"/><limit effort="1" velocity="1" lower="-2" upper="2"/></joint>
  <joint name="tool" type="fixed"><parent link="l3"/><child link="tool0"/><origin xyz="0.1 0 0"/></joint>
</robot>
"""


def test_a_planar_base_is_left_out_of_the_automatic_partition_and_the_demo_and_analyze_run(tmp_path) -> None:
    from pinrate.analysis import analyze
    from pinrate.cli import main

    path = tmp_path / "planar_base_arm.urdf"
    path.write_text(PLANAR_BASE, encoding="utf-8")
    robot = pinrate.load(path)
    partition = pinrate.Partition.auto(robot)
    assert "base_planar" in robot.joint_names and "base_planar" not in partition.joints
    assert partition.joints == ("j1", "j2", "j3")
    assert main(["demo", str(path), "--no-viewer"]) == 0
    assert analyze(robot, samples=200, points=11, tcp_samples=20).sample.spectral_radius.size == 200
    # Named in a partition, the base takes part; a region map over it is refused clearly.
    with_base = pinrate.Partition(["base_planar", "j1"], ["j2", "j3"], linear="xyz", angular="yz")
    assert with_base.describe(robot).splitlines()[-1].startswith("A is 3x4")
    with pytest.raises(pinrate.InputError, match="3 DOF"):
        pinrate.analysis.region_map(robot, joints=["base_planar", "j1"], partition=with_base, points=5)


def test_a_partition_naming_a_joint_off_the_tip_chain_is_an_input_error() -> None:
    robot = pinrate.load(
        Path(__file__).parent.parent / "data" / "third_party" / "stretch_SE3_eoa_wrist_dw3_tool_sg3.urdf"
    )
    partition = pinrate.Partition(["joint_lift", "joint_head_pan", "joint_arm_l0"], ["joint_wrist_yaw"])
    with pytest.raises(pinrate.InputError, match="'joint_head_pan' is not on the chain"):
        pinrate.joint_rates(robot, robot.home(), np.zeros(6), partition=partition)


def _load_text(tmp_path: Path, text: str) -> pinrate.Robot:
    path = tmp_path / "robot.urdf"
    path.write_text(text, encoding="utf-8")
    return pinrate.load(path)


def test_a_shoulder_that_parallelogram_links_mimic_stays_in_the_arm(tmp_path: Path) -> None:
    # Issue 24 item 1: the IRB 6640's side links mimic joint_2; the shoulder was dropped (3 + 2).
    robot = _load_text(tmp_path, parallelogram_arm())
    partition = Partition.auto(robot)
    assert partition.arm == ("joint_1", "joint_2", "joint_3")
    assert partition.wrist == ("joint_4", "joint_5", "joint_6")
    assert robot.tip == "tool0" and "joint_2" not in robot.hand_joints
    assert set(robot.arm_mimics) == {"side_a_joint", "side_b_joint"}
    assert "joint_2" not in robot.tip_choice and "gripper/hand" not in robot.tip_choice

    # The shoulder serves: a target 0.2 rad away on joint_2 alone is reached.
    q_target = robot.home()
    q_target[robot.model.joints[robot.joint_id("joint_2")].idx_q] += 0.2
    run = pinrate.servo(robot, robot.home(), robot.pose(q_target))
    assert run.converged, run.reason

    # A teleop step along the sensor's x moves the tip along it (robot.pose, not the Jacobian).
    home = robot.home()
    step = pinrate.Controller(robot).step(home, [0.05, 0, 0, 0, 0, 0])
    before, after = robot.pose(home), robot.pose(step.q)
    moved = after[:3, 3] - before[:3, 3]
    commanded = before[:3, :3] @ np.array([1.0, 0.0, 0.0])  # the sensor is the tip here
    assert robot.sensor == robot.tip and np.linalg.norm(moved) > 1e-4
    angle = np.degrees(np.arccos(np.clip(moved @ commanded / np.linalg.norm(moved), -1.0, 1.0)))
    assert angle < 1.0 and step.status is pinrate.Status.OK, (angle, step.status, step.detail)


def test_a_mimic_gripper_stays_out_while_the_mimicked_shoulder_stays_in(tmp_path: Path) -> None:
    # Fingers that mimic one another at the end of the chain (one below the other) are a hand.
    robot = _load_text(tmp_path, parallelogram_arm(gripper=True))
    assert set(robot.hand_joints) == {"left_joint", "right_joint", "left_tip_joint"}
    assert robot.tip == "tool0"
    partition = Partition.auto(robot)
    assert partition.joints == tuple(f"joint_{i}" for i in range(1, 7))


def test_a_five_dof_arm_puts_position_first() -> None:
    """Issue 24 item 4: yaw, three pitches and a roll, six rows: A 3x3, W 3x2, position first
    (the description says so); a 6-DOF arm's square blocks do not."""
    robot = pinrate.load(Path(__file__).parent.parent / "data" / "five_dof_arm.urdf")
    partition = Partition.auto(robot)
    assert partition.arm == ("base_yaw", "shoulder_pitch", "elbow_pitch")
    assert partition.wrist == ("wrist_pitch", "wrist_roll")
    assert (partition.linear, partition.angular) == ("xyz", "xyz")
    assert partition.resolve(robot).position_first
    assert "position first" in partition.describe(robot)
    ur5 = pinrate.load("ur5")
    assert not Partition.auto(ur5).resolve(ur5).position_first
    assert "position first" not in Partition.auto(ur5).describe(ur5)
