"""A secondary task for redundant arms: joints toward a preferred posture and away from their
limits, in the null space of the commanded twist (Liégeois 1977).

The rates are q̇ = q̇_task + N (-k ∇H), N = I - J⁺ J the projector onto the null space of J
(the partition's rows and columns, linear rows over the characteristic length), so that
J q̇ = J q̇_task: the twist is untouched, and the secondary motion descends (under a
velocity limit, the controller shrinks N(-k ∇H) first, so the limit never slows the twist
on its account)

    H(q) = ½ Σ_i ((q_i - p_i) / r_i)²  +  ½ Σ_i (max(0, 1 - d_i / (μ r_i)) )²

over the partition's one-coordinate joints: p the preferred posture, r_i the joint's range
(2π without limits), d_i its distance to the nearer limit, μ = :data:`LIMIT_MARGIN`. The
first term pulls toward the posture, the second pushes off a limit once a joint is within
μ of its range from it. H is dimensionless; k (1/s) is the controller's ``posture_gain``.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from ..errors import InputError
from ..solvers.conditioning import truncated_pinv
from .context import StepContext
from .observation import Observation

LIMIT_MARGIN = 0.1
"""μ: the share of a joint's range near each limit where the limit term acts."""


class PostureJoints(NamedTuple):
    """The partition's one-coordinate joints that the secondary task moves.

    Attributes:
        positions: their positions in the partition (columns of the partition's J).
        q_indices: their indices in q.
        lower, upper: their limits (rad or m; ±inf for none).
        preferred: the preferred posture p (rad or m).
        ranges: r_i (rad or m): upper - lower, 2π where a limit is missing.
    """

    positions: np.ndarray
    q_indices: np.ndarray
    lower: np.ndarray
    upper: np.ndarray
    preferred: np.ndarray
    ranges: np.ndarray


def _posture_joints(
    positions: list[int], q_indices: list[int], lower: np.ndarray, upper: np.ndarray, preferred: np.ndarray
) -> PostureJoints:
    """:class:`PostureJoints` with the ranges filled in."""
    finite = np.isfinite(lower) & np.isfinite(upper)
    ranges = np.where(finite, upper - lower, 2.0 * math.pi)
    return PostureJoints(
        np.array(positions, dtype=int), np.array(q_indices, dtype=int), lower, upper, preferred, ranges
    )


def objective(joints: PostureJoints, q: np.ndarray) -> float:
    """H(q) (dimensionless), the module docstring's equation."""
    values = q[joints.q_indices]
    toward = (values - joints.preferred) / joints.ranges
    return 0.5 * float(toward @ toward) + 0.5 * float(_limit_excess(joints, values) @ _limit_excess(joints, values))


def gradient(joints: PostureJoints, q: np.ndarray) -> np.ndarray:
    """∂H/∂q_i over ``joints`` (1/rad or 1/m), in their order."""
    values = q[joints.q_indices]
    toward = (values - joints.preferred) / joints.ranges**2
    excess = _limit_excess(joints, values)
    # d/dq of ½ (1 - d/(μ r))², d = distance to the nearer limit: its sign points away from it
    near_lower = (values - joints.lower) <= (joints.upper - values)
    away = np.where(near_lower, 1.0, -1.0)
    return toward - excess * away / (LIMIT_MARGIN * joints.ranges)


def _limit_excess(joints: PostureJoints, values: np.ndarray) -> np.ndarray:
    distance = np.minimum(values - joints.lower, joints.upper - values)
    return np.maximum(0.0, 1.0 - distance / (LIMIT_MARGIN * joints.ranges))


def _null_space_motion(jacobian: np.ndarray, descent: np.ndarray, threshold: float) -> np.ndarray:
    """N @ descent, N = I - J⁺ J (J: the partition's rows, linear rows already scaled): the
    part of the joint motion ``descent`` (n,) that leaves J's twist unchanged. J⁺ is the
    Moore-Penrose inverse with singular values under ``threshold`` · σ_1 cut, so N is a
    projector for every J."""
    return descent - truncated_pinv(jacobian, threshold) @ (jacobian @ descent)


class PostureTask:
    """The secondary task of a controller (``Controller(posture=..., posture_gain=...)``).

    Args:
        context: the controller's fixed settings.
        posture: ``"home"`` or a configuration (nq,): the preferred posture p.
        gain: k (1/s).

    Raises:
        InputError: a posture that is neither.
    """

    def __init__(self, context: StepContext, posture: object, gain: float) -> None:
        robot = context.robot
        if isinstance(posture, str):
            if posture != "home":
                raise InputError(f"posture must be None, 'home' or a configuration ({robot.nq},), not {posture!r}")
            preferred = robot.home()
        else:
            preferred = robot.check_q(posture)
        model = robot.model
        positions, q_indices = [], []
        for position, name in enumerate(context.names):
            joint = model.joints[robot.joint_id(name)]
            if joint.nq == 1:
                positions.append(position)
                q_indices.append(joint.idx_q)
        lower, upper = (np.array(bounds)[q_indices] for bounds in robot.position_limits())
        self.context = context
        self.gain = gain
        self.joints = _posture_joints(positions, q_indices, lower, upper, preferred[q_indices])
        """The joints it moves, their limits and preferred values."""

    def null_motion(self, observation: Observation, left_out: frozenset[str]) -> np.ndarray:
        """Rates (nv,): -k ∇H projected onto the null space of the partition's J without the
        ``left_out`` joints (the module docstring's equation)."""
        context = self.context
        index = context.index
        descent = np.zeros(index.columns.size)
        descent[self.joints.positions] = -self.gain * gradient(self.joints, observation.q)
        kept = [position for position, name in enumerate(context.names) if name not in left_out]
        scaled = context.reduced(observation.jacobian)[:, kept] * context.row_scale_column
        rates = np.zeros(context.robot.nv)
        rates[index.columns[kept]] = _null_space_motion(scaled, descent[kept], context.singular_threshold)
        return rates


__all__ = [
    "LIMIT_MARGIN",
    "PostureJoints",
    "PostureTask",
    "gradient",
    "objective",
]
