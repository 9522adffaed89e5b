"""ROS description packages as engineers meet them (issue 24): six robots written for pinrate in
``tests/data/ros_corpus`` (README there), each a package folder with a ``.urdf.xacro`` built from
macros, properties, args, ``$(find pkg)`` includes, math expressions and ``package://`` meshes,
expanded by xacrodoc in the test. Each goes through load (tip, partition, home), a servo to a
nearby target, the analysis of its work volume, a teleop jog along the hand's x axis, and
``pinrate demo`` on the command line, all with pinrate's defaults.

The robots: rk6, a 6R industrial arm with a spherical wrist, a tool0 frame, a variant argument
(rk_type) read from a YAML file and a MoveIt-style SRDF beside it; pg6640, a parallelogram arm
whose side links mimic joint_2 and joint_3; wx7, a 7-joint arm whose gripper's finger limits
exclude 0; so5, a 5-joint desktop arm; sda, a dual-arm robot on a torso joint that a dummy joint
mimics, with one mesh not shipped; scara, a SCARA with a quill.
"""

from __future__ import annotations

import re
import subprocess
import sys
import warnings
from dataclasses import dataclass, field
from functools import cache
from pathlib import Path

import numpy as np
import pytest

import pinrate
from pinrate.analysis import analyze
from pinrate.kinematics.targets import nearby_target
from support import DATA, partition_rows_and_columns

pytest.importorskip("xacrodoc", reason="the corpus is .xacro: pip install 'pinrate[xacro]' (the test extra has it)")

CORPUS = DATA / "ros_corpus"


@dataclass(frozen=True)
class Description:
    """One package of the corpus and what an engineer reads off its files by hand."""

    package: str
    tip: str | tuple[str, ...]  # the tool frame; a tuple when either of two is as good (two arms)
    arm: tuple[str, ...]  # the joints of the arm that carries the tip, base to tip
    split: tuple[tuple[str, ...], tuple[str, ...]] | None = None  # (arm, wrist) where the design fixes it
    xacro_args: dict[str, str] = field(default_factory=dict)

    @property
    def path(self) -> Path:
        stem = self.package.removesuffix("_description")
        return CORPUS / self.package / "urdf" / f"{stem}.urdf.xacro"


SIX = tuple(f"joint_{i}" for i in range(1, 7))
SDA_LEFT = ("torso_joint_b1", *(f"arm_left_joint_{i}_{a}" for i, a in zip(range(1, 8), "sleurbt", strict=True)))
SDA_RIGHT = ("torso_joint_b1", *(f"arm_right_joint_{i}_{a}" for i, a in zip(range(1, 8), "sleurbt", strict=True)))
WX7 = ("waist", "shoulder", "upper_arm_roll", "elbow", "forearm_roll", "wrist_angle", "wrist_rotate")
SO5 = ("shoulder_pan", "shoulder_lift", "elbow_flex", "wrist_flex", "wrist_roll")

ROBOTS = {
    "rk6": Description("rk6_description", "tool0", SIX, (SIX[:3], SIX[3:])),
    "rk6_900": Description("rk6_description", "tool0", SIX, (SIX[:3], SIX[3:]), {"rk_type": "rk6_900"}),
    # the side links mimic joint_2 and joint_3: both stay in the arm, the side links out
    "pg6640": Description("pg6640_description", "tool0", SIX, (SIX[:3], SIX[3:])),
    # the fingers (limits [0.015, 0.037] m) are the gripper's; the tip sits between the fingertips
    "wx7": Description("wx7_description", "wx7/ee_gripper_link", WX7, (WX7[:4], WX7[4:])),
    "so5": Description("so5_description", "gripper_frame_link", SO5),
    # the torso turns both arms: it belongs to the arm of either tool0; torso_joint_b2 only mimics it
    "sda": Description("sda_description", ("arm_left_link_tool0", "arm_right_link_tool0"), SDA_LEFT),
    "scara": Description("scara_description", "tool0", ("joint_1", "joint_2", "joint_3", "joint_4")),
}


MISSING_MESH = "package://sda_description/meshes/torso_b2.stl"  # the one mesh the corpus leaves out on purpose


@cache
def loaded(name: str) -> pinrate.Robot:
    """The robot, loaded once for the module (each load expands its xacro)."""
    description = ROBOTS[name]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the missing mesh: its own test below
        return pinrate.load(description.path, xacro_args=description.xacro_args)


def arm_of(name: str, robot: pinrate.Robot) -> tuple[str, ...]:
    if name == "sda" and robot.tip == "arm_right_link_tool0":
        return SDA_RIGHT
    return ROBOTS[name].arm


@pytest.mark.parametrize("name", ROBOTS)
def test_the_default_tip_is_the_tool_frame_and_the_partition_is_the_arm(name: str) -> None:
    description, robot = ROBOTS[name], loaded(name)
    tips = description.tip if isinstance(description.tip, tuple) else (description.tip,)
    assert robot.tip in tips, robot.tip_choice
    partition = pinrate.Partition.auto(robot)
    assert set(partition.joints) == set(arm_of(name, robot)), str(partition)
    if description.split is not None:
        assert (partition.arm, partition.wrist) == description.split, str(partition)
    # every arm here has three independent translations at its tip: each controls linear xyz
    assert partition.linear == "xyz"


@pytest.mark.parametrize("name", ROBOTS)
def test_home_is_inside_every_joints_limits_and_not_singular(name: str) -> None:
    robot = loaded(name)
    home = robot.home()
    lower, upper = robot.position_limits()
    outside = [
        f"{joint}={home[i]:.4f} not in [{lower[i]:.4f}, {upper[i]:.4f}]"
        for i, joint in enumerate(robot.joint_names)
        if not lower[i] <= home[i] <= upper[i]
    ]
    assert not outside, outside
    # the contract's floor: the partition's J at home keeps its rank by a singular value >= 1e-3
    partition = pinrate.Partition.auto(robot)
    rows, columns = partition_rows_and_columns(robot, partition)
    values = np.linalg.svd(robot.jacobian(home)[np.ix_(rows, columns)], compute_uv=False)
    assert values[min(len(rows), len(columns)) - 1] >= 1e-3, (robot.home_choice, values)


def test_the_srdf_home_beside_the_xacro_is_its_named_group_state() -> None:
    robot = loaded("rk6")
    assert robot.srdf_path == CORPUS / "rk6_description" / "urdf" / "rk6.srdf"
    # "home", not the first group_state ("all_zeros", a wrist singularity)
    assert robot.home_choice == "SRDF group_state 'home'"
    np.testing.assert_array_equal(robot.home(), [0.0, 0.2, -0.3, 0.0, 0.9, 0.0])  # the SRDF's values


def test_the_srdf_of_a_moveit_config_package_beside_the_description_gives_the_home() -> None:
    robot = loaded("sda")
    assert robot.srdf_path == CORPUS / "sda_moveit_config" / "config" / "sda.srdf"
    # its "home" has both arms stretched (singular): passed over, said so, "ready" taken
    match = re.fullmatch(
        r"SRDF group_state 'ready'; SRDF group_state 'home' passed over "
        r"\(singular: smallest singular value (\S+) < 0.001\)",
        robot.home_choice,
    )
    assert match and float(match.group(1)) < 1e-12, robot.home_choice  # exactly singular, up to rounding
    ready = {"torso_joint_b1": 0.25, **dict(zip(SDA_LEFT[1:], [0.3, -0.6, 0.2, 1.2, -0.4, 0.9, 0.1], strict=True))}
    for joint, value in ready.items():
        assert robot.home()[robot.joint_names.index(joint)] == value, joint


def test_the_variant_argument_picks_its_dimensions_from_the_yaml() -> None:
    # tool0 at the zero pose, by hand from config/<rk_type>/dimensions.yaml: the upper arm up, the
    # forearm along x, so x = a1 + d4 + d6 and z = d1 + a2 + a3; tool0's z along the approach (+x)
    for name, xyz in (("rk6", [0.100 + 0.420 + 0.080, 0, 0.400 + 0.360 + 0.030]), ("rk6_900", [0.76, 0, 0.945])):
        pose = loaded(name).pose(np.zeros(6))
        np.testing.assert_allclose(pose[:3, 3], xyz, atol=1e-12)  # rounding of a few sums of metres
        np.testing.assert_allclose(pose[:3, 2], [1, 0, 0], atol=1e-12)


def test_every_mesh_is_found_but_the_one_left_out_which_is_named_once() -> None:
    for name in ROBOTS:
        description = ROBOTS[name]
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            robot = pinrate.load(description.path, xacro_args=description.xacro_args)
        messages = [str(warning.message) for warning in caught]
        if name == "sda":
            assert len(messages) == 1 and messages[0].count(MISSING_MESH) == 1, messages
            assert "1 mesh left out" in messages[0]
        else:
            assert messages == []
        # every other visual is drawn, read from inside its package
        meshes = [geometry.meshPath for geometry in robot.visual_model.geometryObjects if geometry.meshPath]
        box = str((CORPUS / description.package / "meshes" / "box.stl").resolve())
        assert meshes and meshes.count(box) == len(meshes), meshes


@pytest.mark.parametrize("name", ROBOTS)
def test_the_servo_reaches_a_nearby_target_with_the_defaults(name: str) -> None:
    robot = loaded(name)
    partition = pinrate.Partition.auto(robot)
    _, target = nearby_target(robot, partition, seed=0)
    trajectory = pinrate.servo(robot, robot.home(), target)
    assert trajectory.converged, trajectory.reason
    # the contract's test, on the controlled components: both below tol (1e-4 m and rad)
    assert trajectory.position_error[-1] < 1e-4 and trajectory.orientation_error[-1] < 1e-4


def square_blocks(robot: pinrate.Robot, partition: pinrate.Partition, q: np.ndarray) -> tuple[np.ndarray, ...]:
    """(A, B, U, W): J's rows and columns by the partition (Shoham & Koren eq. 19), by numpy."""
    m = len(partition.linear)
    rows, _ = partition_rows_and_columns(robot, partition)
    arm = [c for joint in partition.arm for c in robot.velocity_indices(joint)]
    wrist = [c for joint in partition.wrist for c in robot.velocity_indices(joint)]
    jacobian = robot.jacobian(q)
    linear, angular = rows[:m], rows[m:]
    pairs = ((linear, arm), (linear, wrist), (angular, arm), (angular, wrist))
    return tuple(jacobian[np.ix_(r, c)] for r, c in pairs)


def g_matrix(robot: pinrate.Robot, partition: pinrate.Partition, q: np.ndarray) -> np.ndarray:
    """G = U A^-1 B W^-1 (Shoham & Koren eq. 32)."""
    a, b, u, w = square_blocks(robot, partition, q)
    return u @ np.linalg.solve(a, b) @ np.linalg.inv(w)


@pytest.mark.parametrize("name", ROBOTS)
def test_the_analysis_is_of_the_arm(name: str) -> None:
    robot = loaded(name)
    partition = pinrate.Partition.auto(robot)
    report = analyze(robot, samples=400, points=9, tcp_samples=20, progress=False)
    assert report.partition == partition
    assert 0.0 <= report.sample.fraction <= 1.0
    # the samples move only the arm's joints; the others stay at neutral, but the mimic joints,
    # which sit where their leaders put them (side links follow the arm joint they mimic)
    others = [
        i
        for i, joint in enumerate(robot.joint_names)
        if joint not in partition.joints and joint not in robot.mimics.relations
    ]
    neutral = robot.neutral()
    np.testing.assert_array_equal(report.sample.q[:, others], np.tile(neutral[others], (400, 1)))
    np.testing.assert_array_equal(report.sample.q, robot.follow_leaders(report.sample.q.copy()))
    region = report.region
    assert region is not None and set(region.joints) <= set(partition.joints)
    assert not np.any(np.isnan(region.spectral_radius))  # inf where a block is singular, never NaN
    if len(partition.arm) == len(partition.linear) and len(partition.wrist) == len(partition.angular):
        # square blocks: rho at grid points, by numpy from J's blocks; inf exactly where A or W is singular
        for row, column in ((5, 2), (4, 0)):
            q = region.base.copy()
            robot.set_joint_values(q[None, :], region.joints[0], np.array([region.x[column]]))
            robot.set_joint_values(q[None, :], region.joints[1], np.array([region.y[row]]))
            rho = region.spectral_radius[row, column]
            a, _, _, w = square_blocks(robot, partition, q)
            smallest = min(np.linalg.svd(block, compute_uv=False)[-1] for block in (a, w))
            if np.isinf(rho):
                assert smallest < 1e-12, smallest  # a grid point exactly on the singular set, up to rounding
            else:
                # the same J by another route: rounding of a few solves, times kappa(A) kappa(W) < 1e4 here
                assert rho == pytest.approx(max(abs(np.linalg.eigvals(g_matrix(robot, partition, q)))), rel=1e-8)


TICKS = 20
ANGLE = np.radians(1.0)
"""How far off the commanded axis a jog may move the hand. The exact step makes the commanded
twist to first order in dt; the angle off the axis is second order, about |q_dot| dt, and
|q_dot| dt stays below 0.01 rad here (1 mm per tick on links of 0.1 m and more): 0.6 deg. 1 deg
bounds it; the faults the issue reports are 21-69 deg."""

MOVED = {pinrate.Status.OK, pinrate.Status.TWIST_SATURATED}  # the statuses that say "done as told"


def jog_along_hand_x(robot: pinrate.Robot) -> tuple[np.ndarray, list[tuple[np.ndarray, pinrate.Step]], float]:
    """TICKS teleop ticks of full deflection along the hand's x axis from home: the hand's whole
    displacement in its axes at home (m), per tick its displacement in its axes at the tick's
    start (m) with the step, and the largest angle its x axis turned from home's (rad)."""
    teleop = pinrate.Teleop(robot)
    start = robot.pose(teleop.q)
    teleop.command([1.0, 0.0, 0.0], [0.0, 0.0, 0.0], now=0.0)
    ticks = []
    turned = 0.0
    for _ in range(TICKS):
        before = robot.pose(teleop.q)
        step = teleop.tick(now=0.0)
        after = robot.pose(teleop.q)
        ticks.append((before[:3, :3].T @ (after[:3, 3] - before[:3, 3]), step))
        turned = max(turned, float(np.arccos(np.clip(after[:3, 0] @ start[:3, 0], -1.0, 1.0))))
    end = robot.pose(teleop.q)
    return start[:3, :3].T @ (end[:3, 3] - start[:3, 3]), ticks, turned


def angle_from_x(displacement: np.ndarray) -> float:
    size = float(np.linalg.norm(displacement))
    return np.pi if size == 0.0 else float(np.arccos(np.clip(displacement[0] / size, -1.0, 1.0)))


@pytest.mark.parametrize("name", ROBOTS)
def test_teleop_goes_along_the_hand_x_axis_or_says_why_not(name: str) -> None:
    # honesty, tick by tick: a tick reported done as told moved the hand along x (its axes then);
    # any other names its cause
    for tick, (displacement, step) in enumerate(jog_along_hand_x(loaded(name))[1]):
        if step.status in MOVED:
            assert angle_from_x(displacement) < ANGLE, (tick, step.status, displacement)
        else:
            assert step.detail, (tick, step.status)


@pytest.mark.parametrize("name", ROBOTS)
def test_teleop_moves_the_hand_along_its_x_axis(name: str) -> None:
    # Every arm here makes any translation of its tip (linear xyz). An engineer asks for position
    # first: the hand goes along x (the five-joint arm giving up an orientation component), and
    # at 0.1 m/s for TICKS ticks of 0.01 s it covers 20 mm. Each tick goes along the hand's x
    # axis of its own start (within ANGLE); where the arm gives up a rotation (so5), that axis
    # turns, by at most `turned` from home's, and so does the sum of the ticks.
    travelled, _, turned = jog_along_hand_x(loaded(name))
    assert angle_from_x(travelled) < ANGLE + turned, (np.degrees(angle_from_x(travelled)), np.degrees(turned))
    if name != "so5":  # the others make every rotation (0 commanded): it turns by second-order terms only
        assert turned < ANGLE, np.degrees(turned)
    # the length too: 0.1 m/s x 0.01 s per tick, up to the same second-order terms (< 1 %)
    assert np.linalg.norm(travelled) == pytest.approx(0.1 * 0.01 * TICKS, rel=0.05)


def run_demo(description: Description) -> subprocess.CompletedProcess[str]:
    arguments = [f"{key}:={value}" for key, value in description.xacro_args.items()]
    command = [sys.executable, "-m", "pinrate", "demo", str(description.path), "--no-viewer"]
    for argument in arguments:
        command += ["--xacro-arg", argument]
    return subprocess.run(command, capture_output=True, text=True, timeout=300, check=False)


@pytest.mark.parametrize("name", ROBOTS)
def test_the_cli_demo_converges(name: str) -> None:
    result = run_demo(ROBOTS[name])
    assert result.returncode == 0, result.stdout[-2000:] + result.stderr[-2000:]
    assert "converged  yes" in result.stdout
    assert result.stderr.count(MISSING_MESH) == (1 if name == "sda" else 0), result.stderr
