"""``pinrate teleop ROBOT_OR_URDF``: Barker's operator console in the browser (keyboard or
gamepad drive the hand; :mod:`pinrate.teleop.server`). Its arguments are :mod:`.parser`'s."""

from __future__ import annotations

import argparse
import contextlib
import warnings
import webbrowser

from ..errors import InputError
from ..teleop import Teleop
from .arguments import warn
from .outputs import output_folder
from .robot_arguments import load_robot, make_plant, start_configuration

MAX_RATE = 5000.0
"""Hz: the fastest control loop the console accepts (a step costs 40-60 µs in Python)."""


def run(args: argparse.Namespace) -> int:
    """``pinrate teleop``: serve the console until Ctrl-C; the recorded runs are listed at the end."""
    if args.rate > MAX_RATE:
        raise InputError(f"--rate must be at most {MAX_RATE:g} Hz, got {args.rate:g}")
    if args.port > 65535:
        raise InputError(f"--port must be at most 65535, got {args.port}")
    # Made before the robot loads, and removed again if the command is refused before it serves.
    with output_folder(args.record_dir, "record folder"):
        return _serve(args)


def _serve(args: argparse.Namespace) -> int:
    from ..teleop.server import TeleopServer, check_host  # meshcat and tornado only for a console

    with warnings.catch_warnings():  # the server warns about a shared address, once
        warnings.simplefilter("ignore", UserWarning)
        check_host(args.host)
    robot = load_robot(args)
    q0 = None if args.q0 is None else start_configuration(robot, args.q0)
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
        plant=make_plant(robot, args),
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
        print(f"loop       {server.scheduling}")
        print("keys       W/S A/D E/Q: +-x +-y +-z   I/K J/L O/U: about +-x +-y +-z   Space: halt   B: reverse")
        # From the moment the URL is out, Ctrl-C is the documented way to leave the console.
        with contextlib.suppress(KeyboardInterrupt):
            print(f"console    {server.url}   (Ctrl-C to quit)", flush=True)
            if args.open:
                webbrowser.open(server.url, new=2)
            server.wait()
        return 0
    finally:
        server.close()
        for path in server.saved:
            print(f"saved      {path}")
