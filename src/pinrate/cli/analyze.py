"""``pinrate analyze``: where MCA1/2/3 converge on one robot: the share of its work volume,
region maps, and a parameter sweep of a papers' robot, written up as ``report.md`` and PNGs in
``--out``. Importing this module loads the analysis and matplotlib: only this command and
``paper`` need them."""

from __future__ import annotations

import argparse
import time
from pathlib import Path

from .. import analysis, robots
from ..errors import InputError
from ..kinematics.manipulator import Robot
from ..kinematics.partition import Partition
from .outputs import output_folder
from .robot_arguments import load_robot


def _partition_from_args(args: argparse.Namespace, robot: Robot) -> Partition:
    automatic = Partition.auto(robot)
    if args.arm is None and args.wrist is None and args.linear is None and args.angular is None:
        return automatic

    def names(text: str | None, default: tuple[str, ...]) -> tuple[str, ...]:
        return default if text is None else tuple(name for name in text.split(",") if name)

    return Partition(
        names(args.arm, automatic.arm),
        names(args.wrist, automatic.wrist),
        linear=automatic.linear if args.linear is None else args.linear,
        angular=automatic.angular if args.angular is None else args.angular,
    )


def analyze(args: argparse.Namespace) -> int:
    """``pinrate analyze``: the convergence report of one robot, written to ``--out`` (made
    before the long part of the work, and removed again if the command ends without a report)."""
    with output_folder(args.out, "--out") as out:
        return _analyze(args, out)


def _analyze(args: argparse.Namespace, out: Path) -> int:
    robot = load_robot(args)
    partition = _partition_from_args(args, robot)
    factory = None
    if args.sweep is not None:  # checked before the long part of the work ('' too)
        parameter, low, high = analysis.parse_sweep(args.sweep)
        if args.robot not in robots.ROBOT_NAMES:
            raise InputError(
                f"--sweep needs one of the papers' parametric robots ({', '.join(robots.ROBOT_NAMES)}); "
                "for another robot call pinrate.analysis.sweep with a factory"
            )
        if parameter not in robots.parameters(args.robot):
            raise InputError(
                f"{args.robot} has no parameter {parameter!r}; its parameters: "
                f"{', '.join(robots.parameters(args.robot))}"
            )

        def factory(value: float) -> Robot:
            return robots.build(args.robot, tip=args.tip, sensor=args.sensor, **{parameter: value})

    started = time.perf_counter()
    report = analysis.analyze(
        robot,
        samples=args.samples,
        partition=partition,
        rng=args.seed,
        map_joints=args.joints,
        points=args.points,
        workers=args.workers,
        scheduler=args.scheduler,
    )
    if factory is not None:
        report.sweep = analysis.sweep(factory, parameter, low, high, samples=max(1000, args.samples // 25))
    path = analysis.write_report(report, out)
    print(report.markdown(), end="")
    print(
        f"\nwritten: {path} and {', '.join(p.name for p in report.files.values())} "
        f"({time.perf_counter() - started:.1f} s)"
    )
    return 0
