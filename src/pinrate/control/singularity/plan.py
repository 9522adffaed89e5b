"""How a step in the singular region solves (a :class:`Plan`), the protocol every strategy
meets (:class:`Rule`), and the two operations all of them share: solving by a plan and
looking one step ahead."""

from __future__ import annotations

from typing import NamedTuple, Protocol

import numpy as np

from ...solvers.generalized import filtered_rates, generalized_inverter
from ...solvers.reference import Inverter
from ..context import StepContext
from ..observation import Observation
from ..singular_region import ColumnMap, Conditioning, block_of, c_said
from ..status import Status
from .wrist import LostRotation, lost_rotation, wrist_rule


class Plan(NamedTuple):
    """How a step in the singular region solves: the change of variables of the wrist and the
    frozen joints, the inversion used, and what to report."""

    columns: ColumnMap  # the variables the step solves for (wrist pair merged or held, frozen dropped)
    dropped: frozenset[int]  # partition positions held still by the plan (a held wrist joint, frozen joints)
    merged: tuple[int, int, float] | None  # the wrist pair moving as one (split)
    released_by: tuple[int, int] | None  # (held, last): last_then_first releases held when last is blocked
    invert: Inverter
    value: float  # c of the solved system at q
    block: str
    decelerate: bool
    statuses: tuple[Status, ...]
    details: tuple[str, ...]
    frozen: tuple[str, ...]
    lost: LostRotation | None = None  # the rotation the wrist rule leaves out, and the pair's turn that makes it


class Rule(Protocol):
    """A singularity strategy (``Controller(singularity=NAME)``): a module of
    :mod:`pinrate.control.singularity` with these two names."""

    decelerates: bool
    """Whether its steps in and near the region are judged one step ahead and scaled
    (:mod:`.decelerate`)."""

    def near(
        self, context: StepContext, observation: Observation, twist: np.ndarray, weakest: Conditioning, plan: Plan
    ) -> Plan:
        """The plan of a step whose weakest block is under ``slow_threshold`` (c =
        ``weakest.value``), from ``plan``: the wrist rule's change of variables, the
        generalized inverse, no deceleration."""
        ...


def where(weakest: Conditioning, slow_threshold: float) -> str:
    """The words every strategy's detail starts with."""
    return f"block {weakest.block} near singular ({c_said(weakest.value)} < {slow_threshold:g})"


def solve_planned(
    context: StepContext, observation: Observation, twist: np.ndarray, plan: Plan, left_out: frozenset[str]
) -> np.ndarray:
    """Rates (nv,) by the plan's change of variables and inversion, ``left_out`` joints
    (blocked at a limit) held too; with the wrist rule's lost rotation (:mod:`.wrist`), the
    pair's turn r n that makes it (unless one of its joints is held), the other joints solving
    for the rest of the twist. Finite for every J."""
    index = context.index
    dropped = plan.dropped | {context.positions[name] for name in left_out}
    if plan.released_by is not None and plan.released_by[1] in dropped:
        dropped = dropped - {plan.released_by[0]}  # last_then_first: the last is held, the first turns
    columns = (
        plan.columns
        if dropped == plan.dropped
        else ColumnMap.of(index.arm_columns.size, index.wrist_columns.size, dropped, plan.merged)
    )
    reduced = context.reduced(observation.jacobian)
    system = reduced @ columns.matrix

    def solved(command: np.ndarray) -> np.ndarray:
        partial = filtered_rates(
            system,
            index.m,
            columns.n_arm,
            command,
            context.algorithm,
            plan.invert,
            context.row_scale,
            index.position_first,
        )
        return columns.matrix @ partial

    partition_rates = solved(twist)
    lost = plan.lost
    if lost is not None and not any(lost.motion[position] for position in dropped - plan.dropped):
        turn = lost.turn(twist - reduced @ partition_rates)
        partition_rates = turn + solved(twist - reduced @ turn)
    rates = np.zeros(context.robot.nv)
    rates[index.columns] = partition_rates
    return rates


def signs(context: StepContext, reduced: np.ndarray, n_arm: int) -> tuple[float, ...]:
    """Signs of the determinants of the measured blocks that are square: a step that flips
    one has crossed a singularity, whatever c is at its two ends."""
    blocks = (block_of(name, reduced, context.index.m, n_arm, context.row_scale) for name in context.measured)
    return tuple(float(np.sign(np.linalg.det(M))) for M in blocks if M.size and M.shape[0] == M.shape[1])


def lookahead(
    context: StepContext, observation: Observation, rates: np.ndarray, columns: ColumnMap
) -> tuple[float, bool]:
    """(c, crossed): c of the system ``columns`` solves one step of ``rates`` ahead (one
    kinematics pass), and whether the step crosses a singularity of a square block."""
    robot = context.robot
    here = context.reduced(observation.jacobian) @ columns.matrix
    ahead = context.reduced(robot.kinematics(robot.integrate(observation.q, rates, context.dt))[0])
    ahead = ahead @ columns.matrix
    pairs = zip(signs(context, here, columns.n_arm), signs(context, ahead, columns.n_arm), strict=True)
    crossed = any(now * then < 0.0 for now, then in pairs)  # leaving det = 0 is no crossing
    return context.conditioning(ahead, columns.n_arm).value, crossed


def plan_step(context: StepContext, rule: Rule, wrist: str, observation: Observation, twist: np.ndarray) -> Plan | None:
    """How to solve at a q whose cheap conditioning bound fell under ``slow_threshold``: the
    wrist rule's change of variables when two wrist axes are aligned (:mod:`.wrist`), then the
    strategy's ``rule`` when the solved system is still in the region. None when the exact c
    of every measured block is above ``slow_threshold`` after all."""
    reduced = context.reduced(observation.jacobian)
    n_arm, n_wrist = context.index.arm_columns.size, context.index.wrist_columns.size
    weakest = context.conditioning(reduced, n_arm)
    if weakest.value >= context.slow_threshold:
        return None
    statuses: tuple[Status, ...] = ()
    details: tuple[str, ...] = ()
    dropped: frozenset[int] = frozenset()
    merged = released_by = None
    change = wrist_rule(wrist, context, weakest, n_arm, observation.q)
    lost = None
    if change is not None:
        # "turn" turns the pair toward the rotation it leaves out; Barker's rules do not (:mod:`.wrist`).
        lost = lost_rotation(context, reduced, weakest, n_arm) if wrist == "turn" else None
        dropped, merged, released_by = change.dropped, change.merged, change.released_by
        statuses, details = (Status.WRIST_SINGULARITY,), (change.detail,)
        columns = ColumnMap.of(n_arm, n_wrist, dropped, merged)
        weakest = context.conditioning(reduced @ columns.matrix, columns.n_arm)
    columns = ColumnMap.of(n_arm, n_wrist, dropped, merged)
    plan = Plan(
        columns,
        dropped,
        merged,
        released_by,
        generalized_inverter(context.singular_threshold),
        weakest.value,
        weakest.block,
        False,
        statuses,
        details,
        (),
        lost,
    )
    if weakest.value >= context.slow_threshold:
        return plan
    return rule.near(context, observation, twist, weakest, plan)


__all__ = ["Plan", "Rule", "lookahead", "plan_step", "signs", "solve_planned", "where"]
