"""Per-step cost of pinrate's resolved-rate steps and servo loops on UR5, against Pinocchio's floor.

Run: ``make bench`` (or ``python benchmarks/step.py [--robot ur5] [--rounds 40] [--save F]
[--compare F]``).

Every row is the median (and 95th / 99th percentile) over ``rounds`` interleaved rounds
(:mod:`timing`) of the time per call, or per servo step for the servo rows (a run's time
over the steps it took, set-up included). The floor is Pinocchio's bare
``computeFrameJacobian`` of the tip through the Python binding, the least any resolved-rate
step called from Python pays. Both paths are measured in the same process: the compiled core
(``pinrate_core``, where it is installed) and the pure-Python path (``PINRATE_BACKEND=python``
semantics, chosen per row with :func:`pinrate.compiled.use`).
"""

from __future__ import annotations

import argparse
from collections.abc import Callable

import numpy as np
import pinocchio as pin
import timing

import pinrate
from pinrate.kinematics.targets import nearby_target

FLOOR = "pinocchio computeFrameJacobian (floor)"
BARE = "bare Pinocchio+numpy exact servo step"


def measure(robot_name: str, *, batch: int, rounds: int) -> tuple[list[timing.Row], dict[str, float]]:
    robot = pinrate.load(robot_name)
    partition = pinrate.Partition.auto(robot)
    q = robot.home()
    twist = np.array([0.05, -0.02, 0.03, 0.1, -0.05, 0.2])[: partition.m + partition.k]
    model, data, tip = robot.model, robot.model.createData(), robot.tip_id
    _, target = nearby_target(robot, partition, seed=0)
    goal = pin.SE3(target)
    compiled = pinrate.backend().name == "compiled"

    def batched(function: Callable[[], object]) -> Callable[[], object]:
        def run() -> object:
            for _ in range(batch):
                function()
            return batch

        return run

    def floor() -> object:
        return pin.computeFrameJacobian(model, data, q, tip, pin.LOCAL)

    def bare_servo_step() -> object:
        """The least a servo step can be in Python: Pinocchio kinematics, log3, one solve, integrate."""
        pin.computeJointJacobians(model, data, q)
        jacobian = pin.getFrameJacobian(model, data, tip, pin.LOCAL)
        error = pin.updateFramePlacement(model, data, tip).actInv(goal)
        twist = np.concatenate([error.translation, pin.log3(error.rotation)])
        return pin.integrate(model, q, np.linalg.solve(jacobian, twist) * 0.01)

    def servo(algorithm: str, steps: int) -> Callable[[], object]:
        def run() -> int:
            trajectory = pinrate.servo(
                robot, q, target, partition=partition, algorithm=algorithm, max_steps=steps, tol=1e-12
            )
            return trajectory.steps

        return run

    functions: dict[str, tuple[Callable[[], object], int]] = {
        FLOOR: (batched(floor), batch),
        "pinrate sensor-frame Jacobian": (batched(lambda: robot.jacobian(q)), batch),
    }
    for algorithm in ("exact", "mca1", "mca2", "mca3", "schur", "dls"):
        step = batched(
            lambda algorithm=algorithm: pinrate.joint_rates(robot, q, twist, algorithm=algorithm, partition=partition)
        )
        functions[f"pinrate {algorithm} step"] = (step, batch)
    controller = pinrate.Controller(robot, partition=partition)  # default safety: limits, decelerate
    functions["controller step, default safety (exact)"] = (batched(lambda: controller.step(q, twist)), batch)
    # The same step on each path (the default row above takes the compiled one where installed);
    # the teleop form passes the observation it made for its command.
    mca1 = pinrate.Controller(robot, partition=partition, algorithm="mca1")
    observation = controller.observe(q)
    paths = ("python", "compiled") if compiled else ("python",)
    for choice in paths:
        functions[f"controller step (exact), {choice}"] = (
            timing.on(choice, batched(lambda: controller.step(q, twist))),
            batch,
        )
        functions[f"controller step (mca1), {choice}"] = (
            timing.on(choice, batched(lambda: mca1.step(q, twist))),
            batch,
        )
        functions[f"controller step (exact) + observation, {choice}"] = (
            timing.on(choice, batched(lambda: controller.step(q, twist, observation=observation))),
            batch,
        )
    try:  # one controller step plus one MuJoCo plant advance of dt (10 sub-steps of 1 ms), if installed
        from pinrate.plants import MujocoPlant

        plant = MujocoPlant(robot)
        plant.reset(q)
        functions["controller step (exact) + MuJoCo plant advance, dt 0.01"] = (
            batched(lambda: plant.advance(controller.step(q, twist).joint_rates, controller.dt)),
            batch,
        )
    except pinrate.PinrateError:
        pass
    guarded = pinrate.Controller(robot, partition=partition, collision=True)
    functions["controller step, self-collision (exact)"] = (batched(lambda: guarded.step(q, twist)), batch)
    for choice in paths:  # the monitor on each path (the row above takes the compiled one where installed)
        functions[f"controller step, self-collision (exact), {choice}"] = (
            timing.on(choice, batched(lambda: guarded.step(q, twist))),
            batch,
        )
    functions[BARE] = (batched(bare_servo_step), batch)
    functions["servo step, python, mca1, 300-step run"] = (timing.on("python", servo("mca1", 300)), 300)
    functions["servo step, python, exact, 300-step run"] = (timing.on("python", servo("exact", 300)), 300)
    if compiled:
        functions["servo step, compiled, mca1, 2000-step run"] = (timing.on("compiled", servo("mca1", 2000)), 2000)
        functions["servo step, compiled, mca1, 300-step run"] = (timing.on("compiled", servo("mca1", 300)), 300)
        functions["servo step, compiled, exact, 2000-step run"] = (timing.on("compiled", servo("exact", 2000)), 2000)
    rows = timing.interleaved(functions, rounds)
    solves: dict[str, float] = {}
    if compiled:  # the solve alone, timed in C++ (a Python call would cost more than the solve)
        core = pinrate.Controller(robot, partition=partition, algorithm="mca1").compiled()
        assert core is not None
        for algorithm in ("exact", "mca1", "mca2"):
            solves[algorithm] = min(core.solve_seconds(q, twist, algorithm, 200_000) for _ in range(5))
    return rows, solves


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--robot", default="ur5")
    parser.add_argument("--batch", type=int, default=100)
    parser.add_argument("--rounds", type=int, default=30)
    timing.add_arguments(parser)
    args = parser.parse_args()
    print(f"backend: {pinrate.backend()}")
    rows, solves = measure(args.robot, batch=args.batch, rounds=args.rounds)
    by_name = {row.name: row.median for row in rows}
    floor = by_name[FLOOR]
    print(f"{args.robot}: per call (servo rows: per step), {args.rounds} interleaved rounds\n")
    print(f"| {'row':<44} | {'median (us)':>11} | {'p95':>8} | {'p99':>8} | {'x floor':>7} |")
    print(f"|{'-' * 46}|{'-' * 13}|{'-' * 10}|{'-' * 10}|{'-' * 9}|")
    for row in rows:
        print(
            f"| {row.name:<44} | {row.median * 1e6:11.3f} | {row.p95 * 1e6:8.3f} | {row.p99 * 1e6:8.3f} "
            f"| {row.median / floor:7.2f} |"
        )
    if solves:
        print("\nthe solve alone, in C++ (best of 5 x 200,000):")
        for algorithm, seconds in solves.items():
            print(f"  {algorithm:<6} {seconds * 1e9:8.1f} ns  ({seconds / solves['exact']:.2f} x exact)")
    print()
    if "servo step, compiled, mca1, 2000-step run" in by_name:
        print(
            timing.verdict(
                "compiled servo step, 2000-step run", by_name["servo step, compiled, mca1, 2000-step run"] / floor, 1.5
            )
        )
        print(
            timing.verdict(
                "compiled servo step, 300-step run", by_name["servo step, compiled, mca1, 300-step run"] / floor, 2.0
            )
        )
        print(timing.verdict("compiled mca1 solve / exact solve", solves["mca1"] / solves["exact"], 0.8))
        mca1, exact = (by_name[f"servo step, compiled, {name}, 2000-step run"] for name in ("mca1", "exact"))
        whole = mca1 / exact
        print(f"(compiled servo step mca1 / exact, whole steps: {whole:.2f})")
    else:
        print("(the compiled core is not installed: its rows are left out; make core builds it)")
    python_servo = by_name["servo step, python, exact, 300-step run"]
    print(timing.verdict("python servo step (exact) / bare Pinocchio+numpy step", python_servo / by_name[BARE], 1.0))
    print(
        timing.verdict(
            "python mca1 step / exact step", by_name["pinrate mca1 step"] / by_name["pinrate exact step"], 0.8
        )
    )
    if "controller step (exact), compiled" in by_name:
        print(
            timing.verdict(
                "compiled controller step (exact) / floor", by_name["controller step (exact), compiled"] / floor, 5.0
            )
        )
    print(
        timing.verdict(
            "python controller step (exact) / bare Pinocchio+numpy step",
            by_name["controller step (exact), python"] / by_name[BARE],
            2.0,
        )
    )
    default = by_name["controller step, default safety (exact)"]
    print(
        f"(the default controller step costs {default / floor:.1f}x floor; with self-collision "
        f"{by_name['controller step, self-collision (exact)'] / floor:.1f}x)"
    )
    timing.finish(
        rows, args, {"robot": args.robot, "batch": args.batch, "rounds": args.rounds, "backend": str(pinrate.backend())}
    )


if __name__ == "__main__":
    main()
