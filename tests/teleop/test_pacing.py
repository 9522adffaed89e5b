"""The console loop's pace: real-time scheduling asked for, never required; its statistics."""

from __future__ import annotations

import os
import threading
import time

import numpy as np
import pytest

import pinrate
from pinrate.teleop.pacing import LoopStats, request_realtime
from pinrate.teleop.server import TeleopServer


def in_a_thread(priority: int | None) -> tuple[str, int]:
    """What request_realtime says, and the policy the thread then runs under."""
    result: list[tuple[str, int]] = []
    thread = threading.Thread(target=lambda: result.append((request_realtime(priority), os.sched_getscheduler(0))))
    thread.start()
    thread.join()
    return result[0]


def test_real_time_is_asked_for_and_what_was_granted_is_said() -> None:
    said, policy = in_a_thread(None)
    assert said.startswith("normal scheduling") and policy == os.SCHED_OTHER
    said, policy = in_a_thread(10)
    if policy == os.SCHED_FIFO:  # root, CAP_SYS_NICE or an rtprio limit
        assert said == "real-time scheduling (SCHED_FIFO, priority 10)"
    else:  # refused: said so, the thread as it was
        assert "refused" in said and policy == os.SCHED_OTHER
    assert os.sched_getscheduler(0) == os.SCHED_OTHER  # only the asking thread, never the caller's


@pytest.mark.parametrize("priority", [0, 100, True, 50.0, "50"])
def test_a_bad_priority_is_refused(ur5, priority) -> None:
    with pytest.raises(pinrate.InputError, match="realtime_priority"):
        TeleopServer(pinrate.Teleop(ur5), realtime_priority=priority)


ONE_CORE = """
import http.client, os, sys, time
os.sched_setaffinity(0, {min(os.sched_getaffinity(0))})  # one core: the web thread shares it
import pinrate
from pinrate.teleop.server import TeleopServer

robot = pinrate.load("ur5")
teleop = pinrate.Teleop(robot, dt=0.001)
tick = teleop.tick
def slow_tick(now=None):  # 3 ms ticks at a 1 ms period: the loop is always late
    until = time.perf_counter() + 0.003
    while time.perf_counter() < until:
        pass
    return tick(now)
teleop.tick = slow_tick
with TeleopServer(teleop, record_dir=sys.argv[1]) as server:
    time.sleep(0.5)
    latencies = []
    for _ in range(10):
        started = time.monotonic()
        connection = http.client.HTTPConnection("127.0.0.1", server.port, timeout=10)
        connection.request("GET", "/")
        assert connection.getresponse().status == 200
        connection.close()
        latencies.append(time.monotonic() - started)
    started = time.monotonic()
    server.act("halt")
    while not teleop.halted and time.monotonic() - started < 10:
        time.sleep(0.001)
    print(server.scheduling)
    print(max(latencies), time.monotonic() - started)
"""


def test_a_loop_whose_ticks_outlast_their_period_leaves_the_web_thread_running(tmp_path) -> None:
    # Ticks of 3 ms at a 1 ms period on ONE core, real-time where granted: the loop is always
    # late, and a real-time thread that ran its missed ticks back to back would hold the core
    # (measured before the batch limit: pages took 0.6-1.1 s, a halt 0.1-0.3 s). Bound: a
    # batch of at most BATCH_LIMIT (10 ms) then a sleep: a page and a halt come within a few
    # batches; 0.25 s leaves room for a loaded machine.
    import subprocess
    import sys

    result = subprocess.run(
        [sys.executable, "-c", ONE_CORE, str(tmp_path)], capture_output=True, text=True, timeout=120, check=False
    )
    assert result.returncode == 0, result.stderr[-2000:]
    scheduling, numbers = result.stdout.strip().splitlines()[-2:]
    page, halt = (float(value) for value in numbers.split())
    assert page < 0.25 and halt < 0.25, f"{scheduling}: a page took {page:.3f} s, a halt {halt:.3f} s"


def test_a_recording_is_saved_under_normal_scheduling(ur5, tmp_path, monkeypatch) -> None:
    # The save thread is started by the control thread, whose real-time policy a new thread
    # inherits: it must leave it (CPU-heavy encoding at real-time priority would hold the core).
    from pinrate.teleop import actions

    policies: list[int] = []
    save = actions.Recordings.save

    def watched(self, recording):  # type: ignore[no-untyped-def]
        save(self, recording)
        policies.append(os.sched_getscheduler(0))

    monkeypatch.setattr(actions.Recordings, "save", watched)
    teleop = pinrate.Teleop(ur5, dt=0.002)
    with TeleopServer(teleop, record_dir=tmp_path) as server:
        server.act("record", on=True)
        teleop.command([0.5, 0, 0], [0, 0, 0])
        time.sleep(0.3)
        server.act("record", on=False)
        deadline = time.monotonic() + 30
        while not policies and time.monotonic() < deadline:
            time.sleep(0.02)
    assert policies == [os.SCHED_OTHER]


def test_loop_stats_over_a_window() -> None:
    stats = LoopStats(capacity=4)
    for period in (0.5, 0.001, 0.002, 0.003, 0.004):  # the first falls out of the capacity
        stats.add(period)
    np.testing.assert_array_equal(stats.recent(0.0075), [0.002, 0.003, 0.004])  # newest first until >= the window
    summary = stats.summary(1.0)
    assert summary["rate"] == pytest.approx(4 / 0.010)
    assert summary["median_ms"] == pytest.approx(2.5)
    assert summary["p99_ms"] == pytest.approx(3.97)  # linear interpolation: 3 + 0.97 x (4 - 3) ms
