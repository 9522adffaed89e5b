"""Barker's auxiliary elbow control near full extension of the arm (Barker 1983, "Auxiliary
hand control", eq. 45-46, B27-B29), generalised to any arm with an elbow.

At full extension (Barker θ3 = 0, the UR5's elbow = 0) the wrist centre cannot move outward,
along the upper arm: that row of the arm block is lost. Barker replaces it by a rule for the
elbow, and one for the shoulder (vectors in the world, i.e. base, axes; m/s, rad/s, m):

* eq. 45: the elbow follows the command's component along the upper arm,
  θ̇_e = K3 (TVEL · u), except at full extension with an outward command (TVEL · u > 0),
  where it holds: the impossible outward motion is ignored. pinrate orients K3 so that a
  command toward the shoulder bends the elbow further the way it is bent, and at full
  extension the other way from the last bend (Barker: "change the sign on K3 each time");
  an outward command straightens the elbow, and the step stops exactly at full extension;
* eq. 46: the shoulder cancels the elbow's motion of the wrist centre across the line to
  the shoulder, so the hand retracts on that line, and pitches the extended arm with the
  command's pitch component: θ̇_s = -d_e/d_s θ̇_e + K2 (TVEL · p) / d_s, K2 = 1; on Barker's
  arm (A3 = 0, α3 = 90°) d_e = WE and d_s = WE + ES at full extension;
* the other joints serve the rest of the command: the component normal to the arm's plane
  (on Barker's arm the first joint alone moves the wrist centre out of that plane) and the
  angular velocity, less what elbow and shoulder produce there.

pinrate solves the shoulder and the other joints together, from the pitch row (the tip's
velocity along p, which eq. 46 sets), the normal row and the angular rows, by the generalized
inverse. At full extension the pitch row's shoulder and elbow coefficients are d_s and d_e,
so where the other joints do not move the tip along p (on Barker's arm: a command with no
normal component) this is eq. 46 exactly; otherwise the shoulder also cancels their pitch
motion (through the shoulder offset SN, θ1 moves the wrist centre in the arm's plane), which
eq. 46 leaves as an error. Off full extension the coefficients are the exact ones, where
Barker keeps their values at extension: the hand then stays on the line to the shoulder to
first order, not "nearly".

u is the direction from the shoulder axis to the wrist centre (at full extension the upper
arm's, Barker's X2, eq. B28), p = z_s × u the pitch direction in the arm's plane (Y2, eq.
B29), z_s the shoulder axis (the plane's normal), d_e and d_s the distances of the wrist
centre from the elbow and shoulder axes at full extension. K3 (rad per m, :meth:`Elbow.gain`) makes the elbow control
meet the resolved rate at the region's edge β_r: there the elbow rate that retracts the wrist
centre at the commanded speed is d_s / (ES d_e sin β_r), ES = d_s - d_e.

Eq. 39 (Barker's azimuth equation) would give the first joint the in-plane horizontal row
instead; for a radial command, which the arm cannot execute, it would turn the first joint by
TVEL_t / SN and swing the hand sideways: pinrate keeps the normal row.

The elbow is found once per controller (:func:`find_elbow`): an arm joint whose axis is
parallel to an earlier arm joint's (the shoulder), at whose *straight* value (the value that
puts the wrist centre farthest from the shoulder axis) the measured block is singular.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
import pinocchio as pin

from ..kinematics.axes import PARALLEL, Axis, distance_to_axis, local_axis, world_axis, wrist_axes, wrist_centre
from ..kinematics.manipulator import Robot
from ..kinematics.partition import Partition
from ..solvers.conditioning import truncated_pinv

ELBOW_REGION = 0.5
"""rad: the largest default region of the auxiliary elbow control. The default is the bend at
which the measured block's c reaches the slow threshold (the elbow's whole singular region:
decelerate never acts on the elbow's singularity), capped here."""

EXTENDED = 1e-12
"""rad: an elbow this close to its straight value is at full extension."""


@dataclass(frozen=True)
class Elbow:
    """An arm's elbow and shoulder, found at construction (see :func:`find_elbow`).

    Attributes:
        joint, shoulder: joint names.
        position: the elbow's partition position.
        elbow_axis, shoulder_axis: the two joints' ids and local axes.
        wrist: the first two revolute wrist joints, which locate the wrist centre.
        q_index: the elbow's index in q.
        straight: the elbow's value at full extension (rad).
        forearm: d_e, the wrist centre's distance from the elbow axis at full extension (m).
        reach: d_s, its distance from the shoulder axis at full extension (m).
    """

    joint: str
    shoulder: str
    position: int
    elbow_axis: Axis
    shoulder_axis: Axis
    wrist: tuple[Axis, ...]
    q_index: int
    straight: float
    forearm: float
    reach: float

    def gain(self, region: float) -> float:
        """``|K3|`` of eq. 45 (rad per m) for a region of ``region`` rad: d_s / (ES d_e sin β_r),
        the elbow rate per m/s that retracts the wrist centre at the commanded speed at the
        region's edge (the wrist centre's distance from the shoulder axis is
        r(β)² = ES² + d_e² + 2 ES d_e cos β, so dr/dβ = -ES d_e sin β / r)."""
        upper_arm = self.reach - self.forearm
        return self.reach / (upper_arm * self.forearm * math.sin(min(region, math.pi / 2)))


def _upper_arm_frame(
    shoulder_origin: np.ndarray, shoulder_axis: np.ndarray, point: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
    """(u, p, n) in the world: u the unit direction from the shoulder axis toward ``point``
    across the axis, n = the shoulder axis (the arm plane's normal), p = n × u. None when the
    point lies on the shoulder axis."""
    offset = point - shoulder_origin
    radial = offset - (offset @ shoulder_axis) * shoulder_axis
    length = float(np.linalg.norm(radial))
    if length < 1e-9:
        return None
    u = radial / length
    return u, np.cross(shoulder_axis, u), shoulder_axis


def elbow_rate(elbow: Elbow, bend: float, bend_sign: float, outward: float, region: float, dt: float) -> float:
    """θ̇_e (rad/s), eq. 45, from the command's component along the upper arm (m/s).

    ``bend`` = elbow - straight (rad); ``bend_sign`` the way a bend from full extension goes.
    A command toward the shoulder (``outward`` < 0) bends the elbow further the way it is bent;
    an outward one straightens it, and the step ends at full extension, not past it."""
    extended = abs(bend) <= EXTENDED
    if extended and outward > 0.0:
        return 0.0  # eq. 45, first case: the impossible outward motion
    sense = bend_sign if extended else math.copysign(1.0, bend)
    rate = -sense * elbow.gain(region) * outward
    if not extended and (bend + rate * dt) * bend < 0.0:
        return -bend / dt  # ends the step at full extension
    return rate


class ArmFrame(NamedTuple):
    """The arm's directions at q, in the world: ``outward`` u from the shoulder axis to the
    wrist centre (Barker's X2 at full extension), ``pitch`` p = z_s × u (Y2 there), ``normal``
    n = z_s, the shoulder axis."""

    outward: np.ndarray
    pitch: np.ndarray
    normal: np.ndarray


def arm_frame(elbow: Elbow, data: pin.Data, tip: np.ndarray) -> ArmFrame | None:
    """The :class:`ArmFrame` after ``forwardKinematics`` at q (``tip``: the tip's origin in the
    world, m); None with the wrist centre on the shoulder axis."""
    z_s = world_axis(data, elbow.shoulder_axis)
    centre = wrist_centre(data, elbow.wrist, tip)
    directions = _upper_arm_frame(np.array(data.oMi[elbow.shoulder_axis[0]].translation), z_s, centre)
    return None if directions is None else ArmFrame(*directions)


def remaining_rates(rows: np.ndarray, targets: np.ndarray, variables: np.ndarray, threshold: float) -> np.ndarray:
    """Rates (n,) = ``variables`` (n, r) @ y, y the generalized inverse's solution of
    (rows @ variables) y = targets, singular values under ``threshold`` · σ_1 cut (finite for
    every finite input)."""
    if variables.shape[1] == 0 or rows.shape[0] == 0:
        return np.zeros(variables.shape[0])
    return variables @ (truncated_pinv(rows @ variables, threshold) @ targets)


def find_elbow(robot: Robot, partition: Partition, singular_at: Callable[[np.ndarray, int], bool]) -> Elbow | None:
    """The arm's elbow, or None: the first revolute arm joint with an earlier arm joint on
    its chain whose axis is parallel at home (the shoulder), whose straight value (the one
    putting the wrist centre farthest from the shoulder axis, others at home) makes
    ``singular_at(q, elbow's partition position)`` true: the caller's test that the measured
    block is singular there, with the elbow carrying the lost motion."""
    model = robot.model
    data = model.createData()
    home = robot.home()
    arm = list(partition.arm)
    positions = {name: position for position, name in enumerate(partition.arm + partition.wrist)}
    wrist = wrist_axes(model, [robot.joint_id(name) for name in partition.wrist])
    pin.forwardKinematics(model, data, home)
    for name in sorted(arm, key=robot.joint_id):
        joint_id = robot.joint_id(name)
        elbow_axis = _revolute_axis(model, joint_id)
        if elbow_axis is None:
            continue
        shoulder_axis = _shoulder_of(model, data, robot, arm, elbow_axis)
        if shoulder_axis is None:
            continue
        q_index = model.joints[joint_id].idx_q
        straight = _straight_value(robot, data, home, elbow_axis, shoulder_axis, wrist)
        if straight is None:
            pin.forwardKinematics(model, data, home)
            continue
        q = home.copy()
        q[q_index] = straight
        if not singular_at(q, positions[name]):
            pin.forwardKinematics(model, data, home)
            continue
        pin.forwardKinematics(model, data, q)
        centre = wrist_centre(data, wrist, robot.frame_pose(q, robot.tip)[:3, 3])
        z_e, z_s = world_axis(data, elbow_axis), world_axis(data, shoulder_axis)
        shoulder = model.names[shoulder_axis[0]]
        return Elbow(
            joint=name,
            shoulder=shoulder,
            position=positions[name],
            elbow_axis=elbow_axis,
            shoulder_axis=shoulder_axis,
            wrist=wrist,
            q_index=q_index,
            straight=straight,
            forearm=distance_to_axis(centre, np.array(data.oMi[joint_id].translation), z_e),
            reach=distance_to_axis(centre, np.array(data.oMi[shoulder_axis[0]].translation), z_s),
        )
    return None


def _revolute_axis(model: pin.Model, joint_id: int) -> Axis | None:
    """The joint and its axis when it turns with one q (its bend is q - straight), else None."""
    joint = model.joints[joint_id]
    axis = local_axis(model, joint_id) if joint.nq == 1 and joint.nv == 1 else None
    return None if axis is None else (joint_id, axis)


def _shoulder_of(model: pin.Model, data: pin.Data, robot: Robot, arm: list[str], elbow_axis: Axis) -> Axis | None:
    """The nearest ancestor of the elbow among the revolute arm joints whose axis is parallel to
    the elbow's at the current ``data``, with the elbow off its axis."""
    arm_ids = {robot.joint_id(name) for name in arm}
    z_e = world_axis(data, elbow_axis)
    ancestor = model.parents[elbow_axis[0]]
    while ancestor > 0:
        candidate = _revolute_axis(model, ancestor) if ancestor in arm_ids else None
        if candidate is not None:
            z_s = world_axis(data, candidate)
            if np.linalg.norm(np.cross(z_s, z_e)) < PARALLEL and _upper_arm_frame(
                np.array(data.oMi[ancestor].translation), z_s, np.array(data.oMi[elbow_axis[0]].translation)
            ):
                return candidate
        ancestor = model.parents[ancestor]
    return None


def _straight_value(
    robot: Robot, data: pin.Data, home: np.ndarray, elbow_axis: Axis, shoulder_axis: Axis, wrist: tuple[Axis, ...]
) -> float | None:
    """The elbow value (rad) that puts the wrist centre farthest from the shoulder axis, the
    others at home; None when it lies outside the elbow's limits.

    Turning the elbow by δ turns the forearm's vector w (elbow axis to wrist centre, across the
    axis) by δ about the elbow axis z_e, and the reach |ES u + w| is largest when w points
    along u: straight = elbow - φ, φ = atan2(z_e · (u × w), u · w) at home, exact in one
    kinematics pass (a scan would find the flat maximum only to about 1e-8 rad)."""
    model = robot.model
    joint_id, _ = elbow_axis
    q_index = model.joints[joint_id].idx_q
    pin.forwardKinematics(model, data, home)
    z_e, z_s = world_axis(data, elbow_axis), world_axis(data, shoulder_axis)
    elbow_origin = np.array(data.oMi[joint_id].translation)
    frame = _upper_arm_frame(np.array(data.oMi[shoulder_axis[0]].translation), z_s, elbow_origin)
    assert frame is not None  # the shoulder was chosen with the elbow off its axis
    u = frame[0]
    forearm = wrist_centre(data, wrist, robot.frame_pose(home, robot.tip)[:3, 3]) - elbow_origin
    forearm = forearm - (forearm @ z_e) * z_e
    angle = math.atan2(float(z_e @ np.cross(u, forearm)), float(u @ forearm))
    straight = float(home[q_index]) - angle
    bounds = robot.joint_limits(model.names[joint_id])
    if bounds is None:
        return math.remainder(straight, math.tau)
    low, high = bounds
    for candidate in (straight, straight - math.tau, straight + math.tau):
        if low <= candidate <= high:
            return candidate
    return None


__all__ = [
    "ELBOW_REGION",
    "ArmFrame",
    "Elbow",
    "arm_frame",
    "elbow_rate",
    "find_elbow",
    "remaining_rates",
]
