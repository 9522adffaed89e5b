"""One servo run (:func:`~pinrate.control.servo_loop.servo`): its per-step log, the stop
rules of :mod:`pinrate.control.servo_loop` on its error norms, and its two paths: every step by
:meth:`Controller.step` on Python, or the loop in the compiled core with Python taking the steps
the core hands back. Both fill one log the same way and end with the same words."""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from ..compiled import CoreServo
from ..plants import Plant
from .commands import PoseGoal
from .controller import Controller, Observation, error_norms
from .core_collision import core_monitor
from .core_step import DETAILED, STATUSES, core_detail
from .measured import onto_limits
from .stall import stall_cause
from .status import Status
from .trajectory import PlantRecord, Trajectory

DIVERGENCE_FACTOR = 3.0
"""Stop as diverging once position + orientation error exceeds this times its minimum so far."""

STALL_IMPROVEMENT = 0.01
"""The relative fall of the error that counts as progress for the stall rule."""


class ServoLog:
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

    def arguments(self) -> dict[str, np.ndarray]:
        """The arrays the core fills, by the names of its ``run``'s arguments."""
        names = ("q", "rates", "position", "orientation", "radius", "flags", "scale", "hit")
        return {name: getattr(self, name) for name in names}


INITIAL_CAPACITY = 2048
"""Steps a run's arrays hold before they first grow."""


class ServoRun:
    """One servo run: the stop rules of the module docstring over :meth:`Controller.step`,
    on Python (:meth:`python`) or in the compiled core with Python taking the steps it hands
    back (:meth:`compiled`); both fill one log the same way."""

    def __init__(
        self, controller: Controller, goal: PoseGoal, q0: np.ndarray, tol: float, stall_steps: int, max_steps: int
    ) -> None:
        self.controller, self.goal, self.tol = controller, goal, tol
        self.stall_steps, self.max_steps = stall_steps, max_steps
        self.m = controller.index.m
        self.log = ServoLog(q0, controller.robot.nv, max(1, min(max_steps, INITIAL_CAPACITY)))
        self.steps: dict[int, tuple[str, str]] = {}  # step number -> (word, detail) of a Python step
        self.step_number = 0
        self.best = math.inf
        self.progress, self.progress_step = math.inf, 0  # the error at the last 1 % improvement, and when
        self.final, self.reason = "", ""
        self.plant: Plant | None = None
        self.measured: list[tuple[np.ndarray, float, tuple[str, ...]]] = []  # per step: rates, tracking, saturated

    # ------------------------------------------------------------------ the paths
    def python(self) -> None:
        """The run on Python: observe, judge, step, until a stop rule ends it."""
        while True:
            observation, position, orientation = self._record()
            if self._judge(position, orientation):
                return
            if self._python_step(observation):
                return

    def on_plant(self, plant: Plant) -> None:
        """The run in closed loop on ``plant`` (Shoham & Koren's Fig. 3): reset to q0, then
        each step is taken from the configuration the plant measured after the one before
        (:func:`~.measured.onto_limits`), and the plant is advanced by its rates for dt."""
        self.plant = plant
        self.log.q[0] = plant.reset(self.log.q[0]).q
        self.python()

    def compiled(self, core: CoreServo) -> None:
        """The run in the compiled ``core``, Python taking each step the core hands back
        (a step that needs more than the core covers) until a stop rule ends it."""
        outcomes = core.core
        target = np.ascontiguousarray(self.goal.target.homogeneous)
        monitor = self.controller.collision
        # The core's monitor (Controller.compiled has checked that it runs there); a step it
        # slows or halts is handed back.
        collision = None if monitor is None else core_monitor(monitor)
        while True:
            outcome, self.step_number, self.best, self.progress, self.progress_step = core.run(
                q0=self.log.q[self.step_number],
                target=target,
                gain=self.goal.gain,
                tol=self.tol,
                stall_steps=self.stall_steps,
                max_steps=self.max_steps,
                divergence_factor=DIVERGENCE_FACTOR,
                stall_improvement=STALL_IMPROVEMENT,
                step_number=self.step_number,
                best=self.best,
                progress=self.progress,
                progress_step=self.progress_step,
                collision=collision,
                **self.log.arguments(),
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
        view = self.log.q[self.step_number]
        if self.plant is not None:  # the controller's view of the measurement (the record keeps it as measured)
            view, beyond = onto_limits(self.controller, view, self.plant.limit_tolerance)
            if beyond:
                self.final, self.reason = "plant", f"plant: past a position limit: {beyond} at step {self.step_number}"
        observation = self.controller.observe_unchecked(view, self.goal)
        position, orientation = error_norms(observation, self.m)
        self.log.position[self.step_number] = position
        self.log.orientation[self.step_number] = orientation
        self.log.radius[self.step_number] = observation.spectral_radius
        return observation, position, orientation

    def _judge(self, position: float, orientation: float) -> bool:
        """The stop rules at this step's error norms; True when the run ends here."""
        if self.final:  # the plant left the limits (:meth:`_record`)
            return True
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
        """The reason names the cause its window's steps met (:func:`~.stall.stall_cause`)."""
        words, details = self._words()
        window = slice(self.progress_step, self.step_number)
        self.final = "stalled"
        self.reason = (
            f"stalled: error {total:.4g} (m + rad) has not improved by {STALL_IMPROVEMENT:.0%} on "
            f"{self.progress:.4g} (step {self.progress_step}) for {self.stall_steps * self.controller.dt:g} s, "
            f"at step {self.step_number}; {stall_cause(words[window], details[window])}"
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
        self.steps[step_number] = (step.status.word, step.detail)
        self.log.rates[step_number] = step.joint_rates
        self.log.q[step_number + 1] = (
            step.q if self.plant is None else self._advance(self.plant, step.q, step.joint_rates)
        )
        self.step_number = step_number + 1
        return False

    def _advance(self, plant: Plant, commanded: np.ndarray, joint_rates: np.ndarray) -> np.ndarray:
        """The plant advanced by ``joint_rates`` for dt; its measured q. Records the measured
        rates, the tip's distance (m) from where the step's ``commanded`` q would put it,
        and the saturated joints."""
        measurement = plant.advance(joint_rates, self.controller.dt)
        robot = self.controller.robot
        tracking = float(np.linalg.norm(robot.pose(commanded)[:3, 3] - robot.pose(measurement.q)[:3, 3]))
        self.measured.append((measurement.joint_rates, tracking, measurement.saturated))
        return measurement.q

    # ------------------------------------------------------------------ the result
    def _words(self) -> tuple[list[str], list[str]]:
        """Each step's status word and detail: the Python steps' own, the core's from its flags."""
        taken = self.step_number
        flags = self.log.flags[:taken].tolist()
        status = [STATUSES[flag].word for flag in flags]
        details = [""] * taken
        for step_number, flag in enumerate(flags):
            if flag & DETAILED:
                details[step_number] = self._core_detail(step_number, flag)
        for step_number, (word, detail) in self.steps.items():
            status[step_number], details[step_number] = word, detail
        return status, details

    def _core_detail(self, step_number: int, flag: int) -> str:
        """Controller._finish's detail of a step the core took."""
        log = self.log
        return core_detail(
            flag,
            float(log.scale[step_number]),
            lambda: self.controller.position_limit(int(log.hit[step_number])),
            log.q[step_number + 1],
        )

    def trajectory(self) -> Trajectory:
        taken = self.step_number
        status, details = self._words()
        status.append(self.final)
        details.append(self.reason)
        log, controller = self.log, self.controller
        plant = None
        if self.plant is not None:
            names = controller.robot.joint_names
            measured = self.measured[:taken]
            plant = PlantRecord(
                name=self.plant.name,
                measured_rates=np.array([rates for rates, _, _ in measured]).reshape(taken, controller.robot.nv),
                tracking_error=np.array([tracking for _, tracking, _ in measured], dtype=float),
                saturated=np.array([[name in hit for name in names] for _, _, hit in measured], dtype=bool).reshape(
                    taken, controller.robot.nv
                ),
            )
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
            plant=plant,
        )


__all__ = ["DIVERGENCE_FACTOR", "STALL_IMPROVEMENT", "ServoRun"]
