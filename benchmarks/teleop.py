"""The teleop console's speed: sustained control-loop rate with a page attached, and key to
painted frame in Chromium.

Run: ``python benchmarks/teleop.py [--rate 1000] [--seconds 20] [--presses 30]`` (needs
Debian's Chromium at /usr/bin/chromium and Playwright, as the browser tests).

1. **Baseline, same process, same run**: a bare loop that sleeps to the same absolute
   deadlines and does nothing else, so the ratio shows what the controller, the web thread
   and the render thread cost on top of Python's own sleep.
2. **Console**: ``TeleopServer(Teleop(ur5, dt=1/rate))`` with one headless Chromium page
   attached; every loop period (wake-up to wake-up) is kept. The page is driven by key
   presses (W, then S, 250 ms each, so the hand wanders back and forth near home); each
   press's latency is measured in the page from ``keydown`` to the animation frame after the
   first frame of poses that the moved robot produced (``window.pinrate.latencies``).

Targets (issue 12): >= 990 Hz sustained, p99 period <= 2 ms, key to paint <= 30 ms median.
"""

from __future__ import annotations

import argparse
import statistics
import sys
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


def measure(rate: float, seconds: float, presses: int, width: int, height: int) -> dict[str, object]:
    baseline = []
    holder = threading.Thread(target=lambda: baseline.append(bare_loop(rate, min(seconds, 5.0))))
    holder.start()
    holder.join()

    robot = pinrate.load("ur5")
    teleop = pinrate.Teleop(robot, dt=1.0 / rate, timeout=1.0)
    with TeleopServer(teleop) as server, chromium(width, height) as context:
        page = context.new_page()
        page.goto(server.url)
        page.wait_for_function("() => window.pinrate && window.pinrate.controlling && window.pinrate.frames > 0")
        page.wait_for_timeout(2000)  # meshes parsed
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
        latencies = page.evaluate("() => window.pinrate.latencies")
    return {"baseline": baseline[0], "periods": periods, "latencies": np.array(latencies)}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rate", type=float, default=1000.0, help="control loop target (Hz)")
    parser.add_argument("--seconds", type=float, default=20.0, help="at least this long with the page attached")
    parser.add_argument("--presses", type=int, default=30, help="key presses whose latency is measured")
    parser.add_argument("--width", type=int, default=1200)
    parser.add_argument("--height", type=int, default=760)
    timing.add_arguments(parser)
    args = parser.parse_args(argv)
    if not Path(CHROMIUM).exists():
        print(f"needs Chromium at {CHROMIUM}", file=sys.stderr)
        return 2
    result = measure(args.rate, args.seconds, args.presses, args.width, args.height)
    base_rate, base_median, base_p99 = summary(result["baseline"])
    rate, median, p99 = summary(result["periods"])
    latencies = result["latencies"]
    print(f"UR5, target {args.rate:g} Hz, {result['periods'].size} loop periods, {latencies.size} key presses\n")
    print("| loop | rate (Hz) | period median (ms) | period p99 (ms) | p99 × bare |")
    print("|---|---:|---:|---:|---:|")
    print(f"| bare sleep-to-deadline loop (baseline) | {base_rate:.1f} | {base_median:.3f} | {base_p99:.3f} | 1.00 |")
    print(f"| teleop console, page attached | {rate:.1f} | {median:.3f} | {p99:.3f} | {p99 / base_p99:.2f} |")
    if latencies.size:
        print(
            f"\nkey to painted frame (Chromium, headless): median {statistics.median(latencies):.1f} ms, "
            f"max {latencies.max():.1f} ms, p90 {np.percentile(latencies, 90):.1f} ms"
        )
    rows = [
        timing.row_of("bare loop period", result["baseline"].tolist()),
        timing.row_of("teleop console loop period", result["periods"].tolist()),
    ]
    if latencies.size:
        rows.append(timing.row_of("key to painted frame", (latencies * 1e-3).tolist()))
    timing.finish(rows, args, {"rate": args.rate, "seconds": args.seconds, "presses": args.presses})
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
