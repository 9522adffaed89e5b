"""The subcommands of ``pinrate``: ``list``, ``demo``, ``analyze`` and ``paper``, and their parser
(``teleop`` lives in :mod:`.teleop`)."""

from __future__ import annotations

import argparse
import logging
import sys
import time
import warnings
from collections.abc import Sequence

import numpy as np
import pinocchio as pin

from .. import __version__, analysis, robots
from ..checks import check_output_file, check_output_folder
from ..compiled import backend
from ..control.servo_loop import servo
from ..control.trajectory import Trajectory
from ..errors import InputError, PinrateError
from ..kinematics.manipulator import Robot
from ..kinematics.partition import Partition
from ..kinematics.targets import nearby_target
from ..kinematics.urdf_structure import MAX_JOINTS
from ..papers import markdown, results
from ..robots import EXAMPLE_ROBOTS, ROBOT_NAMES, example_robot_data_share, load
from ..solvers.error_map import THEOREM_ALGORITHMS
from ..solvers.registry import ALGORITHMS
from ..theorem.pointwise import coupling_along
from . import teleop
from .arguments import Parser, count, finite, positive, warn

DEMO_MAX_STEPS = 6000
"""The demo's step budget (60 s at dt = 0.01): MCA1 with ρ near 0.8 (TIAGo's arm) needs about
30 s to bring the rotation error under 1e-4 rad; a target it cannot reach stops earlier, as
"stalled" (servo's stall rule)."""


def _list(_: argparse.Namespace) -> int:
    print("The papers' robots (pinrate.robots, urdf/):")
    for name in ROBOT_NAMES:
        summary_line = (getattr(robots, name).__doc__ or "").strip().splitlines()[0]
        print(f"  {name:<16} {summary_line}")
    available = example_robot_data_share() is not None
    note = "" if available else "  (example-robot-data not installed)"
    print(f"example-robot-data arms:{note}")
    for entry in EXAMPLE_ROBOTS.values():
        print(f"  {entry.name:<8} tip {entry.tip:<24} {entry.description}")
    print("Any other URDF: pass its path.")
    return 0


def radius_range(trajectory: Trajectory) -> str:
    """'min .. max' of ρ along a run, and whether a block was singular somewhere."""
    finite = trajectory.spectral_radius[np.isfinite(trajectory.spectral_radius)]
    text = f"{finite.min():.3f} .. {finite.max():.3f}" if finite.size else "undefined"
    return text if finite.size == trajectory.spectral_radius.size else text + " (singular at some steps)"


COUPLING_POINTS = 300
"""At most this many configurations of a run are tested for the coupling (it is a summary)."""

COUPLING_GROWTH = 5.0
"""A run that diverged with ρ < 1 throughout, and whose coupling grew by this factor, is
explained by it (eq. 30)."""


def verdict_lines(robot: Robot, trajectory: Trajectory) -> list[str]:
    """ρ along the run, what it rests on, and the coupling beside it (issue 10: ρ < 1 along a
    path is not sufficient; MCA1's term −U A⁻¹ v of eq. 30 can grow without bound)."""
    radius = radius_range(trajectory)
    algorithm = trajectory.algorithm
    if algorithm not in THEOREM_ALGORITHMS:
        return [
            f"rho        not applicable to {algorithm} (the Theorem is about MCA1/2/3; theirs: {radius} along the path)"
        ]
    basis = (
        "the Theorem"
        if trajectory.partition.resolve(robot).square
        else f"the error map of {algorithm} (blocks not square)"
    )
    lines = [f"rho        {radius} along the path ({basis}: < 1 at a point means converging there, J frozen)"]
    if algorithm == "mca3":
        return lines
    stride = max(1, len(trajectory.q) // COUPLING_POINTS)
    coupling = coupling_along(robot, trajectory.q[::stride], partition=trajectory.partition, algorithm=algorithm)
    finite = coupling[np.isfinite(coupling)]
    if not finite.size:
        return lines
    name, unit, equation = ("|U A^-1|", "rad/m", "30") if algorithm == "mca1" else ("|B W^-1|", "m/rad", "49")
    lines.append(
        f"coupling   {name} {finite[0]:.3g} at the start, {finite.max():.3g} at most {unit} (eq. {equation}: it feeds "
        "the commanded motion into the error and grows as the block nears singularity)"
    )
    radii = trajectory.spectral_radius
    if (
        trajectory.reason.startswith("diverging")
        and np.all(radii[np.isfinite(radii)] < 1)
        and finite[0] > 0
        and finite.max() >= COUPLING_GROWTH * finite[0]
    ):
        lines.append(
            f"why        diverged although rho < 1 at every step: the coupling grew {finite.max() / finite[0]:.0f}x; "
            "rho < 1 along a path is necessary for the frozen-J argument, not sufficient"
        )
    return lines


def summary(robot: Robot, trajectory: Trajectory) -> str:
    """A short, readable account of a servo run."""
    lines = [
        f"robot      {robot.name}   tip {robot.tip}   sensor {robot.sensor}",
        "partition  " + trajectory.partition.describe(robot).replace("\n", "\n           "),
        f"algorithm  {trajectory.algorithm}   dt {trajectory.dt:g} s",
        f"steps      {trajectory.steps}   ({trajectory.steps * trajectory.dt:.2f} s)",
        f"converged  {'yes' if trajectory.converged else 'no'}: {trajectory.reason}",
        f"errors     position {trajectory.position_error[0]:.4g} -> {trajectory.position_error[-1]:.3g} m,"
        f"  orientation {trajectory.orientation_error[0]:.4g} -> {trajectory.orientation_error[-1]:.3g} rad",
        *verdict_lines(robot, trajectory),
    ]
    return "\n".join(lines)


def status_line(index: int, count: int, trajectory: Trajectory) -> str:
    """One console line per servo segment."""
    radius = radius_range(trajectory)
    return (
        f"segment {index}/{count}  {trajectory.algorithm}  {trajectory.steps} steps  "
        f"{'converged' if trajectory.converged else 'NOT converged'}  "
        f"position {trajectory.position_error[-1]:.2e} m  orientation {trajectory.orientation_error[-1]:.2e} rad  "
        f"rho {radius}" + ("" if trajectory.converged else f"  ({trajectory.reason})")
    )


def _targets(args: argparse.Namespace, robot: Robot, partition: Partition, start: np.ndarray) -> list[np.ndarray]:
    if args.target is not None:
        x, y, z, roll, pitch, yaw = args.target
        return [pin.SE3(pin.rpy.rpyToMatrix(roll, pitch, yaw), np.array([x, y, z])).homogeneous]
    return [nearby_target(robot, partition, args.seed + k, start=start)[1] for k in range(args.targets)]


def _load(args: argparse.Namespace) -> Robot:
    robot = load(args.robot, tip=args.tip, sensor=args.sensor, max_joints=args.max_joints)
    if robot.tip_choice != "given":
        print(f"tip        {robot.tip} ({robot.tip_choice}; --tip to choose another)")
    return robot


def _demo(args: argparse.Namespace) -> int:
    record = None
    if args.record:
        if args.no_viewer:
            raise InputError("--record writes the viewer's replay: drop --no-viewer")
        record = check_output_file(args.record, "--record")
    robot = _load(args)
    partition = Partition.auto(robot)
    start = robot.home() if args.q0 is None else _start(robot, args.q0)
    targets = _targets(args, robot, partition, start)
    viewer = None
    if not args.no_viewer:
        from ..viewer import Viewer  # meshcat is imported only when a view is asked for

        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always", UserWarning)
            viewer = Viewer(robot, host=args.host, open_browser=args.open)
        for warning in caught:
            warn(str(warning.message))
        print(f"Meshcat viewer: {viewer.url}", flush=True)
    try:
        q = start
        if viewer is not None:
            viewer.frame(q, [target[:3, 3] for target in targets])
            viewer.show(q)
        all_converged = True
        for index, target in enumerate(targets, start=1):
            trajectory = servo(
                robot,
                q,
                target,
                algorithm=args.algorithm,
                partition=partition,
                dt=args.dt,
                gain=args.gain,
                max_steps=args.max_steps,
                tol=args.tol,
            )
            position, rpy = target[:3, 3], pin.rpy.matrixToRpy(target[:3, :3])
            print(
                f"target     xyz {np.array2string(position, precision=4)} m   "
                f"rpy {np.array2string(rpy, precision=4)} rad (world)"
            )
            if len(targets) == 1 and viewer is None:
                print(summary(robot, trajectory))
            else:
                if index == 1:
                    print("partition  " + partition.describe(robot).replace("\n", "\n           "))
                print(status_line(index, len(targets), trajectory), flush=True)
            if viewer is not None:
                viewer.play(trajectory, target=target, speed=args.speed)
            all_converged &= trajectory.converged
            q = trajectory.q[-1]
        if viewer is not None:
            if record is not None:
                print(f"recorded   {viewer.save_html(record)} ({viewer.recorded_frames} frames)")
            if sys.stdin.isatty() and sys.stdout.isatty():
                print("The view stays up: Ctrl-C to quit.", flush=True)
                try:
                    while True:
                        time.sleep(3600)
                except KeyboardInterrupt:  # the documented way to leave the view: not an interruption
                    pass
        return 0 if all_converged else 1
    finally:
        if viewer is not None:
            viewer.close()


def _start(robot: Robot, values: list[float]) -> np.ndarray:
    """--q0: one value per moving joint in ``robot.joint_names`` order (an angle for a
    continuous joint), checked like any q."""
    if len(values) != len(robot.joint_names):
        raise InputError(
            f"--q0 takes {len(robot.joint_names)} values, one per moving joint ({', '.join(robot.joint_names)}); "
            f"got {len(values)}"
        )
    q = robot.neutral()[None, :]
    for joint, value in zip(robot.joint_names, values, strict=True):
        robot.set_joint_values(q, joint, np.array([value]))
    return robot.check_q(q[0])


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


def _analyze(args: argparse.Namespace) -> int:
    out = check_output_folder(args.out, "--out")  # before the long part of the work
    robot = _load(args)
    partition = _partition_from_args(args, robot)
    factory = None
    if args.sweep:  # checked before the long part of the work
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


def _paper(_: argparse.Namespace) -> int:
    print(markdown(results()), end="")
    return 0


def _robot_arguments(parser: argparse.ArgumentParser, tip_help: str, sensor_help: str) -> None:
    parser.add_argument("robot", help="a name from `pinrate list` or a URDF path")
    parser.add_argument("--tip", help=tip_help)
    parser.add_argument("--sensor", help=sensor_help)
    parser.add_argument(
        "--max-joints",
        type=count(1),
        help=f"refuse URDFs with more moving joints (default {MAX_JOINTS}, or $PINRATE_MAX_JOINTS)",
    )


class _Version(argparse.Action):
    """``--version``: pinrate's version and the path its loops take (the compiled core or
    pure Python, and why)."""

    def __init__(self, option_strings: list[str], dest: str, **keywords: object) -> None:
        super().__init__(option_strings, dest, nargs=0, help="print the version and the backend, then exit")

    def __call__(self, parser: argparse.ArgumentParser, *_: object) -> None:
        print(f"pinrate {__version__}\nbackend: {backend()}")
        parser.exit()


def build_parser() -> argparse.ArgumentParser:
    parser = Parser(prog="pinrate", description="Resolved-rate motion control for URDF arms.")
    parser.add_argument("-v", "--verbose", action="store_true", help="log what pinrate chooses")
    parser.add_argument("--version", action=_Version)
    commands = parser.add_subparsers(dest="command", required=True, parser_class=Parser)

    listing = commands.add_parser("list", help="print every robot name pinrate can load")
    listing.set_defaults(run=_list)

    paper = commands.add_parser("paper", help="recompute every result of the two papers (Markdown table)")
    paper.set_defaults(run=_paper)

    analyze = commands.add_parser("analyze", help="where do MCA1/2/3 converge? report with region maps")
    _robot_arguments(analyze, "TCP frame", "frame the twist is expressed in")
    analyze.add_argument("--arm", help="comma-separated arm joints (default: the automatic partition)")
    analyze.add_argument("--wrist", help="comma-separated wrist joints")
    analyze.add_argument("--linear", help="controlled linear axes, e.g. xy")
    analyze.add_argument("--angular", help="controlled angular axes, e.g. z")
    analyze.add_argument("--samples", type=count(1), default=100_000, help="configurations for the work-volume share")
    analyze.add_argument("--joints", nargs=2, metavar=("X", "Y"), help="the region map's two joints")
    analyze.add_argument("--points", type=count(2), default=121, help="region map grid points per joint (>= 2)")
    analyze.add_argument("--sweep", metavar="PARAM=LO:HI", help="sweep a parameter of a papers' robot")
    analyze.add_argument("--out", default="analysis", help="folder for report.md and the PNGs")
    analyze.add_argument("--workers", type=count(1), default=1, help="processes on this machine")
    analyze.add_argument("--scheduler", help="a Dask scheduler address (needs pinrate[dask])")
    analyze.add_argument("--seed", type=count(0), default=0, help="seed of the samples (>= 0)")
    analyze.set_defaults(run=_analyze)

    demo = commands.add_parser("demo", help="servo a robot from home to a target and summarise")
    _robot_arguments(
        demo,
        "TCP frame (default: the name table's, or the chain's end)",
        "frame the twist is expressed in (default: the tip)",
    )
    demo.add_argument("--algorithm", default="mca1", choices=ALGORITHMS)
    demo.add_argument(
        "--target",
        nargs=6,
        type=finite,
        metavar=("X", "Y", "Z", "R", "P", "Y"),
        help="target tip pose in the world: metres and roll-pitch-yaw radians",
    )
    demo.add_argument(
        "--q0",
        nargs="+",
        type=finite,
        metavar="Q",
        help="start configuration: one value per moving joint, rad or m (default: the robot's home)",
    )
    demo.add_argument("--seed", type=count(0), default=0, help="seed of the default random target (>= 0)")
    demo.add_argument("--dt", type=positive, default=0.01, help="control period in seconds")
    demo.add_argument("--gain", type=positive, default=1.0, help="twist per unit pose error (1/s)")
    demo.add_argument("--max-steps", type=count(0), default=DEMO_MAX_STEPS)
    demo.add_argument("--tol", type=positive, default=1e-4, help="convergence tolerance (m and rad)")
    demo.add_argument("--targets", type=count(1), default=1, help="number of random targets, one after the other")
    demo.add_argument("--speed", type=positive, default=1.0, help="playback speed in the viewer (x real time)")
    demo.add_argument("--open", action="store_true", help="open the viewer in the default browser")
    demo.add_argument("--record", metavar="HTML", help="write a standalone HTML replay of the whole run")
    demo.add_argument(
        "--host",
        default="127.0.0.1",
        help="address the Meshcat server listens on (default: this machine only; another one is warned about)",
    )
    demo.add_argument("--no-viewer", action="store_true", help="headless: print the summary only")
    demo.set_defaults(run=_demo)
    teleop.add_parser(commands, _robot_arguments)
    return parser


def run(argv: Sequence[str] | None = None) -> int:
    """Parse ``argv`` and run the command; a refused input is one line on stderr and 2.

    The process-level concerns (signals, interrupts, closed pipes) are :func:`.entry.main`'s.
    """
    try:
        args = build_parser().parse_args(argv)
    except SystemExit as finished:  # --help, or a usage error already printed on one line
        return finished.code if isinstance(finished.code, int) else 2
    logging.basicConfig(level=logging.INFO if args.verbose else logging.WARNING, format="pinrate: %(message)s")
    try:
        return int(args.run(args))
    except PinrateError as error:
        print(f"pinrate: error: {error}", file=sys.stderr)
        return 2
