"""Configurations per second of the work-volume Theorem test on a 6-DOF arm.

Run: ``python benchmarks/work_volume.py [--robot ur5] [--samples 100000] [--workers 2]
[--save F] [--compare F]``.

Ways of computing ρ at sampled configurations, in one process:

* the naive loop: ``pinrate.convergence(robot, q)`` per configuration (numpy per q);
* the Jacobian floor: Pinocchio's ``computeFrameJacobian`` per configuration through the
  Python binding, nothing else;
* ``pinrate.sample_convergence`` on the pure-Python path: Pinocchio Jacobians per
  configuration, then the block algebra and the eigenvalues batched in closed form
  (:mod:`pinrate.solvers.batched`);
* ``pinrate.sample_convergence`` on the compiled path: Jacobians and closed forms in one C++
  loop (``pinrate_core``), where the core is installed.

Rows are seconds per configuration over interleaved rounds (:mod:`timing`); the table shows
their medians as configurations per second, with the 5th-percentile rate (the slow tail).
"""

from __future__ import annotations

import argparse
from collections.abc import Callable

import numpy as np
import pinocchio as pin
import timing

import pinrate


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--robot", default="ur5")
    parser.add_argument("--samples", type=int, default=100_000)
    parser.add_argument("--naive-samples", type=int, default=5_000)
    parser.add_argument("--repeats", type=int, default=7, help="interleaved rounds")
    parser.add_argument(
        "--workers", type=int, default=0, help="also time N workers: core threads, else processes (0: skip)"
    )
    timing.add_arguments(parser)
    args = parser.parse_args()

    robot = pinrate.load(args.robot)
    configurations = robot.sample_configurations(args.samples, 0)
    model, data, tip = robot.model, robot.model.createData(), robot.tip_id
    compiled = pinrate.backend().name == "compiled"

    def naive() -> None:
        for q in configurations[: args.naive_samples]:
            pinrate.convergence(robot, q)

    def floor() -> None:
        for q in configurations:
            pin.computeFrameJacobian(model, data, q, tip, pin.LOCAL)

    def sample() -> None:
        pinrate.sample_convergence(robot, args.samples, rng=0)

    methods: dict[str, tuple[Callable[[], object], int]] = {
        "naive loop: pinrate.convergence per q": (naive, args.naive_samples),
        "Pinocchio computeFrameJacobian alone (floor)": (floor, args.samples),
        "sample_convergence, python (batched numpy)": (timing.on("python", sample), args.samples),
    }
    if compiled:
        methods["sample_convergence, compiled (one C++ loop)"] = (timing.on("compiled", sample), args.samples)
    if args.workers > 1:
        methods[f"sample_convergence, {args.workers} workers (core threads)"] = (
            lambda: pinrate.sample_convergence(robot, args.samples, rng=0, workers=args.workers),
            args.samples,
        )
    rows = timing.interleaved(methods, args.repeats, warm=1)
    print(f"backend: {pinrate.backend()}")
    print(f"{args.robot}: configurations per second ({args.repeats} interleaved rounds)\n")
    naive_rate, floor_rate = 1.0 / rows[0].median, 1.0 / rows[1].median
    print(f"| {'method':<48} | {'configs/s':>10} | {'p95 rate':>10} | {'x naive':>8} | {'x floor':>8} |")
    print(f"|{'-' * 50}|{'-' * 12}|{'-' * 12}|{'-' * 10}|{'-' * 10}|")
    for row in rows:
        rate = 1.0 / row.median
        print(
            f"| {row.name:<48} | {rate:10,.0f} | {1.0 / row.p95:10,.0f} | {rate / naive_rate:8.1f} "
            f"| {rate / floor_rate:8.2f} |"
        )
    by_name = {row.name: 1.0 / row.median for row in rows}
    print()
    if compiled:
        rate = by_name["sample_convergence, compiled (one C++ loop)"]
        print(timing.verdict("compiled sample_convergence", rate / 1e6, 2.0, at_most=False, unit=" M/s"))
    python_rate = by_name["sample_convergence, python (batched numpy)"]
    print(timing.verdict("python sample_convergence", python_rate / 1e6, 0.5, at_most=False, unit=" M/s"))
    check = pinrate.sample_convergence(robot, 1000, rng=0)
    single = np.array([pinrate.convergence(robot, q).spectral_radius for q in check.q[:100]])
    assert np.allclose(single, check.spectral_radius[:100], rtol=1e-6), "sampled and per-q results disagree"
    timing.finish(rows, args, {"robot": args.robot, "samples": args.samples, "repeats": args.repeats})


if __name__ == "__main__":
    main()
