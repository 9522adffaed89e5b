"""Joint and rate limits of one control step (contract v2, issue 11): q never leaves its
limits, a joint at a limit is held while the others serve the command, motion away is always
executed, and a binding velocity limit scales every rate by one factor."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import pinrate
from pinrate import Controller, InputError, Status
from pinrate.control.limits.velocity import scaled_detail

AL5D = Path(__file__).parent.parent / "data" / "third_party" / "rtb_al5d_robot.urdf"


def robot_named(name: str) -> pinrate.Robot:
    return (
        pinrate.load(AL5D)
        if name == "al5d"
        else getattr(pinrate.robots, name)()
        if name == "scara"
        else pinrate.load(name)
    )


def limited(robot: pinrate.Robot, controller: Controller) -> list[tuple[int, float, float]]:
    """(q index, lower, upper) of the partition's joints with finite limits, from the model."""
    rows = []
    for joint in controller.partition.joints:
        model = robot.model.joints[robot.model.getJointId(joint)]
        lower, upper = robot.model.lowerPositionLimit[model.idx_q], robot.model.upperPositionLimit[model.idx_q]
        if model.nq == 1 and np.isfinite(lower) and np.isfinite(upper):
            rows.append((model.idx_q, float(lower), float(upper)))
    return rows


@pytest.mark.parametrize("name", ["ur5", "panda", "scara", "al5d"])
def test_long_random_commands_never_cross_a_limit_and_rates_keep_their_direction(name: str) -> None:
    robot = robot_named(name)
    speed_limit = 0.8
    # The generalized inverse keeps the walk going through singular regions, where the default
    # would halt it short of the limits (tests/control/test_singularity.py walks that one).
    options = {"dt": 0.02, "singularity": "generalized_inverse"}
    controller = Controller(robot, velocity_limits=speed_limit, **options)
    free = Controller(robot, velocity_limits=np.inf, **options)  # the same step without rate limits
    bounds = limited(robot, controller)
    rng = np.random.default_rng(11)
    q = robot.home()
    for index, lower, upper in bounds[:1] + bounds[-1:]:  # two joints start near a limit: the walk meets them
        q[index] = upper - 0.01 * (upper - lower)
    size = controller.index.rows.size
    seen = set()
    for step_number in range(1500):
        if step_number % 50 == 0:  # a new stick deflection every second
            twist = rng.normal(size=size) * np.where(np.arange(size) < controller.index.m, 0.3, 1.0)
        step = controller.step(q, twist)
        seen.update(step.conditions)
        assert np.all(np.isfinite(step.q)) and np.all(np.isfinite(step.joint_rates))
        for index, lower, upper in bounds:
            assert lower - 1e-12 <= step.q[index] <= upper + 1e-12, (name, step_number, step.detail)
        assert np.abs(step.joint_rates).max() <= speed_limit * (1 + 1e-12)
        if step.status is Status.RATE_LIMITED:
            unlimited = free.step(q, twist).joint_rates
            factor = speed_limit / np.abs(unlimited).max()  # the largest factor meeting every limit
            np.testing.assert_allclose(step.joint_rates, factor * unlimited, rtol=1e-9, atol=1e-12)
        q = step.q
    assert Status.RATE_LIMITED in seen and Status.JOINT_LIMIT in seen, seen


def test_a_joint_at_its_limit_is_held_while_the_others_serve_the_command() -> None:
    robot = pinrate.load("panda")
    controller = Controller(robot, velocity_limits=np.inf, dt=0.01)
    q = robot.home()
    joint = "panda_joint1"
    column = robot.velocity_indices(joint)[0]
    _, upper = robot.joint_limits(joint)
    q[robot.model.joints[robot.joint_id(joint)].idx_q] = upper  # on its limit
    jacobian = robot.jacobian(q)[:, controller.index.columns]
    push = robot.jacobian(q)[:, column] * 0.1  # a twist the joint's motion into its limit makes
    step = controller.step(q, push)
    assert step.status is Status.JOINT_LIMIT and step.frozen == (joint,)
    assert step.q[column] == upper and step.joint_rates[column] == 0.0
    # The other six serve the command: the solution of J without that column, by numpy.
    others = [i for i, c in enumerate(controller.index.columns) if c != column]
    best = np.linalg.solve(jacobian[:, others], push)
    np.testing.assert_allclose(step.joint_rates[controller.index.columns[others]], best, atol=1e-9)

    # Motion away from the limit is executed as commanded.
    away = controller.step(q, -push)
    assert away.status is Status.OK and away.frozen == ()
    assert away.q[column] < upper


def test_a_held_joint_does_not_cycle_between_stop_and_go() -> None:
    robot = pinrate.load("ur5")
    controller = Controller(robot, velocity_limits=np.inf, dt=0.01)
    q = robot.home()
    pan = robot.joint_names.index("shoulder_pan_joint")  # the elbow's limit, pi, is a folded singularity
    _, upper = robot.joint_limits("shoulder_pan_joint")
    q[pan] = upper - 0.003
    push = robot.jacobian(q)[:, pan] * 0.5
    statuses, values = [], []
    for _ in range(50):
        step = controller.step(q, push)
        statuses.append(step.status)
        values.append(step.q[pan])
        q = step.q
    first = statuses.index(Status.JOINT_LIMIT)
    assert all(status is Status.JOINT_LIMIT for status in statuses[first:])  # held from then on
    assert values[first:] == [upper] * (len(values) - first)


def test_velocity_limits_come_from_the_urdf_or_are_given() -> None:
    robot = pinrate.load("ur5")
    from_urdf = Controller(robot).velocity_limits
    np.testing.assert_array_equal(from_urdf, np.array(robot.model.velocityLimit))
    np.testing.assert_array_equal(Controller(robot, velocity_limits=2.0).velocity_limits, np.full(6, 2.0))
    with pytest.raises(pinrate.InputError, match="velocity_limits"):
        Controller(robot, velocity_limits=[1.0, 2.0])
    with pytest.raises(pinrate.InputError, match="velocity_limits"):
        Controller(robot, velocity_limits=-1.0)
    with pytest.raises(pinrate.InputError, match="position_limits"):
        Controller(robot, position_limits="yes")


def test_a_zero_urdf_velocity_means_no_limit(tmp_path: Path) -> None:
    text = (Path(__file__).parent.parent / "data" / "mixed_joints.urdf").read_text(encoding="utf-8")
    import re

    path = tmp_path / "zero_velocity.urdf"
    path.write_text(re.sub(r'velocity="[^"]*"', 'velocity="0"', text), encoding="utf-8")
    robot = pinrate.load(path)
    assert np.all(np.isinf(Controller(robot).velocity_limits))


def test_acceleration_limits_bound_every_change_of_rate_and_keep_its_direction() -> None:
    robot = pinrate.load("ur5")
    limits = np.array([2.0, 2.0, 3.0, 4.0, 4.0, 4.0])  # rad/s²
    controller = Controller(robot, acceleration_limits=limits)
    free = Controller(robot)
    q = robot.home()
    previous = np.zeros(6)
    rng = np.random.default_rng(8)
    twist = rng.normal(size=6) * 0.1
    for index in range(200):
        if index % 40 == 0:
            twist = rng.normal(size=6) * 0.1  # an abrupt new command
        wanted = free.step(q, twist).joint_rates
        step = controller.step(q, twist)
        change = step.joint_rates - previous
        assert np.all(np.abs(change) <= limits * controller.dt * (1 + 1e-12))
        if Status.RATE_LIMITED in step.conditions:  # the change points from the last rates to the wanted ones
            direction = wanted - previous
            np.testing.assert_allclose(change / np.linalg.norm(change), direction / np.linalg.norm(direction))
        else:
            np.testing.assert_allclose(step.joint_rates, wanted)
        previous, q = step.joint_rates, step.q
    controller.reset()
    first = controller.step(q, twist)
    assert np.all(np.abs(first.joint_rates) <= limits * controller.dt * (1 + 1e-12))  # from rest again
    with pytest.raises(InputError, match="acceleration_limits"):
        Controller(robot, acceleration_limits=-1.0)


def test_a_joint_held_at_its_limit_stops_at_once_under_acceleration_limits() -> None:
    robot = pinrate.load("ur5")
    controller = Controller(robot, acceleration_limits=2.0, velocity_limits=np.inf)
    _, upper = robot.joint_limits("elbow_joint")
    q = robot.home()
    q[2] = upper - 0.08
    previous = np.zeros(6)
    for _ in range(60):
        step = controller.step(q, pinrate.JointJog({"elbow_joint": 1.0, "shoulder_pan_joint": 0.2}))
        assert step.q[2] <= upper
        if q[2] == upper:
            assert step.joint_rates[2] == 0.0  # held: no phantom rate
            # the other joint accelerates at its limit, not throttled by the held one
            assert step.joint_rates[0] - previous[0] == pytest.approx(min(0.02, 0.2 - previous[0]), abs=1e-12)
        previous, q = step.joint_rates, step.q
    assert q[2] == upper and previous[0] == pytest.approx(0.2)


def test_a_scale_just_under_one_never_reads_as_one() -> None:
    """A velocity limit that bound says so: 0.9996 printed to 3 digits would be "1"."""
    assert "scaled by 0.25 " in scaled_detail(0.25)
    assert "scaled by 0.9996 " in scaled_detail(0.9996)
    assert "scaled by 0.999999999 " in scaled_detail(1 - 1e-9)
    assert float(scaled_detail(np.nextafter(1.0, 0.0)).split()[3]) < 1.0
