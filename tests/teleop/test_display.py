"""What the console says for each step (pinrate.teleop.display)."""

from __future__ import annotations

import math

import numpy as np

import pinrate
from pinrate import Controller, Status
from pinrate.control.status import WORDS
from pinrate.teleop.display import COLOURS, describe, joint_gauges, joint_values


def test_every_status_has_words_and_a_colour():
    assert set(WORDS) == set(COLOURS) == set(Status)
    assert all(COLOURS[status].startswith("#") for status in Status)
    assert len(set(WORDS.values())) == len(Status) and all(WORDS.values())


def test_idle_moving_halted_and_reversing(ur5):
    controller = Controller(ur5)
    still = controller.step(ur5.home(), np.zeros(6))
    moving = controller.step(ur5.home(), np.array([0.05, 0, 0, 0, 0, 0]))
    assert describe(still).word == "idle"
    assert describe(moving).word == "moving"
    assert describe(moving, reversing=True).word == "reversing: moving"
    assert describe(moving, halted=True).word == "halted"
    assert describe(None).word == "idle"


def test_the_dead_man_is_said_only_once_the_robot_is_still(ur5):
    """The dead man stops the command at once, the robot at the next tick: a moving step
    read after the stop still says "moving", and no dead man beside it."""
    controller = Controller(ur5)
    still = controller.step(ur5.home(), np.zeros(6))
    moving = controller.step(ur5.home(), np.array([0.05, 0, 0, 0, 0, 0]))
    said = describe(moving, dead_man="no input for 0.3 s")
    assert (said.word, said.dead_man) == ("moving", "")
    said = describe(still, dead_man="no input for 0.3 s")
    assert (said.word, said.dead_man) == ("dead man: no input for 0.3 s", "no input for 0.3 s")
    assert describe(None, dead_man="gone").dead_man == "gone"
    assert describe(still, halted=True, dead_man="gone").dead_man == ""


def test_a_joint_limit_names_the_joint(ur5):
    index = ur5.model.joints[ur5.joint_id("wrist_3_joint")].idx_q
    q = ur5.home()
    q[index] = ur5.model.upperPositionLimit[index]
    step = Controller(ur5).step(q, np.array([0, 0, 0, 0, 0, 0.5]))
    said = describe(step)
    assert said.word == step.status.word == "at a joint limit"  # the one vocabulary
    assert "wrist_3_joint" in said.detail


def test_gauges_and_values_follow_the_joints():
    kinova = pinrate.load("kinova")  # continuous joints: two coordinates, one angle
    gauges = joint_gauges(kinova)
    assert [gauge.name for gauge in gauges] == list(kinova.joint_names)
    q = kinova.home()
    values = joint_values(kinova, q)
    for name, gauge, value in zip(kinova.joint_names, gauges, values, strict=True):
        joint = kinova.model.joints[kinova.joint_id(name)]
        if joint.nq == 2:
            assert gauge.lower is None
            assert value == math.atan2(q[joint.idx_q + 1], q[joint.idx_q])
        else:
            assert (gauge.lower, gauge.upper) == kinova.joint_limits(name)
            assert value == q[joint.idx_q]
    scara = pinrate.load("scara")
    units = {gauge.name: gauge.unit for gauge in joint_gauges(scara)}
    prismatic = [name for name in scara.joint_names if scara.model.joints[scara.joint_id(name)].shortname()[10] == "P"]
    assert prismatic and all(units[name] == "m" for name in prismatic)


def test_gauges_say_which_joints_the_partition_drives_and_their_velocity_limits(panda):
    partition = Controller(panda).partition
    gauges = joint_gauges(panda, (*partition.arm, *partition.wrist))
    assert [gauge.name for gauge in gauges if not gauge.driven] == ["panda_finger_joint1", "panda_finger_joint2"]
    for gauge in gauges:
        joint = panda.model.joints[panda.joint_id(gauge.name)]
        assert gauge.velocity == panda.model.velocityLimit[joint.idx_v]
    assert all(gauge.driven for gauge in joint_gauges(panda))  # no partition given: all driven
