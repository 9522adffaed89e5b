"""The console control loop's pace: its wake-up statistics and its place in the OS scheduler.

A 1 kHz loop in Python sleeps to absolute deadlines; how late it wakes is the OS's decision.
On a machine whose cores a browser's software rendering keeps busy, an ordinary thread waits
behind it for milliseconds (measured: p99 4.7 ms on a 2-core VM, where a bare sleeping loop in
the same conditions does no better). A real-time thread does not: :func:`request_realtime`
asks for ``SCHED_FIFO`` for the calling thread, as ros2_control's controller manager does,
where the OS allows it (root, ``CAP_SYS_NICE``, or an ``rtprio`` limit in
``/etc/security/limits.conf``), and says what it got. Such a thread must never take a core
whole, or the web thread, which carries STOP, would wait behind it: a wake-up runs missed
ticks for at most :data:`BATCH_LIMIT`, stops them when a button was pressed, and then sleeps
at least :data:`YIELD_SHARE` of the time it worked (:data:`MIN_SLEEP` at the least).
"""

from __future__ import annotations

import contextlib
import os
import threading
from collections import deque

import numpy as np

STATS_WINDOW = 2.0
"""Seconds of control-loop periods the rate and p99 on the page are measured over."""

REALTIME_PRIORITY = 50
"""``SCHED_FIFO`` priority asked for the control thread (1-99; ros2_control's default)."""

MIN_SLEEP = 1e-4
"""s: the least the control loop sleeps at each wake-up, even when it is behind."""

BATCH_LIMIT = 0.01
"""s: the most a wake-up spends running missed ticks; the rest wait for the next wake-up
(a button pressed meanwhile is taken before them)."""

YIELD_SHARE = 0.25
"""After each wake-up the loop sleeps at least this share of the time it just worked: a
loop whose ticks outlast their period still leaves a core a fifth of its time, so the web
thread, which carries STOP, runs within about :data:`BATCH_LIMIT` on one core too."""


def leave_realtime() -> None:
    """Put the calling thread back under normal scheduling (a thread started by the real-time
    control thread inherits its policy: a recording's save must not run at its priority)."""
    if hasattr(os, "sched_setscheduler"):
        with contextlib.suppress(OSError):  # not permitted, or already normal: nothing to leave
            os.sched_setscheduler(0, os.SCHED_OTHER, os.sched_param(0))


def request_realtime(priority: int | None = REALTIME_PRIORITY) -> str:
    """Put the calling thread under ``SCHED_FIFO`` at ``priority`` where the OS permits;
    return what it runs under, in words (for the terminal and the page). ``None``: ask for
    nothing. Never raises: a refusal leaves the thread as it was."""
    if priority is None:
        return "normal scheduling (real-time not asked for)"
    if not hasattr(os, "sched_setscheduler"):
        return "normal scheduling (this OS has no SCHED_FIFO)"
    try:
        os.sched_setscheduler(0, os.SCHED_FIFO, os.sched_param(priority))  # 0: this thread (Linux)
    except OSError as error:
        return (
            f"normal scheduling (SCHED_FIFO {priority} refused: {error.strerror}; "
            "an rtprio limit or CAP_SYS_NICE allows it)"
        )
    return f"real-time scheduling (SCHED_FIFO, priority {priority})"


class LoopStats:
    """The control loop's recent wake-up periods (s): rate, median and p99."""

    def __init__(self, capacity: int = 200_000) -> None:
        self.periods: deque[float] = deque(maxlen=capacity)
        self._lock = threading.Lock()

    def add(self, period: float) -> None:
        with self._lock:
            self.periods.append(period)

    def recent(self, seconds: float) -> np.ndarray:
        """The periods of the last ``seconds`` of loop time, oldest first."""
        with self._lock:
            periods = list(self.periods)
        total, count = 0.0, 0
        for period in reversed(periods):
            total += period
            count += 1
            if total >= seconds:
                break
        return np.array(periods[len(periods) - count :])

    def summary(self, seconds: float = STATS_WINDOW) -> dict[str, float]:
        periods = self.recent(seconds)
        if not periods.size:
            return {"rate": 0.0, "median_ms": 0.0, "p99_ms": 0.0}
        return {
            "rate": float(periods.size / periods.sum()) if periods.sum() > 0 else 0.0,
            "median_ms": float(np.median(periods) * 1e3),
            "p99_ms": float(np.percentile(periods, 99) * 1e3),
        }


__all__ = [
    "BATCH_LIMIT",
    "MIN_SLEEP",
    "REALTIME_PRIORITY",
    "STATS_WINDOW",
    "YIELD_SHARE",
    "LoopStats",
    "leave_realtime",
    "request_realtime",
]
