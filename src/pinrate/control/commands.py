"""What an operator or a program can command in one control step, besides a twist.

* a twist: the controlled components (m + k,) in partition order, in the sensor frame's axes
  (m/s, rad/s) — a plain array;
* :class:`PoseGoal`: move the tip to a pose (the servo);
* :class:`JointJog`: any subset of the robot's joints at given rates, the others still
  (Barker's individual joint control);
* :class:`Uncoupled`: Barker's uncoupled mode — the arm joints move the wrist centre with the
  linear command, the wrist joints are jogged one by one.

Commands are checked against a robot when they are stepped (a name that is not one of its
joints is an InputError listing them).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np
import pinocchio as pin

from ..checks import PHYSICAL_BOUND, as_pose, check_positive, check_vector
from ..errors import InputError, choices_hint


@dataclass(frozen=True)
class PoseGoal:
    """A command to move the tip to ``target`` (a pose in the world): twist = gain x pose error.

    ``gain`` is in 1/s: the twist commanded per metre and per radian of error.
    """

    target: pin.SE3
    gain: float = 1.0

    @classmethod
    def of(cls, target: object, gain: float = 1.0) -> PoseGoal:
        """A checked goal from a 4x4 homogeneous matrix or a pinocchio.SE3, and a gain > 0."""
        return cls(as_pose(target), check_positive(gain, "gain"))


def _checked_rates(rates: object, what: str) -> dict[str, float]:
    """{joint name: rate}, every rate a finite number within the physical bound."""
    if not isinstance(rates, Mapping):
        raise InputError(
            f"{what} must map joint names to rates, e.g. {{'elbow_joint': 0.2}}, not {type(rates).__name__}"
        )
    checked = {}
    for name, rate in rates.items():
        if not isinstance(name, str):
            raise InputError(f"{what}: joint names must be strings, got {name!r}")
        try:
            value = float(rate)
        except (TypeError, ValueError):
            raise InputError(f"{what}: the rate of {name!r} must be a number, got {rate!r}") from None
        if not math.isfinite(value) or abs(value) > PHYSICAL_BOUND:
            raise InputError(f"{what}: the rate of {name!r} must be finite and within ±{PHYSICAL_BOUND:g}, got {value}")
        checked[name] = value
    return checked


def joint_rate_vector(
    rates: Mapping[str, float], joints: tuple[str, ...], velocity_of: Mapping[str, int], nv: int, what: str
) -> np.ndarray:
    """Rates (nv,) from {joint name: rate} (rad/s or m/s), 0 for joints not named; an
    InputError names a joint not in ``joints`` (the 1-DOF joints that may be jogged)."""
    vector = np.zeros(nv)
    for name, rate in rates.items():
        if name not in velocity_of or name not in joints:
            raise InputError(f"{what}: {name!r} is not a joint that can be jogged." + choices_hint(name, joints))
        vector[velocity_of[name]] = rate
    return vector


@dataclass(frozen=True)
class JointJog:
    """Joints moved at given rates, the others held still: ``rates`` maps joint names to rad/s
    (revolute) or m/s (prismatic). Any 1-DOF joint of the robot may be jogged, in or out of
    the partition, but a mimic joint (its leader moves it; jog the leader). Limits apply as to
    every step (position limits hold a joint at its limit, a velocity limit scales all rates
    alike)."""

    rates: Mapping[str, float] = field(default_factory=dict)

    def __post_init__(self) -> None:
        object.__setattr__(self, "rates", _checked_rates(self.rates, "JointJog"))


@dataclass(frozen=True)
class Uncoupled:
    """Barker's uncoupled mode: ``linear`` (m,) moves the wrist centre — the controlled linear
    components, in the sensor frame's axes, m/s — by the arm joints alone; ``wrist`` maps
    wrist joint names to rates (rad/s), jogged one by one (the wrist joints not named hold).

    The wrist centre is where the first two wrist axes meet (the middle of their common
    perpendicular when they do not; :func:`pinrate.kinematics.axes.wrist_centre`), a point
    of the arm's last body: the wrist joints do not move it, so arm and wrist are uncoupled
    (Barker, "Wrist-centre decoupling"). The arm's wrist-centre block is inverted by the
    generalized inverse whatever ``singularity=`` is (``Status.NEAR_SINGULARITY`` under the
    slow threshold, no deceleration); the velocity limits bound the rates."""

    linear: np.ndarray
    wrist: Mapping[str, float] = field(default_factory=dict)

    def __post_init__(self) -> None:
        try:
            linear = np.asarray(self.linear, dtype=float)
        except (TypeError, ValueError):
            raise InputError(f"Uncoupled.linear must be numbers (m/s), got {self.linear!r}") from None
        if linear.ndim != 1 or not 1 <= linear.size <= 3:
            raise InputError(f"Uncoupled.linear must be a vector of 1 to 3 numbers (m/s), got shape {linear.shape}")
        object.__setattr__(self, "linear", check_vector(linear, linear.size, "Uncoupled.linear (m/s)"))
        object.__setattr__(self, "wrist", _checked_rates(self.wrist, "Uncoupled.wrist"))


__all__ = ["JointJog", "PoseGoal", "Uncoupled", "joint_rate_vector"]
