"""Pose errors and speed saturation: what a sensor on the arm measures and commands.

Shoham & Koren §2, Fig. 3: the sensor sees the target relative to itself, so errors are
expressed in the sensor frame's axes.
"""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin


def pose_error(world_T_tip: pin.SE3, world_T_sensor: pin.SE3, target: pin.SE3) -> np.ndarray:
    """[position error; rotation error] (6,) from the tip to the target, in sensor axes (m, rad).

    With S the sensor pose: position R_s^T (p_target - p_tip) = (S^-1 T_target).p -
    (S^-1 T_tip).p and rotation R_s^T log3(R_target R_tip^T) = log3(R_a R_b^T) with
    R_a = R_s^T R_target and R_b = R_s^T R_tip (log3 commutes with conjugation).

    Exactly zero when the tip is at the target: R_tip^T R_tip is the identity only to
    rounding, and its log3 (about 1e-16 rad) would otherwise move a robot told to stay.
    """
    if np.array_equal(world_T_tip.homogeneous, target.homogeneous):
        return np.zeros(6)
    sensor_T_target = world_T_sensor.actInv(target)
    if world_T_sensor is world_T_tip:
        return np.concatenate([sensor_T_target.translation, pin.log3(sensor_T_target.rotation)])
    sensor_T_tip = world_T_sensor.actInv(world_T_tip)
    return np.concatenate(
        [
            sensor_T_target.translation - sensor_T_tip.translation,
            pin.log3(sensor_T_target.rotation @ sensor_T_tip.rotation.T),
        ]
    )


def norm(values: np.ndarray) -> float:
    """The Euclidean norm of a short vector, its squares summed left to right on Python floats
    (the compiled core sums the same way, so the two paths agree to the bit; numpy's BLAS
    may sum in another order)."""
    return _length(values.tolist())


def _length(values: list[float]) -> float:
    """:func:`norm` of a list of floats."""
    total = 0.0
    for value in values:
        total += value * value
    return math.sqrt(total)


def saturate(values: np.ndarray, limit: float) -> tuple[np.ndarray, bool]:
    """``values`` scaled down, direction kept, to Euclidean norm at most ``limit``; and
    whether it was scaled."""
    length = norm(values)
    if length > limit:
        return values * (limit / length), True
    return values, False


def saturate_twist(
    twist: np.ndarray, m: int, max_linear_speed: float, max_angular_speed: float
) -> tuple[np.ndarray, bool]:
    """The twist (linear rows ``twist[:m]`` in m/s, then angular in rad/s, any one frame's
    axes) scaled by ONE factor, the largest that meets both speed limits (contract v2.1):

        s = min(1, max_linear_speed / ‖v‖, max_angular_speed / ‖ω‖),    twist <- s twist,

    so the commanded screw keeps its direction (scaling the two parts apart would bend it);
    and whether it was scaled. The compiled core computes s with the same operations."""
    factor = 1.0
    values = twist.tolist()
    linear, angular = _length(values[:m]), _length(values[m:])
    if linear > max_linear_speed:
        factor = max_linear_speed / linear
    if angular > max_angular_speed:
        factor = min(factor, max_angular_speed / angular)
    if factor < 1.0:
        return twist * factor, True
    return twist, False
