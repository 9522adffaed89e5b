"""A teleoperated run, tick by tick: saved and loaded as ``.npz`` (the viewer turns it into a
standalone HTML replay, :meth:`pinrate.viewer.Viewer.save_html`)."""

from __future__ import annotations

import os
import zipfile
from collections import deque
from pathlib import Path

import numpy as np

from ..checks import check_count, check_output_file
from ..control.controller import Step
from ..errors import InputError, PinrateError
from ..kinematics.manipulator import Robot

FORMAT = "pinrate-teleop-1"
"""The ``format`` entry of a saved recording: what :meth:`Recording.load` reads."""


class Recording:
    """Every tick of a teleoperated run.

    Attributes (as arrays, oldest first):
        times: wall time of each tick (s, the clock the ticks were given), (N,).
        q: the configuration after each tick (N, nq); ``start`` is the one before the first.
        joint_rates: the rates applied at each tick (N, nv), rad/s or m/s.
        status: each tick's :class:`~pinrate.Status` value, (N,) strings.
        detail: each tick's reason in words, (N,) strings.
    """

    def __init__(self, robot: Robot | None, dt: float, *, max_samples: int = 2_000_000) -> None:
        self.robot_name = robot.name if robot is not None else ""
        self.joint_names = tuple(robot.joint_names) if robot is not None else ()
        self.dt = float(dt)
        self.max_samples = check_count(max_samples, "max_samples", minimum=1)
        self.start: np.ndarray | None = None
        self._ticks: deque[tuple[float, np.ndarray, np.ndarray, str, str]] = deque(maxlen=self.max_samples)

    def __len__(self) -> int:
        return len(self._ticks)

    def add_start(self, q: np.ndarray) -> None:
        self.start = np.array(q, dtype=float)

    def add(self, time: float, step: Step) -> None:
        """Keep one tick (the oldest goes when ``max_samples`` are held)."""
        self._ticks.append((time, step.q, step.joint_rates, step.status.value, step.detail))

    def _column(self, index: int) -> list:
        return [tick[index] for tick in self._ticks]

    @property
    def times(self) -> np.ndarray:
        return np.array(self._column(0), dtype=float)

    @property
    def q(self) -> np.ndarray:
        return np.array(self._column(1), dtype=float).reshape(len(self), -1)

    @property
    def joint_rates(self) -> np.ndarray:
        return np.array(self._column(2), dtype=float).reshape(len(self), -1)

    @property
    def status(self) -> np.ndarray:
        return np.array(self._column(3), dtype=str)

    @property
    def detail(self) -> np.ndarray:
        return np.array(self._column(4), dtype=str)

    def frames(self, fps: float = 30.0) -> np.ndarray:
        """Configurations (F, nq) at ``fps`` frames per second of the recorded wall time
        (the last tick before each frame's time), the start first: what a replay draws."""
        if not len(self):
            return np.zeros((0, 0)) if self.start is None else self.start[None, :]
        times, q = self.times, self.q
        moments = np.arange(times[0], times[-1] + 0.5 / fps, 1.0 / fps)
        picked = np.clip(np.searchsorted(times, moments, side="right") - 1, 0, len(times) - 1)
        first = q[:1] if self.start is None else self.start[None, :]
        return np.vstack([first, q[picked]])

    def save(self, path: str | os.PathLike[str]) -> Path:
        """Write the run as ``.npz`` (numbers and strings only: loads without pickle)."""
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
        """Read what :meth:`save` wrote; PinrateError naming the file when it is not one."""
        try:
            with np.load(Path(path), allow_pickle=False) as data:
                if str(data["format"]) != FORMAT:
                    raise PinrateError(f"{path}: not a pinrate teleop recording (format {data['format']})")
                recording = cls(None, float(data["dt"]), max_samples=max(1, data["times"].size))
                recording.robot_name = str(data["robot"])
                recording.joint_names = tuple(str(name) for name in data["joint_names"])
                if data["start"].size:
                    recording.start = np.array(data["start"], dtype=float)
                columns = (data["times"], data["q"], data["joint_rates"], data["status"], data["detail"])
                for time, q, rates, status, detail in zip(*columns, strict=True):
                    recording._ticks.append((float(time), q, rates, str(status), str(detail)))
        except (OSError, KeyError, ValueError, zipfile.BadZipFile) as error:
            raise InputError(f"cannot read a teleop recording from {path}: {error}") from None
        return recording


__all__ = ["FORMAT", "Recording"]
