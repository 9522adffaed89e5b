"""Configurations per second of the work-volume Theorem test on a 6-DOF arm.

Run: ``python benchmarks/work_volume.py [--robot ur5] [--samples 100000]``.

Three ways of computing ρ at the same sampled configurations, in one process:

* the naive loop: ``pinrate.convergence(robot, q)`` per configuration (numpy per q);
* the Jacobian floor: Pinocchio's ``computeFrameJacobian`` per configuration, nothing else;
* ``pinrate.sample_convergence``: Pinocchio Jacobians per configuration, then the block
  algebra and the eigenvalues batched in closed form (:mod:`pinrate.solvers.batched`).

Each figure is the median of ``repeats`` rounds; every round runs each method once
(interleaved), so a machine that slows down shifts them alike.
"""

from __future__ import annotations

import argparse
import statistics
import time

import numpy as np
import pinocchio as pin

import pinrate


def interleaved_rates(methods: dict[str, tuple[object, int]], repeats: int) -> dict[str, float]:
    """Configurations per second of each (function, count), measured round-robin."""
    times: dict[str, list[float]] = {name: [] for name in methods}
    for _ in range(repeats):
        for name, (function, _count) in methods.items():
            start = time.perf_counter()
            function()
            times[name].append(time.perf_counter() - start)
    return {name: methods[name][1] / statistics.median(values) for name, values in times.items()}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--robot", default="ur5")
    parser.add_argument("--samples", type=int, default=100_000)
    parser.add_argument("--naive-samples", type=int, default=5_000)
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--workers", type=int, default=0, help="also time N worker processes (0: skip)")
    args = parser.parse_args()

    robot = pinrate.load(args.robot)
    configurations = robot.sample_configurations(args.samples, 0)
    model, data, tip = robot.model, robot.model.createData(), robot.tip_id

    def naive() -> None:
        for q in configurations[: args.naive_samples]:
            pinrate.convergence(robot, q)

    def floor() -> None:
        for q in configurations:
            pin.computeFrameJacobian(model, data, q, tip, pin.LOCAL)

    def batched() -> None:
        pinrate.sample_convergence(robot, args.samples, rng=0)

    methods = {
        "naive loop: pinrate.convergence per q": (naive, args.naive_samples),
        "Pinocchio computeFrameJacobian alone (floor)": (floor, args.samples),
        "pinrate.sample_convergence (batched)": (batched, args.samples),
    }
    if args.workers > 1:
        methods[f"pinrate.sample_convergence, {args.workers} processes"] = (
            lambda: pinrate.sample_convergence(robot, args.samples, rng=0, workers=args.workers),
            args.samples,
        )
    rows = list(interleaved_rates(methods, args.repeats).items())
    naive_rate = rows[0][1]
    print(f"{args.robot}: configurations per second (median of {args.repeats} runs)\n")
    floor_rate = rows[1][1]
    print(f"| {'method':<48} | {'configs/s':>10} | {'x naive':>8} | {'x floor':>8} |")
    print(f"|{'-' * 50}|{'-' * 12}|{'-' * 10}|{'-' * 10}|")
    for name, value in rows:
        print(f"| {name:<48} | {value:10,.0f} | {value / naive_rate:8.1f} | {value / floor_rate:8.2f} |")
    check = pinrate.sample_convergence(robot, 1000, rng=0)
    single = np.array([pinrate.convergence(robot, q).spectral_radius for q in check.q[:100]])
    assert np.allclose(single, check.spectral_radius[:100], rtol=1e-6), "batched and per-q results disagree"


if __name__ == "__main__":
    main()
