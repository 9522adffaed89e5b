"""The compiled ρ map (``sample_convergence``) against its bound: the Jacobians alone in C++.

Run: ``python benchmarks/region_map.py [--robots ur5 panda] [--samples 200000] [--repeats 9]
[--threads 2] [--save F] [--compare F]``.

Rows, per robot, in configurations (maps of ρ at one q) per second, measured in interleaved
rounds (:mod:`timing`) so their ratios compare like with like on a shared machine:

* the bound: the core's own kinematics pass for J at each configuration and nothing else
  (``pinrate_core.Servo.jacobian_timing``: the map's loop without its closed forms), on 1 and
  on ``--threads`` threads;
* the compiled map, the core's call alone (``CoreServo.spectral_radius_at``), 1 and N threads;
* ``pinrate.spectral_radius_at`` on given configurations (checks and all), and
  ``sample_convergence`` (drawing the configurations too), 1 and N workers (the core's threads);
* the Python path (Pinocchio from Python, batched numpy), and the way 2 workers ran before:
  worker processes, each rebuilding the robot and mapping its chunks in the core;
* Pinocchio's ``computeFrameJacobian`` called from Python per q, nothing else.

The goal (issue 25): the compiled map at >= 0.8 of the bound on the same thread count, and
N threads faster than one.
"""

from __future__ import annotations

import argparse
from collections.abc import Callable

import numpy as np
import pinocchio as pin
import timing

import pinrate
from pinrate.compiled import rho_map
from pinrate.theorem.parallel import map_chunks
from pinrate.theorem.sampling import CHUNK, _spectral_radius_of_chunk, spectral_radius_at


def robot_rows(name: str, samples: int, threads: int) -> dict[str, tuple[Callable[[], object], int]]:
    """The timed functions of one robot, each (function, configurations per call)."""
    robot = pinrate.load(name)
    partition = pinrate.Partition.auto(robot)
    index = partition.resolve(robot)
    configurations = robot.sample_configurations(samples, 0, joints=partition.joints)
    core = rho_map(robot, tuple(index.rows.tolist()), tuple(index.columns.tolist()), index.m, index.arm_columns.size)
    if core is None:
        raise SystemExit(f"{name}: the compiled core does not map this robot (backend: {pinrate.backend()})")
    model, data, tip = robot.model, robot.model.createData(), robot.tip_id
    chunks = [configurations[start : start + CHUNK] for start in range(0, samples, CHUNK)]

    def python_floor() -> None:
        for q in configurations:
            pin.computeFrameJacobian(model, data, q, tip, pin.LOCAL)

    def processes() -> None:
        map_chunks(_spectral_radius_of_chunk, chunks, robot.spec(), partition, workers=threads, progress=False)

    rows: dict[str, tuple[Callable[[], object], int]] = {}
    for count in (1, threads):
        rows[f"bound: J alone in C++, {count} thread(s)"] = (
            lambda count=count: core.jacobian_seconds(configurations, threads=count),
            samples,
        )
        rows[f"core map call, {count} thread(s)"] = (
            lambda count=count: core.spectral_radius_at(configurations, threads=count),
            samples,
        )
        rows[f"spectral_radius_at, workers={count}"] = (
            lambda count=count: spectral_radius_at(robot, configurations, partition=partition, workers=count),
            samples,
        )
        rows[f"sample_convergence, workers={count}"] = (
            lambda count=count: pinrate.sample_convergence(robot, samples, rng=0, workers=count, progress=False),
            samples,
        )
    rows[f"before: {threads} processes, core per chunk"] = (processes, samples)
    rows["python path: sample_convergence"] = (
        timing.on("python", lambda: pinrate.sample_convergence(robot, samples, rng=0, progress=False)),
        samples,
    )
    rows["Pinocchio computeFrameJacobian from Python"] = (python_floor, samples)
    # The threaded map is the single-threaded one, split: check before timing it.
    single = core.spectral_radius_at(configurations, threads=1)
    np.testing.assert_array_equal(core.spectral_radius_at(configurations, threads=threads), single)
    return rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--robots", nargs="+", default=["ur5", "panda"])
    parser.add_argument("--samples", type=int, default=200_000)
    parser.add_argument("--repeats", type=int, default=9, help="interleaved rounds")
    parser.add_argument("--threads", type=int, default=2)
    timing.add_arguments(parser)
    args = parser.parse_args()
    print(f"backend: {pinrate.backend()}")
    all_rows = []
    for name in args.robots:
        functions = {f"{name}: {row}": value for row, value in robot_rows(name, args.samples, args.threads).items()}
        rows = timing.interleaved(functions, args.repeats, warm=1)
        all_rows += rows
        rate = {row.name.split(": ", 1)[1]: 1.0 / row.median for row in rows}
        print(f"\n{name}: configurations per second, median of {args.repeats} interleaved rounds\n")
        print(f"| {'row':<46} | {'configs/s':>11} | {'p95 rate':>11} | {'x bound (1 thread)':>18} |")
        print(f"|{'-' * 48}|{'-' * 13}|{'-' * 13}|{'-' * 20}|")
        bound = rate["bound: J alone in C++, 1 thread(s)"]
        for row in rows:
            short = row.name.split(": ", 1)[1]
            print(f"| {short:<46} | {rate[short]:11,.0f} | {1.0 / row.p95:11,.0f} | {rate[short] / bound:18.2f} |")
        print()
        for count in sorted({1, args.threads}):
            share = rate[f"core map call, {count} thread(s)"] / rate[f"bound: J alone in C++, {count} thread(s)"]
            print(timing.verdict(f"{name} map / bound, {count} thread(s)", share, 0.8, at_most=False, unit=""))
            share = rate[f"sample_convergence, workers={count}"] / rate[f"bound: J alone in C++, {count} thread(s)"]
            print(timing.verdict(f"{name} sample_convergence / bound, {count}", share, 0.8, at_most=False, unit=""))
        if args.threads > 1:
            speedup = rate[f"core map call, {args.threads} thread(s)"] / rate["core map call, 1 thread(s)"]
            print(timing.verdict(f"{name} map, {args.threads} threads / 1", speedup, 1.0, at_most=False, unit="x"))
    timing.finish(all_rows, args, {"robots": args.robots, "samples": args.samples, "threads": args.threads})


if __name__ == "__main__":
    main()
