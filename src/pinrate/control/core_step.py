"""The control step in the compiled core, per call, and the words of a step the core took.

:meth:`Controller.step <pinrate.control.controller.Controller.step>` hands a twist or pose
step to :class:`CoreStep` where the core covers the controller (:mod:`.compiled_twin`'s
allow-list): in one call the core checks q and the twist as Python would, makes the
kinematics pass (or takes the caller's observation), and runs the step's common path
(saturation, the conditioning bound, the algorithm, the position-limit test, the decelerate
look-ahead, the velocity scale, the self-collision monitor (:mod:`.core_collision`),
integration over dt, the clamp; ``core/src/servo.hpp``'s
``Servo::advance``, the servo loop's own). It hands back, to Python, any input its checks
refuse (Python's checks then raise their own words) and any step that needs more (the
singular region, a joint passing a limit, a singular block, a big step near the region).
The step's :class:`CoreObservation` is made from the pass when it is first read.

A step the core took is said by its flags (SATURATED, RATE_LIMITED, COLLISION_SLOWED,
COLLISION_HALTED, CLAMPED), its velocity scale, the collision monitor's last verdict and the
first limit it clamped: :data:`CONDITIONS` and :func:`core_detail` turn them
into the statuses and the detail :class:`~.finish.Finish` gives the same step, for this
per-call step and the servo loop's log alike (the one mapping).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import MISSING, dataclass, fields
from typing import TYPE_CHECKING, Any, Literal

import numpy as np
import pinocchio as pin

from ..compiled import CoreServo, chosen, core_module
from ..compiled.boundary import CLAMPED, COLLISION_HALTED, COLLISION_SLOWED, RATE_LIMITED, SATURATED, STEP_FLAGS
from ..kinematics.partition import PartitionIndex
from .collision import CollisionMonitor
from .commands import PoseGoal
from .core_collision import core_monitor, core_verdict_detail
from .limits.position import reached_detail
from .limits.velocity import scaled_detail
from .observation import Observation, Step
from .robot_facts import Limit
from .status import Status, ranked


def _conditions(flags: int) -> tuple[Status, ...]:
    """The conditions :class:`~.finish.Finish` ranks for a step with these core flags."""
    if flags & COLLISION_HALTED:  # Finish.halt: the halt alone
        return (Status.HALT_FOR_COLLISION,)
    statuses = [Status.TWIST_SATURATED] if flags & SATURATED else []
    if flags & RATE_LIMITED:
        statuses.append(Status.RATE_LIMITED)
    if flags & COLLISION_SLOWED:
        statuses.append(Status.DECELERATE_FOR_COLLISION)
    if flags & CLAMPED:
        statuses.append(Status.JOINT_LIMIT)
    return ranked(statuses)


CONDITIONS: tuple[tuple[Status, ...], ...] = tuple(_conditions(flags) for flags in range(2 * max(STEP_FLAGS.values())))
"""Every condition a step the core took met, least severe first, indexed by its flags."""

STATUSES: tuple[Status, ...] = tuple(conditions[-1] if conditions else Status.OK for conditions in CONDITIONS)
"""The status (the most severe condition) of a step the core took, indexed by its flags."""

DETAILED = RATE_LIMITED | CLAMPED | COLLISION_SLOWED | COLLISION_HALTED
"""The flags whose conditions carry a detail (a saturated twist has none)."""

COLLIDING = COLLISION_SLOWED | COLLISION_HALTED
"""The flags of a step the collision monitor slowed or halted."""


def core_detail(
    flags: int, scale: float, limit: Callable[[], Limit], next_q: np.ndarray, collision: Callable[[], str] = str
) -> str:
    """The detail of a step the core took: the velocity scale's words, the collision
    monitor's (``collision()``), then the clamped limit's (``limit()`` gives the first one
    clamped; ``next_q`` (nq,) the clamped q), joined as :class:`~.finish.Finish` joins them;
    a halted step's is the monitor's alone."""
    if flags & COLLISION_HALTED:
        return collision()
    parts = []
    if flags & RATE_LIMITED:
        parts.append(scaled_detail(scale))
    if flags & COLLISION_SLOWED:
        parts.append(collision())
    if flags & CLAMPED:
        clamped = limit()
        parts.append(reached_detail(clamped, float(next_q[clamped.q_index])))
    return "; ".join(parts)


class CoreObservation(Observation):
    """The :class:`~.observation.Observation` of a step the core took from q: what its
    kinematics pass saw (J row-major (6, nv), then the tip's and the sensor's pose in the
    world, each a row-major rotation and a translation in m), made into the Observation's
    fields on first read, the poses apart: a step whose observation nobody reads does not
    pay for it, and one read for J and ρ (the console's readout) not for two ``pin.SE3``
    (about a microsecond each)."""

    __slots__ = ("_seen",)
    _seen: tuple[Any, np.ndarray, Sight]  # (q, the caller's float array the core read; the pass; sight)

    if not TYPE_CHECKING:  # to mypy, the fields are the Observation's

        def __getattr__(self, name: str) -> object:
            # Reached only while a field is unset: its group is set from the pass, once.
            if name in _POSES:
                self._set_poses(*object.__getattribute__(self, "_seen"))
            elif name in _OTHERS:
                self._set_others(*object.__getattribute__(self, "_seen"))
            return object.__getattribute__(self, name)  # AttributeError for a name no field has

    def _set_others(self, q: np.ndarray, seen: np.ndarray, sight: Sight) -> None:
        """q, J (a view of the pass), the algorithm, the partition and the defaulted fields."""
        self.q = q
        self.jacobian = seen[: 6 * sight.nv].reshape(6, sight.nv)
        self.algorithm, self.index = sight.algorithm, sight.index
        for field in _DEFAULTED:
            setattr(self, field.name, field.default)

    def _set_poses(self, q: np.ndarray, seen: np.ndarray, sight: Sight) -> None:
        """world_T_tip and world_T_sensor (the same object when the sensor is the tip, as
        :meth:`Robot.kinematics <pinrate.kinematics.manipulator.Robot.kinematics>` gives)."""
        start = 6 * sight.nv
        self.world_T_tip = pin.SE3(seen[start : start + 9].reshape(3, 3), seen[start + 9 : start + 12])
        self.world_T_sensor = (
            self.world_T_tip
            if sight.sensor_at_tip
            else pin.SE3(seen[start + 12 : start + 21].reshape(3, 3), seen[start + 21 : start + 24])
        )


_DEFAULTED = tuple(field for field in fields(Observation) if field.default is not MISSING)
"""The Observation's fields a kinematics pass does not give (goal, error, what is cached)."""

_POSES = frozenset({"world_T_tip", "world_T_sensor"})
_OTHERS = frozenset(field.name for field in fields(Observation)) - _POSES


@dataclass(frozen=True)
class Sight:
    """What a controller's :class:`CoreObservation` needs besides the pass: the algorithm,
    the resolved partition, nv and whether the sensor frame is the tip's."""

    algorithm: str
    index: PartitionIndex
    nv: int
    sensor_at_tip: bool


class CoreStep:
    """A controller's step in the compiled core (``twin``, its :class:`~pinrate.compiled.CoreServo`),
    with what Python does before the step: q checked as :meth:`Robot.check_q
    <pinrate.kinematics.manipulator.Robot.check_q>` and the controller's
    ``check_inside_limits`` check it, the twist as :func:`~pinrate.checks.check_vector` does,
    the kinematics pass and a :class:`PoseGoal`'s pose error, in one call.

    Args:
        twin: the controller's compiled twin.
        limits: the position limits the controller keeps (the core names a clamped one by its
            number in this tuple).
        sight: what the step's :class:`CoreObservation` needs.
        wanted: the controller's twist for a :class:`PoseGoal` at a caller's observation
            (m + k,; a new array).
        collision: the controller's collision monitor, or None (the core runs its
            ``pinrate_core.Collision``, :mod:`.core_collision`).
    """

    def __init__(
        self,
        twin: CoreServo,
        limits: tuple[Limit, ...],
        sight: Sight,
        wanted: Callable[[Observation, PoseGoal], np.ndarray],
        collision: CollisionMonitor | None = None,
    ) -> None:
        self._at, self._given = twin.step_functions()
        self._limits = limits
        self._sight = sight
        self._wanted = wanted
        self._monitor = collision
        self._collision = None if collision is None else core_monitor(collision)

    def __call__(self, q: object, command: object, observation: Observation | None) -> Step | Literal[False] | None:
        """The step from q (or from the caller's ``observation``, then its q and J) with
        ``command`` (a twist (m + k,; partition order, sensor axes, m/s and rad/s) or a
        :class:`PoseGoal`): the :class:`~.observation.Step`; None where Python's checks must
        see the inputs first (one the core does not read, as a list, or one they refuse:
        they say what is wrong); False where the step is Python's."""
        if observation is None:
            if isinstance(command, PoseGoal):
                out = self._at(q, None, command.target.homogeneous, command.gain, self._collision)
            else:
                out = self._at(q, command, None, 0.0, self._collision)
            if not out:
                return out  # the core's None or False
            observation = _new(CoreObservation)
            observation._seen = (q, out[6], self._sight)
        else:
            twist = self._wanted(observation, command) if isinstance(command, PoseGoal) else command
            out = self._given(observation.q, observation.jacobian, twist, self._collision)
            if not out:
                return out
        flags, scale, hit, next_q, rates, twist, _ = out
        detail = core_detail(flags, scale, lambda: self._limits[hit], next_q, self._said) if flags & DETAILED else ""
        return Step(next_q, rates, STATUSES[flags], (), twist, observation, detail, CONDITIONS[flags])

    def _said(self) -> str:
        """The compiled monitor's last verdict in the Python monitor's words."""
        assert self._monitor is not None  # a step flagged by the monitor had one
        return core_verdict_detail(self._monitor, self._collision)


_new = object.__new__


class CorePath:
    """A controller's :class:`CoreStep`, or None where the Python path runs it: found once per
    :func:`pinrate.compiled.use` choice (``PINRATE_BACKEND`` is read then, not per step:
    reading the environment costs more than the step's own checks).

    Args:
        twin: the controller's :meth:`~.controller.Controller.compiled`.
        limits, sight, wanted, collision: as :class:`CoreStep`'s.
    """

    def __init__(
        self,
        twin: Callable[[], CoreServo | None],
        limits: tuple[Limit, ...],
        sight: Sight,
        wanted: Callable[[Observation, PoseGoal], np.ndarray],
        collision: CollisionMonitor | None = None,
    ) -> None:
        self._twin = twin
        self._arguments = (limits, sight, wanted, collision)
        self._steps: dict[str | None, CoreStep | None] = {}

    def __call__(self) -> CoreStep | None:
        choice = chosen()
        step = self._steps.get(choice, _UNKNOWN)
        if step is _UNKNOWN:
            twin = None if core_module() is None else self._twin()
            step = self._steps[choice] = None if twin is None else CoreStep(twin, *self._arguments)
        return step  # type: ignore[return-value]


_UNKNOWN = object()


__all__ = ["CONDITIONS", "STATUSES", "CoreObservation", "CorePath", "CoreStep", "Sight", "core_detail"]
