"""A NaN hunt where the algebra is weakest: zeros, multiples of pi/2, joint limits, stretched
elbows and aligned wrists, for every algorithm. Every answer is finite numbers or a
PinrateError (a singular block); never NaN, inf in rates or an unexpected exception."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

import pinrate
from pinrate.checks import PHYSICAL_BOUND
from pinrate.control import Controller
from pinrate.theorem.sampling import spectral_radius_at
from support import fuzz_count

ROBOTS = ["ur5", "panda", "kinova", "z1", "scara", "planar_polar", "spherical_6dof", "barker_arm", "cartesian"]

ONE_JOINT = """<robot name="one"><link name="base"/><link name="arm"/><link name="tip"/>
<joint name="hinge" type="revolute"><parent link="base"/><child link="arm"/><axis xyz="0 0 1"/>
<limit lower="-2" upper="2" effort="1" velocity="1"/></joint>
<joint name="tool" type="fixed"><parent link="arm"/><child link="tip"/><origin xyz="0.5 0 0"/></joint></robot>"""


def special_configurations(robot: pinrate.Robot, rng: np.random.Generator, count: int) -> np.ndarray:
    """Zeros, neutral, home; all-lower and all-upper limits; then random mixes of 0, ±pi/2,
    pi and the limits per joint (each brought inside the limits)."""
    rows = [robot.neutral(), robot.home()]
    names = robot.joint_names

    def configuration(values: dict[str, float]) -> np.ndarray:
        q = robot.neutral()[None, :].copy()
        for name, value in values.items():
            if robot.model.joints[robot.joint_id(name)].nv == 1:
                low, high = robot.joint_range(name)
                robot.set_joint_values(q, name, np.array([min(max(value, low), high)]))
        return q[0]

    rows.append(configuration(dict.fromkeys(names, 0.0)))
    rows.append(configuration({name: robot.joint_range(name)[0] for name in names}))
    rows.append(configuration({name: robot.joint_range(name)[1] for name in names}))
    for _ in range(count):
        values = {}
        for name in names:
            low, high = robot.joint_range(name)
            values[name] = float(rng.choice([0.0, math.pi / 2, -math.pi / 2, math.pi, low, high]))
        rows.append(configuration(values))
    return np.array(rows)


@pytest.fixture(scope="module")
def one_joint(tmp_path_factory: pytest.TempPathFactory) -> pinrate.Robot:
    path = Path(tmp_path_factory.mktemp("one")) / "one.urdf"
    path.write_text(ONE_JOINT, encoding="utf-8")
    return pinrate.load(path)


@pytest.mark.parametrize("name", [*ROBOTS, "one_joint"])
def test_no_nan_at_singular_configurations(name: str, one_joint: pinrate.Robot) -> None:
    robot = one_joint if name == "one_joint" else pinrate.load(name)
    rng = np.random.default_rng(7)
    configurations = special_configurations(robot, rng, fuzz_count(40))
    partition = pinrate.Partition.auto(robot)
    size = partition.m + partition.k
    twists = [rng.normal(0.0, 1.0, size), np.full(size, PHYSICAL_BOUND), np.zeros(size)]
    radii = spectral_radius_at(robot, configurations, partition=partition)
    assert not np.isnan(radii).any()  # inf marks a singular block; NaN never
    controllers = {algorithm: Controller(robot, algorithm=algorithm) for algorithm in pinrate.ALGORITHMS}
    free = {name: Controller(robot, algorithm=name, position_limits=False) for name in pinrate.ALGORITHMS}
    for q in configurations:
        inside = all(
            limits is None or limits[0] <= q[robot.model.joints[robot.joint_id(name)].idx_q] <= limits[1]
            for name, limits in ((name, robot.joint_limits(name)) for name in robot.joint_names)
        )
        assert np.isfinite(robot.jacobian(q)).all() and np.isfinite(robot.pose(q)).all()
        try:
            result = pinrate.convergence(robot, q)
            assert math.isfinite(result.spectral_radius) and np.isfinite(result.eigenvalues).all()
        except pinrate.SingularBlockError:
            pass
        for algorithm, controller in controllers.items():
            for twist in twists:
                try:
                    rates = pinrate.joint_rates(robot, q, twist, algorithm=algorithm)
                    assert rates.shape == (robot.nv,) and np.isfinite(rates).all(), (algorithm, q, twist)
                except pinrate.SingularBlockError:
                    pass
                stepping = controller
                if not inside:  # neutral, for some arms: refused by name, stepped without the limits
                    with pytest.raises(pinrate.InputError, match="outside the position limits"):
                        controller.step(q, twist)
                    stepping = free[algorithm]
                step = stepping.step(q, twist)
                assert np.isfinite(step.q).all() and np.isfinite(step.joint_rates).all(), (algorithm, q)
                assert step.q.shape == (robot.nq,)


@pytest.mark.parametrize("algorithm", pinrate.ALGORITHMS)
def test_servo_from_a_singular_start_ends_with_finite_records(algorithm: str) -> None:
    # The UR5 at all zeros: shoulder, elbow and wrists aligned at once.
    ur5 = pinrate.load("ur5")
    target = ur5.pose(ur5.home())
    trajectory = pinrate.servo(ur5, np.zeros(6), target, algorithm=algorithm, max_steps=300)
    for values in (trajectory.q, trajectory.position_error, trajectory.orientation_error, trajectory.joint_rates):
        assert np.isfinite(values).all()
    assert not np.isnan(trajectory.spectral_radius).any()
    assert trajectory.reason
