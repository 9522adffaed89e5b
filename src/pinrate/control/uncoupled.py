"""Barker's uncoupled arm/wrist mode (:class:`~pinrate.control.commands.Uncoupled`): the wrist
joints at the rates named, the arm joints moving the wrist centre (a point of the arm's last
body, which the wrist joints do not move) with the linear command, by the generalized
inverse of its arm Jacobian."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import pinocchio as pin

from ..errors import InputError
from ..kinematics.axes import Axis, wrist_centre
from ..solvers.conditioning import inverse_condition, truncated_pinv
from .commands import Uncoupled, joint_rate_vector
from .context import StepContext
from .observation import Observation
from .singular_region import c_said
from .status import Status


class WristCentre:
    """The wrist centre's Jacobian of a controller's arm, on a Pinocchio data of its own.

    Args:
        context: the controller's fixed settings.
        axes: the wrist's first two rotating joints' axes (the centre is where they meet).
        body: the joint whose body carries the first wrist joint (or the tip's, without a wrist).
    """

    def __init__(self, context: StepContext, axes: tuple[Axis, ...], body: int) -> None:
        self.context = context
        self.axes = axes
        self.body = body
        self.data = context.robot.model.createData()

    def jacobian(self, observation: Observation) -> np.ndarray:
        """(m, n_arm): the wrist centre's velocity per arm joint rate, in the sensor frame's
        controlled linear axes (m/s per rad/s)."""
        robot = self.context.robot
        model, data = robot.model, self.data
        index = self.context.index
        pin.computeJointJacobians(model, data, observation.q)
        pin.updateFramePlacements(model, data)
        centre = wrist_centre(data, self.axes, np.array(data.oMf[robot.tip_id].translation))
        jacobian = pin.getJointJacobian(model, data, self.body, pin.ReferenceFrame.LOCAL_WORLD_ALIGNED)
        jacobian = jacobian.reshape(6, model.nv)  # one joint: eigenpy hands back a vector
        lever = centre - np.array(data.oMi[self.body].translation)
        linear = jacobian[:3] - np.cross(lever, jacobian[3:].T).T  # v_p = v_i + ω_i x (p - o_i)
        sensor = observation.world_T_sensor.rotation
        return (sensor.T @ linear)[index.rows[:m]][:, index.arm_columns] if (m := index.m) else np.zeros((0, 0))

    def solver(
        self, observation: Observation, command: Uncoupled, statuses: list[Status], details: list[str]
    ) -> Callable[[frozenset[str]], np.ndarray]:
        """The step's solve (rates (nv,) without the ``left_out`` joints) for ``command``; a
        near-singular arm block is said in ``statuses`` and ``details``. InputError for a
        command of the wrong size."""
        context = self.context
        index, partition = context.index, context.partition
        m = index.m
        if command.linear.size != m:
            raise InputError(
                f"Uncoupled.linear must have the partition's {m} linear components ({partition.linear}), "
                f"got {command.linear.size}"
            )
        wrist = joint_rate_vector(
            command.wrist, partition.wrist, context.velocity_of, context.robot.nv, "Uncoupled.wrist"
        )
        centre_jacobian = self.jacobian(observation)  # (m, n_arm): sensor axes
        if centre_jacobian.size:
            value, _ = inverse_condition(centre_jacobian, min(centre_jacobian.shape))
            if value < context.slow_threshold:
                statuses.append(Status.NEAR_SINGULARITY)
                details.append(f"the arm's wrist-centre block is near singular ({c_said(value)}): generalized inverse")

        def solve(left_out: frozenset[str]) -> np.ndarray:
            rates = wrist.copy()
            for name in left_out:
                rates[context.velocity_of[name]] = 0.0
            kept = [position for position, name in enumerate(partition.arm) if name not in left_out]
            if kept:
                arm = truncated_pinv(centre_jacobian[:, kept], context.singular_threshold) @ command.linear
                rates[index.arm_columns[kept]] = arm
            return rates

        return solve


__all__ = ["WristCentre"]
