"""Per-step cost of pinrate's resolved-rate solutions on UR5, against Pinocchio's floor.

Run: ``make bench`` (or ``python benchmarks/step.py [--robot ur5] [--repeats 40]``).

Every timing is the median over ``repeats`` rounds of the per-call time of a batch of
``batch`` calls. The rounds interleave all the measured steps (round-robin, in this one
process), so a machine that slows down or speeds up shifts every step alike and the
ratios compare like with like.
The floor is Pinocchio's bare ``computeFrameJacobian`` of the tip (one C++ call through
the Python binding), the least any resolved-rate step in Python must pay.
"""

from __future__ import annotations

import argparse
import statistics
import time
from collections.abc import Callable

import numpy as np
import pinocchio as pin

import pinrate
from pinrate.kinematics.targets import nearby_target


def interleaved_medians(functions: dict[str, tuple[Callable[[], object], int]], repeats: int) -> dict[str, float]:
    """Median seconds per call of each (function, batch size), measured round-robin."""
    for function, batch in functions.values():  # warm caches and lazy set-up
        for _ in range(min(batch, 20)):
            function()
    samples: dict[str, list[float]] = {name: [] for name in functions}
    for _ in range(repeats):
        for name, (function, batch) in functions.items():
            start = time.perf_counter()
            for _ in range(batch):
                function()
            samples[name].append((time.perf_counter() - start) / batch)
    return {name: statistics.median(values) for name, values in samples.items()}


def measure(robot_name: str, *, batch: int, repeats: int, servo_steps: int) -> list[tuple[str, float]]:
    robot = pinrate.load(robot_name)
    partition = pinrate.Partition.auto(robot)
    q = robot.home()
    twist = np.array([0.05, -0.02, 0.03, 0.1, -0.05, 0.2])[: partition.m + partition.k]
    model, data, tip = robot.model, robot.model.createData(), robot.tip_id
    _, target = nearby_target(robot, partition, seed=0)

    def floor() -> object:
        return pin.computeFrameJacobian(model, data, q, tip, pin.LOCAL)

    def step(algorithm: str) -> Callable[[], object]:
        return lambda: pinrate.joint_rates(robot, q, twist, algorithm=algorithm, partition=partition)

    goal = pin.SE3(target)
    rows_index = partition.resolve(robot)

    def bare_servo_step() -> object:
        """The least a servo step can be: Pinocchio kinematics, log3, one solve, integrate."""
        pin.computeJointJacobians(model, data, q)
        jacobian = pin.getFrameJacobian(model, data, tip, pin.LOCAL)
        error = pin.updateFramePlacement(model, data, tip).actInv(goal)
        twist = np.concatenate([error.translation, pin.log3(error.rotation)])
        return pin.integrate(model, q, np.linalg.solve(jacobian, twist) * 0.01)

    def servo_step() -> object:
        return pinrate.servo(robot, q, target, partition=partition, max_steps=servo_steps, tol=1e-12)

    functions: dict[str, tuple[Callable[[], object], int]] = {
        "pinocchio computeFrameJacobian (floor)": (floor, batch),
        "pinrate sensor-frame Jacobian": (lambda: robot.jacobian(q), batch),
    }
    for algorithm in ("exact", "mca1", "mca2", "mca3", "schur", "dls"):
        functions[f"pinrate {algorithm} step"] = (step(algorithm), batch)
    controller = pinrate.Controller(robot, partition=partition)  # default safety: limits, decelerate
    functions["controller step, default safety (exact)"] = (lambda: controller.step(q, twist), batch)
    guarded = pinrate.Controller(robot, partition=partition, collision=True)  # + the self-collision monitor
    functions["controller step, self-collision (exact)"] = (lambda: guarded.step(q, twist), batch)
    functions["bare Pinocchio+numpy exact servo step"] = (bare_servo_step, batch)
    functions["pinrate full servo step (mca1)"] = (servo_step, 1)  # one run, divided below
    medians = interleaved_medians(functions, repeats)
    medians["pinrate full servo step (mca1)"] /= servo_steps
    assert rows_index.all_rows  # the bare step assumes the full 6 x nv Jacobian
    return list(medians.items())


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--robot", default="ur5")
    parser.add_argument("--batch", type=int, default=200)
    parser.add_argument("--repeats", type=int, default=40)
    parser.add_argument("--servo-steps", type=int, default=300)
    args = parser.parse_args()
    rows = measure(args.robot, batch=args.batch, repeats=args.repeats, servo_steps=args.servo_steps)
    timings = dict(rows)
    floor = timings["pinocchio computeFrameJacobian (floor)"]
    exact = timings["pinrate exact step"]
    print(f"{args.robot}: median per call, {args.repeats} batches of {args.batch}\n")
    print(f"| {'step':<40} | {'time (us)':>9} | {'x floor':>7} | {'x exact':>7} |")
    print(f"|{'-' * 42}|{'-' * 11}|{'-' * 9}|{'-' * 9}|")
    for name, seconds in rows:
        print(f"| {name:<40} | {seconds * 1e6:9.2f} | {seconds / floor:7.2f} | {seconds / exact:7.2f} |")
    print()
    servo_ratio = timings["pinrate full servo step (mca1)"] / floor
    mca1_ratio = timings["pinrate mca1 step"] / exact
    print(
        f"target: full servo step <= 3x floor      measured {servo_ratio:.2f}x  "
        f"{'met' if servo_ratio <= 3 else 'NOT met'}"
    )
    print(
        f"target: mca1 step <= 0.8x exact step     measured {mca1_ratio:.2f}x  "
        f"{'met' if mca1_ratio <= 0.8 else 'NOT met'}"
    )
    default = timings["controller step, default safety (exact)"] / timings["pinrate full servo step (mca1)"]
    print(
        f"target: default controller step <= full servo step  measured {default:.2f}x  "
        f"{'met' if default <= 1 else 'NOT met'}"
    )
    collision = timings["controller step, self-collision (exact)"] / timings["pinrate full servo step (mca1)"]
    print(f"(the step with self-collision on costs {collision:.2f}x the full servo step)")
    bare = timings["bare Pinocchio+numpy exact servo step"] / floor
    print(f"(a servo step's bare Pinocchio+numpy calls alone cost {bare:.2f}x floor)")


if __name__ == "__main__":
    main()
