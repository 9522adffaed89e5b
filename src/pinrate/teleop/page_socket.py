"""One page's WebSocket (:class:`PageSocket`): who may open one and what its messages may
cost. The handshake passes :class:`~.handlers.Guarded`'s checks, the Origin rule, the token
(:mod:`.access`) and the cap of :data:`MAX_PAGES`; a page may send :data:`MESSAGE_RATE`
messages a second on average, :data:`MESSAGE_BURST` at once, and one that keeps flooding for
:data:`FLOOD_LIMIT` dropped messages is disconnected. What the messages mean, and what the
page is sent, is the console's pages' (:class:`~.protocol.Pages`, through :class:`PageHost`).
"""

from __future__ import annotations

import logging
import math
import time
from typing import Any, Protocol

import tornado.web
import tornado.websocket

from .access import AccessPolicy
from .handlers import Guarded

MAX_PAGES = 8
"""WebSocket clients (pages) connected at once; the next is refused (503)."""

MESSAGE_RATE = 100.0
"""Messages a second a page may send on average (its heartbeat is 20, plus one per change);
:data:`MESSAGE_BURST` at once. Beyond, messages are dropped; a page that keeps flooding for
:data:`FLOOD_LIMIT` dropped messages is disconnected."""

MESSAGE_BURST = 200.0
"""Messages a page may send at once before :data:`MESSAGE_RATE` applies."""

FLOOD_LIMIT = 1000
"""Dropped messages after which a flooding page is disconnected."""

LOG = logging.getLogger("pinrate.teleop")


class PageHost(Protocol):
    """What a page's socket needs of the pages it is one of (:class:`~.protocol.Pages`)."""

    clients: list[PageSocket]

    def open(self, client: PageSocket) -> None: ...

    def message(self, client: PageSocket, message: str | bytes, arrived: float) -> None: ...

    def send(self, client: PageSocket, message: dict[str, Any] | bytes) -> Any: ...

    def close(self, client: PageSocket) -> None: ...


class PageSocket(Guarded, tornado.websocket.WebSocketHandler):
    """One page. The handshake passes :class:`~.handlers.Guarded`'s checks, the Origin rule
    and the cap; its messages are rate-limited, then read by its :class:`~.protocol.Pages`."""

    def initialize(self, access: AccessPolicy, pages: PageHost) -> None:
        self.access = access
        self.pages = pages
        self.pending: Any = None  # the last frame's write, not yet done
        self.client_id = 0
        self.allowance = MESSAGE_BURST
        self.refilled = time.monotonic()
        self.dropped = 0
        self.clock_offset = math.inf  # the least (arrival - the page's stamp) seen, s
        self.offset_at = 0.0  # when clock_offset was last updated (monotonic s)

    def refuse_beyond_host(self, policy: AccessPolicy) -> None:
        """After the Host's (``Guarded.prepare``): the Origin, the token, the cap."""
        if not policy.origin_allowed(self.request.headers.get("Origin"), self.request.host):
            raise tornado.web.HTTPError(403, reason="Origin not allowed")
        if not policy.token_allowed(self.get_query_argument("token", None)):
            raise tornado.web.HTTPError(403, reason="token missing or wrong")
        if len(self.pages.clients) >= MAX_PAGES:
            raise tornado.web.HTTPError(503, reason=f"{MAX_PAGES} pages are connected already")

    def check_origin(self, origin: str) -> bool:
        return self.access.origin_allowed(origin, self.request.host)

    def open(self, *args: str, **kwargs: str) -> None:
        self.set_nodelay(True)
        self.pages.open(self)

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
            self.pages.message(self, message, now)
        except Exception:  # a message must never take the socket (or the console) down
            LOG.debug("unreadable message", exc_info=True)
            self.pages.send(self, {"type": "event", "level": "error", "text": "unreadable message"})

    def on_close(self) -> None:
        self.pages.close(self)


__all__ = ["FLOOD_LIMIT", "MAX_PAGES", "MESSAGE_BURST", "MESSAGE_RATE", "PageHost", "PageSocket"]
