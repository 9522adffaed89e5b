"""The teleop console's speed: sustained control-loop rate with a page attached, and key to
painted frame in Chromium.

Run: ``python benchmarks/teleop.py [--rate 1000] [--seconds 20] [--presses 30]`` (needs
Debian's Chromium at /usr/bin/chromium and Playwright, as the browser tests).

1. **Baseline, same process, same run**: a bare loop that sleeps to the same absolute
   deadlines and does nothing else, so the ratio shows what the controller, the web thread
   and the render thread cost on top of Python's own sleep.
2. **Console without a page**, twice (normal, then real-time scheduling): the same server, its
   hand driven from Python (+x, -x, 250 ms each) with no browser attached.
3. **Console**, twice: ``TeleopServer(Teleop(ur5, dt=1/rate))`` with one headless Chromium
   page attached, first with the control thread under normal scheduling, then asking for
   real-time (``SCHED_FIFO``, :func:`pinrate.teleop.pacing.request_realtime`; the row says
   what the OS granted); every loop period (wake-up to wake-up) is kept. The page is driven
   by key presses (W, then S, 250 ms each, so the hand wanders back and forth near home)
   while the run is recorded; each press's latency is measured in the page from ``keydown``
   to the animation frame after the first frame of poses that the moved robot produced
   (``window.pinrate.latencies``).
4. **Saving**: the periods from "stop recording" until both files (.npz, .html) are written.

Targets (issue 12): >= 990 Hz sustained, p99 period <= 2 ms, key to paint <= 30 ms median.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import tempfile
import threading
import time
from pathlib import Path

import numpy as np
import timing

import pinrate
from pinrate.teleop.server import TeleopServer

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
from browser import CHROMIUM, chromium  # the browser tests' Chromium, flags and all


def bare_loop(rate: float, seconds: float) -> np.ndarray:
    """Periods (s) of a loop that only sleeps to absolute deadlines at ``rate``."""
    period = 1.0 / rate
    periods = []
    deadline = last = time.monotonic()
    end = last + seconds
    while last < end:
        deadline += period
        delay = deadline - time.monotonic()
        if delay > 0:
            time.sleep(delay)
        now = time.monotonic()
        periods.append(now - last)
        last = now
    return np.array(periods)


def summary(periods: np.ndarray) -> tuple[float, float, float]:
    """(rate Hz, median ms, p99 ms)."""
    return periods.size / periods.sum(), float(np.median(periods) * 1e3), float(np.percentile(periods, 99) * 1e3)


def drive(
    rate: float, seconds: float, presses: int, width: int, height: int, priority: int | None, folder: str
) -> dict[str, object]:
    """One console with a page attached: its loop periods while driven (recording the
    while), the periods while that recording is saved, key-to-paint latencies, and what
    scheduling the control thread got."""
    robot = pinrate.load("ur5")
    teleop = pinrate.Teleop(robot, dt=1.0 / rate, timeout=1.0)
    with (
        TeleopServer(teleop, realtime_priority=priority, record_dir=folder) as server,
        chromium(width, height) as context,
    ):
        page = context.new_page()
        page.goto(server.url)
        page.wait_for_function("() => window.pinrate && window.pinrate.controlling && window.pinrate.frames > 0")
        page.wait_for_timeout(2000)  # meshes parsed
        server.act("record", on=True)
        server.stats.periods.clear()
        started = time.monotonic()
        key = "KeyW"
        pressed = 0
        while time.monotonic() - started < seconds or pressed < presses:
            if pressed < presses:
                page.keyboard.down(key)
                page.wait_for_timeout(250)
                page.keyboard.up(key)
                page.wait_for_timeout(250)
                key = "KeyS" if key == "KeyW" else "KeyW"
                pressed += 1
            else:
                page.wait_for_timeout(100)
        periods = server.stats.recent(float("inf"))
        before = len(server.stats.periods)
        server.act("record", on=False)
        while len(server.saved) < 2:
            page.wait_for_timeout(20)
        page.wait_for_timeout(100)
        saving = np.array(list(server.stats.periods)[before:])
        latencies = page.evaluate("() => window.pinrate.latencies")
    return {
        "periods": periods,
        "saving": saving,
        "latencies": np.array(latencies),
        "scheduling": server.scheduling,
    }


def without_page(rate: float, seconds: float, priority: int | None) -> dict[str, object]:
    """The same console with no page attached, its hand driven from Python (+x then -x, 250 ms
    each, as the key presses): what the controller and the loop cost without a browser."""
    robot = pinrate.load("ur5")
    teleop = pinrate.Teleop(robot, dt=1.0 / rate, timeout=1.0)
    with TeleopServer(teleop, realtime_priority=priority) as server:
        server.stats.periods.clear()
        started = time.monotonic()
        sign = 1.0
        while time.monotonic() - started < seconds:
            teleop.command([sign, 0.0, 0.0], [0.0, 0.0, 0.0])
            time.sleep(0.25)
            sign = -sign
        periods = server.stats.recent(float("inf"))
    return {"periods": periods, "scheduling": server.scheduling}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rate", type=float, default=1000.0, help="control loop target (Hz)")
    parser.add_argument("--seconds", type=float, default=20.0, help="at least this long with the page attached")
    parser.add_argument("--presses", type=int, default=30, help="key presses whose latency is measured")
    parser.add_argument("--width", type=int, default=1200)
    parser.add_argument("--height", type=int, default=760)
    parser.add_argument("--realtime-priority", type=int, default=50, help="SCHED_FIFO priority asked for")
    timing.add_arguments(parser)
    args = parser.parse_args(argv)
    if not Path(CHROMIUM).exists():
        print(f"needs Chromium at {CHROMIUM}", file=sys.stderr)
        return 2
    holder: list[np.ndarray] = []
    thread = threading.Thread(target=lambda: holder.append(bare_loop(args.rate, min(args.seconds, 5.0))))
    thread.start()
    thread.join()
    baseline = holder[0]
    alone = {
        label: without_page(args.rate, min(args.seconds, 10.0), priority)
        for label, priority in (("normal", None), ("real-time", args.realtime_priority))
    }
    runs = {}
    with tempfile.TemporaryDirectory() as folder:
        for label, priority in (("normal", None), ("real-time", args.realtime_priority)):
            runs[label] = drive(args.rate, args.seconds, args.presses, args.width, args.height, priority, folder)
    base_rate, base_median, base_p99 = summary(baseline)
    print(f"UR5, target {args.rate:g} Hz, {args.presses} key presses per console\n")
    print("| loop | rate (Hz) | period median (ms) | period p99 (ms) | p99 × bare | max (ms) |")
    print("|---|---:|---:|---:|---:|---:|")
    print(
        f"| bare sleep-to-deadline loop, no page (baseline) | {base_rate:.1f} | {base_median:.3f} | "
        f"{base_p99:.3f} | 1.00 | {baseline.max() * 1e3:.1f} |"
    )
    rows = [timing.row_of("bare loop period", baseline.tolist())]
    for label, run in alone.items():
        periods = run["periods"]
        rate, median, p99 = summary(periods)
        print(
            f"| console, no page, driven from Python: {run['scheduling']} | {rate:.1f} | {median:.3f} | {p99:.3f} | "
            f"{p99 / base_p99:.2f} | {periods.max() * 1e3:.1f} |"
        )
        rows.append(timing.row_of(f"console loop period, {label}, no page", periods.tolist()))
    for label, run in runs.items():
        for part, name in (("periods", "driven"), ("saving", "saving a recording")):
            periods = run[part]
            rate, median, p99 = summary(periods)
            print(
                f"| console, page attached, {name}: {run['scheduling']} | {rate:.1f} | {median:.3f} | {p99:.3f} | "
                f"{p99 / base_p99:.2f} | {periods.max() * 1e3:.1f} |"
            )
            rows.append(timing.row_of(f"console loop period, {label}, {name}", periods.tolist()))
    for label, run in runs.items():
        latencies = run["latencies"]
        if latencies.size:
            print(
                f"\nkey to painted frame ({label} scheduling; Chromium, headless): median "
                f"{statistics.median(latencies):.1f} ms, p90 {np.percentile(latencies, 90):.1f} ms, "
                f"max {latencies.max():.1f} ms"
            )
            rows.append(timing.row_of(f"key to painted frame, {label}", (latencies * 1e-3).tolist()))
    timing.finish(rows, args, {"rate": args.rate, "seconds": args.seconds, "presses": args.presses})
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
