"""Who may reach the teleop console: the security model of :class:`~.server.TeleopServer`.

A robot console is a safety device: whoever drives the page drives the robot. The rules,
applied to every HTTP request and every WebSocket handshake:

- **Host**: the request's ``Host`` header names this server: on a loopback bind
  ``127.0.0.1``, ``localhost`` or ``[::1]`` with the server's port; on another address that
  address (or, for a wildcard bind such as ``0.0.0.0``, an address of this machine) or the
  host name it was given, with the port. A page served under another name (DNS rebinding:
  ``evil.example`` resolving to 127.0.0.1) is refused.
- **Origin** (WebSocket handshakes): required, and exactly ``http://`` + the request's own
  allowed Host: the socket comes from a page this server served, under the name it was
  served under. A client without an Origin is refused (browsers always send one, so only
  scripts omit it, and a script that can omit it can also send a token).
- **Token**: off loopback a random token (:data:`TOKEN_BYTES` bytes, URL-safe) is part of
  the URL the server prints; the page and every socket must present it, so reaching the
  address is not enough: whoever has the URL can drive the robot (the CLI says so).
- **Framing**: ``X-Frame-Options: DENY`` and ``Content-Security-Policy: frame-ancestors
  'none'`` on every response (no invisible console inside another page: clickjacking);
  ``Referrer-Policy: no-referrer`` so that the token never leaves in a Referer.
"""

from __future__ import annotations

import hmac
import ipaddress
import secrets
import socket
from urllib.parse import urlsplit

TOKEN_BYTES = 24
"""Random bytes in the token of a console that listens beyond loopback (192 bits)."""

LOOPBACK_NAMES = frozenset({"127.0.0.1", "localhost", "[::1]"})
"""The names a loopback console answers to (with its port)."""

SECURITY_HEADERS = {
    "X-Frame-Options": "DENY",
    "Content-Security-Policy": "frame-ancestors 'none'",
    "X-Content-Type-Options": "nosniff",
    "Referrer-Policy": "no-referrer",
    "Cache-Control": "no-store",
}
"""Headers every response of the console carries."""


def is_loopback(host: str) -> bool:
    """True when ``host`` (an address or a name) resolves to a loopback address."""
    try:
        return ipaddress.ip_address(socket.gethostbyname(host)).is_loopback
    except (OSError, UnicodeError, ValueError):
        return False


def _machine_addresses() -> set[str]:
    """The IPv4 addresses this machine is known by: its host name's addresses and the one it
    sends from towards the outside (found by connecting a UDP socket: no packet leaves)."""
    addresses = {"127.0.0.1"}
    try:
        for *_, address in socket.getaddrinfo(socket.gethostname(), None, family=socket.AF_INET):
            addresses.add(str(address[0]))
    except (OSError, UnicodeError):
        pass
    outward = _outward_address()
    if outward:
        addresses.add(outward)
    return addresses


def _outward_address() -> str:
    """The address this machine sends from towards a public address ('' without a route)."""
    try:
        with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as probe:
            probe.connect(("192.0.2.1", 9))  # TEST-NET-1: connect() on UDP only picks a route
            return str(probe.getsockname()[0])
    except OSError:
        return ""


class AccessPolicy:
    """The rules above for a server bound to ``host:port``.

    Args:
        host: the address (or name) the server listens on.
        port: its port.
        token: None: a fresh random token when ``host`` is not loopback, none on loopback;
            a string: that token (anywhere); ``""``: none (loopback only: refused elsewhere).

    Attributes:
        token: the token requests must carry (``?token=...``), or ``""``.
        url_host: the host to print in the console's URL: a real address of this machine
            (never ``0.0.0.0``).
    """

    def __init__(self, host: str, port: int, token: str | None = None) -> None:
        self.port = int(port)
        self.loopback = is_loopback(host)
        wildcard = host in ("0.0.0.0", "")
        if token is None:
            token = "" if self.loopback else secrets.token_urlsafe(TOKEN_BYTES)
        if not token and not self.loopback:
            raise ValueError("a console that listens beyond loopback needs a token")
        self.token = token
        if self.loopback:
            names = set(LOOPBACK_NAMES) | {host.lower()}
            self.url_host = host
        elif wildcard:
            names = _machine_addresses() | set(LOOPBACK_NAMES) | {socket.gethostname().lower()}
            self.url_host = _outward_address() or socket.gethostname()
        else:
            names = {host.lower(), socket.gethostbyname(host)}
            self.url_host = host
        self.names = frozenset(names)

    @property
    def url(self) -> str:
        """The URL to open: the real address, the port and, when there is one, the token."""
        query = f"?token={self.token}" if self.token else ""
        return f"http://{self.url_host}:{self.port}/{query}"

    def host_allowed(self, header: str | None) -> bool:
        """True when a ``Host`` header names this server (see the module)."""
        if not header:
            return False
        name, _, port = header.strip().lower().rpartition(":")
        return bool(name) and port == str(self.port) and name in self.names

    def origin_allowed(self, origin: str | None, host_header: str | None) -> bool:
        """True when a handshake's ``Origin`` is the page this server served under
        ``host_header``: ``http://`` + that Host exactly (no Origin: refused)."""
        if not origin or not self.host_allowed(host_header):
            return False
        parts = urlsplit(origin.strip().lower())
        return parts.scheme == "http" and parts.netloc == str(host_header).strip().lower() and not parts.path

    def token_allowed(self, given: str | None) -> bool:
        """True when no token is required, or ``given`` is the token (compared in constant time)."""
        if not self.token:
            return True
        return given is not None and hmac.compare_digest(given.encode("utf-8"), self.token.encode("utf-8"))


__all__ = ["SECURITY_HEADERS", "TOKEN_BYTES", "AccessPolicy", "_machine_addresses", "is_loopback"]
