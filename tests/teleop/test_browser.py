"""The teleop console in a real headless Chromium (tests/browser.py): keys and a simulated
gamepad drive the UR5's hand, poses read from Python; the page says near singularity and
which joint is at its limit; reverse, the dead man on a closed page, one controller.

Headless software rendering can block the page for 100-300 ms a frame, so these servers
use a 1 s dead man (design.md §3). ``PINRATE_DOCS_SCREENSHOTS=1`` also writes the
screenshots into docs/.
"""

from __future__ import annotations

import contextlib
import math
import os
import shutil
import subprocess
import sys
import time
import warnings
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

import pinrate
from browser import chromium, needs_browser
from pinrate.teleop import Recording
from pinrate.teleop import server as server_module
from pinrate.teleop.server import TeleopServer
from support import ROOT

pytestmark = needs_browser

DT = 0.002  # 500 Hz, the console's default
TIMEOUT = 1.0
DOCS = os.environ.get("PINRATE_DOCS_SCREENSHOTS") == "1"

# A standard-layout pad whose axes and buttons the test sets (design.md §3: a fresh snapshot
# per call; gamepadconnected dispatched as a plain Event, as GamepadEvent rejects a fake pad).
FAKE_PAD = """
window.__pad = { axes: [0, 0, 0, 0], buttons: Array(17).fill(0) };
Navigator.prototype.getGamepads = function () {
  const pad = {
    id: "pinrate test pad (STANDARD GAMEPAD)", index: 0, connected: true, mapping: "standard",
    timestamp: performance.now(), axes: window.__pad.axes.slice(),
    buttons: window.__pad.buttons.map((v) => ({ value: v, pressed: v > 0.5, touched: v > 0 })),
  };
  return [pad, null, null, null];
};
window.addEventListener("load", () => {
  const event = new Event("gamepadconnected");
  event.gamepad = navigator.getGamepads()[0];
  window.dispatchEvent(event);
});
"""


@pytest.fixture(scope="module")
def browser():
    with chromium(1200, 760) as context:
        yield context


@pytest.fixture
def console(ur5, tmp_path):
    servers = []

    def start(q0=None, **options):
        teleop = pinrate.Teleop(ur5, q0, **{"dt": DT, "timeout": TIMEOUT, **options})
        server = TeleopServer(teleop, record_dir=tmp_path)
        servers.append(server)
        return server

    yield start
    for server in servers:
        server.close()


def connected_page(browser, server, script: str | None = None):
    """A page on the console (``script`` run before the page's own), controlling, framed once."""
    page = browser.new_page()
    if script is not None:
        page.add_init_script(script)
    page.goto(server.url)
    page.wait_for_function(
        "() => window.pinrate && window.pinrate.controlling && window.pinrate.frames > 0", timeout=60_000
    )
    return page


def open_console(browser, server, *, pad: bool = False):
    page = connected_page(browser, server, FAKE_PAD if pad else None)
    wait_until(lambda: page.evaluate("() => window.viewer.scene_tree.find(['meshcat', 'markers', 'hand']).object"))
    page.wait_for_timeout(500)  # the meshes parse
    return page


def wait_until(condition, timeout: float = 20.0, period: float = 0.05):
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        value = condition()
        if value:
            return value
        time.sleep(period)
    raise AssertionError(f"not within {timeout} s: {condition}")


def still(server, seconds: float = 0.3) -> np.ndarray:
    """q once the robot has not moved for ``seconds``."""
    q = server.snapshot()[0]
    deadline = time.monotonic() + 20
    while time.monotonic() < deadline:
        time.sleep(seconds)
        now = server.snapshot()[0]
        if np.array_equal(now, q):
            return now
        q = now
    raise AssertionError("the robot never came to rest")


def shoot(page, tmp_path: Path, name: str) -> Path:
    path = tmp_path / f"{name}.png"
    page.screenshot(path=str(path))
    if DOCS:
        shutil.copy(path, ROOT / "docs" / path.name)
    return path


def recorded(server, page, action) -> Recording:
    """The run recorded (record button on, ``action()``, off), read back from its .npz."""
    page.click("#record")
    wait_until(lambda: server.teleop.recording)
    action()
    still(server)
    page.click("#record")
    wait_until(lambda: len(server.saved) >= 2, timeout=60)
    npz, html = server.saved[-2:]
    assert html.suffix == ".html" and html.stat().st_size > 100_000
    return Recording.load(npz)


def commanded_time(recording: Recording) -> float:
    """Seconds of ticks that moved (each tick is one dt of motion)."""
    return float(np.count_nonzero(np.abs(recording.joint_rates).max(axis=1) > 0)) * recording.dt


def check_travel(server, recording: Recording, axis: int, rotation: np.ndarray, speed: float, held: float) -> None:
    """Travel = speed x commanded time within 5 %, off-axis under 3 %, time about the hold."""
    start, end = recording.start, recording.q[-1]
    travel = rotation.T @ (server.tip_pose(end)[:3, 3] - server.tip_pose(start)[:3, 3])
    seconds = commanded_time(recording)
    assert seconds == pytest.approx(held, abs=0.35)
    assert travel[axis] == pytest.approx(speed * seconds, rel=0.05)
    assert np.linalg.norm(np.delete(travel, axis)) < 0.03 * abs(travel[axis])


def hold(page, key: str, seconds: float) -> float:
    page.keyboard.down(key)
    started = time.monotonic()
    time.sleep(seconds)
    page.keyboard.up(key)
    return time.monotonic() - started


def test_a_held_key_moves_the_hand_along_its_axis(browser, console, tmp_path):
    server = console()
    page = open_console(browser, server)
    hand = server.sensor_pose()[:3, :3]
    held = {}

    def drive():
        page.keyboard.down("KeyW")
        started = time.monotonic()
        time.sleep(0.7)
        shoot(page, tmp_path, "teleop-moving")  # while the hand moves
        time.sleep(max(0.0, 1.0 - (time.monotonic() - started)))
        page.keyboard.up("KeyW")
        held["s"] = time.monotonic() - started

    recording = recorded(server, page, drive)
    check_travel(server, recording, 0, hand, 0.1, held["s"])
    latencies = page.evaluate("() => window.pinrate.latencies")
    assert latencies and max(latencies) < 2000
    page.close()


def test_base_frame_and_speed_slider(browser, console):
    server = console()
    page = open_console(browser, server)
    page.click("#frame-base")
    wait_until(lambda: server.teleop.frame == "base")
    page.fill("#speed", "50")
    page.dispatch_event("#speed", "input")
    held = {}

    def drive():
        held["s"] = hold(page, "KeyE", 1.0)  # +z of the world

    recording = recorded(server, page, drive)
    check_travel(server, recording, 2, np.eye(3), 0.05, held["s"])
    page.close()


def test_a_gamepad_drives_the_same_motion_and_its_dead_zone_reads_zero(browser, console, tmp_path):
    server = console()
    page = open_console(browser, server, pad=True)
    assert "test pad" in page.inner_text("#pad")
    start = still(server)
    page.evaluate("() => { window.__pad.axes = [0.1, -0.08, 0.05, 0.1]; window.__pad.buttons[7] = 0.1; }")
    time.sleep(0.6)
    np.testing.assert_array_equal(server.snapshot()[0], start)  # inside the dead zone: nothing moves
    hand = server.sensor_pose()[:3, :3]
    held = {}

    def drive():
        page.evaluate("() => { window.__pad.axes = [0, -1, 0, 0]; window.__pad.buttons[7] = 0; }")  # left stick up
        started = time.monotonic()
        time.sleep(1.0)
        page.wait_for_timeout(100)
        shoot(page, tmp_path, "teleop-gamepad")
        page.evaluate("() => { window.__pad.axes = [0, 0, 0, 0]; }")
        held["s"] = time.monotonic() - started

    recording = recorded(server, page, drive)
    check_travel(server, recording, 0, hand, 0.1, held["s"])
    page.close()


def test_full_extension_says_near_singularity_then_the_strategy_acts(browser, console, tmp_path):
    server = console(max_linear_speed=0.25)
    page = open_console(browser, server)
    # tool0's -y is the world's +x at home: straight out from the shoulder.
    page.keyboard.down("KeyD")
    wait_until(lambda: "near singularity" in server_word(page), timeout=15)
    wait_until(lambda: not server.snapshot()[1].joint_rates.any(), timeout=15)  # decelerated to a halt
    shoot(page, tmp_path, "teleop-singularity")
    said = page.evaluate("() => window.pinrate.said.map((s) => s.word)")
    assert "near singularity: halted" in said or "near singularity: decelerating" in said
    step = server.snapshot()[1]
    conditioning = server.teleop.controller.observed_conditioning(step.observation)
    assert conditioning.value >= server.teleop.controller.singular_threshold  # it stopped before singular
    page.select_option("#singularity", "auxiliary_elbow")
    wait_until(lambda: server.teleop.controller.singularity == "auxiliary_elbow")
    wait_until(lambda: "auxiliary elbow" in server_word(page), timeout=15)
    page.wait_for_timeout(300)
    shoot(page, tmp_path, "teleop-auxiliary-elbow")
    page.keyboard.up("KeyD")
    page.close()


def server_word(page) -> str:
    return page.inner_text("#status-word")


def test_a_joint_driven_into_its_limit_is_named_and_never_crosses(browser, console, ur5, tmp_path):
    index = ur5.model.joints[ur5.joint_id("wrist_3_joint")].idx_q
    upper = ur5.model.upperPositionLimit[index]
    q0 = ur5.home()
    q0[index] = upper - 0.3
    server = console(q0)
    page = open_console(browser, server)

    def drive():
        page.keyboard.down("KeyO")  # about the hand's +z: wrist_3 turns up
        wait_until(lambda: server_word(page) == "at a joint limit", timeout=15)
        page.wait_for_timeout(300)
        shoot(page, tmp_path, "teleop-joint-limit")
        assert "wrist_3_joint" in page.inner_text("#status-detail")
        assert "held" in page.get_attribute(f"#joint-{ur5.joint_names.index('wrist_3_joint')}", "class")
        page.keyboard.up("KeyO")

    recording = recorded(server, page, drive)
    assert recording.q[:, index].max() <= upper
    assert recording.q[-1, index] == pytest.approx(upper)
    page.close()


def test_reverse_returns_to_the_recorded_start(browser, console, tmp_path):
    server = console()
    page = open_console(browser, server)
    start = still(server)
    hold(page, "KeyW", 0.6)
    hold(page, "KeyA", 0.6)
    moved = still(server)
    assert np.linalg.norm(server.tip_pose(moved)[:3, 3] - server.tip_pose(start)[:3, 3]) > 0.05
    page.click("#reverse")
    wait_until(lambda: server.teleop.reversing)
    page.wait_for_timeout(300)
    shoot(page, tmp_path, "teleop-reversing")
    wait_until(lambda: not server.teleop.reversing, timeout=10)
    np.testing.assert_allclose(server.snapshot()[0], start, atol=1e-9)
    page.close()


def test_space_and_escape_only_stop_and_resume_is_a_deliberate_click(browser, console):
    server = console()
    page = open_console(browser, server)
    hold(page, "KeyW", 0.3)
    moved = still(server)
    for key in ("Space", "Space", "Escape", "Space"):  # a double press, a repeat: stopped still
        page.keyboard.press(key)
        wait_until(lambda: server.teleop.halted)
        page.wait_for_timeout(300)
        assert server.teleop.halted, f"{key} resumed the robot"
    page.wait_for_function("() => window.pinrate.last.halted")
    assert page.inner_text("#stop") == "STOPPED" and page.is_enabled("#resume")
    hold(page, "KeyS", 0.4)
    page.keyboard.press("KeyB")  # reverse while halted: refused, said
    page.wait_for_function("() => window.pinrate.events.some((e) => e.text.includes('halted: resume first'))")
    time.sleep(0.3)
    assert not server.teleop.reversing
    np.testing.assert_array_equal(server.snapshot()[0], moved)
    page.click("#resume")
    wait_until(lambda: not server.teleop.halted)
    page.wait_for_function("() => !window.pinrate.last.halted")
    assert not page.is_enabled("#resume")
    hold(page, "KeyS", 0.3)
    assert not np.array_equal(still(server), moved)
    page.click("#stop")
    wait_until(lambda: server.teleop.halted)
    page.close()


def test_robot_keys_reach_the_robot_whatever_control_was_used(browser, console):
    server = console()
    page = open_console(browser, server)
    read = "() => [document.querySelector('#singularity').value, document.querySelector('#wrist').value, "
    read += "document.querySelector('#speed').value, window.pinrate.speed]"
    page.select_option("#singularity", "freeze")  # the strategy chosen (Playwright focuses it)
    wait_until(lambda: server.teleop.controller.singularity == "freeze")
    page.click("#speed", position={"x": 60, "y": 5})  # the speed set with the mouse
    page.wait_for_function("() => window.pinrate.speed < 1")
    before = page.evaluate(read)
    start = still(server)
    for control in ("#singularity", "#speed", "#wrist", None):
        if control is not None:
            page.focus(control)  # as a click or a Tab leaves it
        for key in ("ArrowDown", "ArrowUp", "Home", "End", "PageDown", "KeyA", "KeyD", "KeyF", "KeyS"):
            page.keyboard.press(key)
        assert page.evaluate(read) == before, f"a key changed a control focused on {control}"
    page.wait_for_timeout(300)
    assert server.teleop.controller.singularity == "freeze" and server.teleop.controller.wrist == "split"
    page.focus("#wrist")
    q0 = still(server)
    hand = server.sensor_pose(q0)[:3, :3]
    hold(page, "KeyE", 0.4)  # a robot key with a control focused: the hand moves along its +z
    travel = hand.T @ (server.tip_pose(still(server))[:3, 3] - server.tip_pose(q0)[:3, 3])
    assert travel[2] > 0.005
    page.focus("#singularity")
    page.keyboard.press("Space")  # the stop key too
    wait_until(lambda: server.teleop.halted)
    assert page.evaluate(read) == before
    assert not np.array_equal(q0, start)
    page.close()


FREEZE = """(ms) => setTimeout(() => {
  window.__frozenAt = performance.timeOrigin + performance.now();
  const end = performance.now() + ms;
  while (performance.now() < end);
}, 0)"""
"""Block the page's main thread for ``ms`` from a task of its own (page.evaluate returns
first); ``window.__frozenAt``: when it began (epoch ms, the clock of ``time.time()``)."""


def test_a_dead_man_stop_is_shown_as_such(browser, console):
    server = console()
    operator = open_console(browser, server)
    watcher = browser.new_page()
    watcher.goto(server.url)
    watcher.wait_for_function("() => window.pinrate && window.pinrate.frames > 0", timeout=60_000)
    operator.keyboard.down("KeyW")
    wait_until(lambda: server.snapshot()[1] is not None and server.snapshot()[1].joint_rates.any())
    operator.evaluate(FREEZE, 4000)  # the operator's page freezes with W held
    frozen = time.monotonic()
    watcher.wait_for_function("() => window.pinrate.last.dead_man", timeout=10_000)
    assert time.monotonic() - frozen < 3.0
    assert not server.snapshot()[1].joint_rates.any()
    assert watcher.inner_text("#status-word").startswith("dead man:")
    assert "deadman" in watcher.get_attribute("#status", "class")
    operator.keyboard.up("KeyW")  # handled once the page is back
    operator.wait_for_function("() => window.pinrate.last && window.pinrate.last.dead_man", timeout=10_000)
    assert operator.inner_text("#status-word").startswith("dead man:")  # the page itself sees why
    watcher.close()
    operator.close()


SLOW_FRAMES = """
// Software WebGL on a slow machine, on purpose: each animation frame blocks the main thread
// for 600 ms (once per frame, whatever number of callbacks it runs).
const original = window.requestAnimationFrame.bind(window);
let slowed = null;
window.requestAnimationFrame = (callback) => original((time) => {
  if (time !== slowed) {
    slowed = time;
    const end = performance.now() + 600;
    while (performance.now() < end);
  }
  callback(time);
});
"""

DEAD_MAN = 0.25
"""The console's default dead man (s): what an operator runs with."""


def key_held(page, code: str) -> float:
    """Seconds the page held ``code`` (from taking the key down to taking it up): what it
    commanded, whatever its main thread's delays."""
    log = page.evaluate("(code) => window.pinrate.keyLog.filter((entry) => entry.code === code)", code)
    downs = [entry["at"] for entry in log if entry["down"]]
    ups = [entry["at"] for entry in log if not entry["down"]]
    return (ups[-1] - downs[-1]) / 1000.0


def test_a_slow_page_keeps_the_robot_moving_as_commanded(browser, console):
    """Main thread blocked 600 ms a frame, the default 0.25 s dead man: a held W moves the hand
    at least 90 % of speed x held time, and a reversal comes all the way back."""
    server = console(timeout=DEAD_MAN)
    page = connected_page(browser, server, SLOW_FRAMES)
    start = still(server)
    hand = server.sensor_pose(start)[:3, :3]
    hold(page, "KeyW", 2.0)
    moved = still(server)
    held = key_held(page, "KeyW")
    travel = hand.T @ (server.tip_pose(moved)[:3, 3] - server.tip_pose(start)[:3, 3])
    fraction = travel[0] / (0.1 * held)
    print(f"slow page: held {held:.3f} s, travel {travel[0] * 1e3:.1f} mm, {fraction:.1%} of speed x time")
    assert 0.9 <= fraction <= 1.05
    assert np.linalg.norm(travel[1:]) < 0.03 * travel[0]
    assert server.teleop.dead_man == ""
    page.click("#reverse")
    wait_until(lambda: server.teleop.reversing)
    wait_until(lambda: not server.teleop.reversing, timeout=15)
    back = server.tip_pose(still(server))[:3, 3] - server.tip_pose(start)[:3, 3]
    print(f"slow page: the reversal ended {np.linalg.norm(back) * 1e3:.3f} mm from the start")
    assert np.linalg.norm(back) < 1e-6
    page.close()


def test_a_frozen_page_stops_the_robot_within_the_freeze_limit(browser, console):
    server = console(timeout=DEAD_MAN)
    page = open_console(browser, server)
    page.keyboard.down("KeyW")
    wait_until(lambda: server.snapshot()[1] is not None and server.snapshot()[1].joint_rates.any())
    page.evaluate(FREEZE, 5000)  # frozen for good, as far as the robot can tell
    asked = time.time()
    q = server.snapshot()[0]
    moving_until = asked
    while time.time() - asked < 3.5:  # when did the robot last move?
        time.sleep(0.005)
        now = server.snapshot()[0]
        if not np.array_equal(now, q):
            moving_until, q = time.time(), now
    assert server.teleop.dead_man.startswith("the page froze")
    time.sleep(max(0.0, 5.3 - (time.time() - asked)))
    frozen = page.evaluate("() => window.__frozenAt") / 1000.0  # the page is back
    stopped = moving_until - frozen
    print(f"frozen page: the robot stopped {stopped:.3f} s after the freeze (limit {server.freeze_limit:g} s)")
    # The limit counts from the main thread's last sign of life, which may come a slow frame
    # (software rendering: up to ~0.4 s) before the freeze began: hence the lower margin. It
    # still tells this stop from the 0.25 s dead man's.
    assert server.freeze_limit - 0.5 < stopped < server.freeze_limit + 0.15  # slow pages keep going; frozen ones stop
    page.keyboard.up("KeyW")
    page.close()


def zyx(roll: float, pitch: float, yaw: float) -> np.ndarray:
    """Rz(yaw) Ry(pitch) Rx(roll), written out."""
    cr, sr, cp, sp, cy, sy = np.cos(roll), np.sin(roll), np.cos(pitch), np.sin(pitch), np.cos(yaw), np.sin(yaw)
    rz = np.array([[cy, -sy, 0], [sy, cy, 0], [0, 0, 1]])
    ry = np.array([[cp, 0, sp], [0, 1, 0], [-sp, 0, cp]])
    rx = np.array([[1, 0, 0], [0, cr, -sr], [0, sr, cr]])
    return rz @ ry @ rx


def test_the_tip_pose_is_read_out_in_the_world_frame(browser, console):
    server = console()
    page = open_console(browser, server)
    for key in ("KeyW", "KeyE", "KeyI", "KeyJ"):  # off home, every angle non-zero
        hold(page, key, 0.4)
    q = still(server)
    page.wait_for_function(
        "(q) => { const c = window.pinrate.last.configuration; return c.every((v, i) => v === q[i]); }", arg=q.tolist()
    )
    shown = page.evaluate(
        """() => ({
            frame: window.pinrate.last,
            text: ["x", "y", "z", "roll", "pitch", "yaw"].map((id) => document.getElementById("tcp-" + id).textContent),
            name: document.getElementById("tcp-name").textContent,
        })"""
    )
    np.testing.assert_array_equal(shown["frame"]["configuration"], q)
    world_T_tip = server.tip_pose(q)
    text = np.array([float(value) for value in shown["text"]])
    np.testing.assert_allclose(text[:3], world_T_tip[:3, 3], atol=1e-6)  # m
    rotation = world_T_tip[:3, :3]
    rpy = [
        math.atan2(rotation[2, 1], rotation[2, 2]),
        -math.asin(rotation[2, 0]),
        math.atan2(rotation[1, 0], rotation[0, 0]),
    ]
    np.testing.assert_allclose(text[3:], rpy, atol=1e-6)  # rad
    np.testing.assert_allclose(zyx(*shown["frame"]["tip"]["rpy"]), rotation, atol=1e-9)
    np.testing.assert_allclose(shown["frame"]["tip"]["position"], world_T_tip[:3, 3], atol=1e-12)
    assert shown["name"] == server.robot.tip and min(abs(angle) for angle in rpy) > 0.01
    page.close()


NAMES_SHOWN = """() => Array.from(document.querySelectorAll(".joint")).map((row) => {
  const name = row.querySelector(".name");
  const box = name.getBoundingClientRect();
  return { id: row.id, parent: row.parentElement.id, cls: row.className, text: name.textContent,
           title: name.title, cut: name.scrollWidth > name.clientWidth + 0.5, width: box.width,
           lines: Math.round(box.height / parseFloat(getComputedStyle(name).lineHeight)) };
})"""


def test_joint_names_whole_and_joints_not_driven_listed_apart(browser, panda, tmp_path):
    teleop = pinrate.Teleop(panda, dt=DT, timeout=TIMEOUT)
    with TeleopServer(teleop, record_dir=tmp_path) as server:
        page = open_console(browser, server)
        page.wait_for_timeout(300)
        rows = page.evaluate(NAMES_SHOWN)
        partition = teleop.controller.partition
        driven = set(partition.arm) | set(partition.wrist)
        assert [row["text"] for row in rows] == [name for name in panda.joint_names if name in driven] + [
            name for name in panda.joint_names if name not in driven
        ]
        for row in rows:
            assert not row["cut"] and row["lines"] == 1, row  # every name whole, on one line
            assert row["title"].startswith(row["text"])
            if row["text"] in driven:
                assert row["parent"] == "joints"
            else:  # the fingers: listed apart, never "at a limit" (finger 2 sits on its lower one at home)
                assert row["parent"] == "joints-undriven" and "undriven" in row["cls"]
                assert "limit" not in row["cls"] and "near" not in row["cls"]
        assert page.is_visible("#undriven")
        page.close()


def test_ur5_joint_names_fit_and_a_phone_gets_the_whole_width_for_the_view(browser, console):
    server = console()
    page = open_console(browser, server)
    rows = page.evaluate(NAMES_SHOWN)
    assert [row["text"] for row in rows] == list(server.robot.joint_names)
    for row in rows:
        assert not row["cut"] and row["lines"] == 1, row  # shoulder_pan_joint whole
    assert not page.is_visible("#undriven")
    page.set_viewport_size({"width": 390, "height": 844})
    page.wait_for_timeout(500)
    view = page.evaluate(
        """() => ({ stage: document.getElementById("stage").getBoundingClientRect().toJSON(),
                   canvas: window.viewer.renderer.domElement.getBoundingClientRect().toJSON(),
                   panel: document.getElementById("panel").getBoundingClientRect().toJSON(),
                   scroll: document.documentElement.scrollWidth })"""
    )
    assert view["stage"]["left"] == 0 and view["stage"]["width"] == 390
    assert view["canvas"]["width"] == 390 and view["canvas"]["height"] > 300
    assert view["panel"]["top"] >= view["stage"]["bottom"] - 1 and view["panel"]["width"] == 390
    assert view["scroll"] <= 390  # nothing sticks out sideways
    for row in page.evaluate(NAMES_SHOWN):
        assert not row["cut"], row
    page.set_viewport_size({"width": 1200, "height": 760})
    page.close()


def test_a_held_jog_button_moves_that_joint_alone(browser, console):
    server = console()
    page = open_console(browser, server)
    robot = server.robot
    elbow = robot.joint_names.index("elbow_joint")
    start = still(server)
    box = page.locator(f"#joint-{elbow} button.jog.plus").bounding_box()
    page.mouse.move(box["x"] + box["width"] / 2, box["y"] + box["height"] / 2)
    page.mouse.down()
    time.sleep(0.8)
    page.mouse.up()
    q = still(server)
    log = page.evaluate("() => window.pinrate.jogLog")
    held = (log[-1]["at"] - log[-2]["at"]) / 1000.0
    assert [entry["down"] for entry in log[-2:]] == [True, False]
    others = np.delete(np.arange(robot.nq), elbow)
    np.testing.assert_array_equal(q[others], start[others])  # every other joint exactly still
    rate = server_module.JOG_SHARE * robot.model.velocityLimit[elbow]
    assert q[elbow] - start[elbow] == pytest.approx(rate * held, rel=0.05)
    page.close()


def test_the_uncoupled_mode_moves_the_arm_with_the_translation_keys_and_one_wrist_joint_per_pair(browser, console):
    server = console()
    page = open_console(browser, server)
    page.click("#mode-uncoupled")
    wait_until(lambda: server.mode == "uncoupled")
    page.wait_for_function("() => window.pinrate.last.mode === 'uncoupled'")
    assert "wrist_1_joint" in page.inner_text("#mode-help")
    wrist = [server.robot.joint_names.index(name) for name in server.teleop.controller.partition.wrist]
    start = still(server)
    hold(page, "KeyW", 0.5)
    moved = still(server)
    np.testing.assert_array_equal(moved[wrist], start[wrist])  # the wrist joints exactly still
    assert np.abs(moved - start).max() > 0.01  # the arm moved
    hold(page, "KeyJ", 0.3)  # the second pair: the second wrist joint alone
    turned = still(server)
    assert np.flatnonzero(turned != moved).tolist() == [wrist[1]]
    page.click("#mode-twist")
    wait_until(lambda: server.mode == "twist")
    page.close()


FAKE_SPACEMOUSE = """
// A SpaceMouse behind WebHID, as the page sees one: navigator.hid.requestDevice offers it,
// window.__report(id, counts) makes it send an input report (int16 little-endian counts).
(() => {
  const device = new EventTarget();
  Object.assign(device, { vendorId: 0x256f, productId: 0xc635, productName: "SpaceMouse Compact", opened: false });
  device.open = async () => { device.opened = true; };
  device.close = async () => { device.opened = false; };
  const hid = new EventTarget();
  hid.requestDevice = async (options) => { window.__hidFilters = options.filters; return [device]; };
  hid.getDevices = async () => (device.opened ? [device] : []);
  Object.defineProperty(Navigator.prototype, "hid", { get: () => hid, configurable: true });
  const send = (id, counts) => {
    const view = new DataView(new ArrayBuffer(2 * counts.length));
    counts.forEach((count, i) => view.setInt16(2 * i, count, true));
    const event = new Event("inputreport");
    Object.assign(event, { reportId: id, data: view, device });
    device.dispatchEvent(event);
  };
  // As the hardware does, a deflected cap repeats its report (here every 8 ms) until it is
  // back at rest; window.__silence() makes it stop reporting, deflected or not.
  const latest = {};
  let silent = false;
  window.__report = (id, counts) => {
    if (id === 1 && counts.length >= 6) delete latest[2];  // a newer model: one report of six
    latest[id] = counts;
    send(id, counts);
  };
  window.__silence = () => { silent = true; };
  setInterval(() => {
    if (silent) return;
    for (const [id, counts] of Object.entries(latest)) if (counts.some(Boolean)) send(Number(id), counts);
  }, 8);
})();
"""


def held_counts(page, since: int) -> float:
    """Seconds between the page's first and last SpaceMouse report from log entry ``since``."""
    log = page.evaluate("(since) => window.pinrate.hidLog.slice(since)", since)
    return (log[-1]["at"] - log[0]["at"]) / 1000.0


def test_a_spacemouse_drives_the_hand_like_two_3_axis_controllers(browser, console):
    server = console()
    page = connected_page(browser, server, FAKE_SPACEMOUSE)
    page.click("#spacemouse-connect")
    page.wait_for_function("() => document.getElementById('spacemouse').textContent.includes('SpaceMouse Compact')")
    filters = page.evaluate("() => window.__hidFilters")
    assert {f["vendorId"] for f in filters} == {0x256F, 0x046D}
    assert all((f["usagePage"], f["usage"]) == (1, 8) for f in filters)
    start = still(server)
    page.evaluate("() => window.__report(1, [20, -25, 10])")  # a hand resting on the cap: the dead zone
    page.evaluate("() => window.__report(2, [-15, 0, 20])")
    time.sleep(0.6)
    np.testing.assert_array_equal(server.snapshot()[0], start)
    hand = server.sensor_pose(start)[:3, :3]
    since = len(page.evaluate("() => window.pinrate.hidLog"))
    page.evaluate("() => window.__report(1, [0, -350, 0])")  # pushed away from the operator, fully
    time.sleep(1.0)
    page.evaluate("() => window.__report(1, [0, 0, 0])")
    pushed = still(server)
    held = held_counts(page, since)
    travel = hand.T @ (server.tip_pose(pushed)[:3, 3] - server.tip_pose(start)[:3, 3])
    assert travel[0] == pytest.approx(0.1 * held, rel=0.05)  # +x at full speed
    assert np.linalg.norm(travel[1:]) < 0.03 * travel[0]
    # a newer model's single report: rotation about the device's up (z is down): counter-clockwise seen from above
    rotation = server.sensor_pose(pushed)[:3, :3]
    since = len(page.evaluate("() => window.pinrate.hidLog"))
    page.evaluate("() => window.__report(1, [0, 0, 0, 0, 0, -350])")
    time.sleep(0.6)
    page.evaluate("() => window.__report(1, [0, 0, 0, 0, 0, 0])")
    turned = still(server)
    held = held_counts(page, since)
    angle = pin.log3(rotation.T @ server.sensor_pose(turned)[:3, :3])  # in the hand's axes
    assert angle[2] == pytest.approx(0.5 * held, rel=0.05)
    assert np.linalg.norm(angle[:2]) < 0.03 * angle[2]
    page.close()


@pytest.mark.parametrize("slow", [False, True], ids=["page", "slow page"])
def test_a_spacemouse_that_falls_silent_while_deflected_stops_the_hand(browser, console, slow):
    # A cap held deflected whose reports stop (a USB hiccup): its last counts are not held
    # forever; the robot stops after the page's HID_STALE_MS (0.5 s) of its own running time,
    # also on a page whose every frame blocks 600 ms (software rendering): each block counts
    # 0.2 s, so a few frames later.
    server = console()
    page = connected_page(browser, server, FAKE_SPACEMOUSE + (SLOW_FRAMES if slow else ""))
    page.click("#spacemouse-connect")
    page.wait_for_function("() => document.getElementById('spacemouse').textContent.includes('SpaceMouse Compact')")
    page.evaluate("() => window.__report(1, [0, -350, 0])")
    wait_until(lambda: server.snapshot()[1] is not None and server.snapshot()[1].joint_rates.any())
    page.evaluate("() => window.__silence()")
    silenced = time.monotonic()
    wait_until(lambda: not server.snapshot()[1].joint_rates.any(), timeout=10.0)
    # the stale limit on a fast page; on the slow one 3 blocks of 0.6 s count 0.6 s, and the
    # stop goes out with the next one: about 4 frames (2.4 s), bounded at 5 s
    assert time.monotonic() - silenced < (5.0 if slow else 0.5 + server_module.FREEZE_LIMIT)
    page.wait_for_function("() => document.getElementById('spacemouse').textContent.includes('silent')")
    page.close()


SPACEMOUSE_PAD = """
// A SpaceMouse as Chrome may offer it to the Gamepad API: no standard mapping, six axes.
window.__pad = { axes: [0, 0, 0, 0.9, 0.9, 0], buttons: [0, 0] };
Navigator.prototype.getGamepads = function () {
  const pad = {
    id: "3Dconnexion SpaceMouse Pro (Vendor: 256f Product: c62b)", index: 0, connected: true, mapping: "",
    timestamp: performance.now(), axes: window.__pad.axes.slice(),
    buttons: window.__pad.buttons.map((v) => ({ value: v, pressed: v > 0.5, touched: v > 0 })),
  };
  return [pad, null, null, null];
};
"""


def test_a_spacemouse_offered_as_a_gamepad_is_ignored_and_said_so(browser, console):
    server = console()
    page = connected_page(browser, server, SPACEMOUSE_PAD)
    start = still(server)
    time.sleep(0.6)  # its "right stick" (the cap's translation read as a standard pad) held over the dead zone
    np.testing.assert_array_equal(server.snapshot()[0], start)
    text = page.inner_text("#pad")
    assert "SpaceMouse Pro" in text and "ignored" in text
    page.close()


def test_closing_the_page_stops_the_motion_within_the_timeout(browser, console):
    server = console()
    page = open_console(browser, server)
    page.keyboard.down("KeyW")
    wait_until(lambda: server.snapshot()[1] is not None and server.snapshot()[1].joint_rates.any())
    page.close()
    closed = time.monotonic()
    still(server, seconds=0.1)
    assert time.monotonic() - closed < TIMEOUT + 0.5
    # The web thread notes the closed socket on its own clock (late on a loaded machine); the
    # motion's stop above is the claim, the count only has to follow.
    wait_until(lambda: server.clients == 0, timeout=5.0)


def test_one_page_controls_the_others_watch(browser, console, tmp_path):
    server = console()
    first = open_console(browser, server)
    second = browser.new_page()
    second.goto(server.url)
    second.wait_for_function("() => window.pinrate && window.pinrate.frames > 0", timeout=60_000)
    assert "watching" in second.inner_text("#role")
    start = still(server)
    second.keyboard.down("KeyW")
    time.sleep(0.5)
    second.keyboard.up("KeyW")
    np.testing.assert_array_equal(server.snapshot()[0], start)
    second.wait_for_timeout(300)
    shoot(second, tmp_path, "teleop-watching")
    second.keyboard.press("Space")  # the e-stop is everyone's: a watcher may halt the robot
    wait_until(lambda: server.teleop.halted)
    second.click("#resume")  # resuming is not: the watcher's click does nothing
    time.sleep(0.3)
    assert server.teleop.halted
    first.click("#resume")
    wait_until(lambda: not server.teleop.halted)
    first.close()
    second.wait_for_selector("#claim:not([hidden])")
    second.click("#claim")
    second.wait_for_function("() => window.pinrate.controlling")
    hold(second, "KeyW", 0.3)
    assert not np.array_equal(still(server), start)
    second.close()


def test_every_socket_is_on_loopback(browser, console):
    server = console()
    page = open_console(browser, server)
    sockets = own_tcp_sockets()
    assert sockets, "no TCP socket found for this process"
    assert ("127.0.0.1", server.port, "listen") in sockets
    for address, _, _ in sockets:
        assert address == "127.0.0.1"
    page.close()


def own_tcp_sockets() -> list[tuple[str, int, str]]:
    """(local address, port, state) of this process's TCP sockets, from /proc."""
    inodes = set()
    for fd in Path("/proc/self/fd").iterdir():
        try:
            target = os.readlink(fd)
        except OSError:
            continue
        if target.startswith("socket:["):
            inodes.add(target[8:-1])
    found = []
    for table, width in (("/proc/net/tcp", 8), ("/proc/net/tcp6", 32)):
        if not Path(table).exists():
            continue
        for line in Path(table).read_text().splitlines()[1:]:
            fields = line.split()
            if fields[9] not in inodes:
                continue
            address, port = fields[1].split(":")
            ipv4 = ".".join(str(int(address[i : i + 2], 16)) for i in (6, 4, 2, 0)) if width == 8 else ""
            text = ipv4 or "ipv6:" + address
            found.append((text, int(port, 16), "listen" if fields[3] == "0A" else "connected"))
    return found


def test_drawn_links_follow_the_robot(browser, console):
    server = console()
    page = open_console(browser, server)
    hold(page, "KeyS", 0.4)
    q = still(server)
    robot = server.robot
    geometry = robot.visual_model.geometryObjects[2]
    name = server.viewer._visualizer.getViewerNodeName(geometry, pin.GeometryType.VISUAL)

    def drawn_pose() -> np.ndarray:
        elements = page.evaluate(
            """(path) => {
                let node = window.viewer.scene_tree;
                for (const part of path) node = node.children[part];
                const root = window.viewer.scene_tree.children["meshcat"].object;
                window.viewer.scene.updateMatrixWorld(true);
                return root.matrixWorld.clone().invert().multiply(node.object.matrixWorld).elements;
            }""",
            ["meshcat", *name.split("/")],
        )
        return np.array(elements).reshape(4, 4).T

    data, geometry_data = robot.model.createData(), robot.visual_model.createData()
    pin.forwardKinematics(robot.model, data, q)
    pin.updateGeometryPlacements(robot.model, data, robot.visual_model, geometry_data)
    expected = geometry_data.oMg[2].homogeneous @ np.diag([*geometry.meshScale, 1.0])
    # The page draws the still robot's last frame when it arrives (late on a loaded machine):
    # the claim is where the link is drawn, not how soon.
    with contextlib.suppress(AssertionError):
        wait_until(lambda: np.allclose(drawn_pose(), expected, rtol=0, atol=1e-5), timeout=10.0)
    np.testing.assert_allclose(drawn_pose(), expected, atol=1e-5)  # float32 on the page
    page.close()


def test_benchmark_smoke():
    # Timings are not checked here (benchmarks/teleop.py measures them); the script must keep running.
    result = subprocess.run(
        [sys.executable, str(ROOT / "benchmarks" / "teleop.py"), "--seconds", "1", "--presses", "2", "--rate", "500"],
        capture_output=True,
        text=True,
        timeout=300,
        check=False,
    )
    assert result.returncode == 0, result.stderr[-2000:]
    assert "console, page attached, driven" in result.stdout and "saving a recording" in result.stdout
    assert "key to painted frame" in result.stdout


def test_a_shared_console_is_driven_from_its_tokened_url_only(browser, ur5, tmp_path):
    """Off loopback the printed URL carries the token: the page opened from it controls and
    drives; the same address without the token gets no page and no socket."""
    teleop = pinrate.Teleop(ur5, dt=DT, timeout=TIMEOUT)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # "whoever has its URL ... can drive the robot": tested in test_security
        server = TeleopServer(teleop, host="0.0.0.0", record_dir=tmp_path)
    try:
        assert "?token=" in server.url and "0.0.0.0" not in server.url
        untokened = browser.new_page()
        response = untokened.goto(server.url.split("?")[0])
        assert response is not None and response.status == 403
        untokened.close()
        page = open_console(browser, server)
        page.keyboard.down("KeyW")
        wait_until(lambda: server.snapshot()[1] is not None and server.snapshot()[1].joint_rates.any())
        page.keyboard.up("KeyW")
        page.close()
    finally:
        server.close()


def test_a_held_key_drives_the_simulated_robot_along_its_axis(browser, console, ur5):
    """`pinrate teleop --plant mujoco`: the page drives a MuJoCo simulation of the UR5 and
    draws what it measured; the travel is the speed times the commanded time (the PI servos'
    lag, about T = 5 ms of motion, is under the 5 % of check_travel)."""
    pytest.importorskip("mujoco")
    from pinrate.plants import MujocoPlant

    server = console(plant=MujocoPlant(ur5))
    page = open_console(browser, server)
    hand = server.sensor_pose()[:3, :3]
    held = {}

    def drive():
        held["s"] = hold(page, "KeyW", 1.0)

    recording = recorded(server, page, drive)
    check_travel(server, recording, 0, hand, 0.1, held["s"])
    # The recording keeps the plant's measurement (q after each tick), not the integrated rates.
    moving = int(np.flatnonzero(np.abs(recording.joint_rates).max(axis=1) > 0)[10])
    integrated = ur5.integrate(recording.q[moving - 1], recording.joint_rates[moving], recording.dt)
    assert not np.allclose(recording.q[moving], integrated, rtol=0, atol=1e-9)
    assert server.teleop.measurement.time > 1.0
    page.close()
