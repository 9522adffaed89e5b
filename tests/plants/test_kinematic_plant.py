"""The kinematic plant (pinrate.plants.kinematic_plant): the loops' own integration."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

import pinrate
from pinrate.plants import KinematicPlant


def test_it_integrates_the_rates_exactly_and_keeps_time(ur5):
    plant = KinematicPlant(ur5)
    start = plant.reset(ur5.home())
    assert start.time == 0.0 and not start.joint_rates.any()
    rates = np.array([0.1, -0.2, 0.3, 0.0, 0.5, -1.0])
    measurement = plant.advance(rates, 0.02)
    assert np.array_equal(measurement.q, pin.integrate(ur5.model, ur5.home(), rates * 0.02))
    assert np.array_equal(measurement.joint_rates, rates) and measurement.time == 0.02


def test_servo_on_it_is_the_kinematic_servo_bit_for_bit(ur5, panda):
    for robot in (ur5, panda):
        q0 = robot.home()
        target = robot.pose(q0)
        target[:3, 3] += (0.1, -0.05, 0.05)  # a target no joint limit is met on the way to
        kinematic = pinrate.servo(robot, q0, target, algorithm="exact", gain=2.0)
        on_plant = pinrate.servo(robot, q0, target, algorithm="exact", gain=2.0, plant=KinematicPlant(robot))
        # The same operations in the same order: pin.integrate of the same rates.
        assert np.array_equal(on_plant.q, kinematic.q) and on_plant.reason == kinematic.reason
        assert on_plant.plant is not None and not on_plant.plant.tracking_error.any()


def test_bad_commands_are_refused_by_name(ur5):
    plant = KinematicPlant(ur5)
    with pytest.raises(pinrate.InputError, match="joint_rates"):
        plant.advance(np.full(6, np.nan), 0.01)
    with pytest.raises(pinrate.InputError, match=r"shape \(6,\)"):
        plant.advance(np.zeros(5), 0.01)
    with pytest.raises(pinrate.InputError, match="duration"):
        plant.advance(np.zeros(6), -0.01)
