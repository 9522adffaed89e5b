"""The console loop's pace: real-time scheduling asked for, never required; its statistics."""

from __future__ import annotations

import http.client
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


def test_a_loop_whose_ticks_outlast_their_period_leaves_the_web_thread_running(ur5, tmp_path) -> None:
    # Ticks of 3 ms at a 1 ms period: the loop is always late. Real-time or not, it sleeps a
    # little at every wake-up, so the page (which carries STOP) is still served.
    teleop = pinrate.Teleop(ur5, dt=0.001)
    tick = teleop.tick

    def slow_tick(now: float | None = None):
        until = time.perf_counter() + 0.003
        while time.perf_counter() < until:
            pass
        return tick(now)

    teleop.tick = slow_tick  # type: ignore[method-assign]
    with TeleopServer(teleop, record_dir=tmp_path) as server:
        time.sleep(0.3)
        for _ in range(5):
            connection = http.client.HTTPConnection("127.0.0.1", server.port, timeout=10)
            connection.request("GET", "/")
            assert connection.getresponse().status == 200
            connection.close()


def test_loop_stats_over_a_window() -> None:
    stats = LoopStats(capacity=4)
    for period in (0.5, 0.001, 0.002, 0.003, 0.004):  # the first falls out of the capacity
        stats.add(period)
    np.testing.assert_array_equal(stats.recent(0.0075), [0.002, 0.003, 0.004])  # newest first until >= the window
    summary = stats.summary(1.0)
    assert summary["rate"] == pytest.approx(4 / 0.010)
    assert summary["median_ms"] == pytest.approx(2.5)
    assert summary["p99_ms"] == pytest.approx(3.97)  # linear interpolation: 3 + 0.97 x (4 - 3) ms
