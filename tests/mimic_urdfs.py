"""Small URDFs with mimic joints (issue 24 item 1): a shoulder that parallelogram links
mimic, a torso with a mimicking side link below two arms, a gripper of mimic fingers."""

from __future__ import annotations

LIMIT = '<limit lower="-2.5" upper="2.5" effort="1" velocity="2"/>'


def joint(
    name: str, parent: str, child: str, xyz: str, axis: str, inner: str = "", kind: str = "revolute", limit: str = LIMIT
) -> str:
    limit = limit if kind != "fixed" else ""
    return (
        f'<link name="{child}"/><joint name="{name}" type="{kind}"><parent link="{parent}"/>'
        f'<child link="{child}"/><origin xyz="{xyz}"/><axis xyz="{axis}"/>{limit}{inner}</joint>'
    )


def mimic(leader: str, multiplier: float = 1.0) -> str:
    return f'<mimic joint="{leader}" multiplier="{multiplier}" offset="0"/>'


def six_dof(prefix: str = "", parent: str = "base_link") -> str:
    """An IRB-6640-like 6-DOF arm under ``parent``: joint_1..joint_6, a tool0 frame on link_6."""
    p = prefix
    return (
        joint(f"{p}joint_1", parent, f"{p}link_1", "0 0 0.78", "0 0 1")
        + joint(f"{p}joint_2", f"{p}link_1", f"{p}link_2", "0.32 0 0", "0 1 0")
        + joint(f"{p}joint_3", f"{p}link_2", f"{p}link_3", "0 0 1.075", "0 1 0")
        + joint(f"{p}joint_4", f"{p}link_3", f"{p}link_4", "0 0 0.2", "1 0 0")
        + joint(f"{p}joint_5", f"{p}link_4", f"{p}link_5", "1.1 0 0", "0 1 0")
        + joint(f"{p}joint_6", f"{p}link_5", f"{p}link_6", "0.2 0 0", "1 0 0")
        + joint(f"{p}joint_6-tool0", f"{p}link_6", f"{p}tool0", "0.05 0 0", "1 0 0", kind="fixed")
    )


def parallelogram_arm(gripper: bool = False) -> str:
    """The 6-DOF arm whose joint_2 two parallelogram side links mimic: one hangs off link_1,
    the other off link_2, neither on the way to the tip. ``gripper``: two fingers on tool0
    that mimic one another, and a fingertip below one of them that mimics it too (names that
    do not say "finger", so only the structure tells)."""
    sides = joint("side_a_joint", "link_1", "side_a", "0 0.2 0", "0 1 0", mimic("joint_2")) + joint(
        "side_b_joint", "link_2", "side_b", "0 0.2 0.5", "0 1 0", mimic("joint_2", -1.0)
    )
    hand = ""
    if gripper:
        hand = (
            joint("left_joint", "tool0", "left", "0.1 0.02 0", "0 0 1")
            + joint("right_joint", "tool0", "right", "0.1 -0.02 0", "0 0 1", mimic("left_joint", -1.0))
            + joint("left_tip_joint", "left", "left_tip", "0.05 0 0", "0 0 1", mimic("left_joint", -1.0))
        )
    return f'<robot name="irb_like"><link name="base_link"/>{six_dof()}{sides}{hand}</robot>'


def dual_arm_torso() -> str:
    """An SDA10F-like torso joint with a mimicking side link, and two 6-DOF arms on it."""
    torso = joint("torso_joint_b1", "base_link", "torso", "0 0 0.8", "0 0 1") + joint(
        "torso_joint_b2", "base_link", "torso_side", "0.1 0 0.4", "0 0 1", mimic("torso_joint_b1")
    )
    mounts = joint("mount_l", "torso", "mount_left", "0 0.2 0.3", "1 0 0", kind="fixed") + joint(
        "mount_r", "torso", "mount_right", "0 -0.2 0.3", "1 0 0", kind="fixed"
    )
    arms = six_dof("arm_left_", "mount_left") + six_dof("arm_right_", "mount_right")
    return f'<robot name="dual_arm"><link name="base_link"/>{torso}{mounts}{arms}</robot>'


def planar_mimic_on_the_tip_path(follower_limits: tuple[float, float] = (-2.5, 2.5)) -> str:
    """A planar 3R arm whose joint_2 mimics joint_1 (multiplier 0.5, offset 0.1): a closed
    chain's follower between the base and the tip tool0 (issue 24); links 0.5, 0.4, 0.3 m along
    x, every axis z. ``follower_limits``: joint_2's (rad)."""
    follower = '<mimic joint="joint_1" multiplier="0.5" offset="0.1"/>'
    lower, upper = follower_limits
    follower_limit = f'<limit lower="{lower}" upper="{upper}" effort="1" velocity="2"/>'
    return (
        '<robot name="planar_mimic"><link name="base_link"/>'
        + joint("joint_1", "base_link", "link_1", "0 0 0", "0 0 1")
        + joint("joint_2", "link_1", "link_2", "0.5 0 0", "0 0 1", follower, limit=follower_limit)
        + joint("joint_3", "link_2", "link_3", "0.4 0 0", "0 0 1")
        + joint("tool_joint", "link_3", "tool0", "0.3 0 0", "0 0 1", kind="fixed")
        + "</robot>"
    )
