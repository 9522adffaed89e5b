"""The default tip of any URDF: the tool frame of the main arm, gripper and hand joints left
out (pinrate.kinematics.frames; contract v2, "Robot defaults for any URDF")."""

from __future__ import annotations

import warnings
from pathlib import Path

import pytest

import pinrate
from mimic_urdfs import dual_arm_torso, parallelogram_arm
from pinrate.robots import example_robot_data_share

SHARE = example_robot_data_share()
ROBOTS = None if SHARE is None else SHARE / "example-robot-data" / "robots"

# Loaded by path, without the name table: what an engineer would pick, and why.
EXPECTED_TIPS = [
    ("panda_description/urdf/panda.urdf", "panda_hand_tcp"),  # the TCP; prismatic mimic fingers left out
    ("so_arm_description/urdf/so100.urdf", "gripper"),  # the gripper body; the jaw joint 'gripper' left out
    ("so_arm_description/urdf/so101.urdf", "gripper_frame_link"),  # its gripper frame
    ("z1_description/urdf/z1.urdf", "gripperStator"),  # the fixed half of the gripper; jointGripper left out
    ("kinova_description/robots/kinova.urdf", "j2s6s200_end_effector"),  # finger joints left out
    ("ur_description/urdf/ur5_robot.urdf", "tool0"),  # ROS-Industrial's tool flange frame
    ("ur_description/urdf/ur5_gripper.urdf", "tool0"),
    ("xarm_description/urdf/xarm7.urdf", "link_eef"),
    ("baxter_description/urdf/baxter.urdf", "left_gripper"),  # two equal arms: the first in model order
    ("tiago_description/robots/tiago.urdf", "hand_grasping_frame"),  # 36 hand joints left out
    ("tiago_pro_description/robots/tiago_pro.urdf", "arm_left_tool_link"),
]


@pytest.mark.skipif(ROBOTS is None, reason="example-robot-data is not installed")
@pytest.mark.parametrize(("relative", "tip"), EXPECTED_TIPS, ids=[tip for _, tip in EXPECTED_TIPS])
def test_the_default_tip_is_the_tool_frame_of_the_main_arm(relative: str, tip: str) -> None:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # meshes are not needed
        robot = pinrate.load(Path(ROBOTS) / relative)
    assert robot.tip == tip, robot.tip_choice
    assert robot.tip_choice.startswith("chosen: named like a tool centre")
    assert not set(robot.hand_joints) & set(robot.tip_chain())


LIMIT = '<limit lower="-1" upper="1" effort="1" velocity="1"/>'


def arm_with(hand: str, tool: str = "flange") -> str:
    """A 3-joint arm, a fixed frame ``tool`` on its last link, and ``hand`` below that link."""
    joints = "".join(
        f'<joint name="j{i}" type="revolute"><parent link="l{i}"/><child link="l{i + 1}"/>'
        f'<origin xyz="0 0 0.3"/><axis xyz="0 {i % 2} {1 - i % 2}"/>{LIMIT}</joint>'
        for i in range(3)
    )
    links = "".join(f'<link name="l{i}"/>' for i in range(4))
    tool_joint = f'<link name="{tool}"/><joint name="t" type="fixed"><parent link="l3"/><child link="{tool}"/></joint>'
    return f'<robot name="arm">{links}{joints}{tool_joint}{hand}</robot>'


def finger(name: str, kind: str, inner: str = "", parent: str = "l3") -> str:
    limit = '<limit lower="0" upper="0.04" effort="1" velocity="1"/>' if kind != "fixed" else ""
    return (
        f'<link name="{name}_link"/><joint name="{name}" type="{kind}"><parent link="{parent}"/>'
        f'<child link="{name}_link"/><origin xyz="0 0 0.1"/><axis xyz="1 0 0"/>{limit}{inner}</joint>'
    )


@pytest.mark.parametrize(
    ("case", "hand", "left_out"),
    [
        ("prismatic leaf", finger("slider", "prismatic"), {"slider"}),
        ("mimic pair", finger("a", "revolute") + finger("b", "revolute", '<mimic joint="a"/>'), {"a", "b"}),
        ("zero range", finger("stuck", "revolute").replace('upper="0.04"', 'upper="0"'), {"stuck"}),
        ("named jaw", finger("jaw", "revolute"), {"jaw"}),
        ("camelCase gripper", finger("jointGripper", "revolute"), {"jointGripper"}),
    ],
)
def test_gripper_joints_are_left_out_of_the_arm(tmp_path: Path, case: str, hand: str, left_out: set[str]) -> None:
    path = tmp_path / "arm.urdf"
    path.write_text(arm_with(hand), encoding="utf-8")
    robot = pinrate.load(path)
    assert set(robot.hand_joints) == left_out, case
    assert robot.tip == "flange" and robot.tip_chain() == ("j0", "j1", "j2")


def test_a_hand_on_its_own_is_its_own_arm(tmp_path: Path) -> None:
    # Every joint named like a finger: nothing is left out (the fingers are the robot).
    text = arm_with("").replace('name="j', 'name="finger_j')
    path = tmp_path / "hand.urdf"
    path.write_text(text, encoding="utf-8")
    robot = pinrate.load(path)
    assert robot.hand_joints == () and robot.tip_chain() == ("finger_j0", "finger_j1", "finger_j2")


def test_tool_names_win_over_deeper_bare_links(tmp_path: Path) -> None:
    def deeper(tool: str) -> str:
        return f'<link name="cover"/><joint name="c" type="fixed"><parent link="{tool}"/><child link="cover"/></joint>'

    path = tmp_path / "arm.urdf"
    path.write_text(arm_with(deeper("tcp"), tool="tcp"), encoding="utf-8")
    assert pinrate.load(path).tip == "tcp"
    path.write_text(arm_with(deeper("plate"), tool="plate"), encoding="utf-8")
    robot = pinrate.load(path)
    assert robot.tip == "cover" and robot.tip_choice.startswith("chosen: the deepest frame")


def test_a_zero_range_or_mimic_joint_on_the_chain_stays_out_of_the_partition(tmp_path: Path) -> None:
    # j1 locked by its limits; the tip chain still runs through it, the partition does not.
    text = arm_with("").replace(
        '<joint name="j1" type="revolute"><parent link="l1"/><child link="l2"/><origin xyz="0 0 0.3"/>'
        '<axis xyz="0 1 0"/><limit lower="-1" upper="1"',
        '<joint name="j1" type="revolute"><parent link="l1"/><child link="l2"/><origin xyz="0 0 0.3"/>'
        '<axis xyz="0 1 0"/><limit lower="0.5" upper="0.5"',
    )
    path = tmp_path / "locked.urdf"
    path.write_text(text, encoding="utf-8")
    robot = pinrate.load(path)
    assert robot.hand_joints == ("j1",) and "j1" in robot.tip_chain()
    assert "j1" not in pinrate.Partition.auto(robot).joints


def test_a_torso_that_a_side_link_mimics_is_not_a_gripper_joint(tmp_path: Path) -> None:
    # Issue 24 item 1: an SDA10F's torso was left out and called a "gripper/hand joint".
    path = tmp_path / "dual.urdf"
    path.write_text(dual_arm_torso(), encoding="utf-8")
    robot = pinrate.load(path)
    assert robot.hand_joints == () and robot.arm_mimics == ("torso_joint_b2",)
    assert "gripper/hand" not in robot.tip_choice
    assert robot.tip == "arm_left_tool0"  # two equal arms: the first in model order
    assert robot.tip_chain()[0] == "torso_joint_b1"
    partition = pinrate.Partition.auto(robot)
    assert partition.joints[0] == "torso_joint_b1" and "torso_joint_b2" not in partition.joints


def test_mimic_fingers_at_the_end_of_the_chain_are_a_hand(tmp_path: Path) -> None:
    # Two fingers mimicking one another, a fingertip below one mimicking it: none is named like
    # a finger, the structure alone says they are a hand; the shoulder's side links are not.
    path = tmp_path / "arm.urdf"
    path.write_text(parallelogram_arm(gripper=True), encoding="utf-8")
    robot = pinrate.load(path)
    assert set(robot.hand_joints) == {"left_joint", "right_joint", "left_tip_joint"}
    assert set(robot.arm_mimics) == {"side_a_joint", "side_b_joint"}
    assert robot.tip == "tool0" and robot.tip_chain() == tuple(f"joint_{i}" for i in range(1, 7))
