"""Mimic joints: a URDF ``<mimic joint="leader" multiplier="m" offset="o"/>`` makes a joint
(the follower) move with its leader,

    q_follower = m q_leader + o,   so   qdot_follower = m qdot_leader

(rad or m, as the joints are; m defaults to 1, o to 0). Pinocchio 3.3 builds a follower as a
joint of its own, so pinrate keeps the relation itself:

- the tip Jacobian is folded, the chain rule of the tip pose through the relation:
  ``J[:, leader] += m J[:, follower]`` and ``J[:, follower] = 0`` (:func:`fold`), for the
  followers between the base and the tip (a closed chain's; other followers' columns are
  zero anyway);
- every step's rates drive the followers (:meth:`MimicCoupling.drive`), so q keeps the
  relation;
- the configurations pinrate makes (home, samples) put each follower on it, then inside
  its own limits (:meth:`MimicCoupling.follow`);
- a follower's position limits are limits on its leader through the relation
  (:meth:`Mimic.leader_interval`).

A chain of mimics (a follows b, b follows c) is resolved to its root leader, multipliers and
offsets composed: q_a = m_a (m_b q_c + o_b) + o_a. Only 1-DOF joints take part; a relation
that names a missing or multi-DOF joint, or closes a loop, is left out (those joints stay
independent, as Pinocchio built them).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
import pinocchio as pin


@dataclass(frozen=True)
class Mimic:
    """The relation q_follower = multiplier q_leader + offset of a mimic joint (URDF
    ``<mimic>``: multiplier dimensionless for a leader and follower of one kind, offset in the
    follower's unit, rad or m)."""

    leader: str
    multiplier: float = 1.0
    offset: float = 0.0

    def leader_interval(self, lower: float, upper: float) -> tuple[float, float] | None:
        """The leader values that keep the follower within [lower, upper]:
        [(lower - o) / m, (upper - o) / m], ends swapped for m < 0; None for m = 0 (the
        follower stands still whatever the leader does)."""
        if self.multiplier == 0.0:
            return None
        ends = sorted(((lower - self.offset) / self.multiplier, (upper - self.offset) / self.multiplier))
        return ends[0], ends[1]

    def after(self, inner: Mimic) -> Mimic:
        """This relation applied to a leader that itself follows ``inner``'s leader:
        q = m (m_i q_root + o_i) + o."""
        return Mimic(inner.leader, self.multiplier * inner.multiplier, self.multiplier * inner.offset + self.offset)


def as_mimic(relation: str | Mimic) -> Mimic:
    """A leader's name means multiplier 1 and offset 0 (what the URDF's defaults say)."""
    return relation if isinstance(relation, Mimic) else Mimic(relation)


@dataclass(frozen=True)
class Follower:
    """A mimic joint resolved to its root leader, with both joints' places in q and v (a
    continuous joint has two coordinates in q, cos and sin of its angle: ``nq`` 2)."""

    name: str
    relation: Mimic
    q_index: int
    v_index: int
    nq: int
    leader_q_index: int
    leader_v_index: int
    leader_nq: int
    lower: float  # its own position limits (rad or m; infinite for a continuous joint)
    upper: float


def _value(q: np.ndarray, index: int, nq: int) -> np.ndarray:
    """A 1-DOF joint's position (rad or m) in the rows of q (N, nq): its angle for nq = 2."""
    return q[..., index] if nq == 1 else np.arctan2(q[..., index + 1], q[..., index])


def _write(q: np.ndarray, index: int, nq: int, value: np.ndarray | float) -> None:
    if nq == 1:
        q[..., index] = value
    else:
        q[..., index], q[..., index + 1] = np.cos(value), np.sin(value)


class MimicCoupling:
    """The mimic relations of a model (see the module docstring).

    Args:
        model: the Pinocchio model.
        mimic: follower -> its leader's name, or its :class:`Mimic` relation (as the URDF
            says: direct leaders, not yet resolved).

    Attributes:
        leaders: follower -> its direct leader's name (what :mod:`.frames` groups by).
        relations: follower -> its relation to its root leader.
        followers: the resolved followers, in model order.
    """

    def __init__(self, model: pin.Model, mimic: Mapping[str, str | Mimic] | None) -> None:
        direct = {follower: as_mimic(relation) for follower, relation in (mimic or {}).items()}
        self.leaders: dict[str, str] = {follower: relation.leader for follower, relation in direct.items()}

        def one_dof(name: str) -> bool:
            return bool(model.existJointName(name)) and model.joints[model.getJointId(name)].nv == 1

        relations: dict[str, Mimic] = {}
        for follower, relation in direct.items():
            if not (one_dof(follower) and one_dof(relation.leader)):
                continue
            seen = {follower}
            while relation.leader in direct and relation.leader not in seen:  # up the chain to its root
                seen.add(relation.leader)
                relation = relation.after(direct[relation.leader])
            if relation.leader in direct or not one_dof(relation.leader):  # a loop, or a bad link in the chain
                continue
            relations[follower] = relation
        followers = []
        for name, relation in relations.items():
            joint, leader = model.joints[model.getJointId(name)], model.joints[model.getJointId(relation.leader)]
            bounds = (
                (float(model.lowerPositionLimit[joint.idx_q]), float(model.upperPositionLimit[joint.idx_q]))
                if joint.nq == 1
                else (-math.inf, math.inf)
            )
            followers.append(
                Follower(
                    name, relation, joint.idx_q, joint.idx_v, joint.nq, leader.idx_q, leader.idx_v, leader.nq, *bounds
                )
            )
        self.followers: tuple[Follower, ...] = tuple(sorted(followers, key=lambda follower: follower.v_index))
        self.relations: dict[str, Mimic] = {follower.name: follower.relation for follower in self.followers}
        self._by_leader: dict[str, tuple[Follower, ...]] = {}
        for resolved in self.followers:
            leader_name = resolved.relation.leader
            self._by_leader[leader_name] = (*self._by_leader.get(leader_name, ()), resolved)

    def __bool__(self) -> bool:
        return bool(self.followers)

    def of_leader(self, leader: str) -> tuple[Follower, ...]:
        """The followers whose root leader is ``leader``."""
        return self._by_leader.get(leader, ())

    def folded_columns(self, joints: Sequence[str]) -> tuple[tuple[int, int, float], ...]:
        """(leader column, follower column, multiplier) of the followers among ``joints``
        (the tip's chain): what :func:`fold` folds."""
        return tuple(
            (follower.leader_v_index, follower.v_index, follower.relation.multiplier)
            for follower in self.followers
            if follower.name in joints
        )

    def drive(self, rates: np.ndarray) -> np.ndarray:
        """``rates`` (nv,) with each follower's rate set to m times its leader's (rad/s or
        m/s), in place; returned."""
        for follower in self.followers:
            rates[follower.v_index] = follower.relation.multiplier * rates[follower.leader_v_index]
        return rates

    def carry(self, q: np.ndarray, next_q: np.ndarray, rates: np.ndarray, dt: float) -> None:
        """After a stage changed a leader's rate (the clamp onto a limit): each follower's rate
        driven again and its coordinates in ``next_q`` integrated from ``q`` at that rate over
        ``dt`` s, in place."""
        for follower in self.followers:
            rate = follower.relation.multiplier * rates[follower.leader_v_index]
            rates[follower.v_index] = rate
            _write(next_q, follower.q_index, follower.nq, _value(q, follower.q_index, follower.nq) + rate * dt)

    def settle(self, next_q: np.ndarray) -> None:
        """Each follower of ``next_q`` (nq,) inside its own limits, in place: its leader's
        limits keep it there (:func:`coupled_interval`) but for rounding (an ulp)."""
        for follower in self.followers:
            if follower.nq == 1:
                next_q[follower.q_index] = min(max(next_q[follower.q_index], follower.lower), follower.upper)

    def follow(
        self, configurations: np.ndarray, limits: Mapping[str, tuple[float, float] | None], leader: str | None = None
    ) -> np.ndarray:
        """Configurations (nq,) or (N, nq) with each follower (of ``leader``, or all) put on its
        relation to its leader, then inside its own ``limits`` (follower -> (lower, upper) or
        None), in place; returned."""
        for follower in self.followers if leader is None else self.of_leader(leader):
            relation = follower.relation
            value = relation.multiplier * _value(configurations, follower.leader_q_index, follower.leader_nq)
            value = value + relation.offset
            bounds = limits.get(follower.name)
            if bounds is not None:
                value = np.clip(value, *bounds)
            _write(configurations, follower.q_index, follower.nq, value)
        return configurations


def fold(jacobian: np.ndarray, columns: tuple[tuple[int, int, float], ...]) -> np.ndarray:
    """The tip Jacobian (6, nv) with each follower's column folded into its leader's, in place:
    ``J[:, leader] += m J[:, follower]``, ``J[:, follower] = 0`` (the chain rule of the tip
    pose through q_follower = m q_leader + o; ``columns`` from
    :meth:`MimicCoupling.folded_columns`); returned. Linear in J, so it holds in any frame."""
    for leader, follower, multiplier in columns:
        jacobian[:, leader] += multiplier * jacobian[:, follower]
        jacobian[:, follower] = 0.0
    return jacobian


def coupled_interval(
    own: tuple[float, float] | None, followers: Sequence[tuple[Mimic, tuple[float, float] | None]]
) -> tuple[float, float] | None:
    """A leader's position limits with its followers' limits carried onto it through their
    relations (:meth:`Mimic.leader_interval`): the intersection, or the leader's own when the
    intersection is empty (the URDF's limits contradict its relation: nothing better to keep);
    None when nothing bounds it."""
    lower, upper = own if own is not None else (-math.inf, math.inf)
    for relation, bounds in followers:
        interval = None if bounds is None else relation.leader_interval(*bounds)
        if interval is not None:
            lower, upper = max(lower, interval[0]), min(upper, interval[1])
    if lower > upper:
        return own
    return (lower, upper) if math.isfinite(lower) and math.isfinite(upper) else own


__all__ = ["Follower", "Mimic", "MimicCoupling", "as_mimic", "coupled_interval", "fold"]
