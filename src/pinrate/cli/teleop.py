"""``pinrate teleop ROBOT_OR_URDF``: Barker's operator console in the browser (keyboard or
gamepad drive the hand; :mod:`pinrate.teleop.server`)."""

from __future__ import annotations

import argparse
import contextlib
import warnings
import webbrowser

from ..checks import check_output_folder
from ..control.singularity import STRATEGIES, WRIST_STRATEGIES
from ..errors import InputError
from ..solvers.registry import ALGORITHMS
from ..teleop import FRAMES, Teleop
from .arguments import count, positive, warn

MAX_RATE = 5000.0
"""Hz: the fastest control loop the console accepts (a step costs 40-60 µs in Python)."""


def add_parser(commands: argparse._SubParsersAction, robot_arguments) -> None:  # type: ignore[type-arg]
    teleop = commands.add_parser(
        "teleop", help="drive the hand from the browser: keyboard or gamepad, hand or base axes"
    )
    robot_arguments(
        teleop,
        "TCP frame (default: the name table's, or the chain's end)",
        "frame the commands are expressed in: the hand axes (default: the tip)",
    )
    teleop.add_argument("--algorithm", default="exact", choices=ALGORITHMS)
    teleop.add_argument("--singularity", default="decelerate", choices=STRATEGIES, help="near a singular block")
    teleop.add_argument("--wrist", default="split", choices=WRIST_STRATEGIES, help="two wrist axes aligned")
    teleop.add_argument("--frame", default="hand", choices=FRAMES, help="axes of the commands (switchable on the page)")
    teleop.add_argument("--rate", type=positive, default=500.0, help="control loop rate in Hz (default 500)")
    teleop.add_argument(
        "--timeout", type=positive, default=0.25, help="dead man: seconds without input before the command is zero"
    )
    teleop.add_argument("--max-linear-speed", type=positive, default=0.1, help="m/s at full deflection")
    teleop.add_argument("--max-angular-speed", type=positive, default=0.5, help="rad/s at full deflection")
    teleop.add_argument("--collision", action="store_true", help="monitor self-collision (the URDF's collision meshes)")
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
    teleop.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    from ..teleop.server import TeleopServer, check_host  # meshcat and tornado only for a console
    from .commands import _load, _start  # the shared robot loading and --q0 of the demo

    if args.rate > MAX_RATE:
        raise InputError(f"--rate must be at most {MAX_RATE:g} Hz, got {args.rate:g}")
    if args.port > 65535:
        raise InputError(f"--port must be at most 65535, got {args.port}")
    check_output_folder(args.record_dir, "record folder")  # refused before the robot loads
    with warnings.catch_warnings():  # the server warns about a shared address, once
        warnings.simplefilter("ignore", UserWarning)
        check_host(args.host)
    robot = _load(args)
    q0 = None if args.q0 is None else _start(robot, args.q0)
    teleop = Teleop(
        robot,
        q0,
        max_linear_speed=args.max_linear_speed,
        max_angular_speed=args.max_angular_speed,
        timeout=args.timeout,
        frame=args.frame,
        algorithm=args.algorithm,
        singularity=args.singularity,
        wrist=args.wrist,
        dt=1.0 / args.rate,
        collision=args.collision,
    )
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", UserWarning)
        server = TeleopServer(teleop, host=args.host, port=args.port, record_dir=args.record_dir)
    for warning in caught:
        warn(str(warning.message))
    try:
        print(f"partition  {teleop.controller.partition.describe(robot)}".replace("\n", "\n           "))
        print(
            f"teleop     {robot.name}: {args.rate:g} Hz, {teleop.controller.algorithm}, "
            f"singularity {args.singularity}, wrist {args.wrist}, dead man {args.timeout:g} s"
        )
        print("keys       W/S A/D E/Q: +-x +-y +-z   I/K J/L O/U: about +-x +-y +-z   Space: halt   B: reverse")
        print(f"console    {server.url}   (Ctrl-C to quit)", flush=True)
        if args.open:
            webbrowser.open(server.url, new=2)
        with contextlib.suppress(KeyboardInterrupt):  # the documented way to leave the console
            server.wait()
        return 0
    finally:
        server.close()
        for path in server.saved:
            print(f"saved      {path}")
