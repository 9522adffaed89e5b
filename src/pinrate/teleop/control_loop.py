"""The console's control thread (:mod:`pinrate.teleop.server` starts it; its module says
how the three threads share the work): :meth:`Teleop.tick` at the controller's rate (1/dt),
sleeping to absolute deadlines, the buttons' actions between ticks (:mod:`.actions`), and
the dead man for a controlling page that is gone, silent or frozen.

A late wake-up runs the missed ticks, each at its own time, for at most :data:`MAX_CATCH_UP`
of them, and a batch yields to a button pressed meanwhile (:mod:`.pacing`); however late, a
share of the time worked is slept. An exception in a tick halts the robot
(:meth:`.Actions.failed`) and the loop goes on.
"""

from __future__ import annotations

import threading
import time

import numpy as np

from .actions import Actions
from .pacing import BATCH_LIMIT, MIN_SLEEP, YIELD_SHARE, LoopStats, request_realtime
from .protocol import Pages
from .session import Teleop

MAX_CATCH_UP = 0.1
"""Seconds of missed ticks a late control loop runs at once; beyond, the motion waits."""


class ControlLoop:
    """The control thread's loop of one console (:meth:`run` is the thread).

    Args:
        teleop: what the loop ticks; its controller's dt sets the loop's rate.
        pages: the pages connected: the requests of their buttons, who controls, when it
            last spoke, the ``seq`` of its last input.
        actions: what the buttons do, run between ticks.
        stats: the loop's wake-up statistics, which it adds to.
        realtime_priority: the ``SCHED_FIFO`` priority the thread asks for
            (:func:`~.pacing.request_realtime`), or None.
        running: set while the console runs; the loop ends when it is cleared.
        changed: set to ask the render thread for a fresh frame.

    Attributes:
        scheduling: what the thread runs under, in words (once it started).
        scheduled: set once the thread has asked for its scheduling.
        applied_seq: the ``input_seq`` the last ticks applied (the frames say it).
        state_version: counts the wake-ups whose ticks moved the robot or changed its
            status (the render thread sends the links' poses again then).
    """

    def __init__(
        self,
        teleop: Teleop,
        pages: Pages,
        actions: Actions,
        stats: LoopStats,
        *,
        realtime_priority: int | None,
        running: threading.Event,
        changed: threading.Event,
    ) -> None:
        self.teleop = teleop
        self.pages = pages
        self.actions = actions
        self.stats = stats
        self.realtime_priority = realtime_priority
        self.running = running
        self.changed = changed
        self.scheduling = ""
        self.scheduled = threading.Event()
        self.applied_seq = 0
        self.state_version = 0

    def run(self) -> None:
        """Tick until ``running`` is cleared."""
        self.scheduling = request_realtime(self.realtime_priority)
        self.scheduled.set()
        teleop, pages = self.teleop, self.pages
        period = teleop.controller.dt
        started = time.monotonic()
        deadline = started
        last_wake = started
        owed = 0.0
        while self.running.is_set():
            self.actions.run_pending()
            if teleop.controller.dt != period:  # a new controller: keep its rate
                period = teleop.controller.dt
            now = time.monotonic()
            self.stats.add(now - last_wake)
            owed += now - last_wake
            last_wake = now
            ticks = int(owed / period + 1e-9)
            limit = max(1, int(MAX_CATCH_UP / period))
            if ticks > limit:
                ticks, owed = limit, limit * period
            applied_seq = pages.input_seq
            before = teleop.q
            before_status = None if teleop.last is None else teleop.last.status
            done = 0
            try:
                for tick in range(ticks):  # each missed tick at its own time (the recording's times)
                    teleop.tick(now - (ticks - 1 - tick) * period)
                    done += 1
                    # A long batch yields: a button pressed meanwhile (STOP) comes first.
                    if time.monotonic() - now > BATCH_LIMIT or not pages.requests.empty():
                        break
            except Exception as error:  # a bug: the robot halts, the console goes on
                self.actions.failed(error)
                done = ticks
            owed -= done * period
            self.applied_seq = applied_seq
            if ticks and (
                not np.array_equal(teleop.q, before) or teleop.last is None or teleop.last.status is not before_status
            ):
                self.state_version += 1
                self.changed.set()
            silent = pages.controller is None or now - pages.last_heard > teleop.timeout
            # The freeze rule is a controlling page's: a caller driving the Teleop from Python
            # with no page connected is not frozen.
            frozen = pages.controller is not None and now - pages.main_heard > pages.freeze_limit
            if frozen and not teleop.reversing and teleop.dead_man_stop(pages.frozen):
                self.changed.set()  # on this clock, not at the next heartbeat: a late one is no delay
            if (silent or frozen) and teleop.reversing:
                why = (
                    "gone"
                    if pages.controller is None
                    else f"silent for {teleop.timeout:g} s"
                    if silent
                    else f"frozen: its main thread silent for {pages.freeze_limit:g} s"
                )
                teleop.dead_man_stop(f"reversal stopped: the controlling page is {why}")
                pages.event(f"reversal stopped: the controlling page is {why}", "warning")
                self.changed.set()
            deadline += period
            finished = time.monotonic()
            delay = deadline - finished
            # However late, a share of the time worked is slept: a real-time thread never
            # takes a core whole (pacing's docstring).
            time.sleep(max(delay, MIN_SLEEP, YIELD_SHARE * (finished - now)))
            if delay < -MAX_CATCH_UP:
                deadline = time.monotonic()  # far behind: start afresh rather than race


__all__ = ["MAX_CATCH_UP", "ControlLoop"]
