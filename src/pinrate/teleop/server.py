"""The teleop console: one process, one port, three threads around a :class:`~.session.Teleop`.

    with TeleopServer(Teleop(robot, dt=0.002)) as server:   # binds 127.0.0.1
        print(server.url)                                   # open it: keyboard or gamepad drive the hand
        server.wait()                                       # until Ctrl-C

- **web** (its own asyncio loop, tornado): serves the page, meshcat's own ``main.min.js``
  and the recordings, and one WebSocket per page. The page builds the Meshcat viewer itself
  (no iframe: it would take the keyboard's focus) and receives the scene's commands, packed
  as meshcat's server sends them, when it connects; then one JSON frame per render tick.
  The page sends its held keys, its gamepad and its speed slider every 50 ms (the heartbeat)
  and at every change. Every HTTP request's ``Host`` and every WebSocket's ``Origin`` must
  name this server (DNS rebinding). The first page controls; the others watch until the
  control is free and they take it.
- **control**: :meth:`Teleop.tick` at the controller's rate (1/dt), sleeping to absolute
  deadlines; a late wake-up runs the missed ticks (at most 0.1 s of them), so the motion
  follows the wall clock. Buttons reach it through a queue, so only this thread touches the
  Teleop and the robot's ``pin.Data``. A controlling page that is gone or silent for longer
  than the Teleop's timeout stops the robot (the dead man; a reversal too).
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
import ipaddress
import json
import math
import queue
import socket
import sys
import threading
import time
from collections import deque
from collections.abc import Callable
from datetime import datetime
from pathlib import Path
from typing import Any

import numpy as np
import pinocchio as pin
import tornado.httpserver
import tornado.netutil
import tornado.web
import tornado.websocket

from ..checks import check_output_folder, check_positive
from ..control.singularity import STRATEGIES, WRIST_STRATEGIES
from ..errors import InputError, PinrateError
from ..viewer import Viewer
from ..viewer.offline import MAIN_JS
from ..viewer.server import check_host
from .display import describe, joint_gauges, joint_values
from .mapping import KEYS, deflections
from .recording import Recording
from .session import FRAMES, Teleop

STATIC = Path(__file__).parent / "static"
RENDER_RATE = 60.0
"""Frames per second sent to the pages at most."""

MAX_CATCH_UP = 0.1
"""Seconds of missed ticks a late control loop runs at once; beyond, the motion waits."""

STATS_WINDOW = 2.0
"""Seconds of control-loop periods the rate and p99 on the page are measured over."""

REPLAY_FPS = 30.0
"""Frames per second of a recording's HTML replay."""

SWITCH_INTERVAL = 2e-4
"""Seconds a thread holding the GIL runs before a waiting one may take it, while a console
runs (CPython's default, 5 ms, lets the render or web thread delay a 1 kHz tick by up to
5 ms; restored on close)."""


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


def _allowed_hosts(host: str, port: int) -> Callable[[str], bool]:
    """A test of a request's Host header (``name:port``): this server's own address, and on
    loopback also ``localhost``; on a shared address any IP literal or this machine's names."""
    names = {host.lower()}
    loopback = ipaddress.ip_address(socket.gethostbyname(host)).is_loopback
    if loopback:
        names |= {"127.0.0.1", "localhost", "[::1]"}
    else:
        names |= {socket.gethostname().lower(), socket.getfqdn().lower()}

    def allowed(header: str) -> bool:
        name, _, given_port = header.strip().lower().rpartition(":")
        if not name or given_port != str(port):
            return False
        if name in names:
            return True
        if loopback:
            return False
        try:
            ipaddress.ip_address(name.strip("[]"))
        except ValueError:
            return False
        return True

    return allowed


class _HostChecked:
    """Every HTTP request must name this server in its Host header (DNS rebinding)."""

    server: TeleopServer
    request: Any

    def prepare(self) -> None:
        if not self.server.host_allowed(self.request.host):
            raise tornado.web.HTTPError(403, reason="Host not allowed")


class _Page(_HostChecked, tornado.web.RequestHandler):
    def initialize(self, server: TeleopServer) -> None:
        self.server = server

    def get(self) -> None:
        self.set_header("Content-Type", "text/html; charset=utf-8")
        self.set_header("Cache-Control", "no-store")
        self.write((STATIC / "index.html").read_bytes())


class _Static(_HostChecked, tornado.web.StaticFileHandler):
    def initialize(self, path: str, server: TeleopServer, default_filename: str | None = None) -> None:  # type: ignore[override]
        super().initialize(path, default_filename)
        self.server = server


class _Socket(tornado.websocket.WebSocketHandler):
    def initialize(self, server: TeleopServer) -> None:
        self.server = server
        self.pending: Any = None  # the last frame's write, not yet done
        self.client_id = 0

    def check_origin(self, origin: str) -> bool:
        scheme, _, rest = origin.partition("://")
        return scheme == "http" and self.server.host_allowed(rest) and self.server.host_allowed(self.request.host)

    def open(self, *args: str, **kwargs: str) -> None:
        self.set_nodelay(True)
        self.server._open(self)

    def on_message(self, message: str | bytes) -> None:
        self.server._message(self, message)

    def on_close(self) -> None:
        self.server._close(self)


class TeleopServer:
    """The browser console for a :class:`Teleop` (see the module).

    Args:
        teleop: what the console drives; its controller's dt sets the loop's rate.
        host: the address to listen on (127.0.0.1: this machine only; another one is warned
            about, as anyone who reaches it can drive the robot).
        port: the TCP port; 0 picks a free one.
        render_rate: frames per second sent to the pages at most.
        record_dir: folder where recorded runs are saved (``.npz`` and ``.html``).
    """

    def __init__(
        self,
        teleop: Teleop,
        *,
        host: str = "127.0.0.1",
        port: int = 0,
        render_rate: float = RENDER_RATE,
        record_dir: str | Path = ".",
    ) -> None:
        if not isinstance(teleop, Teleop):
            raise InputError(f"TeleopServer takes a pinrate.Teleop, not {type(teleop).__name__}")
        self.teleop = teleop
        self.robot = teleop.robot
        self.host = check_host(host)
        if isinstance(port, bool) or not isinstance(port, int) or not 0 <= port <= 65535:
            raise InputError(f"port must be an integer in [0, 65535], got {port!r}")
        self.render_rate = check_positive(render_rate, "render_rate")
        self.record_dir = check_output_folder(record_dir, "record folder")
        self.stats = LoopStats()
        self.saved: list[Path] = []
        """Files written by recordings, in order."""
        self._actions: queue.SimpleQueue[tuple[str, dict[str, Any], _Socket | None]] = queue.SimpleQueue()
        self._clients: list[_Socket] = []
        self._controller: _Socket | None = None
        self._next_client = 1
        self._last_heard = -math.inf
        self._input_seq = 0
        self._applied_seq = 0
        self._running = threading.Event()
        self._changed = threading.Event()
        self._state_version = 0
        self._pose_lock = threading.Lock()
        self._pose_data = self.robot.model.createData()  # for callers of tip_pose, not the loop's

        self.viewer = Viewer(self.robot, offline=True)
        self.viewer.draw_hand_axes()
        self.viewer.frame(teleop.q)
        self.viewer.show(teleop.q, record=False)
        self._gauges = joint_gauges(self.robot)

        try:
            sockets = tornado.netutil.bind_sockets(port, address=self.host, family=socket.AF_INET)
        except OSError as error:
            raise PinrateError(f"cannot listen on {self.host}:{port}: {error.strerror or error}") from None
        self._sockets = sockets
        self.port = int(sockets[0].getsockname()[1])
        self.url = f"http://{self.host}:{self.port}/"
        self.host_allowed = _allowed_hosts(self.host, self.port)
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
        (frame="hand"/"base"), ``configure`` (singularity=..., wrist=...)."""
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
                (r"/static/(.*)", _Static, {"path": str(STATIC), "server": self}),
                (r"/meshcat/(main\.min\.js)", _Static, {"path": str(MAIN_JS.parent), "server": self}),
                (r"/recordings/(.*)", _Static, {"path": str(self.record_dir), "server": self}),
            ],
            websocket_max_message_size=1 << 16,
            log_function=lambda handler: None,  # the console is the log; tornado's access lines are noise
        )
        http = tornado.httpserver.HTTPServer(app)
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

    def _send(self, client: _Socket, message: dict[str, Any] | bytes) -> None:
        with contextlib.suppress(tornado.websocket.WebSocketClosedError):
            if isinstance(message, bytes):
                client.write_message(message, binary=True)
            else:
                client.write_message(json.dumps(message))

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
            "timeout": teleop.timeout,
            "max_linear_speed": teleop.max_linear_speed,
            "max_angular_speed": teleop.max_angular_speed,
            "algorithm": teleop.controller.algorithm,
            "singularity": options.get("singularity", teleop.controller.singularity),
            "wrist": options.get("wrist", teleop.controller.wrist),
            "singularities": list(STRATEGIES),
            "wrists": list(WRIST_STRATEGIES),
            "frames": list(FRAMES),
            "frame": teleop.frame,
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
            self._last_heard = time.monotonic()
        self._send(client, self._hello(client))
        for packed in self.viewer.scene.packed():  # type: ignore[union-attr]
            self._send(client, packed)
        self._send(client, self._role(client))
        self._changed.set()  # a fresh frame for the new page

    def _close(self, client: _Socket) -> None:
        if client in self._clients:
            self._clients.remove(client)
        if client is self._controller:
            self._controller = None
            self._actions.put(("stop", {}, None))  # the controlling page is gone: stop now
            for other in self._clients:
                self._send(other, self._role(other))

    def _message(self, client: _Socket, message: str | bytes) -> None:
        try:
            data = json.loads(message)
            kind = data["type"]
        except (ValueError, TypeError, KeyError):
            self._send(client, {"type": "event", "level": "error", "text": "unreadable message"})
            return
        if kind == "claim":
            if self._controller is None:
                self._controller = client
                self._last_heard = time.monotonic()
            for other in self._clients:
                self._send(other, self._role(other))
            return
        if client is not self._controller:
            return  # watchers watch
        self._last_heard = time.monotonic()
        if kind == "input":
            self._input(data)
        else:
            self._actions.put((str(kind), data, client))

    def _input(self, data: dict[str, Any]) -> None:
        try:
            speed = min(max(float(data.get("speed", 1.0)), 0.0), 1.0)
            if not math.isfinite(speed):
                speed = 0.0
            keys = [str(code) for code in data.get("keys", [])][:32]
            axes = list(data.get("axes", []))[:16]
            buttons = list(data.get("buttons", []))[:32]
            seq = int(data.get("seq", 0))
        except (TypeError, ValueError):
            return
        deflection = deflections(keys, axes, buttons) * speed
        self.teleop.command(deflection[:3], deflection[3:], now=time.monotonic())
        self._input_seq = seq

    # ------------------------------------------------------------------ control thread
    def _control(self) -> None:
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
                for _ in range(ticks):
                    teleop.tick(now)
            except PinrateError as error:  # never for what the robot does; a bug would land here
                teleop.halt()
                self._event(f"halted: {error}", "error")
            owed -= ticks * period
            self._applied_seq = applied_seq
            if ticks and (
                not np.array_equal(teleop.q, before) or teleop.last is None or teleop.last.status is not before_status
            ):
                self._state_version += 1
                self._changed.set()
            if (self._controller is None or now - self._last_heard > teleop.timeout) and teleop.reversing:
                teleop.stop()  # the page that asked for the reversal is gone or silent
                self._event("reversal stopped: the controlling page is gone or silent", "warning")
            deadline += period
            delay = deadline - time.monotonic()
            if delay > 0:
                time.sleep(delay)
            elif delay < -MAX_CATCH_UP:
                deadline = time.monotonic()  # far behind: start afresh rather than race

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
            self._changed.set()

    def _act(self, action: str, data: dict[str, Any]) -> None:
        teleop = self.teleop
        if action == "stop":
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
                threading.Thread(target=self._save, args=(recording,), daemon=True).start()
        elif action == "frame":
            teleop.frame = str(data.get("frame"))
        elif action == "configure":
            options = {key: data[key] for key in ("singularity", "wrist") if key in data}
            teleop.configure(**options)
            self._event("strategy: " + ", ".join(f"{key} {value}" for key, value in options.items()))
        else:
            raise InputError(f"unknown action {action!r}")

    def _save(self, recording: Recording) -> None:
        """Write a recorded run as .npz and as a standalone HTML replay; tell the pages."""
        stamp = datetime.now().strftime("%Y%m%d-%H%M%S")
        stem = self.record_dir / f"teleop-{self.robot.name}-{stamp}"
        try:
            data = recording.save(stem.with_suffix(".npz"))
            replay = Viewer(self.robot, offline=True)
            replay.draw_hand_axes()
            frames = recording.frames(REPLAY_FPS)
            if len(frames):
                replay.frame(frames[0])
            for q in frames:
                replay.show(q)
            page = replay.save_html(stem.with_suffix(".html"), fps=REPLAY_FPS)
        except (PinrateError, OSError) as error:
            self._event(f"the recording could not be saved: {error}", "error")
            return
        self.saved += [data, page]
        self._event(
            f"saved {len(recording)} ticks: {data.name}, {page.name}",
            links=[f"/recordings/{data.name}", f"/recordings/{page.name}"],
        )

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
        teleop = self.teleop
        q, step = teleop.q.copy(), teleop.last
        said = describe(step, halted=teleop.halted, reversing=teleop.reversing)
        frame: dict[str, Any] = {
            "type": "frame",
            "input_seq": self._applied_seq,
            "status": said.word,
            "colour": said.colour,
            "detail": said.detail,
            "conditions": list(said.conditions),
            "frozen": list(step.frozen) if step is not None else [],
            "moving": bool(step is not None and step.joint_rates.any()),
            "q": joint_values(self.robot, q),
            "halted": teleop.halted,
            "reversing": teleop.reversing,
            "recording": teleop.recording,
            "frame": teleop.frame,
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

    def _broadcast(self, text: str) -> None:
        for client in list(self._clients):
            if client.pending is not None and not client.pending.done():
                continue  # this page is still busy with the last frame: skip one
            with contextlib.suppress(tornado.websocket.WebSocketClosedError):
                client.pending = client.write_message(text)


__all__ = ["LoopStats", "TeleopServer", "check_host"]
