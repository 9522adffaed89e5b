"""The console under attack, over loopback, against the real server (issue 21).

Each test is an attack somebody ran against an earlier console, bounded in count and time:
DNS rebinding, a socket without an Origin, files outside the recordings, framing, a shared
address without a token, idle and slow clients, floods, malformed messages, a backlog that
kept the robot moving, and an exception in the control loop. The model they check is
:mod:`pinrate.teleop.access` and the caps of :mod:`pinrate.teleop.handlers` and
:mod:`pinrate.teleop.protocol` (re-exported by :mod:`pinrate.teleop.server`).
"""

from __future__ import annotations

import asyncio
import contextlib
import gc
import http.client
import json
import logging
import socket
import time
import warnings

import numpy as np
import pytest
import tornado.httpclient
import tornado.websocket

import pinrate
from pinrate.teleop import handlers
from pinrate.teleop import server as server_module
from pinrate.teleop.server import MAX_PAGES, TeleopServer
from support import wait_for

KEY = "dGhlIHNhbXBsZSBub25jZQ=="  # any 16 bytes, base64: RFC 6455's example


@pytest.fixture
def server(ur5, tmp_path):
    teleop = pinrate.Teleop(ur5, dt=0.002, timeout=0.3)
    with TeleopServer(teleop, record_dir=tmp_path / "runs") as running:
        yield running


def handshake(port: int, host: str, origin: str | None, path: str = "/ws", extra: tuple[str, ...] = ()) -> int:
    """The status of a raw WebSocket handshake with exactly these headers."""
    lines = [
        f"GET {path} HTTP/1.1",
        f"Host: {host}",
        "Upgrade: websocket",
        "Connection: Upgrade",
        f"Sec-WebSocket-Key: {KEY}",
        "Sec-WebSocket-Version: 13",
        *extra,
    ]
    if origin is not None:
        lines.append(f"Origin: {origin}")
    with socket.create_connection(("127.0.0.1", port), timeout=10) as raw:
        raw.sendall(("\r\n".join(lines) + "\r\n\r\n").encode())
        answer = b""
        while b"\r\n" not in answer:
            chunk = raw.recv(4096)
            if not chunk:
                break
            answer += chunk
    return int(answer.split(b"\r\n", 1)[0].split()[1])


def request(port: int, path: str, host: str | None = None) -> http.client.HTTPResponse:
    connection = http.client.HTTPConnection("127.0.0.1", port, timeout=10)
    connection.putrequest("GET", path, skip_host=True)
    connection.putheader("Host", host or f"127.0.0.1:{port}")
    connection.endheaders()
    response = connection.getresponse()
    response.body = response.read()  # type: ignore[attr-defined]
    connection.close()
    return response


async def connect(server: TeleopServer, query: str = "") -> tornado.websocket.WebSocketClientConnection:
    own = f"127.0.0.1:{server.port}"
    url = f"ws://{own}/ws{query}"
    return await tornado.websocket.websocket_connect(
        tornado.httpclient.HTTPRequest(url, headers={"Origin": f"http://{own}"})
    )


async def until_role(client: tornado.websocket.WebSocketClientConnection) -> dict:
    """Read until the role message (after hello and the scene)."""
    while True:
        message = await asyncio.wait_for(client.read_message(), 30)
        assert message is not None, "the server closed the socket"
        if isinstance(message, str) and json.loads(message)["type"] == "role":
            return json.loads(message)


# ---------------------------------------------------------------- who may connect
@pytest.mark.parametrize(
    ("host", "origin", "extra"),
    [
        ("evil.example:{port}", "http://evil.example:{port}", ()),  # DNS rebinding: Origin matches Host
        ("evil.example:{port}", "http://evil.example:{port}", ("Sec-Fetch-Site: same-origin",)),
        ("127.0.0.1:{port}", None, ()),  # no Origin: a script, not a page
        ("127.0.0.1:{port}", "http://localhost:{port}", ()),  # served under another name
        ("127.0.0.1:{port}", "https://127.0.0.1:{port}", ()),
        ("127.0.0.1:{port}", "http://127.0.0.1:{port}/x", ()),
        ("127.0.0.1:1", "http://127.0.0.1:1", ()),
    ],
)
def test_a_handshake_that_is_not_from_the_served_page_is_refused(server, host, origin, extra):
    port = server.port
    given = origin.format(port=port) if origin else None
    assert handshake(port, host.format(port=port), given, extra=extra) == 403
    assert server.clients == 0


def test_the_served_page_may_connect(server):
    own = f"127.0.0.1:{server.port}"
    assert handshake(server.port, own, f"http://{own}") == 101
    local = f"localhost:{server.port}"
    assert handshake(server.port, local, f"http://{local}") == 101


def test_only_files_this_server_wrote_are_served(server, tmp_path):
    folder = server.record_dir
    (folder / "id_ed25519").write_text("a secret key")
    (folder / ".ssh").mkdir()
    (folder / ".ssh" / "id_ed25519").write_text("a secret key")
    for path in ("/recordings/id_ed25519", "/recordings/.ssh/id_ed25519", "/recordings/..%2fserver.py"):
        response = request(server.port, path)
        assert response.status == 404, path
        assert b"secret" not in response.body
    for path in ("/static/index.html", "/static/../access.py", "/static/teleop.js%00.png", "/static/"):
        response = request(server.port, path)
        assert response.status == 404, path
        assert b"Traceback" not in response.body
    # a run recorded here is served, under a name of its own each time
    server.act("record", on=True)
    server.teleop.command([1, 0, 0], [0, 0, 0])
    time.sleep(0.05)
    server.act("record", on=False)
    server.act("record", on=True)
    time.sleep(0.05)
    server.act("record", on=False)
    assert wait_for(lambda: len(server.saved) == 4, timeout=60), server.saved
    assert len({path.name for path in server.saved}) == 4  # two runs within a second: four files
    for path in server.saved:
        assert request(server.port, f"/recordings/{path.name}").status == 200


def test_every_answer_forbids_framing(server):
    for path, host in [
        ("/", None),
        ("/static/teleop.js", None),
        ("/meshcat/main.min.js", None),
        ("/nothing", None),
        ("/", "evil.example:1"),
    ]:
        response = request(server.port, path, host)
        assert response.getheader("X-Frame-Options") == "DENY", path
        assert "frame-ancestors 'none'" in (response.getheader("Content-Security-Policy") or ""), path


def test_a_shared_address_needs_the_token_the_url_carries(ur5, tmp_path):
    teleop = pinrate.Teleop(ur5, dt=0.002)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        shared = TeleopServer(teleop, host="0.0.0.0", record_dir=tmp_path)
    with shared:
        assert any("can drive the robot" in str(warning.message) for warning in caught)
        assert "0.0.0.0" not in shared.url
        token = shared.access.token
        assert len(token) >= 32 and f"?token={token}" in shared.url
        port = shared.port
        own = f"127.0.0.1:{port}"
        assert request(port, "/").status == 403
        assert request(port, f"/?token={token[:-1]}").status == 403
        assert request(port, f"/?token={token}").status == 200
        assert handshake(port, own, f"http://{own}") == 403
        assert handshake(port, own, f"http://{own}", path=f"/ws?token={token}") == 101
        # an IP literal that is not this machine's is no Host of this server
        assert request(port, f"/?token={token}", host=f"203.0.113.7:{port}").status == 403
        assert handshake(port, f"203.0.113.7:{port}", f"http://203.0.113.7:{port}", path=f"/ws?token={token}") == 403


# ---------------------------------------------------------------- what a client can cost
def test_a_page_that_never_reads_holds_one_chunk_of_the_scene_not_the_scene(server):
    largest = max(len(chunk) for chunk in server.pages.scene)
    assert sum(len(chunk) for chunk in server.pages.scene) > 2 * largest  # the claim below means something
    sockets = []
    for _ in range(3):
        raw = socket.create_connection(("127.0.0.1", server.port))
        raw.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 4096)
        own = f"127.0.0.1:{server.port}"
        raw.sendall(
            (
                f"GET /ws HTTP/1.1\r\nHost: {own}\r\nOrigin: http://{own}\r\nUpgrade: websocket\r\n"
                f"Connection: Upgrade\r\nSec-WebSocket-Key: {KEY}\r\nSec-WebSocket-Version: 13\r\n\r\n"
            ).encode()
        )
        sockets.append(raw)
    try:
        assert wait_for(lambda: server.clients == 3)
        time.sleep(1.0)
        for client in list(server.pages.clients):
            queued = len(client.ws_connection.stream._write_buffer)  # tornado's unsent bytes
            assert queued <= largest + 64, (queued, largest)
    finally:
        for raw in sockets:
            raw.close()


def test_the_number_of_pages_is_capped(server):
    async def attack():
        clients = [await connect(server) for _ in range(MAX_PAGES)]
        with pytest.raises(tornado.httpclient.HTTPClientError) as refused:
            await connect(server)
        for client in clients:
            client.close()
        return refused.value.code

    assert asyncio.run(attack()) == 503


def test_pages_gone_mid_write_leave_no_unretrieved_task(server, caplog):
    caplog.set_level(logging.ERROR)
    for _ in range(10):
        raw = socket.create_connection(("127.0.0.1", server.port))
        own = f"127.0.0.1:{server.port}"
        raw.sendall(
            (
                f"GET /ws HTTP/1.1\r\nHost: {own}\r\nOrigin: http://{own}\r\nUpgrade: websocket\r\n"
                f"Connection: Upgrade\r\nSec-WebSocket-Key: {KEY}\r\nSec-WebSocket-Version: 13\r\n\r\n"
            ).encode()
        )
        raw.recv(1024)
        raw.setsockopt(socket.SOL_SOCKET, socket.SO_LINGER, b"\x01\x00\x00\x00\x00\x00\x00\x00")  # RST
        raw.close()
    assert wait_for(lambda: server.clients == 0)
    time.sleep(0.3)
    gc.collect()
    unretrieved = [record for record in caplog.records if "never retrieved" in record.getMessage()]
    assert not unretrieved, unretrieved[0].getMessage()


def test_half_sent_requests_neither_lock_the_page_out_nor_stay(ur5, tmp_path, monkeypatch):
    monkeypatch.setattr(handlers, "HEADER_TIMEOUT", 1.0)  # read where the HTTP server is made
    teleop = pinrate.Teleop(ur5, dt=0.002)
    with TeleopServer(teleop, record_dir=tmp_path) as running:
        partial = []
        for _ in range(3 * server_module.MAX_CONNECTIONS):
            raw = socket.create_connection(("127.0.0.1", running.port))
            raw.sendall(b"GET / HTTP/1.1\r\nHost: 127.0.0.1\r\n")  # never the blank line
            partial.append(raw)
        started = time.monotonic()
        assert request(running.port, "/").status == 200
        assert time.monotonic() - started < 2.0
        time.sleep(1.5)  # past the header timeout: the server closed the survivors
        for raw in partial:
            raw.settimeout(2.0)
            with contextlib.suppress(ConnectionResetError):  # closed with a reset: closed too
                assert raw.recv(1024) == b""
            raw.close()


def test_a_claim_flood_costs_the_others_nothing(server):
    async def attack():
        operator = await connect(server)
        await until_role(operator)
        watcher = await connect(server)
        await until_role(watcher)
        sent = 0
        with contextlib.suppress(tornado.websocket.WebSocketClosedError):  # cut off: the point
            while sent < 3000:
                await watcher.write_message(json.dumps({"type": "claim"}))
                sent += 1
        await asyncio.sleep(0.5)
        roles = 0
        while True:
            try:
                message = await asyncio.wait_for(operator.read_message(), 0.2)
            except asyncio.TimeoutError:  # TimeoutError itself from Python 3.11 on
                break
            if isinstance(message, str) and json.loads(message)["type"] == "role":
                roles += 1
        started = time.monotonic()
        status = await asyncio.get_running_loop().run_in_executor(None, lambda: request(server.port, "/").status)
        served = time.monotonic() - started
        closed = watcher.close_code
        if closed is None:
            for _ in range(200):
                if await watcher.read_message() is None:
                    break
            closed = watcher.close_code
        operator.close()
        return roles, status, served, closed, sent

    roles, status, served, closed, sent = asyncio.run(attack())
    assert sent >= server_module.FLOOD_LIMIT
    assert roles == 0  # nothing changed hands: nothing to tell the operator
    assert status == 200 and served < 1.0
    assert closed == 1008  # the flooder is disconnected


@pytest.mark.parametrize(
    ("message", "answered"),
    [
        ('{"type": "input", "seq": 1e400, "keys": ["KeyW"]}', False),  # OverflowError once
        ("[" * 20000 + "]" * 20000, True),  # RecursionError once
        ('{"type": "input", "keys": "KeyW", "axes": {"a": 1}, "speed": "fast"}', False),
        ('"input"', True),
        ("\x00", True),
    ],
)
def test_a_malformed_message_is_refused_and_the_socket_stays(server, message, answered):
    async def attack():
        client = await connect(server)
        await until_role(client)
        await client.write_message(message)
        said = False
        with contextlib.suppress(asyncio.TimeoutError):
            while True:
                reply = await asyncio.wait_for(client.read_message(), 0.5)
                if reply is None:
                    break
                if isinstance(reply, str) and "unreadable message" in reply:
                    said = True
                    break
        await client.write_message(json.dumps({"type": "input", "seq": 7, "keys": []}))
        deadline = time.monotonic() + 5
        while server.pages.input_seq != 7 and time.monotonic() < deadline:
            await asyncio.sleep(0.01)
        await asyncio.sleep(0.2)
        alive = server.clients == 1 and client.close_code is None
        client.close()
        return said, alive

    said, alive = asyncio.run(attack())
    assert alive
    assert server.pages.input_seq == 7
    assert said == answered


def test_a_command_is_aged_from_its_sending_not_its_reading(server):
    """A backlog (messages read late) must not move the robot: a held W stamped by the page
    longer ago than the timeout is a command that has already expired."""

    async def session():
        client = await connect(server)
        await until_role(client)
        for seq in range(1, 6):  # the page's clock: this process's monotonic clock, in ms
            await client.write_message(
                json.dumps({"type": "input", "seq": seq, "keys": [], "sent": time.monotonic() * 1e3})
            )
            await asyncio.sleep(0.02)
        await asyncio.sleep(0.1)
        before = server.teleop.q.copy()
        stale = (time.monotonic() - 2 * server.teleop.timeout) * 1e3
        await client.write_message(json.dumps({"type": "input", "seq": 6, "keys": ["KeyW"], "sent": stale}))
        await asyncio.sleep(0.2)
        after = server.teleop.q.copy()
        await client.write_message(
            json.dumps({"type": "input", "seq": 7, "keys": ["KeyW"], "sent": time.monotonic() * 1e3})
        )
        await asyncio.sleep(0.1)
        fresh = server.teleop.q.copy()
        client.close()
        return before, after, fresh

    before, after, fresh = asyncio.run(session())
    np.testing.assert_array_equal(after, before)  # the stale W never moved the robot
    assert not np.array_equal(fresh, after)  # a fresh one does: the test can see motion


# ---------------------------------------------------------------- the control loop
def test_an_exception_in_a_tick_halts_the_robot_says_so_once_and_the_console_goes_on(server, monkeypatch, caplog):
    caplog.set_level(logging.ERROR, logger="pinrate.teleop")
    real_tick = server.teleop.tick
    failures = {"left": 50}

    def failing_tick(now=None):
        if failures["left"] > 0:
            failures["left"] -= 1
            raise IndexError("a bug in a tick")
        return real_tick(now)

    async def session():
        client = await connect(server)
        await until_role(client)
        monkeypatch.setattr(server.teleop, "tick", failing_tick)
        events = []
        deadline = time.monotonic() + 5
        while failures["left"] > 0 and time.monotonic() < deadline:
            with pytest.raises(asyncio.TimeoutError):
                while True:
                    message = await asyncio.wait_for(client.read_message(), 0.1)
                    if isinstance(message, str) and json.loads(message)["type"] == "event":
                        events.append(json.loads(message))
        assert server.teleop.halted
        await client.write_message(json.dumps({"type": "resume"}))
        await client.write_message(json.dumps({"type": "input", "seq": 1, "keys": ["KeyW"]}))
        before = server.teleop.q.copy()
        await asyncio.sleep(0.2)
        moved = not np.array_equal(server.teleop.q, before)
        client.close()
        return events, moved

    events, moved = asyncio.run(session())
    said = [event for event in events if "control loop failed" in event["text"]]
    assert len(said) == 1 and said[0]["level"] == "error" and "IndexError" in said[0]["text"]
    assert len([record for record in caplog.records if "control loop failed" in record.getMessage()]) == 1
    assert server._threads[1].is_alive()
    assert moved  # resumed: the console is usable again
