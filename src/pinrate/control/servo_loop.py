"""Closed-loop servo of the TCP to a target pose: a loop over :meth:`Controller.step` and
its stop rules.

Each step the sensor sees the pose error and commands (Shoham & Koren §2, Fig. 3)

    v = gain * R_s^T (p_target - p_tip)                 (position error, sensor axes)
    Ω = gain * R_s^T log3(R_target R_tip^T)             (rotation error, sensor axes)

saturated to ``max_linear_speed`` (m/s) and ``max_angular_speed`` (rad/s), turned into
joint rates by the algorithm and integrated over ``dt`` (see :mod:`.controller`).

On the Theorem: with ``gain * dt = 1`` the sensor commands the whole error each sample and
the error of MCA1 maps as e <- G e (eq. 40 with β = 1), so ``|λ(G)|`` < 1 is the exact test.
With smaller ``gain * dt`` the step is e <- (I - gain dt (I - G)) e: ``|λ|`` < 1 remains
sufficient, and only Re λ < 1 is needed as gain dt -> 0.

Stop rules, on the error measure e = ``|position error|`` + ``|rotation error|`` (m + rad, the two
norms ``tol`` applies to):

- **converged**: both norms below ``tol``.
- **diverging**: e > DIVERGENCE_FACTOR × min(e so far) + tol. Near the target the error maps
  linearly, e_k+1 ≈ M e_k; with ρ(M) > 1 it grows geometrically, so it passes 3× its minimum
  after ln 3 / ln ρ steps (12 steps at ρ = 1.1). With ρ(M) < 1 it can still grow for a while
  (M is not normal; far from the target the map is not linear), by at most the condition
  number of M's eigenvectors: a factor of 3 over the best error is past what a convergent run
  shows in pinrate's robots and tests, and cheap to detect early.
- **stalled**: e has not fallen below (1 - STALL_IMPROVEMENT) × its value at the last
  improvement for ``stall_time`` seconds of simulated time (default: max(1 s, 5 / gain), five
  time constants of the first-order error decay e(t) = e0 exp(-gain t) that an exact solver
  gives), or for STALL_MAX_STEPS steps, whichever is fewer. Every continuing window improves
  e by 1 %, and e cannot fall below ``tol`` without converging, so a run ends after at most
  ln(e0 / tol) / ln(1 / 0.99) windows whatever ``max_steps`` is.
- **singular**: the step halted for a singularity (``singularity="decelerate"``: the next
  step would have made a block singular; or the algorithm met a singular block).
- **collision**: the step halted before two links would come within the collision monitor's
  stop distance (``Controller(collision=True)``).
- **max steps**: ``max_steps`` ran out.

A joint limit does not stop the run: the step holds the joint on its limit while the others
go on serving the error (a target the held joint was needed for then ends as "stalled").
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable
from typing import Any

import numpy as np

from ..checks import check_count, check_positive
from ..compiled import CoreServo
from ..compiled.boundary import CLAMPED, RATE_LIMITED, SATURATED, STEP_FLAGS
from ..errors import InputError
from ..kinematics.manipulator import Robot
from ..kinematics.partition import Partition
from .commands import PoseGoal
from .controller import (
    CONTROLLER_OPTIONS,
    MAX_ANGULAR_SPEED,
    MAX_LINEAR_SPEED,
    Controller,
    Observation,
    error_norms,
)
from .status import Status, most_severe
from .trajectory import Trajectory

DIVERGENCE_FACTOR = 3.0
"""Stop as diverging once position + orientation error exceeds this times its minimum so far."""

STALL_IMPROVEMENT = 0.01
"""The relative fall of the error that counts as progress for the stall rule."""

STALL_TIME_CONSTANTS = 5.0
"""Default stall window in time constants (1 / gain) of the error's decay; at least 1 s."""

STALL_MAX_STEPS = 100_000
"""Most steps in a stall window, whatever ``stall_time / dt``: an error that needs more steps
than this to fall 1 % is not progressing at a useful rate (and a tiny dt would otherwise
make the window, and the run, endless in wall-clock time)."""

_STEP_WORDS = {
    Status.TWIST_SATURATED: "saturated",
    Status.JOINT_LIMIT: "joint limit",
    Status.RATE_LIMITED: "rate limited",
    Status.WRIST_SINGULARITY: "wrist singularity",
    Status.NEAR_SINGULARITY: "near singularity",
    Status.DECELERATE_FOR_SINGULARITY: "decelerating",
    Status.AUXILIARY_ELBOW: "auxiliary elbow",
    Status.FROZEN: "frozen",
    Status.DECELERATE_FOR_COLLISION: "slowing for collision",
}
"""The word a step's status leaves in ``Trajectory.status`` ("moving" for the others)."""

MIN_TOL = 1e-12
"""Smallest ``tol`` (m and rad): finer than double precision resolves a pose of a 1 m arm."""


def _options_from_one_place(function: Callable[..., Trajectory]) -> Callable[..., Trajectory]:
    """With ``controller=`` given, any Controller option passed beside it is an InputError
    (whatever its value: an option equal to servo's default is refused too, never ignored)."""

    @functools.wraps(function)
    def checked(*arguments: Any, **keywords: Any) -> Trajectory:
        if keywords.get("controller") is not None:
            given = sorted(set(keywords) & set(CONTROLLER_OPTIONS))
            if given:
                raise InputError(
                    f"servo(controller=...) takes its options from the controller: drop {', '.join(given)} "
                    "(or build the controller with them)"
                )
        return function(*arguments, **keywords)

    return checked


@_options_from_one_place
def servo(
    robot: Robot,
    q0: object,
    target: object,
    *,
    algorithm: str = "mca1",
    partition: Partition | None = None,
    dt: float = 0.01,
    gain: float = 1.0,
    max_steps: int = 2000,
    tol: float = 1e-4,
    max_linear_speed: float = MAX_LINEAR_SPEED,
    max_angular_speed: float = MAX_ANGULAR_SPEED,
    stall_time: float | None = None,
    velocity_limits: object = math.inf,
    singularity: str = "decelerate",
    wrist: str = "split",
    controller: Controller | None = None,
    **controller_options: Any,
) -> Trajectory:
    """Servo the tip from q0 to ``target`` (4x4 pose in the world, or pinocchio.SE3).

    Stops when the norms of the controlled position error (m) and rotation error (rad) are
    both below ``tol`` (converged), or with a reason (see the module's stop rules): the error
    grew past DIVERGENCE_FACTOR times its best (diverging), it has not improved by
    STALL_IMPROVEMENT for ``stall_time`` seconds (stalled; default max(1 s, 5 / gain)), a
    step halted for a singularity, or ``max_steps`` ran out. Joints are held at their position
    limits while the others go on (:class:`Controller`). ``velocity_limits``, ``singularity``
    and ``wrist`` as for :class:`Controller`: the default velocity limits, none, keep the
    papers' simulations as they were; None takes the URDF's.

    Every other :class:`Controller` option is taken by keyword (``collision=True``,
    ``acceleration_limits=2.0``, ``posture="home"``, ...), or a ``controller`` built on this
    ``robot`` is used as it is (then no controller option may be given here; its state, such
    as acceleration-limited rates, carries over from earlier steps). An unknown option is an
    InputError listing the valid ones.
    """
    if controller is None:
        unknown = sorted(set(controller_options) - set(CONTROLLER_OPTIONS))
        if unknown:
            raise InputError(
                f"servo() has no option {', '.join(map(repr, unknown))}; its own are gain, max_steps, tol, "
                f"stall_time, controller, and the Controller's: {', '.join(CONTROLLER_OPTIONS)}"
            )
        controller = Controller(
            robot,
            algorithm=algorithm,
            partition=partition,
            dt=dt,
            max_linear_speed=max_linear_speed,
            max_angular_speed=max_angular_speed,
            velocity_limits=velocity_limits,
            singularity=singularity,
            wrist=wrist,
            **controller_options,
        )
    elif not isinstance(controller, Controller):
        raise InputError(f"controller must be a pinrate.Controller, not {type(controller).__name__}")
    elif controller.robot is not robot:
        raise InputError("the controller was built for another Robot object: servo it on that one")
    q = robot.check_q(q0)
    goal = PoseGoal.of(target, gain)
    tol = check_positive(tol, "tol")
    if tol < MIN_TOL:
        raise InputError(f"tol must be at least {MIN_TOL:g} (m and rad), got {tol!r}")
    max_steps = check_count(max_steps, "max_steps")
    if stall_time is None:
        stall_time = max(1.0, STALL_TIME_CONSTANTS / goal.gain)
    stall_steps = min(math.ceil(check_positive(stall_time, "stall_time") / controller.dt), STALL_MAX_STEPS)
    run = _Run(controller, goal, q, tol, stall_steps, max_steps)
    core = controller.compiled()
    if core is None:
        run.python()
    else:
        run.compiled(core)
    return run.trajectory()


class _Log:
    """One run's per-step arrays, rows indexed by step number, grown by doubling."""

    def __init__(self, q0: np.ndarray, nv: int, capacity: int) -> None:
        self.capacity = capacity
        self.q = np.empty((capacity + 1, q0.size))
        self.q[0] = q0
        self.rates = np.empty((capacity, nv))
        self.position = np.empty(capacity + 1)
        self.orientation = np.empty(capacity + 1)
        self.radius = np.empty(capacity + 1)
        self.flags = np.zeros(capacity, dtype=np.int32)  # the core's step flags (0: a Python step)
        self.scale = np.ones(capacity)
        self.hit = np.full(capacity, -1, dtype=np.int32)

    def grow(self) -> None:
        capacity = 2 * self.capacity
        for name in ("q", "rates", "position", "orientation", "radius"):
            old = getattr(self, name)
            new = np.empty((old.shape[0] - self.capacity + capacity, *old.shape[1:]))
            new[: old.shape[0]] = old
            setattr(self, name, new)
        for name, fill in (("flags", 0), ("scale", 1.0), ("hit", -1)):
            old = getattr(self, name)
            new = np.full(capacity, fill, dtype=old.dtype)
            new[: old.shape[0]] = old
            setattr(self, name, new)
        self.capacity = capacity

    def arguments(self) -> tuple[np.ndarray, ...]:
        return (self.q, self.rates, self.position, self.orientation, self.radius, self.flags, self.scale, self.hit)


INITIAL_CAPACITY = 2048
"""Steps a run's arrays hold before they first grow."""


class _Run:
    """One servo run: the stop rules of the module docstring over :meth:`Controller.step`,
    on Python (:meth:`python`) or in the compiled core with Python taking the steps it hands
    back (:meth:`compiled`); both fill one log the same way."""

    def __init__(
        self, controller: Controller, goal: PoseGoal, q0: np.ndarray, tol: float, stall_steps: int, max_steps: int
    ) -> None:
        self.controller, self.goal, self.tol = controller, goal, tol
        self.stall_steps, self.max_steps = stall_steps, max_steps
        self.m = controller.index.m
        self.log = _Log(q0, controller.robot.nv, max(1, min(max_steps, INITIAL_CAPACITY)))
        self.steps: dict[int, tuple[str, str]] = {}  # step number -> (word, detail) of a Python step
        self.step_number = 0
        self.best = math.inf
        self.progress, self.progress_step = math.inf, 0  # the error at the last 1 % improvement, and when
        self.final, self.reason = "", ""

    # ------------------------------------------------------------------ the two paths
    def python(self) -> None:
        while True:
            observation, position, orientation = self._record()
            if self._judge(position, orientation):
                return
            if self._python_step(observation):
                return

    def compiled(self, core: CoreServo) -> None:
        outcomes = core.core
        target = np.ascontiguousarray(self.goal.target.homogeneous)
        while True:
            outcome, self.step_number, self.best, self.progress, self.progress_step = core.run(
                self.log.q[self.step_number],
                target,
                self.goal.gain,
                self.tol,
                self.stall_steps,
                self.max_steps,
                DIVERGENCE_FACTOR,
                STALL_IMPROVEMENT,
                self.step_number,
                self.best,
                self.progress,
                self.progress_step,
                *self.log.arguments(),
            )
            if outcome not in (outcomes.HANDBACK, outcomes.FULL):
                self._conclude(outcome, outcomes)
                return
            # The core recorded this step's observation and judged it; Python takes the step
            # from an observation of its own (one more kinematics pass, on these steps only).
            q = self.log.q[self.step_number]
            if self._python_step(self.controller.observe_unchecked(q, self.goal)):
                return

    # ------------------------------------------------------------------ one step's parts
    def _record(self) -> tuple[Observation, float, float]:
        """This step's observation, logged; and its error norms (m, rad) as Python floats."""
        observation = self.controller.observe_unchecked(self.log.q[self.step_number], self.goal)
        position, orientation = error_norms(observation, self.m)
        self.log.position[self.step_number] = position
        self.log.orientation[self.step_number] = orientation
        self.log.radius[self.step_number] = observation.spectral_radius
        return observation, position, orientation

    def _judge(self, position: float, orientation: float) -> bool:
        """The stop rules at this step's error norms; True when the run ends here."""
        step_number = self.step_number
        total = position + orientation
        if position < self.tol and orientation < self.tol:
            self._converged()
            return True
        self.best = min(self.best, total)
        if total > DIVERGENCE_FACTOR * self.best + self.tol:
            self._diverging(total)
            return True
        if total < (1.0 - STALL_IMPROVEMENT) * self.progress:
            self.progress, self.progress_step = total, step_number
        elif step_number - self.progress_step >= self.stall_steps:
            self._stalled(total)
            return True
        if step_number == self.max_steps:
            self._out_of_steps()
            return True
        return False

    # The final word and reason of each stop rule, whichever path ended the run.
    def _converged(self) -> None:
        self.final, self.reason = "converged", f"converged in {self.step_number} steps"

    def _out_of_steps(self) -> None:
        self.final, self.reason = "max steps", f"max_steps ({self.max_steps}) reached"

    def _diverging(self, total: float) -> None:
        growth = f"error {total:.4g} grew past {DIVERGENCE_FACTOR:g}x its best {self.best:.4g}"
        self.final, self.reason = "diverging", f"diverging: {growth} at step {self.step_number}"

    def _stalled(self, total: float) -> None:
        self.final = "stalled"
        self.reason = (
            f"stalled: error {total:.4g} (m + rad) has not improved by {STALL_IMPROVEMENT:.0%} on "
            f"{self.progress:.4g} (step {self.progress_step}) for {self.stall_steps * self.controller.dt:g} s, "
            f"at step {self.step_number}"
        )

    def _conclude(self, outcome: int, outcomes: Any) -> None:
        """The final word and reason of a run the core ended."""
        total = float(self.log.position[self.step_number] + self.log.orientation[self.step_number])
        if outcome == outcomes.CONVERGED:
            self._converged()
        elif outcome == outcomes.DIVERGING:
            self._diverging(total)
        elif outcome == outcomes.STALLED:
            self._stalled(total)
        else:
            self._out_of_steps()

    def _python_step(self, observation: Observation) -> bool:
        """Controller.step from this step's observation; True when it halts the run."""
        step_number = self.step_number
        if step_number >= self.log.capacity:
            self.log.grow()
        step = self.controller.step(observation.q, self.goal, observation=observation)
        if step.status is Status.HALT_FOR_SINGULARITY:
            self.final, self.reason = "singular", f"singular: {step.detail} at step {step_number}"
            return True
        if step.status is Status.HALT_FOR_COLLISION:
            self.final, self.reason = "collision", f"collision: {step.detail} at step {step_number}"
            return True
        self.steps[step_number] = (_STEP_WORDS.get(step.status, "moving"), step.detail)
        self.log.rates[step_number] = step.joint_rates
        self.log.q[step_number + 1] = step.q
        self.step_number = step_number + 1
        return False

    # ------------------------------------------------------------------ the result
    def _words(self) -> tuple[list[str], list[str]]:
        """Each step's status word and detail: the Python steps' own, the core's from its flags."""
        taken = self.step_number
        flags = self.log.flags[:taken].tolist()
        status = [_CORE_WORDS[flag] for flag in flags]
        details = [""] * taken
        for step_number, flag in enumerate(flags):
            if flag & (RATE_LIMITED | CLAMPED):
                details[step_number] = self._core_detail(step_number, flag)
        for step_number, (word, detail) in self.steps.items():
            status[step_number], details[step_number] = word, detail
        return status, details

    def _core_detail(self, step_number: int, flag: int) -> str:
        """Controller._finish's detail of a step the core took."""
        parts = []
        if flag & RATE_LIMITED:
            parts.append(f"rates scaled by {self.log.scale[step_number]:.3g} to meet the velocity limits")
        if flag & CLAMPED:
            limit = self.controller.position_limit(int(self.log.hit[step_number]))
            value = self.log.q[step_number + 1][limit.q_index]
            side, bound = ("lower", limit.lower) if value == limit.lower else ("upper", limit.upper)
            parts.append(f"{limit.joint} reached its {side} limit {bound:.4g}")
        return "; ".join(parts)

    def trajectory(self) -> Trajectory:
        taken = self.step_number
        status, details = self._words()
        status.append(self.final)
        details.append(self.reason)
        log, controller = self.log, self.controller
        return Trajectory(
            q=log.q[: taken + 1].copy(),
            position_error=log.position[: taken + 1].copy(),
            orientation_error=log.orientation[: taken + 1].copy(),
            spectral_radius=log.radius[: taken + 1].copy(),
            status=status,
            joint_rates=log.rates[:taken].copy(),
            converged=self.final == "converged",
            reason=self.reason,
            algorithm=controller.algorithm,
            dt=controller.dt,
            partition=controller.partition,
            detail=details,
        )


def _core_word(flag: int) -> str:
    statuses = [Status.TWIST_SATURATED] if flag & SATURATED else []
    if flag & RATE_LIMITED:
        statuses.append(Status.RATE_LIMITED)
    if flag & CLAMPED:
        statuses.append(Status.JOINT_LIMIT)
    return _STEP_WORDS.get(most_severe(*statuses), "moving")


_CORE_WORDS = [_core_word(flag) for flag in range(2 * max(STEP_FLAGS.values()))]
"""The status word of a step the core took, by its flags."""
