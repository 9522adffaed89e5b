"""The robot the command line names, shared by ``demo``, ``analyze`` and ``teleop``: ``ROBOT``
with ``--tip``, ``--sensor``, ``--max-joints`` and ``--xacro-arg`` loaded into a
:class:`~pinrate.Robot`, ``--q0`` checked into a start configuration, and ``--plant`` made
into a plant (the parser declares them, with nothing heavy loaded:
:func:`.parser.add_robot_arguments`).

Importing this module loads numpy and Pinocchio: the subcommands' modules import it, and
:func:`.entry.main` imports those once the arguments are parsed.
"""

from __future__ import annotations

import argparse

import numpy as np

from ..errors import InputError
from ..kinematics.manipulator import Robot
from ..plants import MujocoPlant, Plant
from ..robots import load


def load_robot(args: argparse.Namespace) -> Robot:
    """The robot of ``args.robot``, ``--tip``, ``--sensor``, ``--max-joints`` and ``--xacro-arg``;
    says which tip it chose."""
    for option, frame in (("--tip", args.tip), ("--sensor", args.sensor)):
        if frame is not None and not frame.strip():
            raise InputError(f"{option} must name a frame, got {frame!r}")
    robot = load(
        args.robot, tip=args.tip, sensor=args.sensor, max_joints=args.max_joints, xacro_args=dict(args.xacro_arg)
    )
    if robot.tip_choice != "given":
        print(f"tip        {robot.tip} ({robot.tip_choice}; --tip to choose another)")
    return robot


def start_configuration(robot: Robot, values: list[float]) -> np.ndarray:
    """--q0: one value per moving joint in ``robot.joint_names`` order (an angle for a
    continuous joint), checked like any q."""
    if len(values) != len(robot.joint_names):
        raise InputError(
            f"--q0 takes {len(robot.joint_names)} values, one per moving joint ({', '.join(robot.joint_names)}); "
            f"got {len(values)}"
        )
    q = robot.neutral()[None, :]
    for joint, value in zip(robot.joint_names, values, strict=True):
        robot.set_joint_values(q, joint, np.array([value]))
    return robot.check_q(q[0])


def make_plant(robot: Robot, args: argparse.Namespace) -> Plant | None:
    """``--plant`` and ``--actuator``: None for the kinematic robot (the loops' own
    integration), else a :class:`~pinrate.plants.MujocoPlant` of ``robot``; says which."""
    if args.plant == "kinematic":
        if args.actuator != "velocity" or args.missing_mass is not None:
            option = "--actuator" if args.actuator != "velocity" else "--missing-mass"
            raise InputError(f"{option} is an option of the MuJoCo plant: add --plant mujoco")
        return None
    plant = MujocoPlant(robot, actuator=args.actuator, missing_mass=args.missing_mass)
    print(f"plant      {plant.name}, timestep {plant.timestep * 1e3:g} ms")
    return plant
