"""The kinematic model's own checks (its Jacobian and configurations are tested in
test_manipulator.py, through the Robot that extends it)."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import pinrate
from mimic_urdfs import parallelogram_arm, planar_mimic_on_the_tip_path


def test_a_mimic_joint_on_the_tip_path_is_named_in_a_warning(tmp_path) -> None:
    path = tmp_path / "planar_mimic.urdf"
    path.write_text(planar_mimic_on_the_tip_path())
    with pytest.warns(UserWarning, match=r"'joint_2' \(mimics 'joint_1'\) lies between the base and the tip 'tool0'"):
        robot = pinrate.load(path)
    # Why it warns: with joint_2 = 0.5 joint_1 + 0.1, the tip's true d(p)/d(joint_1) is the
    # central difference below (step 1e-6 rad: truncation ~1e-12 m/rad on 1.2 m of links),
    # and pinrate's column of joint_1 misses 0.5 times joint_2's (by about 0.34 m/rad here).
    q1, q3, h = 0.3, -0.4, 1e-6

    def tip(angle: float) -> np.ndarray:
        return robot.pose(np.array([angle, 0.5 * angle + 0.1, q3]))[:3, 3]

    q = np.array([q1, 0.5 * q1 + 0.1, q3])
    true_column = robot.pose(q)[:3, :3].T @ (tip(q1 + h) - tip(q1 - h)) / (2 * h)
    jacobian = robot.jacobian(q)
    np.testing.assert_allclose(jacobian[:3, 0] + 0.5 * jacobian[:3, 1], true_column, atol=1e-8)
    assert np.linalg.norm(jacobian[:3, 0] - true_column) > 0.1


def test_parallelogram_side_links_off_the_tip_path_raise_no_warning(tmp_path) -> None:
    path = tmp_path / "irb_like.urdf"
    path.write_text(parallelogram_arm())
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        robot = pinrate.load(path)
    assert set(robot.arm_mimics) == {"side_a_joint", "side_b_joint"}
