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


def test_a_start_outside_the_limits_is_refused_naming_the_joint() -> None:
    """Issue 23: panda's neutral pose puts joint4 at 0 (limits [-3.07, -0.07]); a step from it
    used to snap the joint onto its limit (6.98 rad/s realised against 2.175)."""
    panda = pinrate.load("panda")
    outside = panda.neutral()
    with pytest.raises(InputError, match=r"panda_joint4 at 0 \(limits \[-3\.0718"):
        Controller(panda).step(outside, np.zeros(6))
    with pytest.raises(InputError, match="panda_joint4"):
        pinrate.servo(panda, outside, panda.pose(panda.home()))
    with pytest.raises(InputError, match="panda_joint4"):
        pinrate.Teleop(panda, outside)
    # Without position limits nothing is refused, and nothing is snapped back either.
    free = Controller(panda, position_limits=False, acceleration_limits=5.0)
    step = free.step(outside, np.array([0.05, 0, 0, 0, 0, 0]))
    realised = (step.q - outside) / free.dt  # every panda joint is 1-DOF: q moves by rate dt
    np.testing.assert_allclose(realised, step.joint_rates, rtol=1e-9, atol=1e-12)


def side_branch_arm(tmp_path: Path) -> pinrate.Robot:
    """Issue 23's repro: a 2R planar arm and a limited side joint on the base ([0.5, 1.0]),
    which the neutral pose (0) puts outside its limits."""
    axis = '<axis xyz="0 0 1"/><limit lower="-3" upper="3" effort="1" velocity="2"/>'
    urdf = (
        '<robot name="side"><link name="base"/><link name="upper"/><link name="fore"/><link name="hand"/>'
        '<link name="side"/>'
        f'<joint name="shoulder" type="revolute"><parent link="base"/><child link="upper"/>{axis}</joint>'
        f'<joint name="elbow" type="revolute"><parent link="upper"/><child link="fore"/>'
        f'<origin xyz="0.5 0 0"/>{axis}</joint>'
        '<joint name="wrist" type="fixed"><parent link="fore"/><child link="hand"/><origin xyz="0.4 0 0"/></joint>'
        '<joint name="side_joint" type="revolute"><parent link="base"/><child link="side"/><axis xyz="1 0 0"/>'
        '<limit lower="0.5" upper="1.0" effort="1" velocity="1"/></joint></robot>'
    )
    path = tmp_path / "side.urdf"
    path.write_text(urdf, encoding="utf-8")
    return pinrate.load(path, tip="hand")


@pytest.mark.parametrize("singularity", ["decelerate", "generalized_inverse", "freeze", "adaptive_dls"])
def test_a_side_joint_outside_its_limits_never_raises_a_raw_error(tmp_path: Path, singularity: str) -> None:
    """Issue 23: a KeyError came out of the planned solve when a limited joint outside the
    partition sat outside its limits in the singular region (the stretched arm)."""
    robot = side_branch_arm(tmp_path)
    partition = pinrate.Partition(["shoulder", "elbow"], [], linear="xy", angular="")
    stretched = robot.neutral()  # elbow 0: A is singular; side_joint at 0, below its 0.5
    with pytest.raises(InputError, match="side_joint"):
        Controller(robot, partition=partition, singularity=singularity).step(stretched, np.array([0.1, 0.05]))
    for options in ({}, {"acceleration_limits": 3.0}):
        free = Controller(robot, partition=partition, singularity=singularity, position_limits=False, **options)
        q = stretched
        for twist in ([0.1, 0.05], [-0.2, 0.1], [0.0, -0.3]):
            step = free.step(q, np.array(twist))
            assert np.isfinite(step.q).all() and step.q[robot.joint_names.index("side_joint")] == 0.0
            q = step.q


def test_the_acceleration_blend_says_when_it_stops_a_joint_on_its_limit() -> None:
    """Issue 23: the blend stopped a joint on its limit and said only RATE_LIMITED. Here
    wrist_3 runs at 0.5 rad/s toward its upper limit, 0.5 mrad away, and is commanded back:
    a = 25 rad/s² lets the rate fall only to 0.25 rad/s this step, which would carry it 2 mrad
    past the limit, so it stops on it (0.05 rad/s)."""
    robot = pinrate.load("ur5")
    controller = Controller(robot, acceleration_limits=25.0, velocity_limits=np.inf)
    _, upper = robot.joint_limits("wrist_3_joint")
    q = robot.home()
    q[5] = upper - 0.008
    for _ in range(2):  # 0.25 then 0.5 rad/s: 2.5 + 5 mrad
        q = controller.step(q, pinrate.JointJog({"wrist_3_joint": 0.5})).q
    assert q[5] == pytest.approx(upper - 0.0005, abs=1e-12)
    step = controller.step(q, pinrate.JointJog({"wrist_3_joint": -0.5}))
    assert step.q[5] == upper and step.joint_rates[5] == pytest.approx(0.05, abs=1e-9)
    assert Status.JOINT_LIMIT in step.conditions and Status.RATE_LIMITED in step.conditions
    assert step.status is Status.JOINT_LIMIT and "wrist_3_joint" in step.frozen
    assert "acceleration limits" in step.detail


@pytest.mark.parametrize("name", ["ur5", "panda", "scara", "spherical_6dof", "al5d"])
def test_the_rates_said_are_the_rates_applied_and_within_every_limit(name: str) -> None:
    """Random twists and jogs, with velocity and acceleration limits, from inside the limits:
    q stays within them, every 1-DOF joint moves by exactly its reported rate × dt (to the
    rounding of q + v dt), and no rate exceeds its velocity limit."""
    robot = robot_named(name) if name != "spherical_6dof" else pinrate.robots.spherical_6dof()
    rng = np.random.default_rng(23)
    speed = 0.7
    for options in ({}, {"acceleration_limits": 4.0}):
        controller = Controller(robot, velocity_limits=speed, singularity="generalized_inverse", **options)
        bounds = limited(robot, controller)
        q = robot.home()
        size = controller.index.rows.size
        for step_number in range(400):
            if step_number % 40 == 0:
                command: object = rng.normal(size=size) * 0.5
                if rng.random() < 0.3:
                    command = pinrate.JointJog({str(rng.choice(controller.partition.joints)): float(rng.normal())})
            step = controller.step(q, command)
            for index, lower, upper in bounds:
                assert lower <= step.q[index] <= upper
            moved = (step.q - q) / controller.dt
            for joint in robot.model.joints[1:]:
                if joint.nq == 1:
                    # q + v dt rounds to an ulp of the larger of |q| and |q_next|, as their difference
                    scale = max(1.0, abs(q[joint.idx_q]), abs(step.q[joint.idx_q]))
                    rounding = 4 * np.finfo(float).eps * scale / controller.dt
                    assert abs(moved[joint.idx_q] - step.joint_rates[joint.idx_v]) <= rounding, (name, step.detail)
            assert np.abs(step.joint_rates).max() <= speed * (1 + 1e-12)
            q = step.q
