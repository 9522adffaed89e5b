"""Mimic relations (issue 24, the fold): multiplier and offset read from the URDF, chains
resolved to their root leader, a follower's limits carried onto its leader, the fold of J
(against finite differences in test_kinematic_model.py)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import pinrate
from mimic_urdfs import joint, parallelogram_arm
from pinrate import LoadError
from pinrate.kinematics.mimic import Mimic, MimicCoupling, coupled_interval, fold


def chain_urdf(relations: dict[str, str]) -> str:
    """Four revolute joints j1..j4 in a row along x (0.3 m apart), each ``relations[name]``
    the inner XML of its <mimic> (none where absent)."""
    joints = "".join(
        joint(f"j{i}", "base_link" if i == 1 else f"l{i - 1}", f"l{i}", "0.3 0 0", "0 0 1", relations.get(f"j{i}", ""))
        for i in range(1, 5)
    )
    return f'<robot name="chain"><link name="base_link"/>{joints}</robot>'


def load(tmp_path: Path, text: str) -> pinrate.Robot:
    path = tmp_path / "robot.urdf"
    path.write_text(text)
    return pinrate.load(path)


def test_multiplier_and_offset_are_read_with_the_urdf_defaults(tmp_path: Path) -> None:
    robot = load(
        tmp_path,
        chain_urdf({"j2": '<mimic joint="j1" multiplier="-2" offset="0.25"/>', "j4": '<mimic joint="j3"/>'}),
    )
    assert robot.mimics.relations == {"j2": Mimic("j1", -2.0, 0.25), "j4": Mimic("j3", 1.0, 0.0)}
    assert robot.mimics.leaders == {"j2": "j1", "j4": "j3"}


def test_a_multiplier_that_is_not_a_finite_number_is_a_load_error(tmp_path: Path) -> None:
    with pytest.raises(LoadError, match=r"multiplier value \(inf\) is not a valid float"):
        load(tmp_path, chain_urdf({"j2": '<mimic joint="j1" multiplier="inf"/>'}))


def test_a_chain_of_mimics_is_resolved_to_its_root_and_a_loop_is_left_out(tmp_path: Path) -> None:
    # j3 = 2 j2 + 0.1 and j2 = 3 j1 + 0.2, so j3 = 2 (3 j1 + 0.2) + 0.1 = 6 j1 + 0.5 (by hand)
    text = chain_urdf(
        {
            "j2": '<mimic joint="j1" multiplier="3" offset="0.2"/>',
            "j3": '<mimic joint="j2" multiplier="2" offset="0.1"/>',
        }
    )
    robot = load(tmp_path, text)
    relation = robot.mimics.relations["j3"]
    assert relation.leader == "j1"
    assert relation.multiplier == 6.0 and relation.offset == pytest.approx(0.5, abs=1e-15)
    looped = MimicCoupling(robot.model, {"j1": "j2", "j2": "j1", "j4": Mimic("j3", 2.0)})
    assert looped.relations == {"j4": Mimic("j3", 2.0)}  # j1 and j2 stay independent
    assert MimicCoupling(robot.model, {"j1": "no_such_joint"}).relations == {}


def test_a_followers_limits_narrow_its_leaders() -> None:
    # follower in [-1, 1] with q_f = -2 q_l + 0.5: -1 <= -2 q_l + 0.5 <= 1 <=> -0.25 <= q_l <= 0.75
    assert Mimic("l", -2.0, 0.5).leader_interval(-1.0, 1.0) == (-0.25, 0.75)
    assert Mimic("l", 0.0, 0.5).leader_interval(-1.0, 1.0) is None
    assert coupled_interval((-0.5, 2.0), [(Mimic("l", -2.0, 0.5), (-1.0, 1.0))]) == (-0.25, 0.75)
    # contradictory limits keep the leader's own; a leader without limits takes the follower's
    assert coupled_interval((1.0, 2.0), [(Mimic("l", -2.0, 0.5), (-1.0, 1.0))]) == (1.0, 2.0)
    assert coupled_interval(None, [(Mimic("l", -2.0, 0.5), (-1.0, 1.0))]) == (-0.25, 0.75)


def test_fold_moves_each_followers_column_into_its_leaders() -> None:
    jacobian = np.arange(18.0).reshape(6, 3)
    expected = jacobian.copy()
    expected[:, 0] += -2.0 * expected[:, 2]
    expected[:, 2] = 0.0
    np.testing.assert_array_equal(fold(jacobian.copy(), ((0, 2, -2.0),)), expected)


def test_side_links_sit_where_their_leader_puts_them_in_every_configuration_made(tmp_path: Path) -> None:
    robot = load(tmp_path, parallelogram_arm(gripper=True))
    index = {name: robot.model.joints[robot.joint_id(name)].idx_q for name in robot.joint_names}
    samples = np.vstack([robot.home(), robot.sample_configurations(20, 3), robot.generic_configurations()])
    np.testing.assert_array_equal(samples[:, index["side_a_joint"]], samples[:, index["joint_2"]])
    np.testing.assert_array_equal(samples[:, index["side_b_joint"]], -samples[:, index["joint_2"]])
    np.testing.assert_array_equal(samples[:, index["right_joint"]], -samples[:, index["left_joint"]])
    assert np.ptp(samples[:, index["joint_2"]]) > 1.0  # the leader was drawn, its links followed
