"""Start-up time of the ``pinrate`` command line, against the bare interpreter's.

Run: ``python benchmarks/startup.py [--rounds 20] [--save F] [--compare F]``.

Each row is one whole process, started and waited for (its output thrown away): the
baseline ``python -c pass`` (the interpreter and its site initialisation, which no program
can avoid), then ``pinrate --help``, ``pinrate demo --help``, ``pinrate teleop --help`` and
``pinrate --version`` through the console script next to this interpreter, and for
reference the bare imports of numpy and Pinocchio. Rows are medians (and 95th / 99th
percentiles) over interleaved rounds (:mod:`timing`), so a machine that slows down shifts
them all alike; "own" is a row's median minus the baseline's, measured in the same run: what
pinrate itself adds to the interpreter's start. The target (issue 20): ``--help`` of the
command line and of a subcommand owns under 0.3 s.
"""

from __future__ import annotations

import argparse
import os
import shutil
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path

import timing

BASELINE = "python -c pass (baseline)"
TARGET = 0.3
"""Seconds of its own that ``pinrate --help`` (and a subcommand's) may take."""


def console_script() -> list[str]:
    """The ``pinrate`` console script of this interpreter's environment (what a user runs),
    else ``python -m pinrate.cli``."""
    beside = Path(sys.executable).parent / "pinrate"
    if beside.exists():
        return [str(beside)]
    found = shutil.which("pinrate")
    return [found] if found else [sys.executable, "-m", "pinrate.cli"]


def process(argv: list[str]) -> Callable[[], object]:
    def run() -> object:
        subprocess.run(argv, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, check=True)
        return None

    return run


def measure(rounds: int) -> list[timing.Row]:
    pinrate = console_script()
    python = [sys.executable]
    commands = {
        BASELINE: [*python, "-c", "pass"],
        "pinrate --help": [*pinrate, "--help"],
        "pinrate demo --help": [*pinrate, "demo", "--help"],
        "pinrate teleop --help": [*pinrate, "teleop", "--help"],
        "pinrate --version": [*pinrate, "--version"],
        "python -c 'import numpy' (reference)": [*python, "-c", "import numpy"],
        "python -c 'import pinocchio' (reference)": [*python, "-c", "import pinocchio"],
    }
    return timing.interleaved({name: (process(argv), 1) for name, argv in commands.items()}, rounds)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=20)
    timing.add_arguments(parser)
    args = parser.parse_args()
    print(f"{' '.join(console_script())}: whole processes, {args.rounds} interleaved rounds\n")
    rows = measure(args.rounds)
    baseline = next(row.median for row in rows if row.name == BASELINE)
    print(f"| {'row':<42} | {'median (ms)':>11} | {'p95':>7} | {'p99':>7} | {'own (ms)':>8} | {'x baseline':>10} |")
    print(f"|{'-' * 44}|{'-' * 13}|{'-' * 9}|{'-' * 9}|{'-' * 10}|{'-' * 12}|")
    for row in rows:
        print(
            f"| {row.name:<42} | {row.median * 1e3:11.1f} | {row.p95 * 1e3:7.1f} | {row.p99 * 1e3:7.1f} "
            f"| {(row.median - baseline) * 1e3:8.1f} | {row.median / baseline:10.2f} |"
        )
    print()
    by_name = {row.name: row.median for row in rows}
    for name in ("pinrate --help", "pinrate demo --help", "pinrate teleop --help"):
        print(timing.verdict(f"{name}, own", by_name[name] - baseline, TARGET, unit=" s"))
    print(
        f"(--version imports the compiled core's bridge, and with it numpy and Pinocchio: "
        f"{by_name['pinrate --version'] - baseline:.3f} s own)"
    )
    timing.finish(
        rows,
        args,
        {"rounds": args.rounds, "command": console_script(), "backend": os.environ.get("PINRATE_BACKEND", "auto")},
    )


if __name__ == "__main__":
    main()
