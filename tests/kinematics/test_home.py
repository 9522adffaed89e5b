"""A well-conditioned home for any URDF (pinrate.kinematics.home; contract v2)."""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pytest

import pinrate
from pinrate.kinematics.home import WELL_CONDITIONED, find_home
from pinrate.robots import example_robot_data_share
from support import fuzz_count, partition_rows_and_columns, random_urdf

SHARE = example_robot_data_share()
FILES = [
    "panda_description/urdf/panda.urdf",
    "so_arm_description/urdf/so100.urdf",
    "z1_description/urdf/z1.urdf",
    "kinova_description/robots/kinova.urdf",
    "ur_description/urdf/ur5_robot.urdf",
    "xarm_description/urdf/xarm7.urdf",
    "baxter_description/urdf/baxter.urdf",
]


def smallest_singular_values(robot: pinrate.Robot, q: np.ndarray) -> list[float]:
    """σ_min of the partition's J and of its square blocks, from numpy's SVD (independent of
    pinrate.kinematics.home)."""
    partition = pinrate.Partition.auto(robot)
    jacobian = robot.jacobian(q)[np.ix_(*partition_rows_and_columns(robot, partition))]
    arm = sum(len(robot.velocity_indices(joint)) for joint in partition.arm)
    blocks = (jacobian[: partition.m, :arm], jacobian[partition.m :, arm:])
    square = [block for block in blocks if block.size and block.shape[0] == block.shape[1]]
    return [float(np.linalg.svd(block, compute_uv=False).min()) for block in (jacobian, *square)]


@pytest.mark.skipif(SHARE is None, reason="example-robot-data is not installed")
@pytest.mark.parametrize("relative", FILES, ids=[Path(f).stem for f in FILES])
def test_a_urdf_by_path_starts_well_conditioned_inside_its_limits(relative: str) -> None:
    path = SHARE / "example-robot-data" / "robots" / relative
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        robot, again = pinrate.load(path), pinrate.load(path)
    home = robot.home()
    np.testing.assert_array_equal(home, again.home())  # deterministic
    lower, upper = robot.position_limits()
    assert np.all(home >= lower - 1e-12) and np.all(home <= upper + 1e-12)
    assert min(smallest_singular_values(robot, home)) >= WELL_CONDITIONED, robot.home_choice


LIMIT = '<limit lower="-2.5" upper="2.5" effort="1" velocity="1"/>'
PLANAR = f"""<robot name="planar"><link name="base"/><link name="upper"/><link name="fore"/><link name="tcp"/>
<joint name="shoulder" type="revolute"><parent link="base"/><child link="upper"/><axis xyz="0 0 1"/>{LIMIT}</joint>
<joint name="elbow" type="revolute"><parent link="upper"/><child link="fore"/><origin xyz="0.5 0 0"/>
<axis xyz="0 0 1"/>{LIMIT}</joint>
<joint name="tool" type="fixed"><parent link="fore"/><child link="tcp"/><origin xyz="0.4 0 0"/></joint></robot>"""


def test_a_stretched_neutral_is_replaced_by_a_bent_elbow(tmp_path: Path) -> None:
    path = tmp_path / "planar.urdf"
    path.write_text(PLANAR, encoding="utf-8")
    robot = pinrate.load(path)
    # At elbow = 0 the planar Jacobian's determinant 0.5 * 0.4 * sin(elbow) vanishes.
    assert robot.home_choice.startswith("searched near neutral")
    assert abs(0.5 * 0.4 * np.sin(robot.home()[1])) >= WELL_CONDITIONED


def srdf(states: dict[str, float]) -> str:
    body = "".join(
        f'<group_state name="{name}" group="arm"><joint name="shoulder" value="0.3"/>'
        f'<joint name="elbow" value="{elbow}"/></group_state>'
        for name, elbow in states.items()
    )
    return f'<robot name="planar"><group name="arm"><chain base_link="base" tip_link="tcp"/></group>{body}</robot>'


@pytest.mark.parametrize(
    ("states", "chosen", "elbow"),
    [
        ({"ready": 1.1, "home": 0.9}, "SRDF group_state 'home'", 0.9),  # 'home' first, whatever the order
        ({"home": 0.0, "ready": 1.1}, "SRDF group_state 'ready'", 1.1),  # a singular 'home' is passed over
        ({"stretched": 0.0}, "searched near neutral", None),  # no usable state: the search
    ],
)
def test_an_srdf_beside_the_urdf_gives_the_home(tmp_path: Path, states: dict, chosen: str, elbow: float | None) -> None:
    (tmp_path / "planar.urdf").write_text(PLANAR, encoding="utf-8")
    (tmp_path / "planar.srdf").write_text(srdf(states), encoding="utf-8")
    robot = pinrate.load(tmp_path / "planar.urdf")
    assert robot.home_choice.startswith(chosen)
    if elbow is not None:
        np.testing.assert_allclose(robot.home(), [0.3, elbow])
    for name, state_elbow in states.items():
        # a stretched state (elbow 0: the planar determinant 0.5 * 0.4 * sin(elbow) is 0) is
        # passed over by name, and says why
        passed = f"SRDF group_state '{name}' passed over (singular" in robot.home_choice
        assert passed == (state_elbow == 0.0), robot.home_choice


def test_a_named_pose_outside_the_limits_is_passed_over_by_name(tmp_path: Path) -> None:
    # (An SRDF's states are put inside the limits when read; find_home checks whatever it is given.)
    (tmp_path / "planar.urdf").write_text(PLANAR, encoding="utf-8")
    robot = pinrate.load(tmp_path / "planar.urdf")
    _, why = find_home(robot, pinrate.Partition.auto(robot), [("pose 'far'", np.array([0.3, 3.5]))])
    assert why.endswith("; pose 'far' passed over (outside the limits of elbow)"), why


@pytest.mark.parametrize("seed", range(fuzz_count(40)))
def test_home_is_inside_every_joint_s_limits(tmp_path: Path, seed: int) -> None:
    """Issue 23/24: random trees whose limits exclude 0 (a joint's neutral value) got neutral
    as home, outside the limits, where no controller step may start."""
    rng = np.random.default_rng(seed)
    path = tmp_path / "random.urdf"
    path.write_text(random_urdf(rng), encoding="utf-8")
    try:
        robot = pinrate.load(path)
    except pinrate.PinrateError:
        return  # no arm in this tree
    home = robot.home()
    for joint in robot.joint_names:
        limits = robot.joint_limits(joint)
        if limits is not None:
            value = home[robot.model.joints[robot.joint_id(joint)].idx_q]
            assert limits[0] <= value <= limits[1], (joint, value, limits, robot.home_choice)
