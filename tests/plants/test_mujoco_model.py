"""The MuJoCo model of a robot (pinrate.plants.mujoco_model): the same kinematics and
inertia as Pinocchio's model, checked against Pinocchio's own computations."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

import pinrate
from pinrate.errors import PlantError

mujoco = pytest.importorskip("mujoco")

from pinrate.plants.mujoco_model import DEFAULT_ARMATURE, build_spec, joint_layout, joint_space_inertia  # noqa: E402

# ur5 (revolute), panda (prismatic fingers, an unaligned axis), kinova (continuous joints),
# so101 (light links), xarm7 (URDF damping).
ROBOTS = ("ur5", "panda", "kinova", "so101", "xarm7")


@pytest.mark.parametrize("name", ROBOTS)
def test_the_tip_and_the_joint_space_inertia_are_pinocchios(name):
    robot = pinrate.load(name)
    model = build_spec(robot, timestep=0.001).compile()
    data = mujoco.MjData(model)
    layout = joint_layout(robot, model)
    site = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_SITE, "tip")
    pin_data = robot.model.createData()
    for seed in range(10):
        q = robot.random_configuration(seed)
        data.qpos[:] = layout.to_mujoco(q)
        mujoco.mj_forward(model, data)
        pose = robot.pose(q)
        # Two products of at most ~10 rigid transforms of a <= 1.5 m arm: rounding ~1e-15 m.
        assert np.allclose(data.site_xpos[site], pose[:3, 3], rtol=0, atol=1e-12)
        assert np.allclose(data.site_xmat[site].reshape(3, 3), pose[:3, :3], rtol=0, atol=1e-12)
        inertia = joint_space_inertia(mujoco, model, data)
        mujoco_inertia = inertia[np.ix_(layout.qvel, layout.qvel)] - np.diag(model.dof_armature[layout.qvel])
        crba = pin.crba(robot.model, pin_data, q)
        crba = np.triu(crba) + np.triu(crba, 1).T
        reference = crba[np.ix_(layout.idx_v, layout.idx_v)]
        # Two composite-rigid-body sums of the same inertias: agreement to rounding of M's scale.
        assert np.allclose(mujoco_inertia, reference, rtol=0, atol=1e-10 * max(1.0, np.abs(reference).max()))
        assert np.allclose(pin.difference(robot.model, q, layout.from_mujoco(data.qpos, robot.nq)), 0, atol=1e-12)


def test_limits_damping_and_armature_come_from_the_urdf():
    robot = pinrate.load("xarm7")
    model = build_spec(robot, timestep=0.001).compile()
    layout = joint_layout(robot, model)
    joint = robot.model.joints[robot.joint_id("joint1")]
    index = list(layout.names).index("joint1")
    mj_joint = model.dof_jntid[layout.qvel[index]]
    lower, upper = robot.model.lowerPositionLimit[joint.idx_q], robot.model.upperPositionLimit[joint.idx_q]
    assert tuple(model.jnt_range[mj_joint]) == (lower, upper)  # radians as given, never degrees
    assert model.dof_damping[layout.qvel[index]] == robot.model.damping[joint.idx_v] == 10.0
    assert model.dof_armature[layout.qvel[index]] == DEFAULT_ARMATURE  # a URDF has none
    assert model.opt.integrator == mujoco.mjtIntegrator.mjINT_IMPLICITFAST


def test_a_continuous_joint_is_an_unlimited_hinge_and_its_angle_maps_both_ways():
    robot = pinrate.load("kinova")
    model = build_spec(robot, timestep=0.001).compile()
    layout = joint_layout(robot, model)
    assert layout.continuous.any()
    q = robot.random_configuration(3)
    qpos = layout.to_mujoco(q)
    for k in np.flatnonzero(layout.continuous):
        cos, sin = q[layout.idx_q[k]], q[layout.idx_q[k] + 1]
        assert qpos[layout.qpos[k]] == pytest.approx(np.arctan2(sin, cos), abs=1e-15)
        assert not model.jnt_limited[model.dof_jntid[layout.qvel[k]]]


def test_a_robot_without_inertias_is_refused_naming_its_joints_or_given_a_mass():
    robot = pinrate.load("barker_arm")  # the paper's kinematics: no <inertial> anywhere
    with pytest.raises(PlantError, match=r"theta1, theta2, theta3.*missing_mass"):
        build_spec(robot, timestep=0.001)
    model = build_spec(robot, timestep=0.001, missing_mass=2.0).compile()
    assert np.allclose(model.body_mass[1:], 2.0)
