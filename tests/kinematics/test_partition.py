"""The arm/wrist partition (eq. 17-19) and the contract's automatic rule."""

from __future__ import annotations

import numpy as np
import pytest

import pinrate
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
