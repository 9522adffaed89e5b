"""The operator's actions (the page's buttons, :meth:`.TeleopServer.act`) and the saving of
recorded runs.

:class:`Actions` runs on the control thread, which alone touches the Teleop and the robot's
``pin.Data``: stop, halt, resume, reverse, home, record, frame, mode, configure; what an
action refuses is said on the page that asked. A recorded run is saved by
:class:`Recordings` on a thread of its own, as ``.npz`` and as a standalone HTML replay (at
:data:`REPLAY_FPS`, from the console's own encoded scene, so the control loop is never held
off for long), under a new name in the record folder; only those files are served.
"""

from __future__ import annotations

import contextlib
import logging
import queue
import threading
import time
import traceback
from collections.abc import Callable
from datetime import datetime
from pathlib import Path
from typing import Any

from ..errors import InputError, PinrateError
from ..viewer import Viewer
from .pacing import leave_realtime
from .protocol import Pages
from .recording import Recording
from .session import MODES, Teleop

REPLAY_FPS = 30.0
"""Frames per second of a recording's HTML replay."""

LOG = logging.getLogger("pinrate.teleop")


class Recordings:
    """The recorded runs one console saves, and what it may serve of them.

    Args:
        record_dir: the folder the files go to.
        robot: the robot's name (in the files' names).
        viewer: the console's viewer, whose encoded scene the HTML replay reuses.
        token: the console's URL token, or None (in the links to the files).
        say: how the pages are told (:meth:`.Pages.event`).

    Attributes:
        saved: the files written, in order.
        served: what ``/recordings/NAME`` may return: the files written, by name.
    """

    def __init__(
        self, record_dir: Path, *, robot: str, viewer: Viewer, token: str | None, say: Callable[..., None]
    ) -> None:
        self.record_dir = record_dir
        self.robot = robot
        self.viewer = viewer
        self.token = token
        self.say = say
        self.saved: list[Path] = []
        self.served: dict[str, Path] = {}
        self._saving: list[threading.Thread] = []
        self._lock = threading.Lock()

    def start(self, recording: Recording) -> None:
        """Save a run on a thread of its own (the control loop goes on)."""
        saving = threading.Thread(target=self.save, args=(recording,), name="pinrate-teleop-save", daemon=True)
        self._saving = [thread for thread in self._saving if thread.is_alive()] + [saving]
        saving.start()

    def join(self, timeout: float = 60.0) -> None:
        """Wait for the saves started: their files are written whole."""
        for saving in list(self._saving):
            saving.join(timeout=timeout)

    def save(self, recording: Recording) -> None:
        """Write a recorded run as .npz and as a standalone HTML replay; tell the pages."""
        leave_realtime()  # started by the control thread: not at its priority
        try:
            with self._lock:  # one save at a time: the names stay unique
                self._write(recording)
        except Exception as error:  # said, never a dead thread's traceback
            self.say(f"the recording could not be saved: {error}", "error")
            LOG.error("the recording could not be saved", exc_info=error)

    def _write(self, recording: Recording) -> None:
        """Each file is written whole or not at all (:func:`~pinrate.files.replace_file`), so
        only whole files are served; a recording whose replay fails is still saved and said."""
        stem = self._stem()
        try:
            data = recording.save(stem.with_suffix(".npz"))
        except PinrateError as error:
            self.say(f"the recording could not be saved: {error}", "error")
            return
        self.saved.append(data)
        self.served[data.name] = data
        try:
            # The console's own scene, already encoded: no mesh is read again, and no step
            # holds the GIL long enough to delay the control loop's tick.
            page = self.viewer.save_replay(stem.with_suffix(".html"), recording.frames(REPLAY_FPS), fps=REPLAY_FPS)
        except PinrateError as error:
            self.say(
                f"saved {len(recording)} ticks: {data.name}; its replay could not be written: {error}",
                "error",
                links=[self.link(data.name)],
            )
            return
        self.saved.append(page)
        self.served[page.name] = page
        self.say(
            f"saved {len(recording)} ticks: {data.name}, {page.name}",
            links=[self.link(data.name), self.link(page.name)],
        )

    def _stem(self) -> Path:
        """A new file stem in the record folder, ``teleop-ROBOT-YYYYmmdd-HHMMSS[-N]``: no
        file of a recording (.npz, .html) has it yet, so two runs never overwrite each other."""
        stamp = datetime.now().strftime("%Y%m%d-%H%M%S")
        base = f"teleop-{self.robot}-{stamp}"
        for number in range(1, 10_000):
            stem = self.record_dir / (base if number == 1 else f"{base}-{number}")
            if not any(stem.with_suffix(suffix).exists() for suffix in (".npz", ".html")):
                return stem
        raise PinrateError(f"no free file name for a recording in {self.record_dir}")

    def link(self, name: str) -> str:
        """The page-relative URL of a recording file (with the token when there is one)."""
        return f"/recordings/{name}" + (f"?token={self.token}" if self.token else "")


class Actions:
    """What the operator's buttons do, run on the control thread (:meth:`run_pending`), and
    what a failure in that thread does (:meth:`failed`).

    Args:
        teleop: what the actions act on.
        pages: the pages, told what happened (and whose ``mode`` the mode switch sets).
        recordings: where a recorded run goes when the recording stops.
    """

    def __init__(self, teleop: Teleop, pages: Pages, recordings: Recordings) -> None:
        self.teleop = teleop
        self.pages = pages
        self.recordings = recordings
        self._failure = ""  # the last control-loop failure said, so that a repeat is said once

    def run_pending(self) -> None:
        """Do the actions the pages (and :meth:`.TeleopServer.act`) asked for, in order; what
        one refuses is said on the page that asked, a bug in one is a :meth:`failed`."""
        while True:
            try:
                action, data, client = self.pages.requests.get_nowait()
            except queue.Empty:
                return
            try:
                self.act(action, data)
            except PinrateError as error:
                self.pages.event(f"{action}: {error}", "error", client)
            except Exception as error:  # a bug: as for a tick
                self.failed(error)
            else:
                if action == "resume":
                    self._failure = ""
            self.pages.changed.set()

    def failed(self, error: BaseException) -> None:
        """A tick (or an action) raised: halt the robot, say so once on the pages and in the
        terminal (with the traceback there), and keep serving: the operator may resume or go
        home."""
        with contextlib.suppress(Exception):
            self.teleop.stop()
        try:
            self.teleop.halt()
        except Exception:  # halted whatever the Teleop's state
            self.teleop.halted = True
        text = f"the control loop failed ({type(error).__name__}: {error}); the robot is halted"
        if text != self._failure:
            self._failure = text
            LOG.error("%s\n%s", text, "".join(traceback.format_exception(error)).rstrip())
            self.pages.event(text, "error")
        self.pages.changed.set()

    def act(self, action: str, data: dict[str, Any]) -> None:
        """Do one action (``data``: its arguments, as a page sent them). Raises
        :class:`~pinrate.errors.InputError` for what it refuses."""
        teleop = self.teleop
        if action == "stop":
            reason = data.get("dead_man")
            if reason:
                teleop.dead_man_stop(str(reason))
            else:
                teleop.stop()
        elif action == "halt":
            teleop.halt()
        elif action == "resume":
            teleop.resume()
        elif action == "reverse":
            if not teleop.reverse(time.monotonic()):
                self.pages.event("nothing to reverse: no motion recorded since the last mark", "warning")
        elif action == "home":
            teleop.reset()
            self.pages.event("back at home")
        elif action == "record":
            if data.get("on", not teleop.recording):
                if not teleop.recording:
                    teleop.start_recording()
                    self.pages.event("recording")
            elif teleop.recording:
                recording = teleop.stop_recording()
                if not len(recording):
                    self.pages.event("recording stopped: no tick was recorded, nothing saved", "warning")
                    return
                self.recordings.start(recording)
        elif action == "frame":
            teleop.frame = str(data.get("frame"))
        elif action == "mode":
            mode = str(data.get("mode"))
            if mode not in MODES:
                raise InputError(f"mode must be one of {', '.join(MODES)}, not {mode!r}")
            if mode == "uncoupled" and not teleop.controller.index.m:
                raise InputError(
                    "the uncoupled mode moves the wrist centre: this partition controls no linear component"
                )
            self.pages.mode = mode
            self.pages.event(
                "keys and sticks: " + ("the hand" if mode == "twist" else "arm (wrist centre) and wrist joints")
            )
        elif action == "configure":
            options = {key: data[key] for key in ("singularity", "wrist") if key in data}
            teleop.configure(**options)
            self.pages.event("strategy: " + ", ".join(f"{key} {value}" for key, value in options.items()))
        else:
            raise InputError(f"unknown action {action!r}")


__all__ = ["REPLAY_FPS", "Actions", "Recordings"]
