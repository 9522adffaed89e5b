"""The MuJoCo plant (pinrate.plants.mujoco_plant) in closed loop: servo and teleop read what
it measured, and it behaves as the servos it declares."""

from __future__ import annotations

import math
import sys

import numpy as np
import pytest

import pinrate
from pinrate import Teleop
from pinrate.errors import PlantError

pytest.importorskip("mujoco")

from pinrate.plants import MujocoPlant


def _target(robot):
    target = robot.pose(robot.home())
    target[:3, 3] += (0.10, -0.05, 0.05)  # the design's prototype: 122 mm away, no limit on the way
    return target


def test_a_velocity_servo_answers_a_step_as_its_first_order_law(ur5):
    """At rest at home, a step command on the last joint: implicit Euler (MuJoCo's
    implicitfast integrates the servo's damping k_v = M_jj / T implicitly) gives, after k
    sub-steps of h, q̇_k = q̇_cmd (1 - (1 + h / T)^-k) exactly for an uncoupled joint."""
    plant = MujocoPlant(ur5)
    plant.reset(ur5.home())
    command = np.zeros(6)
    command[5] = 0.5
    ratio = 1.0 / (1.0 + plant.timestep / plant.time_constant)
    for k in range(1, 31):
        measured = plant.advance(command, plant.timestep).joint_rates[5]
        # wrist_3's coupling to the other joints (M's off-diagonal, 0.2 % of its M_jj here): 0.5 % of the command.
        assert measured == pytest.approx(0.5 * (1.0 - ratio**k), abs=0.005 * 0.5)


@pytest.mark.parametrize("name", ["ur5", "panda"])
def test_servo_on_velocity_servos_converges_where_the_kinematic_one_does(name):
    robot = pinrate.load(name)
    target = _target(robot)
    kinematic = pinrate.servo(robot, robot.home(), target, algorithm="exact", gain=2.0, tol=1e-6)
    plant = MujocoPlant(robot)
    simulated = pinrate.servo(robot, robot.home(), target, algorithm="exact", gain=2.0, tol=1e-6, plant=plant)
    assert simulated.converged and kinematic.converged
    assert np.linalg.norm(robot.pose(simulated.q[-1])[:3, 3] - target[:3, 3]) < 1e-6
    # Each joint lags its command by about q̇ T (a first-order servo); the command itself
    # changes as the loop corrects the lag, so the two runs differ by at most twice that.
    steps = min(len(simulated.q), len(kinematic.q))
    lag = 2.0 * plant.time_constant * np.abs(kinematic.joint_rates).max()
    assert np.abs(simulated.q[:steps] - kinematic.q[:steps]).max() <= lag
    record = simulated.plant
    assert record is not None and record.name == plant.name
    assert record.measured_rates.shape == simulated.joint_rates.shape
    # The measured q is not the integrated rates: the record says by how much.
    assert 0 < record.tracking_error.max() < 1e-2


def test_position_servos_still_converge_at_the_commanded_gain(ur5):
    """The reference is integrated from the last reference, not from the lagging measured q,
    so the loop keeps its gain: the error decays as exp(-gain t) (within 5 %)."""
    trajectory = pinrate.servo(
        ur5,
        ur5.home(),
        _target(ur5),
        algorithm="exact",
        gain=2.0,
        tol=1e-7,
        plant=MujocoPlant(ur5, actuator="position"),
    )
    assert trajectory.converged
    error = trajectory.position_error + trajectory.orientation_error
    first, last = round(1.0 / trajectory.dt), round(3.0 / trajectory.dt)
    rate = math.log(error[first] / error[last]) / (trajectory.time[last] - trajectory.time[first])
    assert rate == pytest.approx(2.0, rel=0.05)


def test_a_trajectory_on_a_plant_saves_and_loads_its_record(ur5, tmp_path):
    trajectory = pinrate.servo(ur5, ur5.home(), _target(ur5), algorithm="exact", plant=MujocoPlant(ur5), max_steps=50)
    loaded = pinrate.Trajectory.load(trajectory.save(tmp_path / "run.npz"))
    assert loaded.plant is not None and loaded.plant.name == trajectory.plant.name
    for field in ("measured_rates", "tracking_error", "saturated"):
        assert np.array_equal(getattr(loaded.plant, field), getattr(trajectory.plant, field))
    assert trajectory.reversed().plant is None  # a reversal is a plan, not a measurement


def test_teleop_on_the_plant_never_crosses_a_joint_limit(panda):
    """Jogging panda_joint4 into its upper limit at full speed: the velocity servo overshoots
    where its command stops (about q̇ T) and MuJoCo's limit is a stiff spring; the controller
    reads the measurement put on the limit (within the plant's tolerance) and never drives
    past it, and the console does not halt."""
    plant = MujocoPlant(panda)
    teleop = Teleop(panda, plant=plant, dt=0.01)
    joint = panda.model.joints[panda.joint_id("panda_joint4")]
    upper = panda.model.upperPositionLimit[joint.idx_q]
    tolerance = plant.limit_tolerance[joint.idx_v]
    now = 0.0
    reached = False
    for _ in range(300):
        teleop.jog({"panda_joint4": 2.0}, now)
        step = teleop.tick(now)
        now += 0.01
        measured = teleop.measurement.q
        assert measured[joint.idx_q] <= upper + tolerance
        assert np.all(teleop.q >= panda.model.lowerPositionLimit) and np.all(teleop.q <= panda.model.upperPositionLimit)
        reached |= step.status is pinrate.Status.JOINT_LIMIT
    assert reached and not teleop.halted and not teleop.plant_fault
    assert teleop.measurement.time == pytest.approx(300 * 0.01)  # the plant's clock: one dt a tick


def test_a_missing_mujoco_is_one_error_naming_the_extra(ur5, monkeypatch):
    monkeypatch.setitem(sys.modules, "mujoco", None)  # import mujoco then fails
    with pytest.raises(PlantError, match=r'pip install "pinrate\[mujoco\]"'):
        MujocoPlant(ur5)


def test_bad_options_are_refused_by_name(ur5):
    with pytest.raises(pinrate.InputError, match="actuator must be one of 'velocity', 'position'"):
        MujocoPlant(ur5, actuator="torque")
    with pytest.raises(pinrate.InputError, match="timestep"):
        MujocoPlant(ur5, timestep=0.0)
    with pytest.raises(pinrate.InputError, match="plant was built for another Robot"):
        pinrate.servo(pinrate.load("ur5"), ur5.home(), _target(ur5), plant=MujocoPlant(ur5))
    with pytest.raises(pinrate.InputError, match="built on this robot"):
        Teleop(pinrate.load("ur5"), plant=MujocoPlant(ur5))


def test_a_joint_jog_on_the_plant_moves_only_that_joint(ur5):
    """The other joints' servos hold their rates at zero, not their positions: they drift
    only by the jogged joint's reaction through the coupling (measured: 1 % of its motion on
    the wrist_1 joint; bounded here at 2 %)."""
    plant = MujocoPlant(ur5)
    teleop = Teleop(ur5, plant=plant, dt=0.01)
    start = teleop.q.copy()
    for tick in range(50):
        teleop.jog({"elbow_joint": 0.3}, tick * 0.01)
        teleop.tick(tick * 0.01)
    moved = np.abs(teleop.q - start)
    elbow = ur5.model.joints[ur5.joint_id("elbow_joint")].idx_q
    assert moved[elbow] > 0.1
    assert np.delete(moved, elbow).max() < 0.02 * moved[elbow]
