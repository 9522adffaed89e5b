"""The teleop console: one process, one port, three threads around a :class:`~.session.Teleop`.

    with TeleopServer(Teleop(robot, dt=0.002)) as server:   # binds 127.0.0.1
        print(server.url)                                   # open it: keyboard or gamepad drive the hand
        server.wait()                                       # until Ctrl-C

- **web** (its own asyncio loop, tornado): serves the page, meshcat's own ``main.min.js``
  and the recordings, and one WebSocket per page. The page builds the Meshcat viewer itself
  (no iframe: it would take the keyboard's focus) and receives the scene's commands, packed
  as meshcat's server sends them, when it connects; then one JSON frame per render tick.
  The page's socket lives in a dedicated worker (``static/heartbeat.js``), which sends the
  held keys, the gamepad and the speed slider every 50 ms (the heartbeat) and at every
  change (and a SpaceMouse's counts, read through WebHID, and the joint jog buttons held),
  each stamped with its clock (``sent``) and with when the page's main thread last
  spoke (``alive``): a main thread that rendering blocks for a second keeps the robot moving,
  one silent for :data:`FREEZE_LIMIT` stops it. Who may connect is
  :mod:`.access`'s rule (Host and Origin on every request and handshake, a token off
  loopback, no framing). The first page controls; the others watch until the control is
  free and they take it. What one client can cost is capped: :data:`MAX_PAGES` sockets,
  :data:`MAX_CONNECTIONS` HTTP connections (the oldest goes first), :data:`HEADER_TIMEOUT`
  to send a request's headers, :data:`MESSAGE_RATE` messages a second; the scene is encoded
  once and sent to each page one chunk at a time, and a page still busy with a frame skips
  the next.
- **control**: :meth:`Teleop.tick` at the controller's rate (1/dt), sleeping to absolute
  deadlines; a late wake-up runs the missed ticks (at most 0.1 s of them), so the motion
  follows the wall clock. Buttons reach it through a queue, so only this thread touches the
  Teleop and the robot's ``pin.Data``. A controlling page that is gone or silent for longer
  than the Teleop's timeout stops the robot (the dead man; a reversal too), one whose main
  thread is silent for :data:`FREEZE_LIMIT` too, and every frame then says why
  (``dead_man``, :attr:`.Teleop.dead_man`) until the operator drives again. A command is
  aged from when the page sent it, not from when it was read, so a backlog never keeps the
  robot moving. An exception in a tick halts the robot, is said once on the page and in the
  terminal, and the console goes on (resume is the operator's decision).
- **render**: at most ``render_rate`` frames per second, only when something changed, each
  link's pose from the viewer's own ``pin.Data``; a page still busy with the last frame
  skips this one.

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
import logging
import math
import queue
import socket
import sys
import threading
import time
import traceback
import warnings
from datetime import datetime
from pathlib import Path
from typing import Any

import numpy as np
import pinocchio as pin
import tornado.httpserver
import tornado.iostream
import tornado.netutil
import tornado.web
import tornado.websocket

from ..checks import check_output_folder, check_positive
from ..control.singularity import STRATEGIES, WRIST_STRATEGIES
from ..errors import InputError, PinrateError
from ..viewer import Viewer
from ..viewer.offline import MAIN_JS
from ..viewer.server import check_host
from .access import SECURITY_HEADERS, AccessPolicy
from .display import describe, joint_gauges, joint_values
from .mapping import KEYS, deflections
from .pacing import MIN_SLEEP, REALTIME_PRIORITY, LoopStats, request_realtime
from .recording import Recording
from .session import FRAMES, MODES, Teleop

STATIC = Path(__file__).parent / "static"
RENDER_RATE = 60.0
"""Frames per second sent to the pages at most."""

MAX_CATCH_UP = 0.1
"""Seconds of missed ticks a late control loop runs at once; beyond, the motion waits."""

REPLAY_FPS = 30.0
"""Frames per second of a recording's HTML replay."""

MAX_PAGES = 8
"""WebSocket clients (pages) connected at once; the next is refused (503)."""

MAX_CONNECTIONS = 64
"""HTTP connections open at once; a new one beyond closes the oldest (so half-sent requests
cannot lock the operator's page out)."""

HEADER_TIMEOUT = 10.0
"""Seconds a connection has to send a request's headers (and an idle keep-alive to stay)."""

MESSAGE_RATE = 100.0
"""Messages a second a page may send on average (its heartbeat is 20, plus one per change);
:data:`MESSAGE_BURST` at once. Beyond, messages are dropped; a page that keeps flooding for
:data:`FLOOD_LIMIT` dropped messages is disconnected."""

MESSAGE_BURST = 200.0
FLOOD_LIMIT = 1000

FREEZE_LIMIT = 1.5
"""s: how long the page's main thread may be silent while its heartbeat goes on (the page's
worker, static/heartbeat.js, stamps each message with ``alive``: when the main thread last
spoke) before the held command is zeroed and a reversal stopped (a frozen page: the keys it
holds may no longer be the operator's). A slow page, whose main thread rendering blocks for
up to a second a frame, keeps driving; a frozen one stops the robot this long (or the
Teleop's timeout when longer) after its main thread's last sign of life, which a page that is
not blocked gives every 50 ms and every animation frame. The control loop checks it on its
own clock, so a late heartbeat delays nothing; the Teleop's timeout still applies to the
heartbeat itself: a page gone or silent stops the robot within it."""

JOG_SHARE = 0.2
"""A joint's jog button held, at 100 % speed, jogs it at this share of its velocity limit
(of ``max_angular_speed`` or ``max_linear_speed`` when the model gives none)."""

CLOCK_DRIFT = 1e-3
"""s/s: how fast the estimated offset between a page's clock and the server's may grow
(clock rates differ by well under 1e-4 on NTP-disciplined machines)."""

LOG = logging.getLogger("pinrate.teleop")

SWITCH_INTERVAL = 2e-4
"""Seconds a thread holding the GIL runs before a waiting one may take it, while a console
runs (CPython's default, 5 ms, lets the render or web thread delay a 1 kHz tick by up to
5 ms; restored on close)."""


def _retrieved(future: Any) -> None:
    """Done callback of every write and task: its failure (a page gone) is read, so asyncio
    never reports it as never retrieved; a page gone mid-write is no error."""
    if not future.cancelled():
        future.exception()


class _Busy:
    """A page's pending write while its scene is still being sent: never done."""

    @staticmethod
    def done() -> bool:
        return False


def _listed(value: object) -> list[Any]:
    """A message's list field, or [] when it is anything else."""
    return list(value) if isinstance(value, list) else []


class _Guarded(tornado.web.RequestHandler):
    """Every response carries :data:`~.access.SECURITY_HEADERS`; every request must name this
    server in its Host header (DNS rebinding), and, where ``needs_token``, carry the token."""

    needs_token = False
    server: TeleopServer

    def initialize(self, server: TeleopServer) -> None:
        self.server = server

    def set_default_headers(self) -> None:
        for name, value in SECURITY_HEADERS.items():
            self.set_header(name, value)

    def prepare(self) -> None:
        policy = self.server.access
        if not policy.host_allowed(self.request.host):
            raise tornado.web.HTTPError(403, reason="Host not allowed")
        self.refuse_beyond_host(policy)

    def refuse_beyond_host(self, policy: AccessPolicy) -> None:
        """The checks after the Host's: the token, where ``needs_token``."""
        if self.needs_token and not policy.token_allowed(self.get_query_argument("token", None)):
            raise tornado.web.HTTPError(403, reason="this console needs the URL it printed, with its token")

    def write_error(self, status_code: int, **kwargs: Any) -> None:
        self.set_header("Content-Type", "text/plain; charset=utf-8")
        self.finish(f"{status_code} {self._reason}\n")  # never a traceback


class _Missing(_Guarded):
    """Every other path: 404 (with the security headers)."""

    def get(self, *args: str) -> None:
        raise tornado.web.HTTPError(404)


class _Page(_Guarded):
    needs_token = True

    def get(self) -> None:
        self.set_header("Content-Type", "text/html; charset=utf-8")
        self.write(self.server.files["index.html"][1])


class _File(_Guarded):
    """The console's own files, read once at start: nothing else on disk is reachable."""

    def get(self, name: str) -> None:
        entry = self.server.files.get(name)
        if entry is None or name == "index.html":
            raise tornado.web.HTTPError(404)
        self.set_header("Content-Type", entry[0])
        self.write(entry[1])


class _Recording(_Guarded):
    """A file this server wrote (a recording's .npz or .html), by name; nothing else."""

    needs_token = True

    def get(self, name: str) -> None:
        path = self.server.served.get(name)
        if path is None:
            raise tornado.web.HTTPError(404)
        try:
            content = path.read_bytes()
        except OSError:
            raise tornado.web.HTTPError(404) from None
        kind = "text/html; charset=utf-8" if path.suffix == ".html" else "application/octet-stream"
        self.set_header("Content-Type", kind)
        if path.suffix != ".html":
            self.set_header("Content-Disposition", f'attachment; filename="{path.name}"')
        self.write(content)


class _Socket(_Guarded, tornado.websocket.WebSocketHandler):
    """One page. The handshake passes :class:`_Guarded`'s checks, the Origin rule and the cap."""

    def initialize(self, server: TeleopServer) -> None:
        self.server = server
        self.pending: Any = None  # the last frame's write, not yet done
        self.client_id = 0
        self.allowance = MESSAGE_BURST
        self.refilled = time.monotonic()
        self.dropped = 0
        self.clock_offset = math.inf  # the least (arrival - the page's stamp) seen, s
        self.offset_at = 0.0  # when clock_offset was last updated (monotonic s)

    def refuse_beyond_host(self, policy: AccessPolicy) -> None:
        """After the Host's (:meth:`_Guarded.prepare`): the Origin, the token, the cap."""
        if not policy.origin_allowed(self.request.headers.get("Origin"), self.request.host):
            raise tornado.web.HTTPError(403, reason="Origin not allowed")
        if not policy.token_allowed(self.get_query_argument("token", None)):
            raise tornado.web.HTTPError(403, reason="token missing or wrong")
        if len(self.server._clients) >= MAX_PAGES:
            raise tornado.web.HTTPError(503, reason=f"{MAX_PAGES} pages are connected already")

    def check_origin(self, origin: str) -> bool:
        return self.server.access.origin_allowed(origin, self.request.host)

    def open(self, *args: str, **kwargs: str) -> None:
        self.set_nodelay(True)
        self.server._open(self)

    def on_message(self, message: str | bytes) -> None:
        now = time.monotonic()
        self.allowance = min(MESSAGE_BURST, self.allowance + (now - self.refilled) * MESSAGE_RATE)
        self.refilled = now
        if self.allowance >= MESSAGE_BURST:
            self.dropped = 0  # calm again: the flood is over
        if self.allowance < 1.0:
            self.dropped += 1
            if self.dropped >= FLOOD_LIMIT:
                self.close(1008, "too many messages")
            return
        self.allowance -= 1.0
        try:
            self.server._message(self, message, now)
        except Exception:  # a message must never take the socket (or the console) down
            LOG.debug("unreadable message", exc_info=True)
            self.server._send(self, {"type": "event", "level": "error", "text": "unreadable message"})

    def on_close(self) -> None:
        self.server._close(self)


class _Server(tornado.httpserver.HTTPServer):
    """At most :data:`MAX_CONNECTIONS` HTTP connections (a socket that became a WebSocket
    leaves tornado's count, and :data:`MAX_PAGES` caps those): a new one beyond closes the
    oldest, so connections that never finish their headers cannot lock the page out."""

    def handle_stream(self, stream: tornado.iostream.IOStream, address: tuple[Any, ...]) -> None:
        live: set[Any] = self._connections  # tornado's own: HTTP1ServerConnection objects
        order: dict[Any, None] = getattr(self, "_pinrate_order", {})
        self._pinrate_order = order = {connection: None for connection in order if connection in live}
        while len(order) >= MAX_CONNECTIONS:
            oldest = next(iter(order))
            del order[oldest]
            oldest.stream.close()
        known = set(live)
        super().handle_stream(stream, address)
        order.update(dict.fromkeys(live - known))


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
        saved: the files recordings wrote, in order.
        scheduling: what the control thread runs under, in words (once it started).
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
        self.scheduling = ""
        self._scheduled = threading.Event()
        self.stats = LoopStats()
        self.saved: list[Path] = []
        self.served: dict[str, Path] = {}
        """What ``/recordings/NAME`` may return: the files this server wrote, by name."""
        self.files = {
            "index.html": ("text/html; charset=utf-8", (STATIC / "index.html").read_bytes()),
            "teleop.js": ("text/javascript; charset=utf-8", (STATIC / "teleop.js").read_bytes()),
            "teleop.css": ("text/css; charset=utf-8", (STATIC / "teleop.css").read_bytes()),
            "heartbeat.js": ("text/javascript; charset=utf-8", (STATIC / "heartbeat.js").read_bytes()),
            "main.min.js": ("text/javascript; charset=utf-8", MAIN_JS.read_bytes()),
        }
        """The console's own files (content type, bytes), read once: all it serves besides
        the recordings."""
        self._saving: list[threading.Thread] = []
        self._save_lock = threading.Lock()
        self._failure = ""  # the last control-loop failure said, so that a repeat is said once
        self._actions: queue.SimpleQueue[tuple[str, dict[str, Any], _Socket | None]] = queue.SimpleQueue()
        self._clients: list[_Socket] = []
        self._controller: _Socket | None = None
        self._next_client = 1
        self._last_heard = -math.inf  # when the controlling page last sent (monotonic s)
        self._main_heard = -math.inf  # when its main thread last spoke (monotonic s)
        self._input_seq = 0
        self._applied_seq = 0
        self._running = threading.Event()
        self._changed = threading.Event()
        self._state_version = 0
        self._pose_lock = threading.Lock()
        self._pose_data = self.robot.model.createData()  # for callers of tip_pose, not the loop's
        self._render_data = self.robot.model.createData()  # the render thread's, for the tip readout

        self.viewer = Viewer(self.robot, offline=True)
        self.viewer.draw_hand_axes()
        self.viewer.frame(teleop.q)
        self.viewer.show(teleop.q, record=False)
        self._scene = self.viewer.scene.packed()  # type: ignore[union-attr]  # encoded once, shared by every page
        partition = teleop.controller.partition
        self._gauges = joint_gauges(self.robot, (*partition.arm, *partition.wrist))
        joggable = set(teleop.controller.joggable)
        self._jog_gauges = {gauge.name: gauge for gauge in self._gauges if gauge.name in joggable}
        self.mode = "twist"
        """What the keys and sticks command: ``"twist"`` (the hand) or ``"uncoupled"``
        (Barker's arm/wrist mode; see :meth:`.Teleop.command`); the page's mode switch."""

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
        self._loop: asyncio.AbstractEventLoop | None = None
        self._web_ready = threading.Event()
        self._threads = [
            threading.Thread(target=self._serve, name="pinrate-teleop-web", daemon=True),
            threading.Thread(target=self._control, name="pinrate-teleop-control", daemon=True),
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
        self._scheduled.wait(5.0)

    # ------------------------------------------------------------------ life
    def __enter__(self) -> TeleopServer:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    @property
    def rate(self) -> float:
        """The control loop's rate (Hz): 1 / the controller's dt."""
        return 1.0 / self.teleop.controller.dt

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
            self._save(self.teleop.stop_recording())
        for saving in list(self._saving):  # a save started just before: its files are written whole
            saving.join(timeout=60)
        loop = self._loop
        if loop is not None and loop.is_running():
            loop.call_soon_threadsafe(loop.stop)
        if self._threads[0].is_alive():
            self._threads[0].join(timeout=5)
        for sock in self._sockets:
            with contextlib.suppress(OSError):
                sock.close()
        sys.setswitchinterval(self._switch_interval)

    # ------------------------------------------------------------------ what callers read
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

    @property
    def clients(self) -> int:
        """Pages connected now."""
        return len(self._clients)

    def act(self, action: str, **arguments: Any) -> None:
        """Queue a button's action for the control loop (what a page's button sends):
        ``halt``, ``resume``, ``reverse``, ``home``, ``record`` (on=True/False), ``frame``
        (frame="hand"/"base"), ``mode`` (mode="twist"/"uncoupled"), ``configure``
        (singularity=..., wrist=...)."""
        self._actions.put((action, arguments, None))

    # ------------------------------------------------------------------ web thread
    def _serve(self) -> None:
        loop = asyncio.new_event_loop()
        asyncio.set_event_loop(loop)
        self._loop = loop
        app = tornado.web.Application(
            [
                (r"/", _Page, {"server": self}),
                (r"/ws", _Socket, {"server": self}),
                (r"/static/(teleop\.js|teleop\.css|heartbeat\.js)", _File, {"server": self}),
                (r"/meshcat/(main\.min\.js)", _File, {"server": self}),
                (r"/recordings/([^/]+)", _Recording, {"server": self}),
            ],
            default_handler_class=_Missing,
            default_handler_args={"server": self},
            websocket_max_message_size=1 << 16,
            log_function=lambda handler: None,  # the console is the log; tornado's access lines are noise
        )
        http = _Server(
            app,
            idle_connection_timeout=HEADER_TIMEOUT,  # tornado's header timeout (default 3600 s)
            body_timeout=HEADER_TIMEOUT,
            max_header_size=16 << 10,
            max_body_size=64 << 10,
        )
        http.add_sockets(self._sockets)
        loop.call_soon(self._web_ready.set)
        try:
            loop.run_forever()
        finally:
            http.stop()
            for client in list(self._clients):
                with contextlib.suppress(Exception):
                    client.close()
            with contextlib.suppress(Exception):
                loop.run_until_complete(asyncio.sleep(0))
            loop.close()

    def _send(self, client: _Socket, message: dict[str, Any] | bytes) -> Any:
        """Write one message to a page; the write's future (its failure, a page gone
        mid-write, is retrieved here: never a "Task exception was never retrieved")."""
        try:
            if isinstance(message, bytes):
                written = client.write_message(message, binary=True)
            else:
                written = client.write_message(json.dumps(message))
        except tornado.websocket.WebSocketClosedError:
            return None
        written.add_done_callback(_retrieved)
        return written

    def _hello(self, client: _Socket) -> dict[str, Any]:
        teleop = self.teleop
        options = teleop.options
        return {
            "type": "hello",
            "client": client.client_id,
            "robot": self.robot.name,
            "tip": self.robot.tip,
            "sensor": self.robot.sensor,
            "joints": [gauge.__dict__ for gauge in self._gauges],
            "keys": sorted(KEYS),
            "rate": self.rate,
            "scheduling": self.scheduling,
            "timeout": teleop.timeout,
            "freeze_limit": self.freeze_limit,
            "max_linear_speed": teleop.max_linear_speed,
            "max_angular_speed": teleop.max_angular_speed,
            "algorithm": teleop.controller.algorithm,
            "singularity": options.get("singularity", teleop.controller.singularity),
            "wrist": options.get("wrist", teleop.controller.wrist),
            "singularities": list(STRATEGIES),
            "wrists": list(WRIST_STRATEGIES),
            "frames": list(FRAMES),
            "frame": teleop.frame,
            "modes": list(MODES),
            "wrist_joints": list(teleop.controller.partition.wrist),
            "joggable": sorted(self._jog_gauges),
            "jog_share": JOG_SHARE,
            "controls": [("vx", "vy", "vz", "wx", "wy", "wz")[row] for row in teleop.controller.index.rows],
        }

    def _role(self, client: _Socket) -> dict[str, Any]:
        return {"type": "role", "controlling": client is self._controller, "free": self._controller is None}

    def _open(self, client: _Socket) -> None:
        client.client_id = self._next_client
        self._next_client += 1
        self._clients.append(client)
        if self._controller is None:
            self._controller = client
            self._last_heard = self._main_heard = time.monotonic()
        self._send(client, self._hello(client))
        loop = self._loop
        if loop is not None:
            loop.create_task(self._send_scene(client)).add_done_callback(_retrieved)

    async def _send_scene(self, client: _Socket) -> None:
        """The shared encoded scene, one chunk at a time (a page that does not read holds one
        chunk, not the scene), then the page's role; frames start after it."""
        client.pending = _Busy()  # no frame until the scene is there
        for packed in self._scene:
            written = self._send(client, packed)
            if written is None:
                return
            with contextlib.suppress(tornado.websocket.WebSocketClosedError, tornado.iostream.StreamClosedError):
                await written
            if client not in self._clients:
                return
        client.pending = None
        self._send(client, self._role(client))
        self._changed.set()  # a fresh frame for the new page

    def _close(self, client: _Socket) -> None:
        if client in self._clients:
            self._clients.remove(client)
        if client is self._controller:
            self._controller = None
            self._actions.put(("stop", {"dead_man": "the controlling page is gone"}, None))  # stop now
            for other in self._clients:
                self._send(other, self._role(other))

    def _message(self, client: _Socket, message: str | bytes, arrived: float) -> None:
        """One message from a page, read at ``arrived`` (monotonic s). Unreadable ones (not
        JSON, too deep, not an object) raise; :meth:`_Socket.on_message` answers them."""
        data = json.loads(message)
        if not isinstance(data, dict) or not isinstance(data.get("type"), str):
            raise ValueError("not a message")
        kind = data["type"]
        if kind == "claim":
            if self._controller is None:
                self._controller = client
                self._last_heard = self._main_heard = arrived
                for other in self._clients:  # only a change of hands is news
                    self._send(other, self._role(other))
            return
        if client is not self._controller:
            if kind == "halt":  # an e-stop anyone watching may press: halting is always safe
                self._actions.put(("halt", {}, client))
            return  # otherwise watchers watch
        sent = self._sent_at(client, data.get("sent"), arrived)
        self._last_heard = sent
        self._main_heard = sent - self._main_silence(data)
        if kind == "input":
            self._input(data, sent)
        else:
            self._actions.put((kind, data, client))

    @staticmethod
    def _main_silence(data: dict[str, Any]) -> float:
        """s the page's main thread had been silent when the message was sent: ``sent`` minus
        ``alive`` (both ms on the clock of the page's worker), 0 for a message without them
        (its sender vouches for itself)."""
        sent, alive = data.get("sent"), data.get("alive")
        for stamp in (sent, alive):
            if isinstance(stamp, bool) or not isinstance(stamp, int | float) or not math.isfinite(stamp):
                return 0.0
        return max(0.0, (float(sent) - float(alive)) / 1000.0)  # type: ignore[arg-type]

    @property
    def _frozen(self) -> str:
        return f"the page froze: its main thread silent for {self.freeze_limit:g} s"

    @property
    def freeze_limit(self) -> float:
        """s of main-thread silence that stop the robot (:data:`FREEZE_LIMIT`, or the
        Teleop's timeout when longer)."""
        return max(FREEZE_LIMIT, self.teleop.timeout)

    @staticmethod
    def _sent_at(client: _Socket, stamp: object, arrived: float) -> float:
        """When the page sent a message, on this process's monotonic clock: the page's own
        stamp (``sent``, ms of its ``performance.now()``) plus the smallest offset seen
        between the two clocks (the least delay), which may grow by :data:`CLOCK_DRIFT` a
        second. A backlog of old messages so reads as old: the dead man counts from sending.
        Without a stamp, the arrival."""
        if isinstance(stamp, bool) or not isinstance(stamp, int | float) or not math.isfinite(stamp):
            return arrived
        page_time = float(stamp) / 1000.0
        elapsed = max(0.0, arrived - client.offset_at)
        client.clock_offset = min(client.clock_offset + CLOCK_DRIFT * elapsed, arrived - page_time)
        client.offset_at = arrived
        return min(arrived, page_time + client.clock_offset)

    def _input(self, data: dict[str, Any], sent: float) -> None:
        try:
            speed = min(max(float(data.get("speed", 1.0)), 0.0), 1.0)
            if not math.isfinite(speed):
                speed = 0.0
            keys = [str(code) for code in _listed(data.get("keys"))][:32]
            axes = _listed(data.get("axes"))[:16]
            buttons = _listed(data.get("buttons"))[:32]
            counts = _listed(data.get("hid"))[:6]  # a SpaceMouse's raw counts, read by the page (WebHID)
            jog = self._jog_rates(data.get("jog"), speed)
            seq = data.get("seq", 0)
            seq = int(seq) if isinstance(seq, int | float) and math.isfinite(seq) else self._input_seq
        except (TypeError, ValueError, OverflowError):
            return
        deflection = deflections(keys, axes, buttons, counts) * speed
        if sent - self._main_heard > self.freeze_limit and (deflection.any() or jog or self.teleop.reversing):
            self.teleop.dead_man_stop(self._frozen)
        elif jog:  # a jog button held wins over the sticks and keys
            self.teleop.jog(jog, now=sent)
        else:
            self.teleop.command(deflection[:3], deflection[3:], now=sent, mode=self.mode)
        self._input_seq = seq

    def _jog_rates(self, signs: object, speed: float) -> dict[str, float]:
        """{joint: rate} from a message's ``jog`` ({joint name: deflection in [-1, 1]}, the
        page's held +/- buttons): deflection x speed x :data:`JOG_SHARE` x the joint's
        velocity limit (rad/s or m/s). Names that are not the robot's joints are ignored."""
        if not isinstance(signs, dict):
            return {}
        rates = {}
        for name, sign in list(signs.items())[:16]:
            gauge = self._jog_gauges.get(name)
            if gauge is None or isinstance(sign, bool) or not isinstance(sign, int | float) or not math.isfinite(sign):
                continue
            fallback = self.teleop.max_linear_speed if gauge.unit == "m" else self.teleop.max_angular_speed
            limit = gauge.velocity if gauge.velocity is not None else fallback
            rate = min(max(float(sign), -1.0), 1.0) * speed * JOG_SHARE * limit
            if rate:
                rates[name] = rate
        return rates

    # ------------------------------------------------------------------ control thread
    def _control(self) -> None:
        self.scheduling = request_realtime(self.realtime_priority)
        self._scheduled.set()
        teleop = self.teleop
        period = teleop.controller.dt
        started = time.monotonic()
        deadline = started
        last_wake = started
        owed = 0.0
        while self._running.is_set():
            self._run_actions()
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
            applied_seq = self._input_seq
            before = teleop.q
            before_status = None if teleop.last is None else teleop.last.status
            try:
                for tick in range(ticks):  # each missed tick at its own time (the recording's times)
                    teleop.tick(now - (ticks - 1 - tick) * period)
            except Exception as error:  # a bug: the robot halts, the console goes on
                self._failed(error)
            owed -= ticks * period
            self._applied_seq = applied_seq
            if ticks and (
                not np.array_equal(teleop.q, before) or teleop.last is None or teleop.last.status is not before_status
            ):
                self._state_version += 1
                self._changed.set()
            silent = self._controller is None or now - self._last_heard > teleop.timeout
            # The freeze rule is a controlling page's: a caller driving the Teleop from Python
            # with no page connected is not frozen.
            frozen = self._controller is not None and now - self._main_heard > self.freeze_limit
            if frozen and not teleop.reversing and teleop.dead_man_stop(self._frozen):
                self._changed.set()  # on this clock, not at the next heartbeat: a late one is no delay
            if (silent or frozen) and teleop.reversing:
                why = (
                    "gone"
                    if self._controller is None
                    else f"silent for {teleop.timeout:g} s"
                    if silent
                    else f"frozen: its main thread silent for {self.freeze_limit:g} s"
                )
                teleop.dead_man_stop(f"reversal stopped: the controlling page is {why}")
                self._event(f"reversal stopped: the controlling page is {why}", "warning")
                self._changed.set()
            deadline += period
            delay = deadline - time.monotonic()
            # Always a little sleep, however late: a real-time thread never takes a core whole.
            time.sleep(max(delay, MIN_SLEEP))
            if delay < -MAX_CATCH_UP:
                deadline = time.monotonic()  # far behind: start afresh rather than race

    def _failed(self, error: BaseException) -> None:
        """A tick raised: halt the robot, say so once on the pages and in the terminal (with
        the traceback there), and keep serving: the operator may resume or go home."""
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
            self._event(text, "error")
        self._changed.set()

    def _run_actions(self) -> None:
        while True:
            try:
                action, data, client = self._actions.get_nowait()
            except queue.Empty:
                return
            try:
                self._act(action, data)
            except PinrateError as error:
                self._event(f"{action}: {error}", "error", client)
            except Exception as error:  # a bug: as for a tick
                self._failed(error)
            else:
                if action == "resume":
                    self._failure = ""
            self._changed.set()

    def _act(self, action: str, data: dict[str, Any]) -> None:
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
                self._event("nothing to reverse: no motion recorded since the last mark", "warning")
        elif action == "home":
            teleop.reset()
            self._event("back at home")
        elif action == "record":
            if data.get("on", not teleop.recording):
                if not teleop.recording:
                    teleop.start_recording()
                    self._event("recording")
            elif teleop.recording:
                recording = teleop.stop_recording()
                if not len(recording):
                    self._event("recording stopped: no tick was recorded, nothing saved", "warning")
                    return
                saving = threading.Thread(target=self._save, args=(recording,), name="pinrate-teleop-save", daemon=True)
                self._saving = [thread for thread in self._saving if thread.is_alive()] + [saving]
                saving.start()
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
            self.mode = mode
            self._event(
                "keys and sticks: " + ("the hand" if mode == "twist" else "arm (wrist centre) and wrist joints")
            )
        elif action == "configure":
            options = {key: data[key] for key in ("singularity", "wrist") if key in data}
            teleop.configure(**options)
            self._event("strategy: " + ", ".join(f"{key} {value}" for key, value in options.items()))
        else:
            raise InputError(f"unknown action {action!r}")

    def _stem(self) -> Path:
        """A new file stem in the record folder, ``teleop-ROBOT-YYYYmmdd-HHMMSS[-N]``: no
        file of a recording (.npz, .html) has it yet, so two runs never overwrite each other."""
        stamp = datetime.now().strftime("%Y%m%d-%H%M%S")
        base = f"teleop-{self.robot.name}-{stamp}"
        for number in range(1, 10_000):
            stem = self.record_dir / (base if number == 1 else f"{base}-{number}")
            if not any(stem.with_suffix(suffix).exists() for suffix in (".npz", ".html")):
                return stem
        raise PinrateError(f"no free file name for a recording in {self.record_dir}")

    def _save(self, recording: Recording) -> None:
        """Write a recorded run as .npz and as a standalone HTML replay; tell the pages."""
        try:
            with self._save_lock:  # one save at a time: the names stay unique
                self._write(recording)
        except Exception as error:  # said, never a dead thread's traceback
            self._event(f"the recording could not be saved: {error}", "error")
            LOG.error("the recording could not be saved", exc_info=error)

    def _write(self, recording: Recording) -> None:
        stem = self._stem()
        try:
            data = recording.save(stem.with_suffix(".npz"))
            # The console's own scene, already encoded: no mesh is read again, and no step
            # holds the GIL long enough to delay the control loop's tick.
            page = self.viewer.save_replay(stem.with_suffix(".html"), recording.frames(REPLAY_FPS), fps=REPLAY_FPS)
        except (PinrateError, OSError) as error:
            self._event(f"the recording could not be saved: {error}", "error")
            return
        self.saved += [data, page]
        self.served.update({data.name: data, page.name: page})
        self._event(
            f"saved {len(recording)} ticks: {data.name}, {page.name}",
            links=[self._link(data.name), self._link(page.name)],
        )

    def _link(self, name: str) -> str:
        """The page-relative URL of a recording file (with the token when there is one)."""
        token = self.access.token
        return f"/recordings/{name}" + (f"?token={token}" if token else "")

    def _event(
        self, text: str, level: str = "info", client: _Socket | None = None, links: list[str] | None = None
    ) -> None:
        message = {"type": "event", "level": level, "text": text, "links": links or []}
        loop = self._loop
        if loop is None or not self._running.is_set():
            return
        targets = [client] if client is not None else None

        def deliver() -> None:
            for other in targets or list(self._clients):
                self._send(other, message)

        with contextlib.suppress(RuntimeError):  # the loop closed meanwhile
            loop.call_soon_threadsafe(deliver)

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
            if self._clients:
                version = self._state_version
                frame = self._frame(poses=version != shown_version or started - last_stats > 1.0)
                shown_version = version
                last_stats = started
                loop = self._loop
                if loop is not None:
                    with contextlib.suppress(RuntimeError):
                        loop.call_soon_threadsafe(self._broadcast, json.dumps(frame))
            spare = interval - (time.monotonic() - started)
            if spare > 0:
                time.sleep(spare)

    def _frame(self, *, poses: bool) -> dict[str, Any]:
        """One frame for the pages: the status (``status``, ``colour``, ``detail``,
        ``conditions``; ``dead_man``: why the dead man stopped the robot, or None), the joints
        (``q``: each joint's value in velocity order; ``configuration``: q itself), the tip's
        pose in the world (``tip``: :meth:`_tip_readout`), the console's state (``halted``,
        ``reversing``, ``recording``, ``frame``, ``mode``, the strategies, the loop's
        rate), the last step's numbers and, when ``poses``, every link's pose."""
        teleop = self.teleop
        q, step = teleop.q.copy(), teleop.last
        dead_man = teleop.dead_man
        said = describe(step, halted=teleop.halted, reversing=teleop.reversing, dead_man=dead_man)
        frame: dict[str, Any] = {
            "type": "frame",
            "input_seq": self._applied_seq,
            "dead_man": dead_man or None,
            "status": said.word,
            "colour": said.colour,
            "detail": said.detail,
            "conditions": list(said.conditions),
            "frozen": list(step.frozen) if step is not None else [],
            "moving": bool(step is not None and step.joint_rates.any()),
            "q": joint_values(self.robot, q),
            "configuration": q.tolist(),
            "tip": self._tip_readout(q),
            "halted": teleop.halted,
            "reversing": teleop.reversing,
            "recording": teleop.recording,
            "frame": teleop.frame,
            "mode": self.mode,
            "singularity": teleop.controller.singularity,
            "wrist": teleop.controller.wrist,
            "loop": self.stats.summary(),
        }
        if step is not None:
            observation = step.observation
            rho = observation.spectral_radius
            conditioning = teleop.controller.observed_conditioning(observation)
            frame["rho"] = rho if math.isfinite(rho) else None
            frame["conditioning"] = {"value": conditioning.value, "block": conditioning.block}
            frame["twist"] = [float(value) for value in step.twist]
        if poses:
            frame["poses"] = {
                path: transform.T.reshape(-1).tolist() for path, transform in self.viewer.node_transforms(q).items()
            }
        return frame

    def _tip_readout(self, q: np.ndarray) -> dict[str, Any]:
        """The tip's pose in the world (base) frame at q, for the page: ``position`` (m) and
        ``rpy`` (rad: roll, pitch, yaw with world_R_tip = Rz(yaw) Ry(pitch) Rx(roll),
        Pinocchio's ``matrixToRpy``), from the render thread's own ``pin.Data``."""
        model, data = self.robot.model, self._render_data
        pin.framesForwardKinematics(model, data, q)
        world_T_tip = data.oMf[self.robot.tip_id]
        return {
            "name": self.robot.tip,
            "position": [float(value) for value in world_T_tip.translation],
            "rpy": [float(value) for value in pin.rpy.matrixToRpy(world_T_tip.rotation)],
        }

    def _broadcast(self, text: str) -> None:
        for client in list(self._clients):
            if client.pending is not None and not client.pending.done():
                continue  # this page is still busy with the last frame: skip one
            with contextlib.suppress(tornado.websocket.WebSocketClosedError):
                client.pending = client.write_message(text)


__all__ = ["LoopStats", "TeleopServer", "check_host"]
