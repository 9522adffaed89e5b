"""The compiled core's view of a controller: whether it covers the controller's options
(an allow-list that fails closed), the settings it runs with, and the controller's twin
(:class:`~pinrate.compiled.CoreServo`). ``controller`` is a
:class:`~pinrate.control.controller.Controller` (this module sits below it)."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from ..compiled import CoreServo, ServoSettings, backend, core_kinematics, core_servo
from ..errors import UnsupportedByCoreError
from ..solvers.reference import DLS_DAMPING, EXACT_RCOND
from .core_collision import python_reason
from .singularity.decelerate import WATCH_FACTOR, WATCHED_STEP

Coverage = tuple[Callable[[Any], bool] | None, str | Callable[[Any], str]]

COMPILED_COVERAGE: dict[str, Coverage] = {
    # (covered at this controller's value, or None: at every value; why not), first reason first
    "singularity": (lambda c: c.auxiliary is None, "auxiliary elbow control runs on the Python path"),
    "posture": (lambda c: c.posture is None, "a posture task runs on the Python path"),
    "acceleration_limits": (lambda c: c.acceleration_limits is None, "acceleration limits run on the Python path"),
    "collision": (lambda c: python_reason(c.collision) is None, lambda c: str(python_reason(c.collision))),
    "partition": (
        lambda c: c.index.small or c.index.pseudo_g,
        "a tall A or a wide W (rho is then the error map's) runs on the Python path",
    ),
    # Read by the core (ServoSettings), or acting only in steps it hands back to Python (the
    # singular region, a joint passing a limit) or through an option above.
    "robot": (None, ""),
    "algorithm": (None, ""),
    "dt": (None, ""),
    "wrist": (None, ""),
    "velocity_limits": (None, ""),
    "position_limits": (None, ""),
    "singular_threshold": (None, ""),
    "slow_threshold": (None, ""),
    "max_linear_speed": (None, ""),
    "max_angular_speed": (None, ""),
    "elbow_region": (None, ""),
    "posture_gain": (None, ""),
}
"""The compiled core's allow-list: every ``Controller`` option with whether the core covers it
at a controller's value and why not (in words, or a function of the controller giving them:
the collision monitor's reason is its own). A test keeps its keys equal to ``Controller``'s
parameters; an option added without an entry keeps its controllers on Python
(:meth:`.Controller.compiled_reason`)."""


def twin(controller: Any) -> CoreServo | None:
    """``controller``'s compiled twin with its settings as they are now (cached per robot and
    settings); None where the core refuses the robot. The caller has checked :func:`reason`."""
    # Everything settings() reads: a servo call builds a controller afresh, and the
    # same settings come back.
    key = (
        controller.partition,
        controller.algorithm,
        controller.dt,
        controller.max_linear_speed,
        controller.max_angular_speed,
        controller.slow_threshold,
        controller.singularity,
        controller.position_limits,
        controller.velocity_limits.tobytes(),
        controller.joint_limits,
        controller.characteristic_length,
        controller.context.square_j,
        tuple(controller.context.ranks.values()),
    )
    try:
        return core_servo(controller.robot, key, lambda: settings(controller))
    except UnsupportedByCoreError:
        return None


def reason(controller: Any, options: tuple[str, ...]) -> str | None:
    """Why this controller's loops run on Python though the core may be there (None when
    nothing in the configuration stops the core): an option missing from
    :data:`COMPILED_COVERAGE` (not covered: it fails closed, whatever the backend), the
    core's reason (a mimic joint between the base and the tip among them), the first option
    the table does not cover at its value, a mimic joint whose leader the partition moves
    (the core integrates q without driving it), or a partition that cannot make every twist."""
    for option in options:
        if option not in COMPILED_COVERAGE:
            return f"the option {option!r} is not known to the compiled core: the Python path runs"
    try:
        if core_kinematics(controller.robot) is None:
            return backend().reason
    except UnsupportedByCoreError as unsupported:
        return str(unsupported)
    for covered, why in COMPILED_COVERAGE.values():
        if covered is not None and not covered(controller):
            return why if isinstance(why, str) else why(controller)
    driven = [
        follower.name
        for follower in controller.robot.mimics.followers
        if follower.relation.leader in controller.partition.joints
    ]
    if driven:
        return (
            f"mimic joint {', '.join(map(repr, driven))} follows a joint of the partition, and the compiled core "
            "does not drive mimic joints when it integrates q: the Python path runs"
        )
    if controller.context.ranks["J"] < controller.index.rows.size:
        return (
            "the partition's joints cannot make every twist (generic rank "
            f"{controller.context.ranks['J']} for {controller.index.rows.size} components): each step's "
            "residual is judged, and a tall W's position first solved, on the Python path "
            "(Status.UNACHIEVABLE_TWIST)"
        )
    return None


def settings(controller: Any) -> ServoSettings:
    """What the compiled step needs of ``controller``, field by field."""
    index = controller.index
    return ServoSettings(
        rows=tuple(index.rows.tolist()),
        columns=tuple(index.columns.tolist()),
        m=index.m,
        n_arm=int(index.arm_columns.size),
        algorithm=controller.algorithm,
        measured=controller.context.measured,
        row_scale=tuple(controller.context.row_scale.tolist()),
        slow_threshold=controller.slow_threshold,
        watch=controller.rule.decelerates,
        watch_factor=WATCH_FACTOR,
        watched_step=WATCHED_STEP,
        max_linear_speed=controller.max_linear_speed,
        max_angular_speed=controller.max_angular_speed,
        dt=controller.dt,
        position_limits=controller.position_limits,
        limits=tuple((limit.q_index, limit.velocity, limit.lower, limit.upper) for limit in controller.joint_limits),
        rate_limits=tuple(controller.rate_limits.rows),
        exact_rcond=EXACT_RCOND,
        dls_damping=DLS_DAMPING,
        small=index.small,
        ranks=(controller.context.ranks["J"], controller.context.ranks["A"], controller.context.ranks["W"]),
    )


__all__ = ["COMPILED_COVERAGE", "reason", "settings", "twin"]
