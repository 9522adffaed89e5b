"""What the console shows, in words and numbers: the step's status as the operator reads it
(Barker's complaints: which way are the hand's axes, how close are the joints to their
limits, why did it slow down), each joint's value against its limits. Pure functions: the
server turns them into JSON."""

from __future__ import annotations

import math
from collections.abc import Iterable
from dataclasses import dataclass

import numpy as np

from ..control.controller import Step
from ..control.status import Status
from ..kinematics.axes import joint_value
from ..kinematics.manipulator import Robot

GREY, GREEN, BLUE, AMBER, ORANGE, PURPLE, RED, BLACK = (
    "#7f7f7f",
    "#2ca02c",
    "#1f77b4",
    "#d4a017",
    "#ff7f0e",
    "#9467bd",
    "#d62728",
    "#111111",
)

COLOURS: dict[Status, str] = {
    Status.OK: GREEN,
    Status.TWIST_SATURATED: BLUE,
    Status.RATE_LIMITED: AMBER,
    Status.UNACHIEVABLE_TWIST: ORANGE,
    Status.JOINT_LIMIT: ORANGE,
    Status.WRIST_SINGULARITY: ORANGE,
    Status.NEAR_SINGULARITY: ORANGE,
    Status.DECELERATE_FOR_SINGULARITY: ORANGE,
    Status.DECELERATE_FOR_COLLISION: ORANGE,
    Status.AUXILIARY_ELBOW: PURPLE,
    Status.FROZEN: RED,
    Status.HALT_FOR_SINGULARITY: RED,
    Status.HALT_FOR_COLLISION: RED,
}
"""Each status's colour on the console (its words are :attr:`Status.word <pinrate.Status.word>`)."""


@dataclass(frozen=True)
class Said:
    """A step's status as the console shows it; ``dead_man``: the dead man's reason when the
    words are the dead man's, else "" (a frame never says "dead man" beside "moving")."""

    word: str
    colour: str
    detail: str
    conditions: tuple[str, ...]
    dead_man: str = ""


def describe(
    step: Step | None, *, halted: bool = False, reversing: bool = False, dead_man: str = "", fault: str = ""
) -> Said:
    """The words and colour for ``step``: "idle" when nothing moved and nothing limited it,
    "halted" while the operator's halt holds (or the plant's: ``fault`` says why), "dead
    man: …" (black) when the dead man stopped the robot (``dead_man``:
    :attr:`.session.Teleop.dead_man`) and it has not moved since,
    "reversing: …" during a reversal; the detail names the joint, the block and the numbers
    (the step's own ``detail``), and the frozen joints."""
    if halted:
        why = f"{fault}: click resume" if fault else "the operator halted the robot: click resume to drive it"
        return Said("halted", RED, why, ())
    if dead_man and not reversing and (step is None or not step.joint_rates.any()):
        detail = "the robot stopped because the operator's input stopped; drive again to go on"
        return Said(f"dead man: {dead_man}", BLACK, detail, (), dead_man)
    if step is None:
        return Said("idle", GREY, "", ())
    word, colour = step.status.word, COLOURS[step.status]
    if step.status is Status.OK and not step.joint_rates.any():
        word, colour = "idle", GREY
    detail = step.detail
    if step.frozen and step.status is not Status.JOINT_LIMIT:
        detail = f"{detail}; frozen: {', '.join(step.frozen)}" if detail else f"frozen: {', '.join(step.frozen)}"
    if reversing:
        word = f"reversing: {word}"
    return Said(word, colour, detail, tuple(condition.word for condition in step.conditions))


@dataclass(frozen=True)
class JointGauge:
    """One joint on the console: its value against its limits (None: unlimited), whether the
    controller drives it (a joint of the partition's arm or wrist; the others, a gripper's
    fingers, hold still unless jogged), and its velocity limit (rad/s or m/s; None when the
    model gives none or a joint of several freedoms)."""

    name: str
    unit: str
    lower: float | None
    upper: float | None
    driven: bool = True
    velocity: float | None = None


def joint_gauges(robot: Robot, driven: Iterable[str] | None = None) -> list[JointGauge]:
    """Every moving joint, in velocity order: unit ("rad" or "m"), position limits, driven
    (its name is in ``driven``: the partition's joints; None: every joint) and velocity limit."""
    chosen = None if driven is None else set(driven)
    gauges = []
    model = robot.model
    for name in robot.joint_names:
        joint = model.joints[robot.joint_id(name)]
        kind = joint.shortname()  # JointModelPX, JointModelPrismaticUnaligned, ...
        prismatic = kind.startswith("JointModelP") and not kind.startswith("JointModelPlanar")
        limits = robot.joint_limits(name) if joint.nq == 1 else None
        lower, upper = limits if limits is not None else (None, None)
        velocity = float(model.velocityLimit[joint.idx_v]) if joint.nv == 1 else math.nan
        gauges.append(
            JointGauge(
                name,
                "m" if prismatic else "rad",
                lower,
                upper,
                chosen is None or name in chosen,
                velocity if math.isfinite(velocity) and velocity > 0 else None,
            )
        )
    return gauges


def joint_values(robot: Robot, q: np.ndarray) -> list[float | None]:
    """Each moving joint's value at q, in velocity order (:func:`~pinrate.kinematics.axes.joint_value`:
    q itself for 1-coordinate joints, the angle atan2(sin, cos) for continuous joints, None
    for joints of more freedoms)."""
    return [joint_value(robot.model, robot.joint_id(name), q) for name in robot.joint_names]


__all__ = ["COLOURS", "JointGauge", "Said", "describe", "joint_gauges", "joint_values"]
