"""The console's HTTP side: what it serves and what one client may cost it.

The page, its script, stylesheet and heartbeat worker, meshcat's own ``main.min.js``
(:func:`console_files`: read once at start, so nothing else on disk is reachable) and the
recordings this server wrote, by name; every other path is 404. Every handler is
:class:`Guarded`: :mod:`.access`'s rule (Host on every request, the token where the page
needs it, no framing) and never a traceback. The WebSocket handler (:mod:`.page_socket`) is
one too. The HTTP server (:func:`web_server`) caps what a client can cost:
:data:`MAX_CONNECTIONS` connections (the oldest goes first) and :data:`HEADER_TIMEOUT` to
send a request's headers.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import tornado.httpserver
import tornado.iostream
import tornado.web

from ..viewer.offline import MAIN_JS
from .access import SECURITY_HEADERS, AccessPolicy

STATIC = Path(__file__).parent / "static"

MAX_CONNECTIONS = 64
"""HTTP connections open at once; a new one beyond closes the oldest (so half-sent requests
cannot lock the operator's page out)."""

HEADER_TIMEOUT = 10.0
"""Seconds a connection has to send a request's headers (and an idle keep-alive to stay)."""

MAX_MESSAGE = 1 << 16
"""Bytes a WebSocket message may have (a page's are well under 1 kB)."""

Files = dict[str, tuple[str, bytes]]
"""The console's own files by name: (content type, bytes)."""


def console_files() -> Files:
    """The console's own files (content type, bytes), read once: all it serves besides the
    recordings."""
    return {
        "index.html": ("text/html; charset=utf-8", (STATIC / "index.html").read_bytes()),
        "teleop.js": ("text/javascript; charset=utf-8", (STATIC / "teleop.js").read_bytes()),
        "teleop.css": ("text/css; charset=utf-8", (STATIC / "teleop.css").read_bytes()),
        "heartbeat.js": ("text/javascript; charset=utf-8", (STATIC / "heartbeat.js").read_bytes()),
        "main.min.js": ("text/javascript; charset=utf-8", MAIN_JS.read_bytes()),
    }


class Guarded(tornado.web.RequestHandler):
    """Every response carries :data:`~.access.SECURITY_HEADERS`; every request must name this
    server in its Host header (DNS rebinding), and, where ``needs_token``, carry the token.
    Each handler's ``initialize`` takes ``access``, the :class:`~.access.AccessPolicy`."""

    needs_token = False
    access: AccessPolicy

    def set_default_headers(self) -> None:
        for name, value in SECURITY_HEADERS.items():
            self.set_header(name, value)

    def prepare(self) -> None:
        policy = self.access
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


class Missing(Guarded):
    """Every other path: 404 (with the security headers)."""

    def initialize(self, access: AccessPolicy) -> None:
        self.access = access

    def get(self, *args: str) -> None:
        raise tornado.web.HTTPError(404)


class Page(Guarded):
    """The console's page (with the token when there is one)."""

    needs_token = True

    def initialize(self, access: AccessPolicy, files: Files) -> None:
        self.access = access
        self.files = files

    def get(self) -> None:
        self.set_header("Content-Type", "text/html; charset=utf-8")
        self.write(self.files["index.html"][1])


class File(Guarded):
    """The console's own files, read once at start: nothing else on disk is reachable."""

    def initialize(self, access: AccessPolicy, files: Files) -> None:
        self.access = access
        self.files = files

    def get(self, name: str) -> None:
        entry = self.files.get(name)
        if entry is None or name == "index.html":
            raise tornado.web.HTTPError(404)
        self.set_header("Content-Type", entry[0])
        self.write(entry[1])


class RecordingFile(Guarded):
    """A file this server wrote (a recording's .npz or .html), by name; nothing else."""

    needs_token = True

    def initialize(self, access: AccessPolicy, served: dict[str, Path]) -> None:
        self.access = access
        self.served = served

    def get(self, name: str) -> None:
        path = self.served.get(name)
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


class CappedServer(tornado.httpserver.HTTPServer):
    """At most :data:`MAX_CONNECTIONS` HTTP connections (a socket that became a WebSocket
    leaves tornado's count, and :data:`~.page_socket.MAX_PAGES` caps those): a new one beyond
    closes the oldest, so connections that never finish their headers cannot lock the page out."""

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


def web_server(
    access: AccessPolicy,
    files: Files,
    served: dict[str, Path],
    socket: tuple[type[Guarded], dict[str, Any]],
) -> CappedServer:
    """The console's HTTP server: the page (``/``), its files, meshcat's script, the
    recordings in ``served`` and, at ``/ws``, ``socket`` (the WebSocket handler and its
    ``initialize`` arguments); not yet listening (add the sockets)."""
    app = tornado.web.Application(
        [
            (r"/", Page, {"access": access, "files": files}),
            (r"/ws", *socket),
            (r"/static/(teleop\.js|teleop\.css|heartbeat\.js)", File, {"access": access, "files": files}),
            (r"/meshcat/(main\.min\.js)", File, {"access": access, "files": files}),
            (r"/recordings/([^/]+)", RecordingFile, {"access": access, "served": served}),
        ],
        default_handler_class=Missing,
        default_handler_args={"access": access},
        websocket_max_message_size=MAX_MESSAGE,
        log_function=lambda handler: None,  # the console is the log; tornado's access lines are noise
    )
    return CappedServer(
        app,
        idle_connection_timeout=HEADER_TIMEOUT,  # tornado's header timeout (default 3600 s)
        body_timeout=HEADER_TIMEOUT,
        max_header_size=16 << 10,
        max_body_size=64 << 10,
    )


__all__ = [
    "HEADER_TIMEOUT",
    "MAX_CONNECTIONS",
    "STATIC",
    "CappedServer",
    "File",
    "Guarded",
    "Missing",
    "Page",
    "RecordingFile",
    "console_files",
    "web_server",
]
