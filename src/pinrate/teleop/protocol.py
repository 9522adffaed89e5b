"""The pages' side of the console: one WebSocket per page, what it may send and what it is sent.

The page builds the Meshcat viewer itself (no iframe: it would take the keyboard's focus) and
receives the scene's commands, packed as meshcat's server sends them, when it connects
(encoded once, shared by every page, sent one chunk at a time); then its role, then one JSON
frame per render tick (:mod:`.readout`; a page still busy with a frame skips the next). The
page's socket lives in a dedicated worker (``static/heartbeat.js``), which sends the held
keys, the gamepad and the speed slider every 50 ms (the heartbeat) and at every change (and a
SpaceMouse's counts, read through WebHID, and the joint jog buttons held), each stamped with
its clock (``sent``) and with when the page's main thread last spoke (``alive``): a main
thread that rendering blocks for a second keeps the robot moving, one silent for
:data:`FREEZE_LIMIT` stops it. A command is aged from when the page sent it
(:meth:`Pages.sent_at`), not from when it was read, so a backlog never keeps the robot moving.

The first page controls; the others watch until the control is free and they take it (a
``claim``); a watcher may only halt. The controlling page's buttons become requests for the
control thread (:attr:`Pages.requests`); its input becomes the Teleop's command at once.
What one page can cost is capped: :data:`MAX_PAGES` sockets, :data:`MESSAGE_RATE` messages a
second (a page that keeps flooding is disconnected; the socket's rules are
:mod:`.page_socket`'s), a claim broadcast only when the control changes hands; an unreadable
message is answered, never raised.
"""

from __future__ import annotations

import asyncio
import contextlib
import json
import math
import queue
import threading
import time
from collections.abc import Callable
from typing import Any

import tornado.iostream
import tornado.websocket

from .display import JointGauge
from .mapping import deflections
from .page_socket import FLOOD_LIMIT, MAX_PAGES, MESSAGE_BURST, MESSAGE_RATE, PageSocket
from .session import Teleop

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


Request = tuple[str, dict[str, Any], PageSocket | None]
"""An action for the control thread: (name, arguments, the page that asked or None)."""


class Pages:
    """The pages connected to one console: who controls, what they say, what they are sent.

    Everything here runs on the web thread's loop (``loop``) but :meth:`event`, which
    any thread may call.

    Args:
        teleop: what the controlling page's input commands.
        scene: the viewer's scene, encoded once (meshcat's packed commands).
        jog_gauges: the joints a jog button may move, by name.
        hello: the first message to a page, given its client number.
        running: set while the console runs (no event is sent otherwise).
        changed: set to ask the render thread for a fresh frame.

    Attributes:
        clients: the pages connected, in order.
        controller: the page in control, or None.
        requests: the actions asked for (:data:`Request`), for the control thread.
        mode: what the keys and sticks command: ``"twist"`` (the hand) or ``"uncoupled"``
            (Barker's arm/wrist mode; see :meth:`.Teleop.command`); the page's mode switch.
        last_heard: when the controlling page last sent (monotonic s, its sending time).
        main_heard: when its main thread last spoke (monotonic s).
        input_seq: the ``seq`` of the last input applied to the Teleop.
    """

    def __init__(
        self,
        teleop: Teleop,
        *,
        scene: list[bytes],
        jog_gauges: dict[str, JointGauge],
        hello: Callable[[int], dict[str, Any]],
        running: threading.Event,
        changed: threading.Event,
    ) -> None:
        self.teleop = teleop
        self.scene = scene
        self.jog_gauges = jog_gauges
        self.hello = hello
        self.running = running
        self.changed = changed
        self.loop: asyncio.AbstractEventLoop | None = None
        self.requests: queue.SimpleQueue[Request] = queue.SimpleQueue()
        self.clients: list[PageSocket] = []
        self.controller: PageSocket | None = None
        self.next_client = 1
        self.last_heard = -math.inf
        self.main_heard = -math.inf
        self.input_seq = 0
        self.mode = "twist"

    @property
    def freeze_limit(self) -> float:
        """s of main-thread silence that stop the robot (:data:`FREEZE_LIMIT`, or the
        Teleop's timeout when longer)."""
        return max(FREEZE_LIMIT, self.teleop.timeout)

    @property
    def frozen(self) -> str:
        """Why a frozen page stopped the robot, in words."""
        return f"the page froze: its main thread silent for {self.freeze_limit:g} s"

    # ------------------------------------------------------------------ what pages are sent
    def send(self, client: PageSocket, message: dict[str, Any] | bytes) -> Any:
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

    def role(self, client: PageSocket) -> dict[str, Any]:
        return {"type": "role", "controlling": client is self.controller, "free": self.controller is None}

    def event(
        self, text: str, level: str = "info", client: PageSocket | None = None, links: list[str] | None = None
    ) -> None:
        """Say ``text`` on every page (or on ``client``'s), from any thread."""
        message = {"type": "event", "level": level, "text": text, "links": links or []}
        loop = self.loop
        if loop is None or not self.running.is_set():
            return
        targets = [client] if client is not None else None

        def deliver() -> None:
            for other in targets or list(self.clients):
                self.send(other, message)

        with contextlib.suppress(RuntimeError):  # the loop closed meanwhile
            loop.call_soon_threadsafe(deliver)

    def broadcast(self, text: str) -> None:
        """A frame to every page that is done with the last one (the others skip it)."""
        for client in list(self.clients):
            if client.pending is not None and not client.pending.done():
                continue  # this page is still busy with the last frame: skip one
            with contextlib.suppress(tornado.websocket.WebSocketClosedError):
                client.pending = client.write_message(text)

    # ------------------------------------------------------------------ pages coming and going
    def open(self, client: PageSocket) -> None:
        client.client_id = self.next_client
        self.next_client += 1
        self.clients.append(client)
        if self.controller is None:
            self.controller = client
            self.last_heard = self.main_heard = time.monotonic()
        self.send(client, self.hello(client.client_id))
        loop = self.loop
        if loop is not None:
            loop.create_task(self.send_scene(client)).add_done_callback(_retrieved)

    async def send_scene(self, client: PageSocket) -> None:
        """The shared encoded scene, one chunk at a time (a page that does not read holds one
        chunk, not the scene), then the page's role; frames start after it."""
        client.pending = _Busy()  # no frame until the scene is there
        for packed in self.scene:
            written = self.send(client, packed)
            if written is None:
                return
            with contextlib.suppress(tornado.websocket.WebSocketClosedError, tornado.iostream.StreamClosedError):
                await written
            if client not in self.clients:
                return
        client.pending = None
        self.send(client, self.role(client))
        self.changed.set()  # a fresh frame for the new page

    def close(self, client: PageSocket) -> None:
        if client in self.clients:
            self.clients.remove(client)
        if client is self.controller:
            self.controller = None
            self.requests.put(("stop", {"dead_man": "the controlling page is gone"}, None))  # stop now
            for other in self.clients:
                self.send(other, self.role(other))

    # ------------------------------------------------------------------ what pages say
    def message(self, client: PageSocket, message: str | bytes, arrived: float) -> None:
        """One message from a page, read at ``arrived`` (monotonic s). Unreadable ones (not
        JSON, too deep, not an object) raise; ``PageSocket.on_message`` answers them."""
        data = json.loads(message)
        if not isinstance(data, dict) or not isinstance(data.get("type"), str):
            raise ValueError("not a message")
        kind = data["type"]
        if kind == "claim":
            if self.controller is None:
                self.controller = client
                self.last_heard = self.main_heard = arrived
                for other in self.clients:  # only a change of hands is news
                    self.send(other, self.role(other))
            return
        if client is not self.controller:
            if kind == "halt":  # an e-stop anyone watching may press: halting is always safe
                self.requests.put(("halt", {}, client))
            return  # otherwise watchers watch
        sent = self.sent_at(client, data.get("sent"), arrived)
        self.last_heard = sent
        self.main_heard = sent - self.main_silence(data)
        if kind == "input":
            self.input(data, sent)
        else:
            self.requests.put((kind, data, client))

    @staticmethod
    def main_silence(data: dict[str, Any]) -> float:
        """s the page's main thread had been silent when the message was sent: ``sent`` minus
        ``alive`` (both ms on the clock of the page's worker), 0 for a message without them
        (its sender vouches for itself)."""
        sent, alive = data.get("sent"), data.get("alive")
        for stamp in (sent, alive):
            if isinstance(stamp, bool) or not isinstance(stamp, int | float) or not math.isfinite(stamp):
                return 0.0
        return max(0.0, (float(sent) - float(alive)) / 1000.0)  # type: ignore[arg-type]

    @staticmethod
    def sent_at(client: PageSocket, stamp: object, arrived: float) -> float:
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

    def input(self, data: dict[str, Any], sent: float) -> None:
        """The controlling page's input, sent at ``sent``: the Teleop's command (or jog) now."""
        try:
            speed = min(max(float(data.get("speed", 1.0)), 0.0), 1.0)
            if not math.isfinite(speed):
                speed = 0.0
            keys = [str(code) for code in _listed(data.get("keys"))][:32]
            axes = _listed(data.get("axes"))[:16]
            buttons = _listed(data.get("buttons"))[:32]
            counts = _listed(data.get("hid"))[:6]  # a SpaceMouse's raw counts, read by the page (WebHID)
            jog = self.jog_rates(data.get("jog"), speed)
            seq = data.get("seq", 0)
            seq = int(seq) if isinstance(seq, int | float) and math.isfinite(seq) else self.input_seq
        except (TypeError, ValueError, OverflowError):
            return
        deflection = deflections(keys, axes, buttons, counts) * speed
        if sent - self.main_heard > self.freeze_limit and (deflection.any() or jog or self.teleop.reversing):
            self.teleop.dead_man_stop(self.frozen)
        elif jog:  # a jog button held wins over the sticks and keys
            self.teleop.jog(jog, now=sent)
        else:
            self.teleop.command(deflection[:3], deflection[3:], now=sent, mode=self.mode)
        self.input_seq = seq

    def jog_rates(self, signs: object, speed: float) -> dict[str, float]:
        """{joint: rate} from a message's ``jog`` ({joint name: deflection in [-1, 1]}, the
        page's held +/- buttons): deflection x speed x :data:`JOG_SHARE` x the joint's
        velocity limit (rad/s or m/s). Names that are not the robot's joints are ignored."""
        if not isinstance(signs, dict):
            return {}
        rates = {}
        for name, sign in list(signs.items())[:16]:
            gauge = self.jog_gauges.get(name)
            if gauge is None or isinstance(sign, bool) or not isinstance(sign, int | float) or not math.isfinite(sign):
                continue
            fallback = self.teleop.max_linear_speed if gauge.unit == "m" else self.teleop.max_angular_speed
            limit = gauge.velocity if gauge.velocity is not None else fallback
            rate = min(max(float(sign), -1.0), 1.0) * speed * JOG_SHARE * limit
            if rate:
                rates[name] = rate
        return rates


__all__ = [
    "CLOCK_DRIFT",
    "FLOOD_LIMIT",
    "FREEZE_LIMIT",
    "JOG_SHARE",
    "MAX_PAGES",
    "MESSAGE_BURST",
    "MESSAGE_RATE",
    "PageSocket",
    "Pages",
    "Request",
]
