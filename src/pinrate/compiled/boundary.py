"""What crosses between pinrate and its compiled core, said once on the Python side and
compared with the core's own definitions (``core/src/boundary.hpp``) when the core loads.

Names cross, not positions: :class:`ServoSettings` fills ``pinrate_core.Settings`` field by
field, by name; the algorithm crosses as its name, the measured blocks as their letters.
The constants both sides use (the singularity rule's ratio, the Viète cut of the 3x3
eigenvalues, the input checks' physical bound and unit tolerance), the names they share
(kernels, outcomes, step flags, measured blocks, joint kinds) and the settings' field names
are checked by :func:`disagreements`; a core that differs in any is not used
(:func:`pinrate.backend` says which).
"""

from __future__ import annotations

from dataclasses import dataclass, fields
from types import ModuleType
from typing import Any

from .. import checks
from ..kinematics import kinematic_model
from ..solvers import eigen, singular
from ..solvers.singular import PINV_RCOND

KERNELS = ("exact", "schur", "mca1", "mca2", "mca3", "dls")
"""The algorithms the core implements, in its order (``pinrate_core.KERNELS``)."""

OUTCOMES = ("CONVERGED", "DIVERGING", "STALLED", "MAX_STEPS", "HANDBACK", "FULL")
"""What ends a run of the core's loop, by value (``pinrate_core.OUTCOMES``)."""

SATURATED = 1
"""Step flag: the twist was scaled down (``Status.TWIST_SATURATED``)."""

RATE_LIMITED = 2
"""Step flag: the rates were scaled to the velocity limits (``Status.RATE_LIMITED``)."""

CLAMPED = 4
"""Step flag: a joint was clamped to a position limit (``Status.JOINT_LIMIT``)."""

COLLISION_SLOWED = 8
"""Step flag: the collision monitor scaled the rates (``Status.DECELERATE_FOR_COLLISION``)."""

COLLISION_HALTED = 16
"""Step flag, alone: the collision monitor halted the step (``Status.HALT_FOR_COLLISION``)."""

STEP_FLAGS = {
    "SATURATED": SATURATED,
    "RATE_LIMITED": RATE_LIMITED,
    "CLAMPED": CLAMPED,
    "COLLISION_SLOWED": COLLISION_SLOWED,
    "COLLISION_HALTED": COLLISION_HALTED,
}
"""The flags of a step the core took (``pinrate_core.STEP_FLAGS``)."""

MEASURABLE = ("A", "W", "J")
"""The blocks the conditioning bound may measure (``pinrate_core.MEASURABLE``)."""

REBUILT_JOINTS = frozenset(
    {
        "JointModelRX",
        "JointModelRY",
        "JointModelRZ",
        "JointModelRevoluteUnaligned",
        "JointModelRUBX",
        "JointModelRUBY",
        "JointModelRUBZ",
        "JointModelRevoluteUnboundedUnaligned",
        "JointModelPX",
        "JointModelPY",
        "JointModelPZ",
        "JointModelPrismaticUnaligned",
    }
)
"""Pinocchio joint kinds the core rebuilds (``pinrate_core.JOINT_KINDS``): every kind a
URDF's revolute, continuous and prismatic joints become (a robot with any other runs on
Python)."""


@dataclass(frozen=True)
class ServoSettings:
    """What the compiled step needs of a :class:`~pinrate.control.Controller`. Each field
    sets the field of ``pinrate_core.Settings`` of the same name (the core refuses a servo
    with one unset, and pinrate a core whose fields are not these).

    Attributes:
        rows: J's rows of the twist, partition order (m linear first), indices 0-5.
        columns: velocity indices of the partition's joints, arm then wrist.
        m, n_arm: linear rows, arm joints.
        algorithm: a name of :data:`KERNELS`.
        measured: the blocks the conditioning bound measures (of :data:`MEASURABLE`).
        row_scale: 1/L on linear rows, 1 on angular (m + k,).
        slow_threshold: c under which a step is in the singular region (handed back).
        watch, watch_factor, watched_step: the decelerate rule's one-step-ahead test.
        max_linear_speed, max_angular_speed: m/s, rad/s (inf for none).
        dt: s.
        position_limits: keep q within the limits.
        limits: rows (q index, v index, lower, upper) of the position limits (rad or m).
        rate_limits: rows (v index, limit) of the velocity limits (rad/s or m/s).
        exact_rcond, dls_damping: :mod:`pinrate.solvers.reference`'s constants.
        small: A and W square of size <= 3 (the closed forms); else pseudo-inverses, which
            needs A not tall and W not wide (ρ of the pseudo-inverse G is then the error map's).
        ranks: the generic ranks of J, A and W (c is σ_rank / σ_1).
        pinv_rcond: the pseudo-inverses' relative cut-off.
    """

    rows: tuple[int, ...]
    columns: tuple[int, ...]
    m: int
    n_arm: int
    algorithm: str
    measured: tuple[str, ...]
    row_scale: tuple[float, ...]
    slow_threshold: float
    watch: bool
    watch_factor: float
    watched_step: float
    max_linear_speed: float
    max_angular_speed: float
    dt: float
    position_limits: bool
    limits: tuple[tuple[int, int, float, float], ...]
    rate_limits: tuple[tuple[int, float], ...]
    exact_rcond: float
    dls_damping: float
    small: bool = True
    ranks: tuple[int, int, int] = (6, 3, 3)
    pinv_rcond: float = PINV_RCOND


def _field_disagreements(core: ModuleType) -> list[str]:
    """Where ``pinrate_core.Settings``' fields and :class:`ServoSettings`' differ: each field
    missing on one side, named."""
    settings = getattr(core, "Settings", None)
    theirs = getattr(settings, "FIELDS", None)
    if settings is None or theirs is None:
        return ["pinrate_core has no Settings.FIELDS"]
    ours = [field.name for field in fields(ServoSettings)]
    found = [f"ServoSettings.{name} is no field of pinrate_core.Settings" for name in ours if name not in theirs]
    found += [f"pinrate_core.Settings.{name} is no field of ServoSettings" for name in theirs if name not in ours]
    found += [
        f"pinrate_core.Settings names {name} but has no such attribute"
        for name in theirs
        if name in ours and not hasattr(settings, name)
    ]
    return found


def _ours() -> dict[str, Any]:
    """This pinrate's side of each constant the core exports, read now (from the modules
    that define them)."""
    return {
        "SINGULAR_RATIO": singular.SINGULAR_RATIO,
        "FLAT": eigen.FLAT,
        "PHYSICAL_BOUND": checks.PHYSICAL_BOUND,
        "UNIT_TOLERANCE": kinematic_model.UNIT_TOLERANCE,
        "KERNELS": KERNELS,
        "OUTCOMES": OUTCOMES,
        "STEP_FLAGS": STEP_FLAGS,
        "MEASURABLE": MEASURABLE,
        "JOINT_KINDS": REBUILT_JOINTS,
    }


def _same(name: str, theirs: Any, ours: Any) -> bool:
    if name == "JOINT_KINDS":  # a set: the core's order is its own
        return isinstance(theirs, tuple) and frozenset(theirs) == ours
    if isinstance(ours, dict):
        return isinstance(theirs, dict) and theirs == ours
    return type(theirs) is type(ours) and theirs == ours


def disagreements(core: ModuleType) -> list[str]:
    """Where ``core`` (``pinrate_core``) and this pinrate disagree: each constant that differs
    (named, with both values) and each settings field missing on one side. Empty where they
    agree."""
    found = []
    for name, ours in _ours().items():
        theirs = getattr(core, name, None)
        if not _same(name, theirs, ours):
            shown = sorted(ours) if isinstance(ours, frozenset) else ours
            found.append(f"{name} is {theirs!r} in pinrate_core but {shown!r} in pinrate")
    return found + _field_disagreements(core)
