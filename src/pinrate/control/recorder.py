"""Recording the recent motion and playing it back backwards (Barker 1983, "recording and
reversing a motion": the operator's evacuation along the way the hand came).

:class:`Recorder` keeps the configurations of the last ``history`` seconds (and at most
``max_samples`` of them), each with its time stamp (s). :meth:`Recorder.playback` returns a
:class:`Playback` that retraces them from the newest to the oldest at the pace they were
recorded: each step commands the joint rates that reach the configuration recorded τ seconds
before the newest, τ advancing by the controller's dt per step, as a :class:`JointJog`
through :meth:`Controller.step`, so every limit of the controller applies. A step slowed by a
limit advances τ only by the share it achieved: the playback falls behind the clock and
stays on the path (an acceleration limit or a joint held at a limit bends it as little as
they allow); a step that cannot move at all ends the playback. Between two samples the
configuration is interpolated on the configuration space (``pinocchio.interpolate``), so the
path stays within the joint limits that both ends respect.
"""

from __future__ import annotations

import math
from collections import deque

import numpy as np
import pinocchio as pin

from ..checks import check_count, check_positive
from ..errors import InputError
from .commands import JointJog
from .controller import Controller, Step

MAX_SAMPLES = 100_000
"""Default bound of a recorder's samples (30 s at 1 kHz fits three times)."""


class Recorder:
    """A bounded record of recent configurations and their times.

    Args:
        history: seconds of motion kept, counted back from the newest sample.
        max_samples: at most this many samples are kept (the oldest go first).
    """

    def __init__(self, history: float = 30.0, *, max_samples: int = MAX_SAMPLES) -> None:
        self.history = check_positive(history, "history")
        self.max_samples = check_count(max_samples, "max_samples", minimum=2)
        self._times: deque[float] = deque(maxlen=self.max_samples)
        self._configurations: deque[np.ndarray] = deque(maxlen=self.max_samples)

    def __len__(self) -> int:
        return len(self._times)

    def record(self, time: float, q: np.ndarray) -> None:
        """Add the configuration ``q`` at ``time`` (s); samples older than ``history`` before
        it are dropped. A time earlier than the newest is an InputError; at the same time the
        sample replaces the newest."""
        try:
            stamp = float(time)
        except (TypeError, ValueError):
            raise InputError(f"time must be a number of seconds, not {time!r}") from None
        if not math.isfinite(stamp):
            raise InputError(f"time must be finite, got {stamp}")
        if self._times and stamp < self._times[-1]:
            raise InputError(f"time {stamp} s is before the newest sample's {self._times[-1]} s")
        try:
            configuration = np.array(q, dtype=float)
        except (TypeError, ValueError):
            raise InputError(f"q must be a vector of numbers, not {type(q).__name__}") from None
        shape = self._configurations[0].shape if self._configurations else None
        if configuration.ndim != 1 or (shape is not None and configuration.shape != shape):
            raise InputError(f"q must have the shape of the recorded ones {shape}, got {configuration.shape}")
        if not np.isfinite(configuration).all():
            raise InputError("q contains NaN or inf")
        if self._times and stamp == self._times[-1]:
            self._times.pop()
            self._configurations.pop()
        self._times.append(stamp)
        self._configurations.append(configuration)
        while self._times[0] < stamp - self.history:
            self._times.popleft()
            self._configurations.popleft()

    def truncate(self, time: float) -> None:
        """Drop the samples recorded after ``time`` (s): what a playback has retraced."""
        while self._times and self._times[-1] > time:
            self._times.pop()
            self._configurations.pop()

    def clear(self) -> None:
        """Forget every sample."""
        self._times.clear()
        self._configurations.clear()

    @property
    def times(self) -> np.ndarray:
        """The samples' times (n,), oldest first (s)."""
        return np.array(self._times)

    @property
    def configurations(self) -> np.ndarray:
        """The samples' configurations (n, nq), oldest first."""
        return np.array(self._configurations)

    def playback(self, controller: Controller) -> Playback:
        """A backward playback of the recorded window through ``controller`` (see the module)."""
        if self._configurations and self._configurations[0].shape != (controller.robot.nq,):
            raise InputError(
                f"the recording holds configurations of {self._configurations[0].shape[0]} coordinates, "
                f"{controller.robot.name!r} has {controller.robot.nq}"
            )
        if len(self._times) < 2:
            raise InputError("nothing to play back: the recorder holds fewer than two samples")
        return Playback(controller, self.times, self.configurations)


class Playback:
    """The recorded motion retraced backwards, one controller step at a time.

    Attributes:
        elapsed: τ (s), how far back along the recording the playback has come.
        done: the oldest configuration is reached, or a step could not move at all (a joint
            held at a limit, a halt): a loop ``while not playback.done`` always ends.
        stopped: why it ended early, in words ("" when it reached the oldest configuration).
    """

    def __init__(self, controller: Controller, times: np.ndarray, configurations: np.ndarray) -> None:
        self.controller = controller
        self._times = times
        self._configurations = configurations
        self.duration = float(times[-1] - times[0])
        self.elapsed = 0.0
        self.done = False
        self.stopped = ""

    def target(self, elapsed: float) -> np.ndarray:
        """The configuration recorded ``elapsed`` seconds before the newest (interpolated)."""
        moment = self._times[-1] - min(max(elapsed, 0.0), self.duration)
        after = int(np.searchsorted(self._times, moment, side="left"))
        if after == 0:
            return self._configurations[0].copy()
        before = after - 1
        span = self._times[after] - self._times[before]
        share = 0.0 if span <= 0.0 else (moment - self._times[before]) / span
        model = self.controller.robot.model
        return pin.interpolate(model, self._configurations[before], self._configurations[after], share)

    def step(self, q: np.ndarray) -> Step:
        """One step from q toward the configuration dt further back; ``done`` when the oldest
        is reached."""
        controller = self.controller
        robot = controller.robot
        ahead = min(self.elapsed + controller.dt, self.duration)
        goal = self.target(ahead)
        requested = pin.difference(robot.model, q, goal) / controller.dt
        jog = JointJog({name: float(requested[robot.velocity_indices(name)[0]]) for name in controller.joggable})
        step = controller.step(q, jog)
        requested_norm = float(np.linalg.norm(requested))
        achieved = 1.0 if requested_norm == 0.0 else float(np.linalg.norm(step.joint_rates)) / requested_norm
        self.elapsed = min(self.elapsed + controller.dt * min(achieved, 1.0), self.duration)
        if ahead >= self.duration and achieved >= 1.0 - 1e-12:
            self.done = True
        elif requested_norm > 0.0 and achieved <= 1e-12:
            self.done = True
            self.stopped = f"the playback could not move ({step.status.value}: {step.detail})"
        return step


__all__ = ["MAX_SAMPLES", "Playback", "Recorder"]
