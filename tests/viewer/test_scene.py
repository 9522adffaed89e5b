"""The viewer without a browser: server lifetime, binding, drawing data, the demo command."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import textwrap
import time
from urllib.parse import urlparse

import numpy as np
import pinocchio as pin
import pytest

import pinrate
from pinrate.viewer import MeshcatServer, Viewer, path_colours


def process_alive(pid: int) -> bool:
    try:
        with open(f"/proc/{pid}/stat") as stat:
            return stat.read().split()[2] != "Z"
    except FileNotFoundError:
        return False


def listening_addresses(port: int) -> set[str]:
    """Local IPv4 addresses listening on ``port`` (from /proc/net/tcp, Linux)."""
    addresses = set()
    with open("/proc/net/tcp") as table:
        for line in table.readlines()[1:]:
            local, state = line.split()[1], line.split()[3]
            address, port_hex = local.split(":")
            if state == "0A" and int(port_hex, 16) == port:
                addresses.add(".".join(str(int(address[i : i + 2], 16)) for i in (6, 4, 2, 0)))
    return addresses


linux_only = pytest.mark.skipif(not os.path.exists("/proc/net/tcp"), reason="needs Linux /proc")


@linux_only
def test_server_listens_on_loopback_only_and_closes() -> None:
    server = MeshcatServer()
    try:
        port = urlparse(server.web_url).port
        assert listening_addresses(port) == {"127.0.0.1"}
    finally:
        server.close()
    time.sleep(0.2)
    assert not process_alive(server.pid)
    assert listening_addresses(port) == set()


@linux_only
def test_server_dies_with_a_killed_parent() -> None:
    script = textwrap.dedent("""
        import sys, time
        from pinrate.viewer import MeshcatServer
        server = MeshcatServer()
        print(server.pid, server.web_url, flush=True)
        time.sleep(60)
    """)
    parent = subprocess.Popen([sys.executable, "-c", script], stdout=subprocess.PIPE, text=True)
    try:
        pid, url = parent.stdout.readline().split()
        assert process_alive(int(pid))
        parent.kill()  # no atexit, no finally: only the server's own watch can save us
        parent.wait()
        deadline = time.monotonic() + 10
        while process_alive(int(pid)) and time.monotonic() < deadline:
            time.sleep(0.1)
        assert not process_alive(int(pid)), "the orphaned Meshcat server is still running"
        port = urlparse(url).port
        while listening_addresses(port) and time.monotonic() < deadline:  # the kernel frees it just after
            time.sleep(0.1)
        assert listening_addresses(port) == set()
    finally:
        parent.kill()
        parent.stdout.close()


@linux_only
def test_ctrl_c_on_the_demo_closes_the_server() -> None:
    demo = subprocess.Popen(
        [sys.executable, "-m", "pinrate.cli", "demo", "scara", "--speed", "0.2"],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        line = demo.stdout.readline()
        assert line.startswith("Meshcat viewer: http://127.0.0.1:"), line
        port = urlparse(line.split()[-1]).port
        time.sleep(1.0)
        demo.send_signal(signal.SIGINT)
        assert demo.wait(timeout=20) == 130  # interrupted: the CLI's documented exit code
        assert "Traceback" not in demo.stderr.read()
        deadline = time.monotonic() + 5
        while listening_addresses(port) and time.monotonic() < deadline:
            time.sleep(0.1)
        assert listening_addresses(port) == set()
    finally:
        demo.kill()
        demo.stdout.close()
        demo.stderr.close()


def test_path_colours() -> None:
    colours = path_colours(np.array([0.2, 0.99, 1.0, 3.0, np.inf]))
    assert colours.shape == (3, 5)
    np.testing.assert_array_equal(colours[:, 0], colours[:, 1])  # both converge: one colour
    np.testing.assert_array_equal(colours[:, 2], colours[:, 4])  # ρ >= 1 and undefined: the other
    assert not np.array_equal(colours[:, 0], colours[:, 2])


@pytest.fixture(scope="module")
def scara_viewer():
    viewer = Viewer(pinrate.robots.scara())
    yield viewer
    viewer.close()


def test_node_transforms_are_pinocchio_placements(scara_viewer) -> None:
    robot = scara_viewer.robot
    q = robot.random_configuration(4)
    transforms = scara_viewer.node_transforms(q)
    data = robot.model.createData()
    geometry_data = robot.visual_model.createData()
    pin.forwardKinematics(robot.model, data, q)
    pin.updateGeometryPlacements(robot.model, data, robot.visual_model, geometry_data)
    assert len([name for name in transforms if name.startswith("pinrate/")]) == robot.visual_model.ngeoms
    for index, geometry in enumerate(robot.visual_model.geometryObjects):
        np.testing.assert_allclose(
            transforms[f"pinrate/visuals/{geometry.name}"], geometry_data.oMg[index].homogeneous, atol=1e-12
        )
    np.testing.assert_allclose(transforms["markers/tcp"], robot.pose(q), atol=1e-12)


def test_play_records_frames_and_writes_html(scara_viewer, tmp_path) -> None:
    robot = scara_viewer.robot
    target = robot.pose(robot.random_configuration(2))
    trajectory = pinrate.servo(robot, robot.home(), target, max_steps=60)
    before = scara_viewer.recorded_frames
    scara_viewer.play(trajectory, target=target, realtime=False, fps=20)
    assert scara_viewer.recorded_frames > before
    html = scara_viewer.save_html(tmp_path / "run.html")
    text = html.read_text()
    assert text.startswith("\n") or "<html>" in text
    assert "set_animation" in text or "animations" in text
    with pytest.raises(ValueError, match="points"):
        scara_viewer.add_path(np.zeros((3, 2)), [0.1, 0.2, 0.3])


def test_a_viewer_that_does_not_record_keeps_no_frame(tmp_path) -> None:
    robot = pinrate.load("scara")
    viewer = Viewer(robot, offline=True, record=False)
    for seed in range(5):
        viewer.show(robot.random_configuration(seed))
    assert viewer.recorded_frames == 0
    assert viewer.save_html(tmp_path / "scene.html").stat().st_size > 0  # the scene alone


def test_demo_records_html(tmp_path) -> None:
    out = tmp_path / "demo.html"
    result = subprocess.run(
        [
            sys.executable,
            "-m",
            "pinrate.cli",
            "demo",
            "planar_polar",
            "--speed",
            "1000",
            "--targets",
            "2",
            "--record",
            str(out),
        ],
        capture_output=True,
        text=True,
        timeout=120,
        check=False,
    )
    assert result.returncode == 0, result.stderr[-2000:]
    assert "segment 1/2" in result.stdout and "segment 2/2" in result.stdout
    assert out.stat().st_size > 10_000


def test_save_replay_animates_the_recorded_configurations(tmp_path) -> None:
    # The replay's last keyframe of the TCP marker is the tip's pose at the last configuration,
    # as the robot itself computes it (robot.pose: its own pin.Data, no viewer code), and the
    # page carries the scene's commands as well as the animation.
    import base64
    import re

    import umsgpack

    robot = pinrate.load("ur5")
    viewer = Viewer(robot, offline=True)
    rng = np.random.default_rng(3)
    configurations = np.array([robot.random_configuration(rng) for _ in range(5)])
    page = viewer.save_replay(tmp_path / "replay.html", configurations, fps=10, loop=False)
    texts = re.findall(r'^  "([A-Za-z0-9+/=]*)"( \+)?', page.read_text(), re.M)
    commands, current = [], ""
    for text, joined in texts:
        current += text
        if not joined:
            commands.append(umsgpack.unpackb(base64.b64decode(current)))
            current = ""
    assert len(commands) == len(viewer.scene.packed()) + 1
    animation = commands[-1]
    assert animation["type"] == "set_animation" and animation["options"]["repetitions"] == 1
    (tcp,) = [entry for entry in animation["animations"] if entry["path"].endswith("markers/tcp")]
    tracks = {track["name"]: track for track in tcp["clip"]["tracks"]}
    times = np.frombuffer(tracks[".position"]["times"].data, dtype=np.float32)
    np.testing.assert_array_equal(times, np.arange(5))
    positions = np.frombuffer(tracks[".position"]["values"].data, dtype=np.float32).reshape(5, 3)
    quaternions = np.frombuffer(tracks[".quaternion"]["values"].data, dtype=np.float32).reshape(5, 4)
    for index, q in enumerate(configurations):
        expected = pin.SE3ToXYZQUAT(pin.SE3(robot.pose(q)))  # x y z qx qy qz qw
        # float32 storage: 6e-8 relative; a quaternion is defined up to its sign.
        np.testing.assert_allclose(positions[index], expected[:3], atol=1e-6)
        sign = np.sign(np.dot(quaternions[index], expected[3:]))
        np.testing.assert_allclose(sign * quaternions[index], expected[3:], atol=1e-6)
    with Viewer(robot) as live, pytest.raises(pinrate.InputError, match="offline"):
        live.save_replay(tmp_path / "x.html", configurations)


def test_a_page_that_fails_part_way_leaves_the_old_page(tmp_path, monkeypatch) -> None:
    """save_replay and save_html write whole pages or none: a write that fails part-way (a
    full disk) is an InputError naming the file, the page it was replacing left as it was
    and no temporary file left beside it."""
    import errno

    from pinrate.viewer.offline import SceneCommands

    robot = pinrate.load("ur5")
    viewer = Viewer(robot, offline=True)
    viewer.show(robot.home())
    pieces = SceneCommands.html_pieces

    def fails_part_way(self, *args, **kwargs):
        for count, piece in enumerate(pieces(self, *args, **kwargs)):
            if count == 3:
                raise OSError(errno.ENOSPC, "No space left on device")
            yield piece

    monkeypatch.setattr(SceneCommands, "html_pieces", fails_part_way)
    page = tmp_path / "replay.html"
    for save in (lambda: viewer.save_replay(page, np.array([robot.home()] * 3)), lambda: viewer.save_html(page)):
        page.write_text("the old page", encoding="utf-8")
        with pytest.raises(pinrate.InputError, match=r"replay\.html.*No space left on device"):
            save()
        assert page.read_text(encoding="utf-8") == "the old page"
        assert os.listdir(tmp_path) == ["replay.html"]
    monkeypatch.setattr(SceneCommands, "html_pieces", pieces)
    assert viewer.save_html(page) == page and "<html>" in page.read_text(encoding="utf-8")
