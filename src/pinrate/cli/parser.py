"""The command line's parser: every subcommand's arguments, their choices and help.

Parsing imports nothing heavy: ``pinrate --help``, ``pinrate demo --help`` and a refused
argument answer before numpy, Pinocchio or matplotlib load (issue 20); each subcommand's
module (:mod:`.robot_list`, :mod:`.demo`, :mod:`.analyze`, :mod:`.paper_results`,
:mod:`~pinrate.cli.teleop`) is imported by :func:`.entry.main` once the arguments are parsed. So the
choices the parser offers are copies of the tuples that define them in the lower layers,
which import numpy; the CLI's tests check every copy against its source.
"""

from __future__ import annotations

import argparse
from collections.abc import Callable

from .arguments import Parser, count, finite, positive, within, xacro_argument

ALGORITHMS = ("exact", "schur", "mca1", "mca2", "mca3", "dls")
"""A copy of :data:`pinrate.solvers.registry.ALGORITHMS`."""

STRATEGIES = ("decelerate", "generalized_inverse", "freeze", "auxiliary_elbow", "adaptive_dls")
"""A copy of :data:`pinrate.control.singularity.STRATEGIES`."""

WRIST_STRATEGIES = ("turn", "split", "hold_first", "last_then_first")
"""A copy of :data:`pinrate.control.singularity.WRIST_STRATEGIES`."""

FRAMES = ("hand", "base")
"""A copy of :data:`pinrate.teleop.session.FRAMES`."""

PLANTS = ("kinematic", "mujoco")
"""``--plant``: the joints follow the rates exactly, or a MuJoCo simulation (:mod:`pinrate.plants`)."""

ACTUATORS = ("velocity", "position")
"""A copy of :data:`pinrate.plants.mujoco_plant.ACTUATORS`."""

MAX_JOINTS = 100
"""A copy of :data:`pinrate.kinematics.urdf_structure.MAX_JOINTS` (for the help text only)."""

MAX_STEPS = 1_000_000
"""A copy of :data:`pinrate.control.servo_loop.MAX_STEPS` (``demo --max-steps``' bound)."""

SPEEDS = (1e-3, 1e3)
"""The viewer's playback speeds ``demo --speed`` accepts (× real time): a segment's frames are
slept through at this rate, and 1e-300 would ask for a sleep no clock can count."""

DEMO_MAX_STEPS = 6000
"""The demo's step budget (60 s at dt = 0.01): MCA1 with ρ near 0.8 (TIAGo's arm) needs about
30 s to bring the rotation error under 1e-4 rad; a target it cannot reach stops earlier, as
"stalled" (servo's stall rule)."""


def add_robot_arguments(parser: argparse.ArgumentParser, tip_help: str, sensor_help: str) -> None:
    """The robot and its frames, shared by ``analyze``, ``demo`` and ``teleop`` (loaded by
    :func:`.robot_arguments.load_robot`)."""
    parser.add_argument(
        "robot", help="a name from `pinrate list`, a URDF path or a .xacro path (expanded; needs pinrate[xacro])"
    )
    parser.add_argument("--tip", help=tip_help)
    parser.add_argument("--sensor", help=sensor_help)
    parser.add_argument(
        "--max-joints",
        type=count(1),
        help=f"refuse URDFs with more moving joints (default {MAX_JOINTS}, or $PINRATE_MAX_JOINTS)",
    )
    parser.add_argument(
        "--xacro-arg",
        action="append",
        type=xacro_argument,
        default=[],
        metavar="NAME:=VALUE",
        help="a .xacro file's xacro:arg, e.g. ur_type:=ur10e (repeatable; the last value of a name wins)",
    )


class _Version(argparse.Action):
    """``--version``: prints what ``text()`` returns (pinrate's version and the path its
    loops take), then exits."""

    def __init__(self, option_strings: list[str], dest: str, text: Callable[[], str]) -> None:
        super().__init__(option_strings, dest, nargs=0, help="print the version and the backend, then exit")
        self.text = text

    def __call__(self, parser: argparse.ArgumentParser, *_: object) -> None:
        print(self.text())
        parser.exit()


def build_parser(version: Callable[[], str]) -> argparse.ArgumentParser:
    """The ``pinrate`` parser; ``args.command`` names the subcommand. ``version`` gives
    ``--version``'s text (called only for ``--version``: it may import what it needs)."""
    parser = Parser(prog="pinrate", description="Resolved-rate motion control for URDF arms.")
    parser.add_argument("-v", "--verbose", action="store_true", help="log what pinrate chooses")
    parser.add_argument("--version", action=_Version, text=version)
    commands = parser.add_subparsers(dest="command", required=True, parser_class=Parser)
    commands.add_parser("list", help="print every robot name pinrate can load")
    commands.add_parser("paper", help="recompute every result of the two papers (Markdown table)")
    _analyze(commands.add_parser("analyze", help="where do MCA1/2/3 converge? report with region maps"))
    _demo(commands.add_parser("demo", help="servo a robot from home to a target and summarise"))
    _teleop(
        commands.add_parser("teleop", help="drive the hand from the browser: keyboard or gamepad, hand or base axes")
    )
    return parser


def _analyze(analyze: argparse.ArgumentParser) -> None:
    add_robot_arguments(analyze, "TCP frame", "frame the twist is expressed in")
    analyze.add_argument("--arm", help="comma-separated arm joints (default: the automatic partition)")
    analyze.add_argument("--wrist", help="comma-separated wrist joints")
    analyze.add_argument("--linear", help="controlled linear axes, e.g. xy")
    analyze.add_argument("--angular", help="controlled angular axes, e.g. z")
    analyze.add_argument("--samples", type=count(1), default=100_000, help="configurations for the work-volume share")
    analyze.add_argument("--joints", nargs=2, metavar=("X", "Y"), help="the region map's two joints")
    analyze.add_argument("--points", type=count(2), default=121, help="region map grid points per joint (>= 2)")
    analyze.add_argument("--sweep", metavar="PARAM=LO:HI", help="sweep a parameter of a papers' robot")
    analyze.add_argument("--out", default="analysis", help="folder for report.md and the PNGs")
    analyze.add_argument(
        "--workers", type=count(1), default=1, help="threads of the compiled core (else processes) on this machine"
    )
    analyze.add_argument("--scheduler", help="a Dask scheduler address (needs pinrate[dask])")
    analyze.add_argument("--seed", type=count(0), default=0, help="seed of the samples (>= 0)")


def _demo(demo: argparse.ArgumentParser) -> None:
    add_robot_arguments(
        demo,
        "TCP frame (default: the name table's, or the chain's end)",
        "frame the twist is expressed in (default: the tip)",
    )
    demo.add_argument(
        "--algorithm",
        choices=ALGORITHMS,
        help="default: mca1, and for a target it does not reach (the Theorem's rho >= 1 on the way) "
        "exact from the same start, both runs reported",
    )
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
    demo.add_argument(
        "--max-steps",
        type=count(0, MAX_STEPS),
        default=DEMO_MAX_STEPS,
        help=f"the step budget of each segment (at most {MAX_STEPS:,}: a run records every step)",
    )
    demo.add_argument("--tol", type=positive, default=1e-4, help="convergence tolerance (m and rad)")
    demo.add_argument("--targets", type=count(1), default=1, help="number of random targets, one after the other")
    demo.add_argument(
        "--speed",
        type=within(*SPEEDS),
        default=1.0,
        help=f"playback speed in the viewer (x real time, {SPEEDS[0]:g} to {SPEEDS[1]:g})",
    )
    demo.add_argument("--open", action="store_true", help="open the viewer in the default browser")
    demo.add_argument("--record", metavar="HTML", help="write a standalone HTML replay of the whole run")
    demo.add_argument(
        "--host",
        default="127.0.0.1",
        help="address the Meshcat server listens on (default: this machine only; another one is warned about)",
    )
    demo.add_argument("--no-viewer", action="store_true", help="headless: print the summary only")
    add_plant_arguments(demo)
    demo.add_argument(
        "--plot", metavar="PNG", help="with --plant mujoco: the commanded and measured joint rates of the run, as a PNG"
    )


def add_plant_arguments(parser: argparse.ArgumentParser) -> None:
    """``--plant`` and ``--actuator``: what the controller drives (demo and teleop)."""
    parser.add_argument(
        "--plant",
        default="kinematic",
        choices=PLANTS,
        help="what the controller drives: the kinematic robot (default) or a MuJoCo simulation of it "
        '(pip install "pinrate[mujoco]"), read back each step',
    )
    parser.add_argument(
        "--actuator", default="velocity", choices=ACTUATORS, help="the MuJoCo plant's joint servos (default velocity)"
    )
    parser.add_argument(
        "--missing-mass",
        type=positive,
        metavar="KG",
        help="the MuJoCo plant's mass for each moving link the URDF gives none (a 5 cm sphere at its joint)",
    )


def _teleop(teleop: argparse.ArgumentParser) -> None:
    add_robot_arguments(
        teleop,
        "TCP frame (default: the name table's, or the chain's end)",
        "frame the commands are expressed in: the hand axes (default: the tip)",
    )
    teleop.add_argument("--algorithm", default="exact", choices=ALGORITHMS)
    teleop.add_argument("--singularity", default="decelerate", choices=STRATEGIES, help="near a singular block")
    teleop.add_argument("--wrist", default="turn", choices=WRIST_STRATEGIES, help="two wrist axes aligned")
    teleop.add_argument("--frame", default="hand", choices=FRAMES, help="axes of the commands (switchable on the page)")
    teleop.add_argument("--rate", type=positive, default=500.0, help="control loop rate in Hz (default 500)")
    teleop.add_argument(
        "--timeout", type=positive, default=0.25, help="dead man: seconds without input before the command is zero"
    )
    teleop.add_argument("--max-linear-speed", type=positive, default=0.1, help="m/s at full deflection")
    teleop.add_argument("--max-angular-speed", type=positive, default=0.5, help="rad/s at full deflection")
    teleop.add_argument("--collision", action="store_true", help="monitor self-collision (the URDF's collision meshes)")
    add_plant_arguments(teleop)
    teleop.add_argument(
        "--q0", nargs="+", type=float, metavar="Q", help="start configuration: one value per moving joint"
    )
    teleop.add_argument(
        "--host",
        default="127.0.0.1",
        help="address the console listens on (default: this machine only; another one is warned about)",
    )
    teleop.add_argument("--port", type=count(0), default=0, help="TCP port (default: a free one)")
    teleop.add_argument("--record-dir", default=".", help="folder for recorded runs (.npz and .html)")
    teleop.add_argument("--open", action="store_true", help="open the console in the default browser")
