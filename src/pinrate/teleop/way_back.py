"""The operator's way back (Barker 1983, "recording and reversing a motion"): the motion a
:class:`~pinrate.teleop.session.Teleop` recorded, on its motion clock, and the reversal that
retraces it (a :class:`~pinrate.control.recorder.Playback` of the
:class:`~pinrate.control.recorder.Recorder`).

The record holds only motion: each tick that moves the robot advances the motion clock by
dt, idle ticks do not. When a reversal ends, however it ends, the record is cut back to where
the robot is, so that a later reversal goes on from there; a mark made during the reversal
(:attr:`WayBack.mark_due`) clears the record instead, then."""

from __future__ import annotations

import math

import numpy as np

from ..control.controller import Step
from ..control.recorder import Playback, Recorder


class WayBack:
    """One Teleop's record and its reversal.

    Args:
        history: s of motion kept.

    Attributes:
        clock: the motion clock (s), advanced by dt on each tick that moves the robot;
            the record's newest sample, when there is one, is at it.
        playback: the reversal running, or None.
        reversed_at: the ``now`` (s) of the :meth:`~.session.Teleop.reverse` call the
            reversal serves: only a command dated after it ends the reversal.
        mark_due: a mark made during the reversal, applied when it ends.
    """

    def __init__(self, history: float) -> None:
        self.recorder = Recorder(history)
        """The motion kept (times on the motion clock, s)."""
        self.clock = 0.0
        self.playback: Playback | None = None
        self.reversed_at = -math.inf
        self.mark_due = False

    def record(self, q: np.ndarray, next_q: np.ndarray, dt: float) -> None:
        """A tick moved the robot from ``q`` to ``next_q``: the clock advances by ``dt``
        (``q`` is recorded first when the record is empty)."""
        if not len(self.recorder):
            self.recorder.record(self.clock, q)
        self.clock += dt
        self.recorder.record(self.clock, next_q)

    def mark(self) -> None:
        """Start a new segment here: the record is cleared (during a reversal, when it ends)."""
        if self.playback is not None:
            self.mark_due = True
        else:
            self.recorder.clear()

    def clear(self) -> None:
        """Forget the record and a mark waiting for a reversal's end."""
        self.recorder.clear()
        self.mark_due = False

    def step(self, q: np.ndarray) -> Step:
        """The reversal's step from ``q``; the reversal ends when it is back at its start."""
        playback = self.playback
        assert playback is not None
        step = playback.step(q)
        if playback.done:
            self.end(step.q)
        return step

    def end(self, q: np.ndarray) -> None:
        """Forget what the playback retraced, so the record ends at ``q``, where the robot is
        (the record alone, once it has come all the way back); or, when a mark waited for
        the end, forget the whole record: the new segment starts here.

        The record is not changed while a playback runs (no operator step records, mark
        waits, reset and configure end or keep the playback first), so its newest sample is
        where the playback began and ``elapsed`` counts back from it.
        """
        playback = self.playback
        if playback is None:
            return
        self.playback = None
        if self.mark_due:
            self.mark_due = False
            self.recorder.clear()
            return
        if not len(self.recorder):
            return
        times = self.recorder.times
        oldest, newest = float(times[0]), float(times[-1])
        completed = playback.done and not playback.stopped  # then newest - elapsed may round past oldest
        reached = oldest if completed else max(oldest, newest - playback.elapsed)
        self.recorder.truncate(reached)
        self.clock = reached
        self.recorder.record(reached, q)


__all__ = ["WayBack"]
