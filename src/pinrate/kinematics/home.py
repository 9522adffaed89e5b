"""A non-singular home for any URDF (contract v2, "Robot defaults for any URDF").

Pinocchio's neutral pose (all zeros) is singular for most arms: a stretched elbow, aligned
wrist axes. ``Robot.home()`` is never singular when a well-conditioned configuration exists
within the joint limits: the SRDF's group_state named ``home`` (else its first) when that is
well-conditioned, else neutral when it is *comfortable* and clear of the limits, else the
most comfortable configuration of a deterministic search at growing distance from neutral
(clear of the limits), else neutral.

Well-conditioned (the contract's floor): the smallest singular value of the partition's
Jacobian, and of each square block A and W that MCA1/2/3 invert (Shoham & Koren eq. 19,
24-25), is at least :data:`WELL_CONDITIONED` (m/rad or 1/rad, in the sensor frame's units).
A matrix that is rank-deficient everywhere (Stretch's four collinear telescoping joints; a
5-DOF arm's 6 x 5 Jacobian is not) is judged by its singular value number r, r its generic
rank (:func:`generic_ranks`): otherwise every configuration would count as singular.

Comfortable (what the search aims for, so the first motions stay clear of singularities):
well-conditioned, and every block's inverse condition number σ_min/σ_max at least
:data:`COMFORTABLE_CONDITIONING` (scale-free: a 0.3 m arm and a 3 m arm are judged alike).
The search stops at the smallest distance from neutral where a comfortable draw exists;
failing that, it takes the best-conditioned draw of all. (Whether MCA1/2/3 converge there is
the Theorem's business, one layer up: ``pinrate.convergence``.)
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .kinematic_model import KinematicModel
from .partition import Partition, split_blocks

WELL_CONDITIONED = 1e-3
"""Smallest singular value a home's partition Jacobian and square blocks must reach."""

COMFORTABLE_CONDITIONING = 0.2
"""Inverse condition number σ_min/σ_max that the blocks A and W (eq. 19) of a searched home
should reach."""

SEARCH_FRACTIONS = (0.05, 0.1, 0.2, 0.3, 0.4, 0.55, 0.7, 0.85, 1.0)
"""How far from neutral the search looks, as fractions of each joint's half range (at most
π), in order."""

LIMIT_MARGIN = 0.05
"""Searched homes keep this fraction of each joint's range away from its limits."""

SEARCH_DRAWS = 32
"""Configurations tried at each distance (seeded: the search is deterministic)."""


@dataclass(frozen=True)
class HomeQuality:
    """How good a configuration is as a home (see the module docstring).

    Attributes:
        smallest_singular_value: min over the partition's J and square A, W (m/rad, 1/rad).
        inverse_condition: min over A and W of σ_min/σ_max (dimensionless; 0 when singular).
    """

    smallest_singular_value: float
    inverse_condition: float

    @property
    def well_conditioned(self) -> bool:
        return self.smallest_singular_value >= WELL_CONDITIONED

    @property
    def comfortable(self) -> bool:
        return self.well_conditioned and self.inverse_condition >= COMFORTABLE_CONDITIONING

    def rank(self) -> tuple[bool, float]:
        """Sort key, best last: well-conditioned, then the conditioning."""
        return (self.well_conditioned, self.inverse_condition)


Ranks = tuple[int, int, int]
"""Generic ranks of the partition's (J, A, W): their largest rank over a sample of configurations."""

RANK_TOLERANCE = 1e-9
"""A singular value below this fraction of the largest does not count towards a rank."""


def generic_ranks(robot: KinematicModel, partition: Partition) -> Ranks:
    """The ranks J, A and W have almost everywhere: a robot whose joints can never span a
    direction (Stretch's four collinear telescoping joints, a 5-DOF arm's six rows) is judged
    on the directions it can span."""
    ranks = [0, 0, 0]
    for q in robot.generic_configurations(partition.joints):
        for i, values in enumerate(_singular_values(robot, partition, q)):
            if values.size:
                ranks[i] = max(ranks[i], int(np.sum(values > RANK_TOLERANCE * values.max())))
    return ranks[0], ranks[1], ranks[2]


def _singular_values(robot: KinematicModel, partition: Partition, q: np.ndarray) -> list[np.ndarray]:
    """Singular values (descending) of the partition's J, A and W at q; empty for an empty matrix."""
    index = partition.resolve(robot)
    jacobian = robot.jacobian_unchecked(q)[np.ix_(index.rows, index.columns)]
    A, _, _, W = split_blocks(jacobian, index.m, len(index.arm_columns))
    return [np.linalg.svd(M, compute_uv=False) if M.size else np.zeros(0) for M in (jacobian, A, W)]


def _home_quality(robot: KinematicModel, partition: Partition, q: np.ndarray, ranks: Ranks) -> HomeQuality:
    """:class:`HomeQuality` at q (one Jacobian, one SVD per matrix). Each matrix is judged by
    its singular value number rank (``ranks`` from :func:`generic_ranks`) rather than its
    last, so directions it can never span do not make every configuration singular."""
    values = _singular_values(robot, partition, q)
    if values[0].size == 0:
        return HomeQuality(0.0, 0.0)
    index = partition.resolve(robot)
    square = (False, index.m == index.arm_columns.size, index.k == index.wrist_columns.size)

    def judged(i: int) -> float:
        return float(values[i][ranks[i] - 1]) if 0 < ranks[i] <= values[i].size else 0.0

    smallest = [judged(0)] + [judged(i) for i in (1, 2) if square[i] and values[i].size]
    inverse_conditions = [
        judged(i) / float(values[i][0]) if values[i][0] > 0 else 0.0 for i in (1, 2) if values[i].size
    ]
    return HomeQuality(min(smallest), min(inverse_conditions, default=1.0))


def srdf_states(path: Path) -> list[str]:
    """The group_state names of an SRDF, in file order (empty when it cannot be read)."""
    try:
        root = ET.parse(path).getroot()
    except (ET.ParseError, OSError):
        return []
    return [state.get("name", "") for state in root.iter("group_state") if state.get("name")]


def find_home(
    robot: KinematicModel, partition: Partition, named: Sequence[tuple[str, np.ndarray]] = ()
) -> tuple[np.ndarray, str]:
    """(q, why), q inside every joint's position limits: the first of ``named`` (label, q)
    that is within the limits and well-conditioned, else neutral (each joint it puts outside
    its limits moved onto the nearest one) if it is comfortable and clear of the limits, else
    the most comfortable of SEARCH_DRAWS seeded draws at the smallest distance from neutral
    (SEARCH_FRACTIONS) where one is comfortable, else the best well-conditioned draw of all,
    else that neutral. Every mimic joint is at m q_leader + o, then inside its own limits
    (:meth:`~.kinematic_model.KinematicModel.follow_leaders`); a leader is drawn where its
    mimic joints stay inside theirs (:meth:`~.kinematic_model.KinematicModel.joint_range`)."""
    ranks = generic_ranks(robot, partition)
    passed_over: list[str] = []  # what a user who wrote an SRDF home needs to read when it is not taken
    for label, given in named:
        q = robot.follow_leaders(given.copy())  # its mimic joints where their leaders put them
        outside = _outside_limits(robot, q)
        quality = _home_quality(robot, partition, q, ranks)
        if not outside and quality.well_conditioned:
            return q.copy(), "; ".join([label, *passed_over])
        why = (
            f"outside the limits of {', '.join(outside)}"
            if outside
            else (f"singular: smallest singular value {quality.smallest_singular_value:.3g} < {WELL_CONDITIONED:g}")
        )
        passed_over.append(f"{label} passed over ({why})")
    home, why = _search(robot, partition, ranks)
    return home, "; ".join([why, *passed_over])


def _search(robot: KinematicModel, partition: Partition, ranks: Ranks) -> tuple[np.ndarray, str]:
    """find_home without named poses: neutral if comfortable, else the seeded search."""
    neutral = robot.follow_leaders(robot.neutral())
    moved = _outside_limits(robot, neutral, coupled=True)
    for joint in moved:  # onto its nearest limit: a home is inside every joint's limits
        low, high = robot.joint_range(joint)
        index = robot.model.joints[robot.joint_id(joint)].idx_q  # a 1-DOF joint: one coordinate
        neutral[index] = min(max(neutral[index], low), high)
    robot.follow_leaders(neutral)
    label = f"neutral, with {', '.join(moved)} moved onto the nearest limit" if moved else "neutral"
    if _home_quality(robot, partition, neutral, ranks).comfortable and not _near_a_limit(robot, partition, neutral):
        return neutral, f"{label} (well-conditioned)"
    generator = np.random.default_rng(0)
    joints = [joint for joint in partition.joints if robot.model.joints[robot.joint_id(joint)].nv == 1]
    best: tuple[HomeQuality, np.ndarray, float] | None = None
    for fraction in SEARCH_FRACTIONS:
        draws = np.tile(neutral, (SEARCH_DRAWS, 1))
        for joint in joints:
            low, high = robot.joint_range(joint)
            # A home on a limit would stop the first motion towards it: keep a margin.
            low, high = low + LIMIT_MARGIN * (high - low), high - LIMIT_MARGIN * (high - low)
            centre = 0.0 if low <= 0.0 <= high else (low + high) / 2  # neutral, or mid-range if outside
            half = min((high - low) / 2, math.pi) if math.isfinite(high - low) else math.pi
            values = np.clip(centre + fraction * half * generator.uniform(-1.0, 1.0, SEARCH_DRAWS), low, high)
            robot.set_joint_values(draws, joint, values)
        qualities = [_home_quality(robot, partition, q, ranks) for q in draws]
        comfortable = [i for i, quality in enumerate(qualities) if quality.comfortable]
        if comfortable:
            chosen = max(comfortable, key=lambda i: qualities[i].inverse_condition)
            return draws[chosen], _searched(qualities[chosen], fraction, "comfortable")
        leader = max(range(SEARCH_DRAWS), key=lambda i: qualities[i].rank())
        if best is None or qualities[leader].rank() > best[0].rank():
            best = (qualities[leader], draws[leader], fraction)
    if best is not None and best[0].well_conditioned:
        return best[1], _searched(best[0], best[2], "no comfortable one found; the best well-conditioned")
    return neutral, f"{label} (singular; no well-conditioned configuration found near it)"


def _searched(quality: HomeQuality, fraction: float, which: str) -> str:
    return (
        f"searched near neutral ({which} of {SEARCH_DRAWS} configurations within {fraction:.0%} of each "
        f"joint's half range): smallest singular value {quality.smallest_singular_value:.3g}, "
        f"inverse condition number {quality.inverse_condition:.2f}"
    )


def _outside_limits(robot: KinematicModel, q: np.ndarray, *, coupled: bool = False) -> list[str]:
    """The joints ``q`` puts outside their position limits; ``coupled``: the joints that no
    other joint moves (not mimic joints), outside their limits narrowed by their mimic joints'
    (:meth:`~.kinematic_model.KinematicModel.coupled_limits`)."""
    outside = []
    for joint in robot.joint_names:
        if coupled and joint in robot.mimics.relations:
            continue
        limits = robot.coupled_limits(joint) if coupled else robot.joint_limits(joint)
        if limits is not None and not limits[0] <= q[robot.model.joints[robot.joint_id(joint)].idx_q] <= limits[1]:
            outside.append(joint)
    return outside


def _near_a_limit(robot: KinematicModel, partition: Partition, q: np.ndarray) -> bool:
    """Whether a partition joint of q is within LIMIT_MARGIN of its range from a limit."""
    for joint in partition.joints:
        limits = robot.joint_limits(joint)
        if limits is None:
            continue
        low, high = limits
        value = q[robot.model.joints[robot.joint_id(joint)].idx_q]
        if min(value - low, high - value) < LIMIT_MARGIN * (high - low):
            return True
    return False
