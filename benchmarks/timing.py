"""Interleaved timing for pinrate's benchmarks: rounds, percentiles, and A/B files.

Every measured function runs once per round, round-robin, so a machine that slows down or
speeds up shifts every row alike and ratios within one run compare like with like. A row's
statistics are over its rounds: the median, and the 95th and 99th percentiles (the slow
tail a control loop feels). ``--save FILE`` writes them as JSON; ``--compare FILE`` prints
each row's median against the saved one (after / before), so a change can be A/B-measured
on one machine: run with ``--save before.json``, change, run with ``--compare before.json``.
"""

from __future__ import annotations

import argparse
import json
import math
import platform
import statistics
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from pinrate.compiled import use


@dataclass(frozen=True)
class Row:
    """One measured row: seconds per unit of work (a call, a step, a configuration)."""

    name: str
    median: float
    p95: float
    p99: float
    rounds: int


def percentile(values: list[float], fraction: float) -> float:
    """The ``fraction`` quantile by linear interpolation between order statistics."""
    ordered = sorted(values)
    position = fraction * (len(ordered) - 1)
    low = math.floor(position)
    high = min(low + 1, len(ordered) - 1)
    return ordered[low] + (ordered[high] - ordered[low]) * (position - low)


def row_of(name: str, values: list[float]) -> Row:
    """A row from samples measured elsewhere (a loop's periods, latencies), in seconds."""
    return Row(name, statistics.median(values), percentile(values, 0.95), percentile(values, 0.99), len(values))


def interleaved(functions: dict[str, tuple[Callable[[], object], int]], rounds: int, *, warm: int = 3) -> list[Row]:
    """Seconds per unit of each (function, units per call), measured round-robin.

    A function returning a number reports how many units it did (a servo run: its steps);
    else the given count is used.
    """
    for function, _units in functions.values():  # caches, lazy set-up, the core's first build
        for _ in range(warm):
            function()
    samples: dict[str, list[float]] = {name: [] for name in functions}
    for _ in range(rounds):
        for name, (function, units) in functions.items():
            start = time.perf_counter()
            done = function()
            elapsed = time.perf_counter() - start
            count = done if isinstance(done, int) and not isinstance(done, bool) and done > 0 else units
            samples[name].append(elapsed / count)
    return [row_of(name, values) for name, values in samples.items()]


def on(choice: str, function: Callable[[], object]) -> Callable[[], object]:
    """``function`` run on one of pinrate's paths ("python" or "compiled"), then the default again."""

    def run() -> object:
        use(choice)
        try:
            return function()
        finally:
            use(None)

    return run


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--save", type=Path, help="write the rows' statistics to this JSON file")
    parser.add_argument("--compare", type=Path, help="print each row's median against this saved run")


def save(rows: list[Row], path: Path, settings: dict[str, object]) -> None:
    record = {
        "machine": platform.platform(),
        "python": platform.python_version(),
        "settings": settings,
        "rows": {
            row.name: {"median": row.median, "p95": row.p95, "p99": row.p99, "rounds": row.rounds} for row in rows
        },
    }
    path.write_text(json.dumps(record, indent=2) + "\n", encoding="utf-8")
    print(f"\nsaved {len(rows)} rows to {path}")


def compare(rows: list[Row], path: Path) -> None:
    before = json.loads(path.read_text(encoding="utf-8"))["rows"]
    print(f"\nagainst {path} (median after / before; < 1 is faster):\n")
    print(f"| {'row':<58} | {'before, µs':>10} | {'after, µs':>10} | {'ratio':>6} |")
    print(f"|{'-' * 60}|{'-' * 12}|{'-' * 12}|{'-' * 8}|")
    for row in rows:
        old = before.get(row.name)
        if old is None:
            print(f"| {row.name:<58} | {'-':>10} | {row.median * 1e6:10.3f} | {'new':>6} |")
            continue
        ratio = row.median / old["median"]
        print(f"| {row.name:<58} | {old['median'] * 1e6:10.3f} | {row.median * 1e6:10.3f} | {ratio:6.2f} |")


def finish(rows: list[Row], arguments: argparse.Namespace, settings: dict[str, object]) -> None:
    """--save and --compare, as asked."""
    if arguments.compare is not None:
        compare(rows, arguments.compare)
    if arguments.save is not None:
        save(rows, arguments.save, settings)


def verdict(label: str, value: float, target: float, *, at_most: bool = True, unit: str = "x") -> str:
    met = value <= target if at_most else value >= target
    sign = "<=" if at_most else ">="
    return f"target: {label} {sign} {target:g}{unit}: measured {value:.3g}{unit}  {'met' if met else 'NOT met'}"
