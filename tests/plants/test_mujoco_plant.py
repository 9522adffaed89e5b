"""The MuJoCo plant (pinrate.plants.mujoco_plant) in closed loop: servo and teleop read what
it measured, and it behaves as the servos it declares."""

from __future__ import annotations

import math
import sys

import numpy as np
import pinocchio as pin
import pytest

import pinrate
from pinrate import Teleop
from pinrate.errors import PlantError
from pinrate.kinematics.targets import nearby_target

pytest.importorskip("mujoco")

from pinrate.plants import MujocoPlant


def _target(robot):
    target = robot.pose(robot.home())
    target[:3, 3] += (0.10, -0.05, 0.05)  # the design's prototype: 122 mm away, no limit on the way
    return target


def test_a_velocity_servo_is_the_pi_law_integrated_as_mujoco_does(ur5):
    """At rest at home, a step command u on the last joint. The servo's law,
    τ = k_v (u - q̇) + k_i (q_ref - q) with q_ref advanced by u h before each sub-step, and
    MuJoCo's implicitfast (the velocity damping k_v taken implicitly, then q from the new
    q̇), integrated here by hand for the joint alone:

        q̇_k+1 = q̇_k + h τ_k / (M_jj + h k_v),    q_k+1 = q_k + h q̇_k+1."""
    plant = MujocoPlant(ur5)
    q = plant.reset(ur5.home()).q[5]
    inertia, period, step = plant.inertia[5], plant.time_constant, plant.timestep
    damping, stiffness = inertia / period, inertia / (4.0 * period**2)
    command = np.zeros(6)
    command[5] = u = 0.5
    rate, reference = 0.0, q
    for _ in range(60):
        measured = plant.advance(command, step)
        reference += u * step
        torque = damping * (u - rate) + stiffness * (reference - q)
        rate += step * torque / (inertia + step * damping)
        q += step * rate
        # wrist_3's coupling to the other joints (M's off-diagonal: 0.2 % of its M_jj here): 0.5 % of u.
        assert measured.joint_rates[5] == pytest.approx(rate, abs=0.005 * u)
        assert measured.q[5] == pytest.approx(q, abs=0.005 * u * step * 60)


def test_the_integral_holds_a_joint_against_gravity(ur5):
    """Without the drives' gravity compensation, a still command: the PI loop brings every
    joint to rest (a P-only velocity loop would sag at τ_g / k_v for as long as it is held),
    at the offset where the integral's force carries gravity: k_i (q_ref - q) = g(q), so
    q - q_ref = -g / k_i (g from Pinocchio's generalized gravity, an independent
    computation; to 2 %, the offset's own change of g)."""
    plant = MujocoPlant(ur5, gravity_compensation=False)
    home = plant.reset(ur5.home()).q
    for _ in range(300):  # 3 s: the loop's double pole at -1 / (2 T) = -100/s has long settled
        measured = plant.advance(np.zeros(6), 0.01)
    assert np.abs(measured.joint_rates).max() < 1e-9
    gravity = pin.computeGeneralizedGravity(ur5.model, ur5.model.createData(), home)
    stiffness = plant.inertia / (4.0 * plant.time_constant**2)
    offset = -gravity / stiffness
    assert np.abs(offset).max() > 1e-3  # the UR5's shoulder and elbow carry their links
    assert np.allclose(measured.q - home, offset, rtol=0.02, atol=1e-9)


@pytest.mark.parametrize(
    ("name", "gravity_compensation"),
    [("ur5", True), ("panda", True), ("kinova", True), ("so101", True), ("xarm7", True), ("ur5", False)],
)
def test_servo_on_velocity_servos_converges_where_the_kinematic_one_does(name, gravity_compensation):
    """The UR5 and the panda, kinova's continuous joints, the SO-101's 10-gram links, the
    xArm7's URDF damping (10 N m s/rad), and gravity fought by the servos alone; the
    controller keeps the URDF's velocity limits, where the drives saturate.

    The tip's paths agree within T times the total variation of the kinematic run's tip
    velocity: a change Δv of the commanded velocity leaves the PI loop's position behind by
    Δv t exp(-t / 2T) at most (its error obeys M ë + k_v ė + k_i e = 0, a double pole at
    -1 / 2T; peak 0.74 T Δv at t = 2T), and the outer loop, which drives the pose error down
    at every configuration, does not let such deviations add up beyond their sum."""
    robot = pinrate.load(name)
    _, target = nearby_target(robot, pinrate.Partition.auto(robot), 3)
    # The URDF's velocity limits on the controller, as on a real arm: the drives saturate there.
    settings = {"algorithm": "exact", "gain": 2.0, "tol": 1e-6, "velocity_limits": None}
    kinematic = pinrate.servo(robot, robot.home(), target, **settings)
    plant = MujocoPlant(robot, gravity_compensation=gravity_compensation)
    simulated = pinrate.servo(robot, robot.home(), target, plant=plant, **settings)
    assert simulated.converged and kinematic.converged
    assert np.linalg.norm(robot.pose(simulated.q[-1])[:3, 3] - target[:3, 3]) < 1e-6
    steps = min(len(simulated.q), len(kinematic.q))
    kinematic_tip = np.array([robot.pose(q)[:3, 3] for q in kinematic.q[:steps]])
    simulated_tip = np.array([robot.pose(q)[:3, 3] for q in simulated.q[:steps]])
    velocity = np.vstack([np.zeros(3), np.diff(kinematic_tip, axis=0) / kinematic.dt])
    variation = np.linalg.norm(np.diff(velocity, axis=0), axis=1).sum()
    assert np.linalg.norm(simulated_tip - kinematic_tip, axis=1).max() <= plant.time_constant * variation
    record = simulated.plant
    assert record is not None and record.name == plant.name
    assert record.measured_rates.shape == simulated.joint_rates.shape
    # The measured q is not the integrated rates: the record says by how much.
    assert 0 < record.tracking_error.max() < plant.time_constant * variation


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
    """Jogging panda_joint4 into its upper limit at full speed: the controller's q never
    passes it (the measurement within the plant's tolerance is put on it), the console does
    not halt, and the simulated joint stops at the limit's stiff stop: a critically damped
    spring of time constant τ = 2 sub-steps takes up a joint arriving at speed v within
    v τ / e, bounded here by v τ with v the joint's velocity limit."""
    plant = MujocoPlant(panda)
    teleop = Teleop(panda, plant=plant, dt=0.01)
    joint = panda.model.joints[panda.joint_id("panda_joint4")]
    upper = panda.model.upperPositionLimit[joint.idx_q]
    speed = panda.model.velocityLimit[joint.idx_v]
    now = 0.0
    reached = False
    for _ in range(300):
        teleop.jog({"panda_joint4": 2.0}, now)
        step = teleop.tick(now)
        now += 0.01
        assert teleop.measurement.q[joint.idx_q] - upper <= speed * 2.0 * plant.timestep
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
    """The other joints' servos hold them: the jogged joint's reaction through the coupling
    moves them only while the integral catches it."""
    plant = MujocoPlant(ur5)
    teleop = Teleop(ur5, plant=plant, dt=0.01)
    start = teleop.q.copy()
    for tick in range(50):
        teleop.jog({"elbow_joint": 0.3}, tick * 0.01)
        teleop.tick(tick * 0.01)
    moved = np.abs(teleop.q - start)
    elbow = ur5.model.joints[ur5.joint_id("elbow_joint")].idx_q
    assert moved[elbow] > 0.1
    assert np.delete(moved, elbow).max() < 1e-3 * moved[elbow]


def test_the_controllers_dt_and_the_simulations_step_are_independent(ur5):
    """An advance of any duration runs n = ceil(duration / timestep) equal sub-steps; the
    plant's clock is the sum of the durations. Halving the sub-step changes a motion from
    rest by the integrator's first-order error only: the servo's transient moves a joint by
    about v 2T, computed with a relative error of order h / 2T, so by v h at most."""
    coarse, fine = MujocoPlant(ur5), MujocoPlant(ur5, timestep=0.0005)
    rates = np.array([0.2, -0.1, 0.1, 0.3, 0.0, 0.5])
    for plant in (coarse, fine):
        plant.reset(ur5.home())
        plant.advance(rates, 0.0025)
    assert coarse.model.opt.timestep == pytest.approx(0.0025 / 3) and fine.model.opt.timestep == pytest.approx(0.0005)
    for plant in (coarse, fine):
        last = plant.advance(rates, 0.0175)
    assert last.time == pytest.approx(0.02)
    difference = np.abs(coarse.advance(rates, 1e-9).q - fine.advance(rates, 1e-9).q).max()
    assert 0 < difference < np.abs(rates).max() * coarse.timestep
