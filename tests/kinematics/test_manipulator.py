"""Loading robots and the sensor-frame Jacobian (Shoham & Koren eq. 1-8)."""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin
import pytest

import pinrate
from pinrate.robots import EXAMPLE_ROBOTS
from pinrate.robots.catalog import example_robot_path
from support import DATA, finite_difference_jacobian


# ---------------------------------------------------------------------- loading
@pytest.mark.parametrize("name", ["ur3", "ur5", "ur10", "panda", "z1", "xarm7", "so100", "so101", "kinova"])
def test_every_catalog_robot_loads_with_its_tip(name: str) -> None:
    robot = pinrate.load(name)
    assert robot.tip == EXAMPLE_ROBOTS[name].tip
    assert robot.sensor == robot.tip
    home = robot.home()
    assert home.shape == (robot.nq,)
    lower, upper = robot.position_limits()
    finite = np.isfinite(lower) & np.isfinite(upper)
    assert np.all((home[finite] >= lower[finite] - 1e-12) & (home[finite] <= upper[finite] + 1e-12))


def test_contract_tips(ur5: pinrate.Robot, panda: pinrate.Robot) -> None:
    assert ur5.tip == "tool0"
    assert panda.tip == "panda_hand_tcp"


def test_ur5_home_is_not_singular_while_zero_is(ur5: pinrate.Robot) -> None:
    # UR5's all-zero pose has a rank-deficient Jacobian (the contract's reason for a home pose).
    assert np.linalg.matrix_rank(ur5.jacobian(np.zeros(6)), tol=1e-9) < 6
    assert np.linalg.svd(ur5.jacobian(ur5.home()), compute_uv=False).min() > 1e-2


def test_srdf_reference_configurations_are_exposed(panda: pinrate.Robot) -> None:
    assert "default" in panda.reference_configurations
    np.testing.assert_allclose(panda.reference_configurations["default"][3], -2.35619)
    # the home is the SRDF's "default" state, its mimic finger (panda_finger_joint2 = 1 x
    # panda_finger_joint1 + 0, which the state leaves at 0) where its leader puts it
    expected = panda.reference_configurations["default"].copy()
    expected[8] = expected[7]
    assert expected[8] == 0.001
    np.testing.assert_allclose(panda.home(), expected)


def test_joint_names_follow_the_velocity_vector(panda: pinrate.Robot) -> None:
    assert panda.joint_names[:7] == tuple(f"panda_joint{i}" for i in range(1, 8))
    assert panda.nv == len(panda.joint_names) == 9


def test_load_by_path_chooses_the_end_of_the_longest_chain() -> None:
    robot = pinrate.load(DATA / "mixed_joints.urdf")
    # yaw-slide-roll-pitch is the longest moving chain; its deepest frame is the tool link.
    assert robot.tip == "tool"
    assert robot.sensor == "tool"


def test_load_by_str_path_and_pathlike_agree() -> None:
    by_str = pinrate.load(str(DATA / "mixed_joints.urdf"), tip="tool")
    by_path = pinrate.load(DATA / "mixed_joints.urdf", tip="tool")
    q = by_str.random_configuration(3)
    np.testing.assert_allclose(by_str.pose(q), by_path.pose(q))


def test_a_name_that_is_link_and_joint_means_the_link() -> None:
    robot = pinrate.load("so100", tip="gripper")
    frame = robot.model.frames[robot.tip_id]
    assert frame.type == pin.FrameType.BODY


def test_continuous_joints_have_two_coordinates() -> None:
    robot = pinrate.load("kinova")
    assert (robot.nq, robot.nv) == (9, 6)
    q = robot.random_configuration(7)
    jacobian = robot.jacobian(q)
    assert jacobian.shape == (6, 6)
    np.testing.assert_allclose(jacobian, finite_difference_jacobian(robot, q), atol=1e-6)


def test_random_configuration_respects_limits_and_seeds(mixed: pinrate.Robot) -> None:
    lower, upper = mixed.position_limits()
    samples = mixed.sample_configurations(500, rng=1)
    for joint in ("yaw", "slide", "pitch"):
        i = mixed.model.joints[mixed.joint_id(joint)].idx_q
        assert samples[:, i].min() >= lower[i] and samples[:, i].max() <= upper[i]
    roll = mixed.model.joints[mixed.joint_id("roll")].idx_q
    np.testing.assert_allclose(np.hypot(samples[:, roll], samples[:, roll + 1]), 1.0)
    np.testing.assert_array_equal(mixed.random_configuration(5), mixed.random_configuration(5))
    generator = np.random.default_rng(5)
    np.testing.assert_array_equal(mixed.random_configuration(generator).shape, (mixed.nq,))


# ---------------------------------------------------------------------- the Jacobian
@pytest.mark.parametrize("seed", range(5))
def test_ur5_jacobian_matches_finite_differences(ur5: pinrate.Robot, seed: int) -> None:
    q = ur5.random_configuration(seed)
    np.testing.assert_allclose(ur5.jacobian(q), finite_difference_jacobian(ur5, q), atol=1e-6)


@pytest.mark.parametrize("seed", range(5))
def test_panda_jacobian_matches_finite_differences(panda: pinrate.Robot, seed: int) -> None:
    q = panda.random_configuration(seed)
    jacobian = panda.jacobian(q)
    np.testing.assert_allclose(jacobian, finite_difference_jacobian(panda, q), atol=1e-6)
    # The fingers do not move the hand's TCP.
    np.testing.assert_allclose(jacobian[:, 7:], 0.0, atol=1e-12)


@pytest.mark.parametrize("seed", range(5))
@pytest.mark.parametrize("sensor", ["link2", "tool", "base", "pitch"])
def test_mixed_joint_jacobian_matches_finite_differences(seed: int, sensor: str) -> None:
    robot = pinrate.load(DATA / "mixed_joints.urdf", tip="tool", sensor=sensor)
    q = robot.random_configuration(seed)
    np.testing.assert_allclose(robot.jacobian(q), finite_difference_jacobian(robot, q), atol=1e-6)


def test_sensor_on_another_branch(mixed: pinrate.Robot) -> None:
    robot = pinrate.load(DATA / "mixed_joints.urdf", tip="tool", sensor="finger")
    q = robot.random_configuration(11)
    np.testing.assert_allclose(robot.jacobian(q), finite_difference_jacobian(robot, q), atol=1e-6)


def test_linear_rows_rotated_back_are_world_velocities(ur5: pinrate.Robot) -> None:
    # R_world_sensor J_linear is the world-frame velocity (eq. 7-8), checked on plain q + dq.
    q = ur5.random_configuration(4)
    world_rotation = ur5.pose(q)[:3, :3]
    jacobian = ur5.jacobian(q)
    np.testing.assert_allclose(world_rotation @ jacobian[:3], finite_difference_world_linear(ur5, q), atol=1e-6)


def finite_difference_world_linear(robot: pinrate.Robot, q: np.ndarray, step: float = 1e-6) -> np.ndarray:
    columns = []
    for i in range(robot.nv):
        dq = np.zeros(robot.nq)
        dq[i] = step
        columns.append((robot.pose(q + dq)[:3, 3] - robot.pose(q - dq)[:3, 3]) / (2 * step))
    return np.column_stack(columns)


# ---------------------------------------------------------------------- bad input
def test_missing_file_names_it(tmp_path) -> None:
    path = tmp_path / "nowhere.urdf"
    with pytest.raises(pinrate.LoadError, match=r"nowhere\.urdf"):
        pinrate.load(path)


def test_malformed_xml_names_the_file(tmp_path) -> None:
    path = tmp_path / "broken.urdf"
    path.write_text("<robot name='x'><link name='a'></robot>")
    with pytest.raises(pinrate.LoadError, match=r"broken\.urdf.*malformed XML"):
        pinrate.load(path)


def test_xml_that_is_not_a_urdf(tmp_path) -> None:
    path = tmp_path / "page.urdf"
    path.write_text("<html><body/></html>")
    with pytest.raises(pinrate.LoadError, match=r"page\.urdf.*not a URDF"):
        pinrate.load(path)


def test_urdf_pinocchio_rejects_is_a_load_error(tmp_path) -> None:
    path = tmp_path / "nolimits.urdf"
    path.write_text(
        '<robot name="r"><link name="a"/><link name="b"/><joint name="j" type="revolute">'
        '<parent link="a"/><child link="b"/></joint></robot>'
    )
    with pytest.raises(pinrate.LoadError, match=r"nolimits\.urdf"):
        pinrate.load(path)


def test_unknown_robot_name_lists_the_known_ones() -> None:
    with pytest.raises(pinrate.LoadError) as error:
        pinrate.load("ur55")
    message = str(error.value)
    assert "'ur55'" in message and "ur5" in message and "panda" in message and "scara" in message


def test_unknown_frame_lists_the_frames() -> None:
    with pytest.raises(pinrate.FrameError) as error:
        pinrate.load("ur5", tip="tool9")
    assert "tool9" in str(error.value) and "tool0" in str(error.value)
    with pytest.raises(pinrate.PinrateError, match="sensor"):
        pinrate.load("ur5", sensor="camera")


@pytest.mark.parametrize("bad", [np.zeros(5), np.zeros(7), np.zeros((6, 1)), "abc"])
def test_q_of_the_wrong_shape(ur5: pinrate.Robot, bad: object) -> None:
    with pytest.raises(pinrate.InputError, match="q"):
        ur5.jacobian(bad)


@pytest.mark.parametrize("value", [math.nan, math.inf, -math.inf])
def test_q_with_nan_or_inf_names_the_joint(ur5: pinrate.Robot, value: float) -> None:
    q = ur5.home()
    q[2] = value
    with pytest.raises(pinrate.InputError, match="elbow_joint"):
        ur5.pose(q)
    with pytest.raises(ValueError):  # InputError is a ValueError too
        ur5.jacobian(q)


def test_missing_mesh_warns_but_kinematics_work(tmp_path) -> None:
    text = (
        (DATA / "mixed_joints.urdf")
        .read_text()
        .replace(
            '<link name="tool"/>',
            '<link name="tool"><visual><geometry><mesh filename="package://nowhere/tool.stl"/>'
            "</geometry></visual></link>",
        )
    )
    path = tmp_path / "with_mesh.urdf"
    path.write_text(text)
    # Named when the robot loads (pinrate.kinematics.urdf_meshes), and left out of its geometry.
    with pytest.warns(UserWarning, match=r"1 mesh left out .*: package://nowhere/tool.stl \(not found\)"):
        robot = pinrate.load(path, tip="tool")
    assert robot.jacobian(robot.neutral()).shape == (6, robot.nv)
    assert robot.visual_model.ngeoms == 0


def test_example_robot_meshes_load(ur5: pinrate.Robot) -> None:
    assert ur5.visual_model.ngeoms >= 6


@pytest.mark.parametrize("value", [1.0 + 1e6, -1e12, 1e305])
def test_q_beyond_the_physical_bound_names_the_joint(ur5: pinrate.Robot, value: float) -> None:
    q = ur5.home()
    q[4] = value
    with pytest.raises(pinrate.InputError, match=r"physical bound.*q\[4\] \(wrist_2_joint\)"):
        ur5.jacobian(q)


@pytest.mark.parametrize("pair", [(2.0, 0.0), (0.0, 0.0), (0.6, 0.6), (1.0 + 1e-5, 0.0)])
def test_a_continuous_pair_off_the_unit_circle_is_refused(pair: tuple[float, float]) -> None:
    # Before: (2, 0) was accepted, the tip rotation had det 4 and jacobian() and kinematics()
    # disagreed by 3.0.
    kinova = pinrate.load("kinova")
    q = kinova.home()
    joint = kinova.model.joints[kinova.joint_id(kinova.joint_names[0])]
    assert joint.nq == 2  # the first joint is continuous
    q[joint.idx_q : joint.idx_q + 2] = pair
    for call in (kinova.pose, kinova.jacobian):
        with pytest.raises(pinrate.InputError, match=rf"{kinova.joint_names[0]}.*unit \(cos, sin\)"):
            call(q)


def test_a_continuous_pair_within_the_tolerance_is_accepted() -> None:
    kinova = pinrate.load("kinova")
    q = kinova.home()
    q[0:2] = (math.cos(0.4) * (1 + 1e-9), math.sin(0.4))
    assert np.isfinite(kinova.jacobian(q)).all()


def test_a_robot_with_no_moving_joint_is_a_load_error() -> None:
    model = pin.Model()
    model.addFrame(pin.Frame("plate", 0, 0, pin.SE3.Identity(), pin.FrameType.OP_FRAME))
    with pytest.raises(pinrate.LoadError, match="no moving joint"):
        pinrate.Robot(model, name="plate")


@pytest.mark.parametrize("tip", ["base_link", "world", "base"])
def test_a_tip_fixed_to_the_world_is_a_load_error_naming_it(tip: str) -> None:
    with pytest.raises(pinrate.LoadError, match=rf"tip frame '{tip}' has no moving joint between it and the world"):
        pinrate.load("ur5", tip=tip)


def test_generic_configurations_are_one_deterministic_set_within_the_limits() -> None:
    from pinrate.kinematics.kinematic_model import GENERIC_SAMPLES

    robot = pinrate.load("panda")
    configurations = robot.generic_configurations()
    assert configurations.shape == (GENERIC_SAMPLES + 1, robot.nq)
    np.testing.assert_array_equal(configurations[0], robot.neutral())
    np.testing.assert_array_equal(configurations, robot.generic_configurations())  # seeded
    lower, upper = robot.position_limits()
    drawn = configurations[1:]  # neutral itself may lie outside (the panda's joint4 does)
    assert ((drawn >= lower) & (drawn <= upper)).all()
    only = robot.generic_configurations(["panda_joint2"])
    moved = np.flatnonzero((only != robot.neutral()).any(axis=0))
    assert moved.tolist() == [robot.model.joints[robot.joint_id("panda_joint2")].idx_q]


# ---------------------------------------------------------------- the home of a model built by hand


def smallest_singular_value(robot: pinrate.Robot, q: np.ndarray) -> float:
    """The partition Jacobian's smallest singular value at q, by numpy's SVD of the rows and
    columns the partition names (independent of pinrate.kinematics.home)."""
    partition = pinrate.Partition.auto(robot)
    rows = ["xyz".index(a) for a in partition.linear] + [3 + "xyz".index(a) for a in partition.angular]
    columns = [robot.model.joints[robot.model.getJointId(j)].idx_v for j in partition.arm + partition.wrist]
    return float(np.linalg.svd(robot.jacobian(q)[np.ix_(rows, columns)], compute_uv=False)[-1])


def inside_every_limit(robot: pinrate.Robot, q: np.ndarray) -> bool:
    lower, upper = robot.position_limits()
    return bool(np.all((lower <= q) & (q <= upper)))


def test_a_hand_built_model_gets_the_home_that_load_gives() -> None:
    """Issue 24: pinrate.Robot(model) (Pink's route) searches the home as pinrate.load does.
    The panda's neutral pose puts joint4 outside its limits [-3.07, -0.07] rad."""
    urdf = example_robot_path(EXAMPLE_ROBOTS["panda"].urdf)
    robot = pinrate.Robot(pin.buildModelFromUrdf(str(urdf)))
    assert not inside_every_limit(robot, robot.neutral())
    home = robot.home()
    assert inside_every_limit(robot, home), robot.home_choice
    assert smallest_singular_value(robot, home) >= 1e-3  # the contract's floor
    np.testing.assert_array_equal(home, pinrate.load(urdf).home())  # the same search, the same draws
    assert "searched" in robot.home_choice


def test_a_model_with_reference_configurations_takes_them_as_load_does(panda: pinrate.Robot) -> None:
    # pinrate.load("panda") read the SRDF into the model: its 'default' pose is the curated home.
    # (A Pinocchio 3.3 model does not carry the URDF's <mimic>: the caller passes the relations.)
    robot = pinrate.Robot(panda.model, mimic=panda.mimics.relations)
    np.testing.assert_array_equal(robot.home(), panda.home())
    assert robot.home()[8] == robot.home()[7]  # the mimic finger follows in both
    assert "'default'" in robot.home_choice


def test_a_given_home_is_kept_and_the_search_can_be_turned_off(panda: pinrate.Robot) -> None:
    given = panda.home() + 0.01
    assert np.array_equal(pinrate.Robot(panda.model, reference_configurations={"home": given}).home(), given)
    unsearched = pinrate.Robot(panda.model, search_home=False)
    assert np.array_equal(unsearched.home(), unsearched.neutral()) and unsearched.home_choice == "neutral"


@pytest.mark.parametrize("algorithm", ["exact", "mca1"])
def test_servo_and_a_teleop_step_from_a_hand_built_home(algorithm: str) -> None:
    robot = pinrate.Robot(pin.buildModelFromUrdf(str(example_robot_path(EXAMPLE_ROBOTS["panda"].urdf))))
    home = robot.home()
    step = pinrate.Controller(robot, algorithm=algorithm).step(home, np.array([0.05, 0.0, 0.0, 0.0, 0.0, 0.0]))
    assert step.status == pinrate.Status.OK
    # 5 cm/s along the sensor's x for dt = 0.01 s: the tip moves 0.5 mm along x (first order;
    # the second-order term is below 1e-6 m at these rates).
    moved = robot.pose(home)[:3, :3].T @ (robot.pose(step.q)[:3, 3] - robot.pose(home)[:3, 3])
    np.testing.assert_allclose(moved, [5e-4, 0.0, 0.0], atol=2e-6)
    target = robot.pose(home)
    target[:3, 3] += [0.0, 0.05, -0.05]
    # gain 1/s: the exact error decays as exp(-t), from 0.071 m to tol 1e-4 in ln(707) = 6.6 s
    # (656 steps); mca1's coupling (rho 0.3) leaves an orientation error that takes 1151 steps.
    trajectory = pinrate.servo(robot, home, target, algorithm=algorithm, max_steps=2000)
    assert trajectory.converged, trajectory.reason
