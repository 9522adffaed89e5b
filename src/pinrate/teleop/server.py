"""The teleop console: one process, one port, three threads around a :class:`~.session.Teleop`.

    with TeleopServer(Teleop(robot, dt=0.002)) as server:   # binds 127.0.0.1
        print(server.url)                                   # open it: keyboard or gamepad drive the hand
        server.wait()                                       # until Ctrl-C

- **web** (its own asyncio loop, tornado): serves the page, meshcat's own ``main.min.js``
  and the recordings (:mod:`.handlers`), and one WebSocket per page (:mod:`.protocol`: the
  scene's commands when it connects, then one JSON frame per render tick; the page's
  heartbeat, stamped with its clock and its main thread's last sign of life; who controls).
  Who may connect is :mod:`.access`'s rule (Host and Origin on every request and handshake,
  a token off loopback, no framing). The first page controls; the others watch until the
  control is free and they take it. What one client can cost is capped: :data:`MAX_PAGES`
  sockets, :data:`MAX_CONNECTIONS` HTTP connections (the oldest goes first),
  :data:`HEADER_TIMEOUT` to send a request's headers, :data:`MESSAGE_RATE` messages a
  second; the scene is encoded once and sent to each page one chunk at a time, and a page
  still busy with a frame skips the next.
- **control** (:mod:`.control_loop`): :meth:`Teleop.tick` at the controller's rate (1/dt),
  sleeping to absolute deadlines; a late wake-up runs the missed ticks (at most 0.1 s of
  them), so the motion follows the wall clock. Buttons reach it through a queue (:mod:`.actions` does them), so
  only this thread touches the Teleop and the robot's ``pin.Data``. A controlling page that
  is gone or silent for longer than the Teleop's timeout stops the robot (the dead man; a
  reversal too), one whose main thread is silent for :data:`FREEZE_LIMIT` too, and every
  frame then says why (``dead_man``, :attr:`.Teleop.dead_man`) until the operator drives
  again. A command is aged from when the page sent it, not from when it was read, so a
  backlog never keeps the robot moving. An exception in a tick halts the robot, is said
  once on the page and in the terminal, and the console goes on (resume is the operator's
  decision).
- **render**: at most ``render_rate`` frames per second (:mod:`.readout` says what a frame
  holds), only when something changed, each link's pose from the viewer's own ``pin.Data``;
  a page still busy with the last frame skips this one.

While a console runs, the interpreter's thread switch interval is 0.2 ms
(:data:`SWITCH_INTERVAL`), so the other threads cannot hold the control loop off for
CPython's default 5 ms.

Threads are daemons and nothing else is started: a killed process leaves no child and no
port behind.
"""

from __future__ import annotations

import asyncio
import contextlib
import json
import socket
import sys
import threading
import time
import warnings
from pathlib import Path
from typing import Any

import numpy as np
import pinocchio as pin
import tornado.netutil

from ..checks import check_output_folder, check_positive
from ..errors import InputError, PinrateError
from ..viewer.server import check_host
from .access import AccessPolicy
from .actions import REPLAY_FPS as REPLAY_FPS
from .actions import Actions, Recordings
from .control_loop import MAX_CATCH_UP as MAX_CATCH_UP
from .control_loop import ControlLoop
from .handlers import HEADER_TIMEOUT as HEADER_TIMEOUT
from .handlers import MAX_CONNECTIONS as MAX_CONNECTIONS
from .handlers import STATIC as STATIC
from .handlers import console_files, web_server
from .pacing import REALTIME_PRIORITY, LoopStats
from .protocol import CLOCK_DRIFT as CLOCK_DRIFT
from .protocol import FLOOD_LIMIT as FLOOD_LIMIT
from .protocol import FREEZE_LIMIT as FREEZE_LIMIT
from .protocol import JOG_SHARE, Pages, PageSocket
from .protocol import MAX_PAGES as MAX_PAGES
from .protocol import MESSAGE_BURST as MESSAGE_BURST
from .protocol import MESSAGE_RATE as MESSAGE_RATE
from .readout import Readout
from .session import Teleop

RENDER_RATE = 60.0
"""Frames per second sent to the pages at most."""

SWITCH_INTERVAL = 2e-4
"""Seconds a thread holding the GIL runs before a waiting one may take it, while a console
runs (CPython's default, 5 ms, lets the render or web thread delay a 1 kHz tick by up to
5 ms; restored on close)."""


class TeleopServer:
    """The browser console for a :class:`Teleop` (see the module).

    Args:
        teleop: what the console drives; its controller's dt sets the loop's rate.
        host: the address to listen on (127.0.0.1: this machine only). Another one (``0.0.0.0``:
            every interface) gets a random token in :attr:`url`, and a warning: whoever has
            that URL and reaches the address can drive the robot.
        port: the TCP port; 0 picks a free one.
        render_rate: frames per second sent to the pages at most.
        record_dir: folder where recorded runs are saved (``.npz`` and ``.html``); only the
            files this server writes there are served.
        token: the URL's token (see :class:`~.access.AccessPolicy`): None chooses (a random
            one off loopback, none on it).
        realtime_priority: the ``SCHED_FIFO`` priority the control thread asks for
            (:func:`~.pacing.request_realtime`; granted to root, ``CAP_SYS_NICE`` or an
            ``rtprio`` limit, else the thread runs as any other); None asks for nothing.

    Attributes:
        url: the console's URL: a real address, the port and the token when there is one.
        access: the :class:`~.access.AccessPolicy` every request and handshake passes.
        pages: the pages connected (:class:`~.protocol.Pages`).
        actions: what the buttons do (:class:`~.actions.Actions`).
        recordings: the recorded runs saved (:class:`~.actions.Recordings`).
        control_loop: the control thread's loop (:class:`~.control_loop.ControlLoop`).
    """

    def __init__(
        self,
        teleop: Teleop,
        *,
        host: str = "127.0.0.1",
        port: int = 0,
        render_rate: float = RENDER_RATE,
        record_dir: str | Path = ".",
        token: str | None = None,
        realtime_priority: int | None = REALTIME_PRIORITY,
    ) -> None:
        if not isinstance(teleop, Teleop):
            raise InputError(f"TeleopServer takes a pinrate.Teleop, not {type(teleop).__name__}")
        self.teleop = teleop
        self.robot = teleop.robot
        with warnings.catch_warnings():  # check_host's warning speaks of a viewer; ours follows
            warnings.simplefilter("ignore")
            self.host = check_host(host)
        if isinstance(port, bool) or not isinstance(port, int) or not 0 <= port <= 65535:
            raise InputError(f"port must be an integer in [0, 65535], got {port!r}")
        self.render_rate = check_positive(render_rate, "render_rate")
        self.record_dir = check_output_folder(record_dir, "record folder")
        if realtime_priority is not None and (
            isinstance(realtime_priority, bool)
            or not isinstance(realtime_priority, int)
            or not 1 <= realtime_priority <= 99
        ):
            raise InputError(f"realtime_priority must be None or an integer in [1, 99], got {realtime_priority!r}")
        self.realtime_priority = realtime_priority
        self.stats = LoopStats()
        self.files = console_files()
        """The console's own files (content type, bytes), read once: all it serves besides
        the recordings."""
        self._running = threading.Event()
        self._changed = threading.Event()
        self._pose_lock = threading.Lock()
        self._pose_data = self.robot.model.createData()  # for callers of tip_pose, not the loop's

        self.readout = Readout(teleop, self.stats)
        self.viewer = self.readout.viewer

        try:
            sockets = tornado.netutil.bind_sockets(port, address=self.host, family=socket.AF_INET)
        except OSError as error:
            raise PinrateError(f"cannot listen on {self.host}:{port}: {error.strerror or error}") from None
        self._sockets = sockets
        self.port = int(sockets[0].getsockname()[1])
        try:
            self.access = AccessPolicy(self.host, self.port, token)
        except ValueError as error:
            for sock in sockets:
                sock.close()
            raise InputError(f"TeleopServer on {self.host}: {error}") from None
        self.url = self.access.url
        if not self.access.loopback:
            warnings.warn(
                f"the teleop console listens on {self.host}: whoever has its URL (it carries a token) "
                "and can reach this machine can drive the robot",
                stacklevel=2,
            )
        self.pages = Pages(
            teleop,
            scene=self.readout.scene,
            jog_gauges=self.readout.jog_gauges,
            hello=self._hello,
            running=self._running,
            changed=self._changed,
        )
        self.recordings = Recordings(
            self.record_dir, robot=self.robot.name, viewer=self.viewer, token=self.access.token, say=self.pages.event
        )
        self.actions = Actions(teleop, self.pages, self.recordings)
        self.control_loop = ControlLoop(
            teleop,
            self.pages,
            self.actions,
            self.stats,
            realtime_priority=realtime_priority,
            running=self._running,
            changed=self._changed,
        )
        self._web_ready = threading.Event()
        self._threads = [
            threading.Thread(target=self._serve, name="pinrate-teleop-web", daemon=True),
            threading.Thread(target=self.control_loop.run, name="pinrate-teleop-control", daemon=True),
            threading.Thread(target=self._render, name="pinrate-teleop-render", daemon=True),
        ]
        self._switch_interval = sys.getswitchinterval()
        sys.setswitchinterval(min(self._switch_interval, SWITCH_INTERVAL))
        self._running.set()
        for thread in self._threads:
            thread.start()
        if not self._web_ready.wait(10.0):
            self.close()
            raise PinrateError("the teleop web server did not start within 10 s")
        self.control_loop.scheduled.wait(5.0)

    # ------------------------------------------------------------------ life
    def __enter__(self) -> TeleopServer:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    @property
    def rate(self) -> float:
        """The control loop's rate (Hz): 1 / the controller's dt."""
        return 1.0 / self.teleop.controller.dt

    @property
    def scheduling(self) -> str:
        """What the control thread runs under, in words (once it started)."""
        return self.control_loop.scheduling

    def wait(self) -> None:
        """Block until :meth:`close` (or Ctrl-C in the calling thread)."""
        while self._running.is_set():
            time.sleep(0.2)

    def close(self) -> None:
        """Stop the threads and free the port; a run being recorded is saved first."""
        if not self._running.is_set():
            return
        self._running.clear()
        for thread in self._threads[1:]:
            if thread.is_alive() and thread is not threading.current_thread():
                thread.join(timeout=5)
        if self.teleop.recording:
            self.recordings.save(self.teleop.stop_recording())
        self.recordings.join(timeout=60)  # a save started just before: its files are written whole
        loop = self.pages.loop
        if loop is not None and loop.is_running():
            loop.call_soon_threadsafe(loop.stop)
        if self._threads[0].is_alive():
            self._threads[0].join(timeout=5)
        for sock in self._sockets:
            with contextlib.suppress(OSError):
                sock.close()
        sys.setswitchinterval(self._switch_interval)

    # ------------------------------------------------------------------ what callers read
    @property
    def saved(self) -> list[Path]:
        """The files recordings wrote, in order."""
        return self.recordings.saved

    @property
    def served(self) -> dict[str, Path]:
        """What ``/recordings/NAME`` may return: the files this server wrote, by name."""
        return self.recordings.served

    @property
    def mode(self) -> str:
        """What the keys and sticks command: ``"twist"`` (the hand) or ``"uncoupled"``
        (Barker's arm/wrist mode; see :meth:`.Teleop.command`); the page's mode switch."""
        return self.pages.mode

    @property
    def freeze_limit(self) -> float:
        """s of main-thread silence that stop the robot (:data:`FREEZE_LIMIT`, or the
        Teleop's timeout when longer)."""
        return self.pages.freeze_limit

    @property
    def clients(self) -> int:
        """Pages connected now."""
        return len(self.pages.clients)

    def snapshot(self) -> tuple[np.ndarray, Any]:
        """(q, last step) as the control loop left them (a copy of q)."""
        return self.teleop.q.copy(), self.teleop.last

    def tip_pose(self, q: np.ndarray | None = None) -> np.ndarray:
        """The tip's 4x4 pose in the world at q (default: the current one), computed on a
        ``pin.Data`` of its own, so it is safe beside the running loop."""
        return self._frame_pose(self.robot.tip_id, q)

    def sensor_pose(self, q: np.ndarray | None = None) -> np.ndarray:
        """The sensor's 4x4 pose in the world at q (its axes are the hand axes)."""
        return self._frame_pose(self.robot.sensor_id, q)

    def _frame_pose(self, frame_id: int, q: np.ndarray | None) -> np.ndarray:
        q = self.teleop.q.copy() if q is None else np.asarray(q, dtype=float)
        with self._pose_lock:
            pin.framesForwardKinematics(self.robot.model, self._pose_data, q)
            return np.array(self._pose_data.oMf[frame_id].homogeneous)

    def act(self, action: str, **arguments: Any) -> None:
        """Queue a button's action for the control loop (what a page's button sends):
        ``halt``, ``resume``, ``reverse``, ``home``, ``record`` (on=True/False), ``frame``
        (frame="hand"/"base"), ``mode`` (mode="twist"/"uncoupled"), ``configure``
        (singularity=..., wrist=...)."""
        self.pages.requests.put((action, arguments, None))

    # ------------------------------------------------------------------ web thread
    def _serve(self) -> None:
        loop = asyncio.new_event_loop()
        asyncio.set_event_loop(loop)
        self.pages.loop = loop
        socket_handler = (PageSocket, {"access": self.access, "pages": self.pages})
        http = web_server(self.access, self.files, self.served, socket_handler)
        http.add_sockets(self._sockets)
        loop.call_soon(self._web_ready.set)
        try:
            loop.run_forever()
        finally:
            http.stop()
            for client in list(self.pages.clients):
                with contextlib.suppress(Exception):
                    client.close()
            with contextlib.suppress(Exception):
                loop.run_until_complete(asyncio.sleep(0))
            loop.close()

    def _hello(self, client: int) -> dict[str, Any]:
        return self.readout.hello(
            client=client,
            rate=self.rate,
            scheduling=self.scheduling,
            freeze_limit=self.freeze_limit,
            jog_share=JOG_SHARE,
        )

    # ------------------------------------------------------------------ render thread
    def _render(self) -> None:
        interval = 1.0 / self.render_rate
        last_stats = 0.0
        shown_version = -1
        while self._running.is_set():
            started = time.monotonic()
            self._changed.wait(timeout=0.5)
            self._changed.clear()
            if not self._running.is_set():
                return
            if self.pages.clients:
                version = self.control_loop.state_version
                poses = version != shown_version or started - last_stats > 1.0
                frame = self.readout.frame(poses=poses, mode=self.pages.mode, input_seq=self.control_loop.applied_seq)
                shown_version = version
                last_stats = started
                loop = self.pages.loop
                if loop is not None:
                    with contextlib.suppress(RuntimeError):
                        loop.call_soon_threadsafe(self.pages.broadcast, json.dumps(frame))
            spare = interval - (time.monotonic() - started)
            if spare > 0:
                time.sleep(spare)


# The constants of the modules below, as this module had them (pinrate.teleop.server.MAX_PAGES),
# are imported above "as" themselves: re-exported.
__all__ = ["LoopStats", "TeleopServer", "check_host"]
