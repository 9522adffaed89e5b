"""A teleoperated run, tick by tick: saved and loaded as ``.npz`` (the viewer turns it into a
standalone HTML replay, :meth:`pinrate.viewer.Viewer.save_html`).

A recording of zero ticks (recording started and stopped at once) is a valid recording: it
holds the robot, dt and the start configuration, saves and loads like any other, and
:meth:`Recording.frames` gives the start alone. Saving then loading gives back every column
bit for bit.
"""

from __future__ import annotations

import math
import os
import zipfile
from collections import deque
from pathlib import Path

import numpy as np

from ..checks import MAX_SAMPLES, check_count, check_output_file, check_positive
from ..control.controller import Step
from ..control.status import Status
from ..errors import InputError, PinrateError
from ..kinematics.manipulator import Robot

FORMAT = "pinrate-teleop-2"
"""The ``format`` entry of a saved recording: what :meth:`Recording.load` reads (it reads
``pinrate-teleop-1`` too, whose status column held :class:`~pinrate.Status` values instead of
their words)."""

_FIRST_FORMAT = "pinrate-teleop-1"


CHUNK = 2048
"""Ticks converted to an array at a time (see :func:`converted`)."""


def converted(values: list, dtype: type) -> np.ndarray:
    """``np.array(values, dtype=dtype)``, :data:`CHUNK` values at a time into one array.

    One numpy call over a whole recording holds the GIL throughout (2.7 ms for 15,000 ticks
    of a 6-joint arm; a long run, a second and more), which stalls the console's control
    thread while a recording is saved; chunk by chunk, each hold is short.
    """
    if len(values) <= CHUNK:
        return np.array(values, dtype=dtype)
    chunks = range(0, len(values), CHUNK)
    if dtype is str:  # the widest string first, a chunk at a time too
        width = max(max(map(len, values[start : start + CHUNK])) for start in chunks)
        out = np.empty(len(values), dtype=f"<U{max(width, 1)}")
    else:
        first: np.ndarray = np.asarray(values[0], dtype=dtype)
        out = np.empty((len(values), *first.shape), dtype=dtype)
    for start in chunks:
        out[start : start + CHUNK] = values[start : start + CHUNK]
    return out


class Recording:
    """Every tick of a teleoperated run.

    Args:
        robot: the robot driven (its name and joint names are kept); None when unknown.
        dt: the controller's period (s).
        max_samples: at most this many ticks are kept (the oldest go first).

    The ticks are arrays, oldest first (N ticks, N may be 0): :attr:`times`, :attr:`q`,
    :attr:`joint_rates`, :attr:`status` and :attr:`detail`.

    Attributes:
        start: the configuration before the first tick (nq,), None when not given.
        nq, nv: the sizes of a configuration and of the rates (0 when not known).

    Raises:
        InputError: dt not positive, max_samples not a positive integer.
    """

    def __init__(self, robot: Robot | None, dt: float, *, max_samples: int = 2_000_000) -> None:
        self.robot_name = robot.name if robot is not None else ""
        self.joint_names = tuple(robot.joint_names) if robot is not None else ()
        self.nq = robot.nq if robot is not None else 0
        self.nv = robot.nv if robot is not None else 0
        self.dt = check_positive(dt, "dt")
        self.max_samples = check_count(max_samples, "max_samples", minimum=1)
        self.start: np.ndarray | None = None
        self._ticks: deque[tuple[float, np.ndarray, np.ndarray, str, str]] = deque(maxlen=self.max_samples)

    def __len__(self) -> int:
        return len(self._ticks)

    def add_start(self, q: np.ndarray) -> None:
        """Keep ``q`` (a copy) as the configuration before the first tick."""
        self.start = np.array(q, dtype=float)

    def add(self, time: float, step: Step) -> None:
        """Keep one tick at ``time`` (s; one earlier than the newest tick's is kept at the
        newest's, so ``times`` never decreases), copying the step's q and rates; the oldest
        tick goes when ``max_samples`` are held. InputError for a time that is not finite."""
        stamp = float(time)
        if not math.isfinite(stamp):
            raise InputError(f"a tick's time must be finite, got {stamp}")
        if self._ticks and stamp < self._ticks[-1][0]:
            stamp = self._ticks[-1][0]
        q = np.array(step.q, dtype=float)
        rates = np.array(step.joint_rates, dtype=float)
        self._ticks.append((stamp, q, rates, step.status.word, step.detail))

    def _column(self, index: int) -> list:
        return [tick[index] for tick in self._ticks]

    def _rows(self, index: int, width: int) -> np.ndarray:
        if not self._ticks:
            return np.zeros((0, width))
        return converted(self._column(index), float).reshape(len(self), -1)

    @property
    def times(self) -> np.ndarray:
        """The time of each tick (s), as given to :meth:`~.session.Teleop.tick`, (N,); never
        decreasing: a tick dated before the previous one is kept at the previous one's time."""
        return converted(self._column(0), float)

    @property
    def q(self) -> np.ndarray:
        """The configuration after each tick (N, nq); ``start`` is the one before the first."""
        return self._rows(1, self.nq)

    @property
    def joint_rates(self) -> np.ndarray:
        """The rates applied at each tick (N, nv), rad/s or m/s."""
        return self._rows(2, self.nv)

    @property
    def status(self) -> np.ndarray:
        """Each tick's status in words (:attr:`Status.word <pinrate.Status.word>`, as the
        console says it and a servo trajectory keeps it), (N,) strings."""
        return converted(self._column(3), str)

    @property
    def detail(self) -> np.ndarray:
        """Each tick's reason in words, (N,) strings."""
        return converted(self._column(4), str)

    def frames(self, fps: float = 30.0) -> np.ndarray:
        """Configurations (F, nq) at ``fps`` frames per second of the recorded time (the
        last tick at or before each frame's time), the start first: what a replay draws.

        One frame per 1/fps from the first tick's time to the last's (at least one), after
        the start; so a single tick gives (start, its q), and zero ticks the start alone
        ((0, nq) without a start). InputError for an fps that is not positive or that would
        make more than :data:`~pinrate.checks.MAX_SAMPLES` frames.
        """
        fps = check_positive(fps, "fps")
        if not len(self):
            return np.zeros((0, self.nq)) if self.start is None else self.start[None, :].copy()
        times, q = self.times, self.q
        span = float(times[-1] - times[0])
        if span * fps > MAX_SAMPLES:
            raise InputError(
                f"{span:g} s at {fps:g} fps would be {span * fps:.3g} frames, over {MAX_SAMPLES}: lower fps"
            )
        moments = np.arange(times[0], times[-1] + 0.5 / fps, 1.0 / fps)
        picked = np.clip(np.searchsorted(times, moments, side="right") - 1, 0, len(times) - 1)
        first = q[:1] if self.start is None else self.start[None, :]
        return np.vstack([first, q[picked]])

    def save(self, path: str | os.PathLike[str]) -> Path:
        """Write the run as ``.npz`` (numbers and strings only: loads without pickle); zero
        ticks are saved as empty columns. InputError for a path that cannot be written."""
        target = check_output_file(path, "recording file")
        start = self.start if self.start is not None else np.zeros(0)
        with target.open("wb") as stream:
            np.savez_compressed(
                stream,
                format=np.array(FORMAT),
                robot=np.array(self.robot_name),
                joint_names=np.array(self.joint_names, dtype=str),
                dt=np.array(self.dt),
                start=start,
                times=self.times,
                q=self.q,
                joint_rates=self.joint_rates,
                status=self.status,
                detail=self.detail,
            )
        return target

    @classmethod
    def load(cls, path: str | os.PathLike[str]) -> Recording:
        """Read what :meth:`save` wrote, every column as it was saved. PinrateError naming
        the file when it is not a teleop recording; InputError when it cannot be read or its
        columns do not fit together (lengths, widths, times that decrease)."""
        try:
            with np.load(Path(path), allow_pickle=False) as data:
                version = str(data["format"])
                if version not in (FORMAT, _FIRST_FORMAT):
                    raise PinrateError(f"{path}: not a pinrate teleop recording (format {data['format']})")
                times = np.asarray(data["times"], dtype=float)
                q, rates = data["q"], data["joint_rates"]
                status, detail, start = data["status"], data["detail"], data["start"]
                recording = cls(None, float(data["dt"]), max_samples=max(1, times.size))
                robot_name, joint_names = str(data["robot"]), tuple(str(name) for name in data["joint_names"])
        except (OSError, KeyError, ValueError, zipfile.BadZipFile) as error:
            raise InputError(f"cannot read a teleop recording from {path}: {error}") from None
        count = times.size
        if times.ndim != 1 or q.ndim != 2 or rates.ndim != 2 or status.ndim != 1 or detail.ndim != 1:
            raise InputError(f"{path}: the recording's columns have the wrong dimensions")
        if not len(q) == len(rates) == len(status) == len(detail) == count:
            raise InputError(f"{path}: the recording's columns differ in length")
        if start.size and start.shape != (q.shape[1],):
            raise InputError(f"{path}: the start has {start.size} coordinates, the ticks {q.shape[1]}")
        if count and not (np.isfinite(times).all() and (np.diff(times) >= 0).all()):
            raise InputError(f"{path}: the recording's times are not finite and non-decreasing")
        recording.robot_name, recording.joint_names = robot_name, joint_names
        recording.nq, recording.nv = q.shape[1], rates.shape[1]
        if start.size:
            recording.start = np.array(start, dtype=float)
        if version == _FIRST_FORMAT:
            try:
                status = np.array([Status(str(value)).word for value in status], dtype=str)
            except ValueError as error:
                raise InputError(f"{path}: {error}") from None
        for time, configuration, rate, word, reason in zip(times, q, rates, status, detail, strict=True):
            recording._ticks.append((float(time), configuration, rate, str(word), str(reason)))
        return recording


__all__ = ["FORMAT", "Recording"]
