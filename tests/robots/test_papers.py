"""The papers' robots: generated URDFs and the sensor-frame Jacobians printed in the papers."""

from __future__ import annotations

import math

import numpy as np
import pytest

import pinrate
from pinrate import robots
from support import ROOT

URDF_DIR = ROOT / "urdf"


@pytest.mark.parametrize("name", robots.ROBOT_NAMES)
def test_checked_in_urdf_is_in_sync_with_its_generator(name: str) -> None:
    path = URDF_DIR / f"{name}.urdf"
    assert path.is_file(), f"urdf/{name}.urdf missing: run `make urdf`"
    assert path.read_text(encoding="utf-8") == robots.urdf(name), f"urdf/{name}.urdf is stale: run `make urdf`"


@pytest.mark.parametrize("name", robots.ROBOT_NAMES)
def test_loadable_by_name_with_the_papers_frames(name: str) -> None:
    by_name = pinrate.load(name)
    by_function = getattr(robots, name)()
    assert (by_name.tip, by_name.sensor) == (by_function.tip, by_function.sensor)
    q = by_name.random_configuration(0)
    np.testing.assert_allclose(by_name.jacobian(q), by_function.jacobian(q))
    assert np.isfinite(pinrate.convergence(by_name, by_name.home()).spectral_radius)


@pytest.mark.parametrize("seed", range(6))
def test_two_link_planar_is_eq_10_and_independent_of_theta1(seed: int) -> None:
    l1, l2 = 0.7, 0.45
    robot = robots.two_link_planar(l1=l1, l2=l2)
    q = robot.random_configuration(seed)
    s2, c2 = math.sin(q[1]), math.cos(q[1])
    eq_10 = np.array([[l1 * s2, 0.0], [l2 + l1 * c2, l2]])
    np.testing.assert_allclose(robot.jacobian(q)[:2], eq_10, atol=1e-12)
    turned = q.copy()
    turned[0] += 1.234
    np.testing.assert_allclose(robot.jacobian(turned), robot.jacobian(q), atol=1e-12)


@pytest.mark.parametrize("seed", range(4))
def test_cylindrical_is_eq_13(seed: int) -> None:
    robot = robots.cylindrical()
    q = robot.random_configuration(seed)
    np.testing.assert_allclose(robot.jacobian(q)[:3], np.diag([q[2], 1.0, 1.0]), atol=1e-12)


@pytest.mark.parametrize("seed", range(4))
def test_spherical_is_eq_16(seed: int) -> None:
    robot = robots.spherical()
    q = robot.random_configuration(seed)
    theta2, d3 = q[1], q[2]
    np.testing.assert_allclose(robot.jacobian(q)[:3], np.diag([d3 * math.cos(theta2), d3, 1.0]), atol=1e-12)


def test_unknown_parameter_lists_the_parameters() -> None:
    with pytest.raises(pinrate.InputError, match="l1, l2, l3"):
        robots.scara(l4=0.1)


@pytest.mark.parametrize("value", [0.0, -0.1, math.nan, "long"])
def test_lengths_must_be_positive(value: object) -> None:
    with pytest.raises(pinrate.InputError, match="l3"):
        robots.scara(l3=value)


def test_hirata_joint_limit_is_the_papers() -> None:
    robot = robots.hirata_arh300()
    lower, upper = robot.position_limits()
    i = robot.model.joints[robot.joint_id("theta2")].idx_q
    assert math.degrees(lower[i]) == pytest.approx(25) and math.degrees(upper[i]) == pytest.approx(145)
