"""The console's server without a browser: Host and Origin checks, the silent-page watchdog,
and the ``pinrate teleop`` process (Ctrl-C, SIGTERM, SIGKILL leave no process or port)."""

from __future__ import annotations

import asyncio
import http.client
import json
import os
import signal
import socket
import subprocess
import sys
import time

import numpy as np
import pytest
import tornado.httpclient
import tornado.websocket

import pinrate
from pinrate.teleop.server import TeleopServer
from support import wait_for

COMMAND = [sys.executable, "-m", "pinrate.cli"]


@pytest.fixture
def server(ur5, tmp_path):
    teleop = pinrate.Teleop(ur5, dt=0.002, timeout=0.3)
    with TeleopServer(teleop, record_dir=tmp_path) as running:
        yield running


def get(server, path: str, host: str) -> int:
    connection = http.client.HTTPConnection("127.0.0.1", server.port, timeout=10)
    connection.putrequest("GET", path, skip_host=True)
    connection.putheader("Host", host)
    connection.endheaders()
    status = connection.getresponse().status
    connection.close()
    return status


def test_the_page_and_meshcat_are_served_to_their_own_host_only(server):
    own = f"127.0.0.1:{server.port}"
    assert get(server, "/", own) == 200
    assert get(server, "/", f"localhost:{server.port}") == 200
    assert get(server, "/meshcat/main.min.js", own) == 200
    assert get(server, "/static/teleop.js", own) == 200
    assert get(server, "/", f"attacker.example:{server.port}") == 403  # DNS rebinding
    assert get(server, "/", "127.0.0.1:1") == 403
    assert get(server, "/static/../server.py", own) in (403, 404)


async def _connect(server, origin: str | None):
    headers = {"Origin": origin} if origin else {}
    request = tornado.httpclient.HTTPRequest(f"ws://127.0.0.1:{server.port}/ws", headers=headers)
    return await tornado.websocket.websocket_connect(request)


@pytest.mark.parametrize("origin", ["http://attacker.example", "https://127.0.0.1:1", "null"])
def test_a_socket_from_another_origin_is_refused(server, origin):
    async def attempt():
        with pytest.raises(tornado.httpclient.HTTPClientError) as refused:
            await _connect(server, origin)
        return refused.value.code

    assert asyncio.run(attempt()) == 403


def test_a_silent_controlling_page_stops_a_reversal(server):
    """A page that asked for a reversal and then froze (no heartbeat) stops the robot."""

    async def session():
        client = await _connect(server, f"http://127.0.0.1:{server.port}")
        hello = None
        while hello is None or hello.get("type") != "role":
            message = await client.read_message()
            if isinstance(message, str):
                hello = json.loads(message)
        assert hello["controlling"]
        for seq in range(1, 21):  # W held for 0.4 s, heartbeat every 20 ms
            await client.write_message(json.dumps({"type": "input", "seq": seq, "keys": ["KeyW"], "speed": 1}))
            await asyncio.sleep(0.02)
        await client.write_message(json.dumps({"type": "input", "seq": 21, "keys": [], "speed": 1}))
        await asyncio.sleep(0.1)
        await client.write_message(json.dumps({"type": "reverse"}))
        started = time.monotonic()
        while not server.teleop.reversing and time.monotonic() - started < 5:
            await asyncio.sleep(0.01)
        assert server.teleop.reversing
        # silent from now on, connection open
        while server.teleop.reversing and time.monotonic() - started < 5:
            await asyncio.sleep(0.01)
        stopped = time.monotonic() - started
        frame = await _frame_where(client, lambda f: not f["reversing"] and f["dead_man"] is not None)
        client.close()
        return stopped, frame

    stopped, frame = asyncio.run(session())
    assert server.teleop.timeout <= stopped < server.teleop.timeout + 0.3
    assert frame["dead_man"] == "reversal stopped: the controlling page is silent for 0.3 s"
    assert frame["status"].startswith("dead man: reversal stopped")
    assert server.teleop.recorder.times.size > 1  # stopped part-way: motion left to reverse


async def _controlling(server):
    """A socket from the page's own origin, read until its role (it controls)."""
    client = await _connect(server, f"http://127.0.0.1:{server.port}")
    while True:
        message = await client.read_message()
        if isinstance(message, str) and json.loads(message).get("type") == "role":
            assert json.loads(message)["controlling"]
            return client


async def _frame_where(client, condition, timeout: float = 5.0) -> dict:
    """The first frame read that meets ``condition``."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        message = await asyncio.wait_for(client.read_message(), timeout)
        if isinstance(message, str):
            data = json.loads(message)
            if data.get("type") == "frame" and condition(data):
                return data
    raise AssertionError("no such frame")


def test_a_dead_man_stop_is_said_in_the_frames_until_the_operator_drives_again(server):
    """A page that goes silent with W held: the robot stops within the timeout and every
    frame says why (``dead_man``), after the page speaks again too, until it drives."""

    async def session():
        client = await _controlling(server)
        for seq in range(1, 11):
            await asyncio.sleep(0.02)
            await client.write_message(json.dumps({"type": "input", "seq": seq, "keys": ["KeyW"]}))
        silent = time.monotonic()
        frame = await _frame_where(client, lambda f: f["dead_man"] is not None)
        said = time.monotonic() - silent
        assert not server.teleop.last.joint_rates.any()
        await client.write_message(json.dumps({"type": "input", "seq": 11, "keys": []}))  # back, idle
        await asyncio.sleep(0.2)
        server._changed.set()
        later = await _frame_where(client, lambda f: True)
        await client.write_message(json.dumps({"type": "input", "seq": 12, "keys": ["KeyA"]}))
        moving = await _frame_where(client, lambda f: f["moving"])
        client.close()
        return frame, said, later, moving

    frame, said, later, moving = asyncio.run(session())
    assert frame["dead_man"] == "no input for 0.3 s"
    assert frame["status"] == "dead man: no input for 0.3 s"
    assert server.teleop.timeout <= said < server.teleop.timeout + 1.0, said  # + a frame's delivery on a busy machine
    assert later["dead_man"] == "no input for 0.3 s"  # still said once the page is back
    assert moving["dead_man"] is None and moving["status"] != frame["status"]


def test_a_heartbeat_from_a_frozen_page_commands_nothing(server):
    """The worker's heartbeat goes on, but the page's main thread has been silent for longer
    than the freeze limit (``alive`` far behind ``sent``): the held W is zeroed, and said."""
    limit = server.freeze_limit

    async def beat(client, seq: int, keys: list[str], silence: float) -> None:
        now = time.monotonic() * 1e3  # the page's clock: this process's, in ms
        message = {"type": "input", "seq": seq, "keys": keys, "sent": now, "alive": now - silence * 1e3}
        await client.write_message(json.dumps(message))

    async def session():
        client = await _controlling(server)
        for seq in range(1, 11):  # slow: the main thread silent for most of a second, W held
            await beat(client, seq, ["KeyW"], 0.9 * limit)
            await asyncio.sleep(0.02)
        moving = server.teleop.last is not None and server.teleop.last.joint_rates.any()
        for seq in range(11, 21):  # frozen
            await beat(client, seq, ["KeyW"], limit + 0.05)
            await asyncio.sleep(0.02)
        q = server.teleop.q.copy()
        await asyncio.sleep(0.1)
        frozen_still = np.array_equal(server.teleop.q, q)
        frame = await _frame_where(client, lambda f: f["dead_man"] is not None)
        client.close()
        return moving, frozen_still, frame

    moving, frozen_still, frame = asyncio.run(session())
    assert moving and frozen_still
    assert frame["dead_man"] == f"the page froze: its main thread silent for {limit:g} s"


def start_cli(*arguments: str) -> tuple[subprocess.Popen[str], int]:
    process = subprocess.Popen(
        [*COMMAND, "teleop", "ur5", *arguments], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True
    )
    deadline = time.monotonic() + 60
    assert process.stdout is not None
    while time.monotonic() < deadline:
        line = process.stdout.readline()
        if line.startswith("console"):
            url = line.split()[1]
            return process, int(url.rsplit(":", 1)[1].strip("/"))
        assert line or process.poll() is None, process.communicate()
    raise AssertionError("the console never printed its URL")


def port_is_free(port: int) -> bool:
    with socket.socket() as probe:
        try:
            probe.bind(("127.0.0.1", port))
        except OSError:
            return False
    return True


def children(pid: int) -> list[int]:
    found = []
    for entry in os.listdir("/proc"):
        if entry.isdigit():
            try:
                with open(f"/proc/{entry}/stat", encoding="ascii") as stat:
                    if int(stat.read().rsplit(")", 1)[1].split()[1]) == pid:
                        found.append(int(entry))
            except (OSError, ValueError):
                continue
    return found


@pytest.mark.skipif(not os.path.exists("/proc/self/stat"), reason="needs Linux /proc")
def test_sigkill_leaves_no_process_and_no_port():
    process, port = start_cli()
    assert not port_is_free(port)
    assert children(process.pid) == []  # threads only: nothing to orphan
    process.kill()
    process.wait(timeout=10)
    deadline = time.monotonic() + 5
    while not port_is_free(port) and time.monotonic() < deadline:
        time.sleep(0.05)
    assert port_is_free(port)
    process.communicate()


@pytest.mark.parametrize(("signum", "code"), [(signal.SIGINT, 0), (signal.SIGTERM, 143)])
def test_ctrl_c_quits_and_sigterm_terminates_freeing_the_port(signum, code):
    process, port = start_cli("--rate", "250")
    process.send_signal(signum)
    _, err = process.communicate(timeout=20)
    assert process.returncode == code
    assert "Traceback" not in err
    assert port_is_free(port)


@pytest.mark.parametrize(
    ("arguments", "message"),
    [
        (["--rate", "0"], "--rate"),
        (["--rate", "100000"], "--rate must be at most"),
        (["--timeout", "-1"], "--timeout"),
        (["--singularity", "pray"], "--singularity"),
        (["--host", "192.0.2.1"], "not an address of this machine"),
        (["--port", "70000"], "--port"),
        (["--q0", "1", "2"], "--q0 takes 6 values"),
    ],
)
def test_bad_options_are_one_line_and_exit_2(arguments, message):
    result = subprocess.run([*COMMAND, "teleop", "ur5", *arguments], capture_output=True, text=True, timeout=60)
    assert result.returncode == 2, result.stderr
    assert message in result.stderr
    assert result.stderr.startswith("pinrate: error:") and "Traceback" not in result.stderr


def test_a_file_as_record_folder_is_refused(tmp_path):
    blocker = tmp_path / "file"
    blocker.write_text("x")
    result = subprocess.run(
        [*COMMAND, "teleop", "ur5", "--record-dir", str(blocker)], capture_output=True, text=True, timeout=60
    )
    assert result.returncode == 2
    assert "record folder" in result.stderr


def test_snapshot_and_poses_are_safe_beside_the_loop(server, ur5):
    q, _ = server.snapshot()
    np.testing.assert_allclose(server.tip_pose(q), ur5.pose(q), atol=1e-12)


def recorded_run(server, seconds: float):
    """Record ``seconds`` of +x motion through the console's actions; the Recording's files."""
    server.act("record", on=True)
    deadline = time.monotonic() + seconds
    while time.monotonic() < deadline:
        server.teleop.command([1, 0, 0], [0, 0, 0])
        time.sleep(0.02)
    server.act("record", on=False)


def test_each_catch_up_tick_is_recorded_at_its_own_time(server):
    """The loop runs the ticks a late wake-up missed: each is stamped at its own time, so a
    recording's times advance tick by tick (they once shared the wake-up's stamp: 7-86 %)."""
    captured = []
    original = server.teleop.stop_recording

    def keep():
        recording = original()
        captured.append(recording)
        return recording

    server.teleop.stop_recording = keep
    real_tick, calls = server.teleop.tick, [0]

    def sometimes_slow(now=None):  # every 20th tick costs 3 periods: the loop must catch up
        calls[0] += 1
        if calls[0] % 20 == 0:
            time.sleep(0.006)
        return real_tick(now)

    server.teleop.tick = sometimes_slow
    recorded_run(server, 0.5)
    assert wait_for(lambda: len(server.saved) == 2, timeout=30)
    times = captured[0].times
    assert times.size > 100
    assert np.all(np.diff(times) > 0)  # no two ticks share a stamp


CLOSE_RIGHT_AFTER_RECORDING = """
import sys, time, pinrate
from pinrate.teleop.server import TeleopServer
teleop = pinrate.Teleop(pinrate.load("ur5"), dt=0.002, timeout=0.3)
server = TeleopServer(teleop, record_dir=sys.argv[1])
server.act("record", on=True)
for _ in range(15):
    teleop.command([1, 0, 0], [0, 0, 0])
    time.sleep(0.02)
server.act("record", on=False)
time.sleep(0.01)  # the loop takes the action and starts the save
server.close()  # as Ctrl-C does; then the interpreter exits, killing daemon threads
"""


def test_close_right_after_stopping_a_recording_writes_it_whole(tmp_path):
    subprocess.run([sys.executable, "-c", CLOSE_RIGHT_AFTER_RECORDING, str(tmp_path)], check=True, timeout=120)
    assert sorted(path.suffix for path in tmp_path.iterdir()) == [".html", ".npz"]
    assert next(tmp_path.glob("*.html")).read_text().rstrip().endswith("</html>")


def test_a_recording_without_a_tick_is_said_and_not_saved(server, caplog):
    messages = []
    original = server.pages.event
    server.pages.event = lambda text, *args, **kwargs: (messages.append(text), original(text, *args, **kwargs))
    server.teleop.halt()  # the loop still ticks; stop the recording before any tick lands
    server.act("record", on=True)
    server.act("record", on=False)
    assert wait_for(lambda: any("no tick was recorded" in text for text in messages), timeout=30)
    time.sleep(0.3)
    assert server.saved == []  # nothing to replay: no files, and no save thread died
    assert not [record for record in caplog.records if record.levelname == "ERROR"]


def test_with_no_page_a_command_from_python_drives_the_robot(server):
    """No page controls: the page's dead-man rules (silent, frozen) are not the caller's."""
    start = server.snapshot()[0]
    deadline = time.monotonic() + 0.3
    while time.monotonic() < deadline:
        server.teleop.command([1, 0, 0], [0, 0, 0])
        time.sleep(0.02)
    assert not np.array_equal(server.snapshot()[0], start)
    assert not server.teleop.dead_man


def test_a_plant_in_the_console_keeps_to_the_wall_clock(ur5, tmp_path):
    """Each tick advances the plant by the controller's dt and the loop runs its missed ticks,
    so the simulated time follows the wall clock: within 20 % over a second of driving (a
    loaded 2-core machine drops at most what the loop's catch-up rule drops), never ahead
    of it by more than a tick."""
    pytest.importorskip("mujoco")
    from pinrate.plants import MujocoPlant

    teleop = pinrate.Teleop(ur5, dt=0.002, timeout=0.3, plant=MujocoPlant(ur5))
    with TeleopServer(teleop, record_dir=tmp_path) as running:
        simulated, began = running.teleop.measurement.time, time.monotonic()
        while time.monotonic() - began < 1.0:
            running.teleop.command([0.5, 0, 0], [0, 0, 0])
            time.sleep(0.02)
        simulated, elapsed = running.teleop.measurement.time - simulated, time.monotonic() - began
        moved = running.teleop.measurement.joint_rates.any()
    assert 0.8 * elapsed <= simulated <= elapsed + 0.002
    assert moved and not running.teleop.halted
