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
from collections import deque
from pathlib import Path
from typing import Any

import numpy as np

from ..checks import MAX_SAMPLES, PHYSICAL_BOUND, check_count, check_positive
from ..control.controller import Step
from ..control.status import Status
from ..errors import InputError
from ..files import MAX_LOAD_BYTES, NUMBERS, open_npz, replace_file
from ..kinematics.manipulator import Robot

FORMAT = "pinrate-teleop-2"
"""The ``format`` entry of a saved recording: what :meth:`Recording.load` reads (it reads
``pinrate-teleop-1`` too, whose status column held :class:`~pinrate.Status` values instead of
their words)."""

_FIRST_FORMAT = "pinrate-teleop-1"


CHUNK = 2048
"""Ticks converted to an array at a time (see ``_converted``)."""


def _converted(values: list, dtype: type) -> np.ndarray:
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

    def add(self, time: float, step: Step, q: np.ndarray | None = None) -> None:
        """Keep one tick at ``time`` (s; one earlier than the newest tick's is kept at the
        newest's, so ``times`` never decreases), copying ``q`` (default: the step's; a
        plant's measurement after it) and the step's rates; the oldest tick goes when
        ``max_samples`` are held. InputError for a time that is not finite."""
        stamp = float(time)
        if not math.isfinite(stamp):
            raise InputError(f"a tick's time must be finite, got {stamp}")
        if self._ticks and stamp < self._ticks[-1][0]:
            stamp = self._ticks[-1][0]
        q = np.array(step.q if q is None else q, dtype=float)
        rates = np.array(step.joint_rates, dtype=float)
        self._ticks.append((stamp, q, rates, step.status.word, step.detail))

    def _column(self, index: int) -> list:
        return [tick[index] for tick in self._ticks]

    def _rows(self, index: int, width: int) -> np.ndarray:
        if not self._ticks:
            return np.zeros((0, width))
        return _converted(self._column(index), float).reshape(len(self), -1)

    @property
    def times(self) -> np.ndarray:
        """The time of each tick (s), as given to :meth:`~.session.Teleop.tick`, (N,); never
        decreasing: a tick dated before the previous one is kept at the previous one's time."""
        return _converted(self._column(0), float)

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
        return _converted(self._column(3), str)

    @property
    def detail(self) -> np.ndarray:
        """Each tick's reason in words, (N,) strings."""
        return _converted(self._column(4), str)

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
        ticks are saved as empty columns. The file is written whole or not at all
        (:func:`~pinrate.files.replace_file`): a save that fails leaves the file it was
        replacing as it was. InputError naming the file for a path that cannot be written
        or a write that fails."""
        start = self.start if self.start is not None else np.zeros(0)
        columns: dict[str, Any] = {
            "format": np.array(FORMAT),
            "robot": np.array(self.robot_name),
            "joint_names": np.array(self.joint_names, dtype=str),
            "dt": np.array(self.dt),
            "start": start,
            "times": self.times,
            "q": self.q,
            "joint_rates": self.joint_rates,
            "status": self.status,
            "detail": self.detail,
        }
        return replace_file(path, "recording file", lambda stream: np.savez_compressed(stream, **columns))

    @classmethod
    def load(cls, path: str | os.PathLike[str], *, max_bytes: int = MAX_LOAD_BYTES) -> Recording:
        """Read what :meth:`save` wrote, every column as it was saved (format
        ``pinrate-teleop-2``, or ``-1`` with its :class:`~pinrate.Status` values read as
        their words).

        Read by :func:`~pinrate.files.open_npz`: a regular file only, every array's header
        checked before anything is read, and refused when reading it would take more than
        ``max_bytes`` (:data:`~pinrate.files.MAX_LOAD_BYTES`, 2 GiB; each tick counted with
        the :data:`TICK_OBJECT_BYTES` of the objects that hold it). Then every field is
        checked: times (N,) floats, finite and non-decreasing; q (N, nq) and joint_rates
        (N, nv) floats; start (nq,) floats or empty; every number finite within
        ±:data:`~pinrate.checks.PHYSICAL_BOUND` but the times (finite); status and detail
        (N,) text (status a :class:`~pinrate.Status` value in ``-1``); dt a positive finite
        number up to PHYSICAL_BOUND; robot one text; joint_names a list of non-empty
        printable names. A field more or fewer is refused.

        Raises:
            InputError: naming the file (and the field): a missing file or one that is not
                a regular file, not a teleop recording, too big, damaged, or whose fields do
                not hold what they must or do not fit together.
        """
        with open_npz(path, "recording file", max_bytes=max_bytes) as npz:
            if "format" not in npz.members:
                raise npz.refuse(f"is not a pinrate teleop recording (no format {FORMAT!r})")
            version = npz.text("format")
            if version not in (FORMAT, _FIRST_FORMAT):
                raise npz.refuse(f"is not a pinrate teleop recording: format {version[:80]!r}, not {FORMAT!r}")
            npz.fields(_FIELDS)
            (count,) = npz.shape("times", NUMBERS, 1)
            nq, nv = npz.shape("q", NUMBERS, 2)[1], npz.shape("joint_rates", NUMBERS, 2)[1]
            for name, shape in (("q", (count, nq)), ("joint_rates", (count, nv))):
                if npz.members[name].shape != shape:
                    raise npz.refuse(
                        f"has shape {npz.members[name].shape} for {count} ticks: the columns differ in length", name
                    )
            if count and not (nq and nv):
                raise npz.refuse(
                    f"has shape {npz.members['q' if not nq else 'joint_rates'].shape}: ticks without coordinates",
                    "q" if not nq else "joint_rates",
                )
            for name in ("status", "detail"):
                if npz.shape(name, "U", 1) != (count,):
                    raise npz.refuse(
                        f"has {npz.members[name].shape[0]} entries for {count} ticks: the columns differ in length",
                        name,
                    )
            if npz.shape("start", NUMBERS, 1) not in ((0,), (nq,)):
                raise npz.refuse(f"has {npz.members['start'].shape[0]} coordinates, the ticks {nq}", "start")
            npz.reserve(count * TICK_OBJECT_BYTES)
            dt = npz.number("dt")
            if not 0 < dt <= PHYSICAL_BOUND:
                raise npz.refuse(f"is {dt!r}: not a positive finite number up to {PHYSICAL_BOUND:g} s", "dt")
            times = npz.floats("times", 1, finite=False)
            if not np.isfinite(times).all():
                raise npz.refuse(f"holds {times[~np.isfinite(times)][0]!r}: times must be finite", "times")
            if count and (np.diff(times) < 0).any():
                raise npz.refuse(
                    f"decreases at tick {int(np.argmax(np.diff(times) < 0)) + 1}: times must be non-decreasing", "times"
                )
            q, rates, start = npz.floats("q", 2), npz.floats("joint_rates", 2), npz.floats("start", 1)
            status, detail = npz.texts("status"), npz.texts("detail")
            robot_name, joint_names = npz.text("robot"), tuple(npz.names("joint_names"))
            if version == _FIRST_FORMAT:
                unknown = sorted({value for value in status if value not in _STATUS_VALUES})
                if unknown:
                    raise npz.refuse(f"holds {unknown[0][:80]!r}, which no Status has", "status")
                status = [Status(value).word for value in status]
        recording = cls(None, dt, max_samples=max(1, count))
        recording.robot_name, recording.joint_names = robot_name, joint_names
        recording.nq, recording.nv = nq, nv
        if start.size:
            recording.start = start
        recording._ticks.extend(zip(times.tolist(), q, rates, status, detail, strict=True))
        return recording


_STATUS_VALUES = frozenset(status.value for status in Status)

_FIELDS = ("format", "robot", "joint_names", "dt", "start", "times", "q", "joint_rates", "status", "detail")

TICK_OBJECT_BYTES = 400
"""Bytes a loaded tick's objects take beyond its numbers and text (a tuple, a float, two
array views: about 335 measured), counted against ``max_bytes`` by :meth:`Recording.load`."""


__all__ = ["FORMAT", "Recording"]
