"""The kinematic model's own checks (its Jacobian and configurations are tested in
test_manipulator.py, through the Robot that extends it)."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import pinrate
from mimic_urdfs import parallelogram_arm, planar_mimic_on_the_tip_path


@pytest.mark.parametrize("sensor", [None, "base_link"])
def test_a_mimic_joint_on_the_tip_path_is_folded_into_its_leaders_column(tmp_path, sensor) -> None:
    path = tmp_path / "planar_mimic.urdf"
    path.write_text(planar_mimic_on_the_tip_path())
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # nothing to warn about: J knows joint_2 follows joint_1
        robot = pinrate.load(path, sensor=sensor)
    # joint_2 = 0.5 joint_1 + 0.1: the tip's true d(p)/d(joint_1) is the central difference
    # below (step 1e-6 rad: truncation ~h^2 |p'''| / 6 ~ 1e-12 m/rad on 1.2 m of links, rounding
    # ~1e-16 / 1e-6 = 1e-10 m/rad), taken with the relation applied, independent of pinrate's J.
    q1, q3, h = 0.3, -0.4, 1e-6

    def tip(angle: float, third: float = q3) -> np.ndarray:
        return robot.pose(np.array([angle, 0.5 * angle + 0.1, third]))[:3, 3]

    q = np.array([q1, 0.5 * q1 + 0.1, q3])
    sensor_axes = (robot.pose(q) if sensor is None else robot.frame_pose(q, "base_link"))[:3, :3].T
    leader_column = sensor_axes @ (tip(q1 + h) - tip(q1 - h)) / (2 * h)
    third_column = sensor_axes @ (tip(q1, q3 + h) - tip(q1, q3 - h)) / (2 * h)
    jacobian = robot.jacobian(q)
    np.testing.assert_allclose(jacobian[:3, 0], leader_column, atol=1e-8)
    np.testing.assert_allclose(jacobian[:3, 2], third_column, atol=1e-8)
    np.testing.assert_array_equal(jacobian[:, 1], 0.0)  # joint_2 has no motion of its own
    # the angular row: all three joints turn about z, so d(angle)/d(joint_1) = 1 + 0.5
    np.testing.assert_allclose(jacobian[5, 0], 1.5, atol=1e-12)
    assert robot.folds_mimics


def test_parallelogram_side_links_off_the_tip_path_raise_no_warning(tmp_path) -> None:
    path = tmp_path / "irb_like.urdf"
    path.write_text(parallelogram_arm())
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        robot = pinrate.load(path)
    assert set(robot.arm_mimics) == {"side_a_joint", "side_b_joint"}
