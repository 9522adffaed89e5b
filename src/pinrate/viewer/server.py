"""A Meshcat server in its own process: bound to one address, stopped with its parent."""

from __future__ import annotations

import atexit
import ipaddress
import os
import socket
import subprocess
import sys
import time
import warnings

from ..errors import ViewerError

SERVER_START_TIMEOUT = 30.0
"""Seconds the server process has to report its URLs."""


def check_host(host: object) -> str:
    """``host`` if this machine can listen on it; ViewerError naming it otherwise. Warns when
    it is not a loopback address (anyone who reaches this machine can open the viewer)."""
    if not isinstance(host, str) or not host:
        raise ViewerError(f"host must be an address or host name of this machine, got {host!r}")
    try:
        candidates = socket.getaddrinfo(host, 0, type=socket.SOCK_STREAM)
    except (socket.gaierror, UnicodeError) as error:
        reason = getattr(error, "strerror", None) or str(error)
        raise ViewerError(f"host {host!r} is not a known address ({reason})") from None
    candidates = [candidate for candidate in candidates if candidate[0] == socket.AF_INET]
    if not candidates:
        raise ViewerError(f"host {host!r}: meshcat's server listens on IPv4 addresses only (try 127.0.0.1)")
    failure = ""
    for family, kind, protocol, _, address in candidates:
        try:
            with socket.socket(family, kind, protocol) as probe:
                probe.bind(address)
        except OSError as error:
            failure = error.strerror or str(error)
            continue
        if not ipaddress.ip_address(address[0]).is_loopback:
            warnings.warn(
                f"the viewer listens on {host} ({address[0]}): anyone who can reach this machine can open it",
                stacklevel=3,
            )
        return host
    raise ViewerError(f"host {host!r} is not an address of this machine: cannot listen there ({failure})")


def check_reachable(zmq_url: object, timeout: float = 2.0) -> str:
    """``zmq_url`` (``tcp://host:port``) if something accepts connections there; ViewerError
    otherwise (meshcat itself would wait for an answer for ever)."""
    if not isinstance(zmq_url, str) or not zmq_url.startswith("tcp://") or ":" not in zmq_url[6:]:
        raise ViewerError(f"zmq_url must look like 'tcp://127.0.0.1:6000', got {zmq_url!r}")
    host, _, port = zmq_url[6:].rpartition(":")
    try:
        with socket.create_connection((host, int(port)), timeout=timeout):
            return zmq_url
    except (OSError, ValueError) as error:
        reason = getattr(error, "strerror", None) or str(error)
        raise ViewerError(f"no Meshcat server at {zmq_url} ({reason})") from None


class MeshcatServer:
    """A Meshcat server subprocess bound to ``host``; closed on :meth:`close`, on exit, or
    by itself when this process dies (it watches its parent)."""

    def __init__(self, host: str = "127.0.0.1") -> None:
        host = check_host(host)
        command = [
            sys.executable,
            "-u",
            "-m",
            "pinrate.viewer.meshcat_process",
            "--host",
            host,
            "--parent",
            str(os.getpid()),
        ]
        self.process = subprocess.Popen(
            command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, start_new_session=True
        )  # Ctrl-C reaches us, we close it
        atexit.register(self.close)
        self.zmq_url = self._read_line("zmq_url=")
        self.web_url = self._read_line("web_url=")

    def _read_line(self, prefix: str) -> str:
        deadline = time.monotonic() + SERVER_START_TIMEOUT
        assert self.process.stdout is not None
        while time.monotonic() < deadline:
            line = self.process.stdout.readline().decode("utf-8", "replace").strip()
            if line.startswith(prefix):
                return line[len(prefix) :]
            if not line and self.process.poll() is not None:
                error = self.process.stderr.read().decode("utf-8", "replace") if self.process.stderr else ""
                last = [line.strip() for line in error.splitlines() if line.strip()][-1:] or ["no message"]
                raise ViewerError(f"the Meshcat server exited with code {self.process.returncode}: {last[0]}")
        self.close()
        raise ViewerError(f"the Meshcat server did not report {prefix[:-1]} within {SERVER_START_TIMEOUT:g} s")

    @property
    def pid(self) -> int:
        return self.process.pid

    def close(self) -> None:
        """Stop the server and free its ports (idempotent)."""
        if self.process.poll() is None:
            self.process.terminate()
            try:
                self.process.wait(timeout=5)
            except subprocess.TimeoutExpired:
                self.process.kill()
                self.process.wait()
        for stream in (self.process.stdout, self.process.stderr):
            if stream is not None:
                stream.close()
