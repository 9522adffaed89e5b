"""What the control step does near a singular block (Barker 1983, "Singularities associated
with M", "Generalized matrix inverse solution", "Variables held constant near singular
points", "Choose which angle to rotate near singularity"), generalised to any partition.

The blocks watched are the ones the algorithm inverts (:func:`measured_blocks`): J for exact
and dls, A and W for the MCAs, W and J for Schur's form. Each is measured by its inverse
condition number c = σ_r / σ_1 (:mod:`pinrate.solvers.conditioning`; J with its linear rows
divided by the robot's characteristic length). A step is *in the singular region* when the
least c is under ``slow_threshold``; there, ``singularity=`` decides:

* ``"decelerate"`` (default): the generalized inverse's rates, scaled by
  s = (c - singular_threshold) / (slow_threshold - singular_threshold) when the step would
  lower c, and 0 (a halt) when the unscaled step would carry c under ``singular_threshold``
  plus a margin of :data:`HALT_MARGIN` of the band, so that the approach halts in finitely
  many steps on every machine.
  A step that raises c is executed unscaled: the way out is always open (MoveIt Servo's
  look-ahead, on the block actually inverted);
* ``"generalized_inverse"``: Barker's M* (eq. 38, 44, 60) — each inversion by the
  Moore-Penrose inverse with singular values under ``singular_threshold`` · σ_1 cut. On
  Barker's arm this equals the 2x2 reduction (eq. 39-44) at θ3 = 0 for a command in M's
  range (M's null vector leaves θ1 alone), not for a command with an outward part, nor at
  S2 ES + F5 = 0, where the null vector moves θ1 (:mod:`pinrate.papers.barker_arm_rates`);
* ``"freeze"`` (Barker's "variables held constant"): the joints that carry the lost
  direction (those with at least :data:`FREEZE_SHARE` of the largest entry of the weakest
  block's smallest right singular vector) hold still and the others serve the command, until
  a step of all the joints would raise c;
* ``"auxiliary_elbow"`` (Barker eq. 45-46, :mod:`pinrate.control.elbow`): while the elbow
  is within ``elbow_region`` of full extension, the elbow follows the command's component
  along the upper arm (the impossible outward one ignored), the shoulder retracts the hand
  on the line to the shoulder and pitches the arm, the other joints serve the rest, where
  the generalized inverse cannot make the command (it cuts a commanded direction or turns
  the elbow toward full extension); elsewhere as ``"generalized_inverse"`` (Barker's eq. 38,
  which eq. 45-46 supplement);
* ``"adaptive_dls"``: damped least squares with the damping raised as c falls,
  λ = :data:`MAX_DAMPING` · sqrt(1 - (c / slow_threshold)²), relative to each block's σ_1
  (Nakamura & Hanafusa 1986; Chiaverini 1997): the robust baseline.

Wrist singularity (two wrist axes aligned: Barker θ5 = 0, UR5 wrist_2 = 0): W under
``slow_threshold`` with its smallest right singular vector carried by two wrist joints (at
least :data:`WRIST_PAIR_SHARE` of its square). ``wrist=`` then decides those two joints'
rates, whatever ``singularity=`` is, by a change of variables of the wrist columns:

* ``"turn"`` (default): as ``"split"``, and the pair turns against itself toward the
  rotation the aligned axes cannot make, so a servo passes the singularity (:mod:`.wrist`);
* ``"split"``: the pair moves as one joint, each at the same rate (the sign matching the
  axes' orientation): they share the rotation about the common axis equally, eq. 61 — at
  exact alignment this is the Moore-Penrose solution of eq. 60;
* ``"hold_first"``: the first joint of the pair (nearer the base) holds still and the last
  takes the whole rotation, eq. 62;
* ``"last_then_first"``: as ``hold_first`` until the last is held at a position limit, then
  the first takes the rotation, eq. 63.

The thresholds' defaults, measured on the UR5 (:data:`SLOW_THRESHOLD`): c(J) falls about as
0.13 x the elbow angle near the elbow singularity, and c(W) as 0.5 x wrist_2 near the wrist
singularity, so deceleration starts at about 0.15 rad from the elbow singularity and a step
halts at about 0.04 rad; the wrist region starts at about 0.04 rad. At the median of
uniformly drawn UR5 configurations c(J) is 0.066, c(A) 0.20 and c(W) 0.43.
"""

from __future__ import annotations

from types import ModuleType

from ..singular_region import (
    FREEZE_SHARE,
    HALT_MARGIN,
    MAX_DAMPING,
    SINGULAR_THRESHOLD,
    SLOW_THRESHOLD,
    WRIST_PAIR_SHARE,
    WRIST_STRATEGIES,
    ColumnMap,
    Conditioning,
    adaptive_damping,
    carrying_joints,
    check_strategy,
    check_thresholds,
    conditioning,
    deceleration,
    halts,
    measured_blocks,
    wrist_pair,
)
from . import adaptive_dls, auxiliary_elbow, decelerate, freeze, generalized_inverse
from .plan import Plan, Rule, plan_step

RULES: dict[str, ModuleType] = {
    "decelerate": decelerate,
    "generalized_inverse": generalized_inverse,
    "freeze": freeze,
    "auxiliary_elbow": auxiliary_elbow,
    "adaptive_dls": adaptive_dls,
}
"""Each strategy's module (a :class:`~.plan.Rule`: ``decelerates`` and ``near``), by name.
Adding a strategy is adding a module and its name here."""

STRATEGIES = tuple(RULES)
"""The values of ``Controller(singularity=...)``."""

__all__ = [
    "FREEZE_SHARE",
    "HALT_MARGIN",
    "MAX_DAMPING",
    "RULES",
    "SINGULAR_THRESHOLD",
    "SLOW_THRESHOLD",
    "STRATEGIES",
    "WRIST_PAIR_SHARE",
    "WRIST_STRATEGIES",
    "ColumnMap",
    "Conditioning",
    "Plan",
    "Rule",
    "adaptive_damping",
    "carrying_joints",
    "check_strategy",
    "check_thresholds",
    "conditioning",
    "deceleration",
    "halts",
    "measured_blocks",
    "plan_step",
    "wrist_pair",
]
