"""``pinrate demo``: servo a robot from home (or ``--q0``) to one target or several, with the
Meshcat view or headless, and a summary of each run: ρ along the path, what it rests on, and
the coupling beside it (eq. 30, 49).

Importing this module loads numpy and Pinocchio: :func:`.entry.main` does so once the
arguments are parsed (meshcat only when a view is asked for).
"""

from __future__ import annotations

import argparse
import contextlib
import itertools
import os
import sys
import time
import warnings
from collections.abc import Iterator
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
import pinocchio as pin

from ..checks import check_output_file
from ..control.servo_loop import servo
from ..control.trajectory import Trajectory
from ..errors import InputError
from ..kinematics.manipulator import Robot
from ..kinematics.partition import Partition
from ..kinematics.targets import nearby_target
from ..plants import Plant
from ..solvers.error_map import THEOREM_ALGORITHMS
from ..theorem.pointwise import coupling_along
from .arguments import warn
from .robot_arguments import load_robot, make_plant, start_configuration

if TYPE_CHECKING:
    from ..viewer import Viewer


def _radius_range(trajectory: Trajectory) -> str:
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
    radius = _radius_range(trajectory)
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
        *plant_lines(trajectory),
    ]
    return "\n".join(lines)


def plant_lines(trajectory: Trajectory) -> list[str]:
    """What the plant did beside the commands (a run on a plant; none otherwise): the tip's
    tracking error, the joint rates' largest difference, the steps with a saturated actuator."""
    record = trajectory.plant
    if record is None or not trajectory.steps:
        return []
    tracking = record.tracking_error
    difference = np.abs(record.measured_rates - trajectory.joint_rates).max()
    saturated = int(record.saturated.any(axis=1).sum())
    return [
        f"plant      {record.name}",
        f"tracking   tip {tracking.max() * 1e3:.3g} mm at most, {np.sqrt(np.mean(tracking**2)) * 1e3:.3g} mm RMS "
        f"(measured against commanded, per step); joint rates differ by {difference:.3g} at most; "
        f"actuators saturated on {saturated} of {trajectory.steps} steps",
    ]


def _status_line(index: int, count: int, trajectory: Trajectory) -> str:
    """One console line per servo segment."""
    radius = _radius_range(trajectory)
    return (
        f"segment {index}/{count}  {trajectory.algorithm}  {trajectory.steps} steps  "
        f"{'converged' if trajectory.converged else 'NOT converged'}  "
        f"position {trajectory.position_error[-1]:.2e} m  orientation {trajectory.orientation_error[-1]:.2e} rad  "
        f"rho {radius}"
        + ("" if trajectory.plant is None else f"  tracking {trajectory.plant.tracking_error.max() * 1e3:.3g} mm")
        + ("" if trajectory.converged else f"  ({trajectory.reason})")
    )


DEFAULT_ALGORITHM = "mca1"
"""The demo's algorithm when ``--algorithm`` is not given: the paper's cheapest."""

FALLBACK_ALGORITHM = "exact"
"""Run from the same start when the default algorithm does not reach a target: MCA1
converges only where the Theorem's ρ stays below 1 along the path (Shoham & Koren), which a
robot nobody designed for it need not meet; both runs are reported, so the lesson is kept."""


def _segment(
    args: argparse.Namespace, robot: Robot, partition: Partition, q: np.ndarray, target: np.ndarray, plant: Plant | None
) -> list[Trajectory]:
    """The runs of one segment: the algorithm asked for, or the default and, when it does not
    converge, :data:`FALLBACK_ALGORITHM` from the same start (the last run is the one kept);
    on ``plant`` when one is given, with the URDF's velocity limits kept."""
    settings = {
        "partition": partition,
        "dt": args.dt,
        "gain": args.gain,
        "max_steps": args.max_steps,
        "tol": args.tol,
        "plant": plant,
    }
    if plant is not None:  # the drives saturate at the URDF's velocity limits: the controller keeps them
        settings["velocity_limits"] = None
    runs = [servo(robot, q, target, algorithm=args.algorithm or DEFAULT_ALGORITHM, **settings)]
    if args.algorithm is None and not runs[0].converged:
        runs.append(servo(robot, q, target, algorithm=FALLBACK_ALGORITHM, **settings))
    return runs


FRAMED_TARGETS = 20
"""The viewer's opening view frames the robot and at most this many of the first targets."""


def _targets(args: argparse.Namespace, robot: Robot, partition: Partition, start: np.ndarray) -> Iterator[np.ndarray]:
    """The targets, each drawn when its segment starts: ``--targets`` may be any count (the
    run then goes on until Ctrl-C), and the first segment starts at once."""
    if args.target is not None:
        x, y, z, roll, pitch, yaw = args.target
        yield pin.SE3(pin.rpy.rpyToMatrix(roll, pitch, yaw), np.array([x, y, z])).homogeneous
        return
    for k in range(args.targets):
        yield _servable_target(args, robot, partition, args.seed + k, start)


TARGET_DRAWS = 8
"""Draws per demo target: the first whose exact resolved-rate motion from the start reaches it
within the limits is taken, else the last."""


def _servable_target(
    args: argparse.Namespace, robot: Robot, partition: Partition, seed: int, start: np.ndarray
) -> np.ndarray:
    """A :func:`~pinrate.kinematics.targets.nearby_target` that a resolved-rate motion reaches:
    its configuration is within reach joint by joint, but the tip's way to it may pass where a
    joint meets its limit (a target across the first joint's axis asks that joint for half a
    turn). Each draw is tried by a dry run of the exact algorithm from the start (the motion
    the segment's algorithms approximate); the seeds of the draws are ``seed``, then ``seed``
    plus multiples of a large prime, so ``--seed`` stays reproducible."""
    target = start
    for draw in range(TARGET_DRAWS):
        target = nearby_target(robot, partition, seed + draw * 1_000_003, start=start)[1]
        dry_run = servo(robot, start, target, algorithm="exact", partition=partition, dt=args.dt, tol=args.tol)
        if dry_run.converged:
            break
    return target


def _record_file(path: str) -> Path:
    """``--record``, checked before the run: the checks of :func:`~pinrate.checks.check_output_file`,
    then the file is opened for writing (and removed again if this made it), so a place the
    system refuses (``/proc``, ``/sys``, a read-only mount) is refused now rather than after
    the whole run; an existing target must be a regular file. Returns the path."""
    target = check_output_file(path, "--record")
    existed = os.path.lexists(target)
    if existed and not target.is_file():  # the replay replaces a file whole: never a device or a FIFO
        raise InputError(f"--record {str(target)!r} exists and is not a regular file")
    flags = os.O_WRONLY | os.O_NONBLOCK | (0 if existed else os.O_CREAT | os.O_EXCL)  # never truncated here
    try:
        os.close(os.open(target, flags, 0o644))
    except OSError as error:
        raise InputError(f"--record {str(target)!r} cannot be written: {error.strerror or error}") from None
    if not existed:
        with contextlib.suppress(OSError):
            target.unlink()
    return target


def _save_record(viewer: Viewer, target: Path) -> None:
    """The replay written to ``--record``, whole or not at all (:func:`~pinrate.files.replace_file`:
    a write that fails, a full disk, leaves no partial file and is one error line)."""
    print(f"recorded   {viewer.save_html(target)} ({viewer.recorded_frames} frames)")


def demo(args: argparse.Namespace) -> int:
    """``pinrate demo``: 0 when every target was reached, 1 otherwise."""
    record = None
    if args.record is not None:  # '' too: check_output_file refuses it by name
        if args.no_viewer:
            raise InputError("--record writes the viewer's replay: drop --no-viewer")
        record = _record_file(args.record)
    plot = None
    if args.plot is not None:
        if args.plant == "kinematic":
            raise InputError("--plot draws the measured joint rates of a plant: add --plant mujoco")
        plot = check_output_file(args.plot, "--plot")
    robot = load_robot(args)
    plant = make_plant(robot, args)
    partition = Partition.auto(robot)
    start = robot.home() if args.q0 is None else start_configuration(robot, args.q0)
    count = 1 if args.target is not None else args.targets
    targets = _targets(args, robot, partition, start)
    viewer = None
    if not args.no_viewer:
        from ..viewer import Viewer  # meshcat is imported only when a view is asked for

        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always", UserWarning)
            # frames are kept only for --record: a long demo's memory stays flat without it
            viewer = Viewer(robot, host=args.host, open_browser=args.open, record=record is not None)
        for warning in caught:
            warn(str(warning.message))
        print(f"Meshcat viewer: {viewer.url}", flush=True)
    try:
        q = start
        if viewer is not None:
            framed = list(itertools.islice(targets, FRAMED_TARGETS))
            viewer.frame(q, np.array([target[:3, 3] for target in framed]))
            viewer.show(q)
            targets = itertools.chain(framed, targets)
        all_converged = True
        for index, target in enumerate(targets, start=1):
            runs = _segment(args, robot, partition, q, target, plant)
            trajectory = runs[-1]
            position, rpy = target[:3, 3], pin.rpy.matrixToRpy(target[:3, :3])
            print(
                f"target     xyz {np.array2string(position, precision=4)} m   "
                f"rpy {np.array2string(rpy, precision=4)} rad (world)"
            )
            if index == 1 and not (count == 1 and viewer is None):
                print("partition  " + partition.describe(robot).replace("\n", "\n           "))
            for number, run in enumerate(runs):
                if number:
                    print(
                        f"fallback   {runs[0].algorithm} did not reach it: {FALLBACK_ALGORITHM} from the same start "
                        "(--algorithm chooses one and keeps to it)"
                    )
                print(
                    summary(robot, run) if count == 1 and viewer is None else _status_line(index, count, run),
                    flush=True,
                )
            if viewer is not None:
                viewer.play(trajectory, target=target, speed=args.speed)
            all_converged &= trajectory.converged
            q = trajectory.q[-1]
            if plot is not None:
                from ..analysis.plots import plant_tracking_png  # matplotlib only for a plot

                path = plot if count == 1 else plot.with_name(f"{plot.stem}-{index}{plot.suffix}")
                print(f"plot       {plant_tracking_png(trajectory, robot.joint_names, path)} (segment {index})")
        if viewer is not None:
            if record is not None:
                _save_record(viewer, record)
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
