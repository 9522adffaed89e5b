"""Barker's operator at the console: a twist from two 3-axis controllers, one controller step
per tick, a dead man, and the way back (Barker 1983, "resolved-rate control by an operator";
"recording and reversing a motion")::

    teleop = Teleop(robot)                        # q0: robot.home()
    teleop.command([1, 0, 0], [0, 0, 0])          # full deflection along the hand's x axis
    for _ in range(100):
        step = teleop.tick()                      # one Controller.step of dt from teleop.q
    teleop.reverse()                              # retrace the motion back to where it began

Three kinds of command are held (Barker's modes): the hand's twist (:meth:`Teleop.command`,
the default), his uncoupled arm/wrist mode (``command(..., mode="uncoupled")``: the linear
deflections move the wrist centre with the arm joints, each angular one jogs one wrist
joint) and individual joints (:meth:`Teleop.jog`). The dead man ages each alike.

Commands are stick deflections in [-1, 1], scaled by ``max_linear_speed`` (m/s) and
``max_angular_speed`` (rad/s), in the robot's sensor frame's axes (Barker's hand frame when
the sensor is the tip, the default) or, with ``frame="base"``, in the world frame's axes,
turned into the sensor's at each tick. The same speeds bound the commanded twist (the
controller's saturation), so the hand never moves faster than them.

The record of the way back (:mod:`.way_back`) holds only motion: each tick that moves the
robot advances a motion clock by dt, idle ticks do not, so :meth:`Teleop.reverse` retraces
the last ``history`` seconds of motion, not of waiting. :meth:`Teleop.mark` starts a new
segment (the reversal then stops there). A run recorded for saving (:meth:`Teleop.start_recording`) keeps
every tick with its wall time, rates and status (:class:`~.recording.Recording`).

Only the motion calls (:meth:`~Teleop.command`, :meth:`~Teleop.reverse`, :meth:`~Teleop.stop`,
:meth:`~Teleop.halt`, :meth:`~Teleop.reset`) change the motion. A reversal runs until it is
back at its segment's start, a fresh non-zero command arrives, or stop, halt or reset ends
it; whatever ends it, the record then ends where the robot is, so a later reversal goes on
from there. Bookkeeping calls made meanwhile do not stop it: :meth:`~Teleop.mark` (and
:meth:`~Teleop.start_recording`, which marks) takes effect when it ends, so the new segment
starts where the reversal ended; :meth:`~Teleop.configure` lets it go on through the new
controller; :meth:`~Teleop.reverse` lets it go on. The public calls may come in any order:
an invalid argument or call raises the :class:`~pinrate.errors.InputError` its method
documents and changes nothing, and nothing else raises.
"""

from __future__ import annotations

from collections.abc import Mapping
from types import MappingProxyType
from typing import Any

import numpy as np

from ..checks import check_positive
from ..control.commands import JointJog
from ..control.controller import Controller, Step
from ..control.measured import onto_limits
from ..errors import InputError, choices_hint
from ..kinematics.manipulator import Robot, check_robot
from ..plants import Measurement, Plant
from .held import STILL, Held, check_time, deflection
from .recording import Recording
from .way_back import WayBack

FRAMES = ("hand", "base")
"""The values of ``Teleop(frame=...)``: the sensor frame's axes or the world's."""

MODES = ("twist", "uncoupled")
"""The values of ``Teleop.command(mode=...)``: the hand's twist, or Barker's uncoupled
arm/wrist mode (:class:`~pinrate.control.commands.Uncoupled`)."""


class Teleop:
    """The operator's loop on a :class:`~pinrate.control.Controller` (contract v2).

    Args:
        robot: the robot driven; its sensor frame fixes the hand axes.
        q0: the start configuration (nq,); None means ``robot.home()``.
        max_linear_speed: m/s at full deflection; also the controller's TCP speed limit.
        max_angular_speed: rad/s at full deflection; also the controller's limit.
        timeout: s; a command older than this at a tick counts as zero (the dead man).
        history: s of motion kept for :meth:`reverse`.
        frame: ``"hand"`` (the sensor frame's axes, Barker) or ``"base"`` (the world's).
        plant: a :class:`~pinrate.plants.Plant` of ``robot`` that each tick drives for dt:
            :attr:`q` is then what it measured (:mod:`pinrate.control.measured`); None
            (default): each step's own q.
        **controller_options: keyword options of :class:`Controller` (default algorithm
            ``"exact"``).

    Attributes:
        q: the current configuration (nq,).
        measurement: the plant's last :class:`~pinrate.plants.Measurement` (None without a plant).
        last: the last tick's :class:`Step` (None before the first).
        halted: True after :meth:`halt` until :meth:`resume`: ticks command nothing and
            :meth:`reverse` is refused (a halted robot does not move).
        dead_man: why the dead man last stopped the robot, in words ("no input for 0.25 s";
            see :meth:`dead_man_stop`), or "" when it has not since the operator last drove,
            stopped, halted, resumed, reversed or went home. Latched, so that a page that
            went silent sees why the robot stopped once it speaks again.
        plant_fault: why the plant halted the console ("" when it has not), until :meth:`resume`.
    """

    def __init__(
        self,
        robot: Robot,
        q0: object = None,
        *,
        max_linear_speed: float = 0.1,
        max_angular_speed: float = 0.5,
        timeout: float = 0.25,
        history: float = 30.0,
        frame: str = "hand",
        plant: Plant | None = None,
        **controller_options: object,
    ) -> None:
        self.robot = check_robot(robot)
        self.max_linear_speed = check_positive(max_linear_speed, "max_linear_speed")
        self.max_angular_speed = check_positive(max_angular_speed, "max_angular_speed")
        self.timeout = check_positive(timeout, "timeout")
        self.frame = frame
        options = {"algorithm": "exact", **controller_options}
        for name in ("max_linear_speed", "max_angular_speed"):
            if name in options:
                raise InputError(f"{name} is Teleop's own argument, not a controller option")
        self._options = options
        self.controller = self._controller(options)
        self.q = robot.home() if q0 is None else robot.check_q(q0)
        self.controller.check_inside_limits(self.q)
        if plant is not None and (not isinstance(plant, Plant) or plant.robot is not robot):
            raise InputError("plant must be a pinrate.plants.Plant built on this robot")
        self.plant = plant
        self.measurement: Measurement | None = None if plant is None else plant.reset(self.q)
        self._way_back = WayBack(history)
        self.recorder = self._way_back.recorder
        """The motion kept for :meth:`reverse` (times on the motion clock, s)."""
        self.last: Step | None = None
        self.halted = False
        self.dead_man = ""
        self.plant_fault = ""
        self._command = STILL
        self._recording: Recording | None = None

    # ------------------------------------------------------------------ configuration
    @property
    def frame(self) -> str:
        """The axes of the commands: ``"hand"`` (sensor frame) or ``"base"`` (world frame)."""
        return self._frame

    @frame.setter
    def frame(self, value: str) -> None:
        if value not in FRAMES:
            raise InputError(f"frame must be one of {', '.join(FRAMES)}, not {value!r}")
        self._frame = value

    @property
    def options(self) -> dict[str, object]:
        """The controller's keyword options (a copy)."""
        return dict(self._options)

    def _controller(self, options: dict[str, Any]) -> Controller:
        return Controller(
            self.robot, max_linear_speed=self.max_linear_speed, max_angular_speed=self.max_angular_speed, **options
        )

    def configure(self, **controller_options: object) -> None:
        """A new controller with these options changed (``singularity="freeze"``, …); q, the
        record and the command are kept, and a reversal goes on through the new controller
        (its limits apply from the next tick). Bad options raise InputError and change
        nothing."""
        options = {**self._options, **controller_options}
        self.controller, self._options = (controller := self._controller(options)), options
        if self._way_back.playback is not None:
            self._way_back.playback.controller = controller

    # ------------------------------------------------------------------ the operator
    def command(self, linear: object, angular: object, now: object = None, *, mode: str = "twist") -> None:
        """Hold the stick deflections ``linear`` and ``angular`` (3 each, clipped to [-1, 1])
        from ``now`` (s, default ``time.monotonic()``) until the next call; axes as
        :attr:`frame` says. A non-zero command ends a reversal.

        ``mode="twist"`` (Barker's coupled mode): the hand's twist, ``linear`` x
        ``max_linear_speed`` (m/s) and ``angular`` x ``max_angular_speed`` (rad/s).
        ``mode="uncoupled"`` (Barker's uncoupled mode,
        :class:`~pinrate.control.commands.Uncoupled`): ``linear`` x ``max_linear_speed`` is
        the wrist centre's velocity (m/s, the same axes), served by the arm joints alone; each
        angular deflection jogs one wrist joint of the partition, in order (x: the first, y:
        the second, z: the third), at deflection x ``max_angular_speed`` (rad/s; deflections
        beyond the wrist's joints are ignored), the other wrist joints holding still.
        InputError for another mode, or for the uncoupled mode on a partition without
        linear components."""
        linear_deflection = deflection(linear, "linear")
        angular_deflection = deflection(angular, "angular")
        stamp = check_time(now)
        if mode not in MODES:
            raise InputError(f"mode must be one of {', '.join(MODES)}, not {mode!r}")
        if mode == "uncoupled" and not self.controller.index.m:
            raise InputError("the uncoupled mode moves the wrist centre: this partition controls no linear component")
        held = Held(linear_deflection * self.max_linear_speed, angular_deflection * self.max_angular_speed, stamp, mode)
        self._command = held
        if held.moves:
            self.dead_man = ""  # the operator drives again

    def jog(self, rates: Mapping[str, float], now: object = None) -> None:
        """Hold a joint jog (:class:`~pinrate.control.commands.JointJog`, Barker's individual
        joint control) from ``now`` (s, default ``time.monotonic()``) until the next command:
        ``rates`` maps joint names to rad/s (revolute) or m/s (prismatic), every joint not
        named holds still. Any 1-DOF joint may be jogged, in or out of the partition; the
        position and velocity limits apply as to every step, the dead man as to every
        command. A non-zero jog ends a reversal. InputError (nothing changes) for a name that
        is not a joint that can be jogged (the message lists them) or a rate that is not a
        finite number."""
        jog = JointJog(rates)
        stamp = check_time(now)
        joggable = self.controller.joggable
        for name in jog.rates:
            if name not in joggable:
                raise InputError(f"jog: {name!r} is not a joint that can be jogged." + choices_hint(name, joggable))
        held = Held(np.zeros(3), np.zeros(3), stamp, "jog", MappingProxyType(dict(jog.rates)))
        self._command = held
        if held.moves:
            self.dead_man = ""

    def stop(self) -> None:
        """Zero the command and end a reversal (the robot stops at the next tick); the record
        then ends where the robot is, and a :meth:`mark` made during the reversal applies."""
        self._command = STILL
        self.dead_man = ""
        self._way_back.end(self.q)

    def dead_man_stop(self, reason: str) -> bool:
        """:meth:`stop` because the operator's input stopped (the console's page is gone,
        silent or frozen), and say so: :attr:`dead_man` becomes ``reason`` when something was
        stopped (a non-zero command held, fresh or expired, or a reversal). True then; False
        otherwise (the robot was still: what :attr:`dead_man` said stays)."""
        stopped = self._command.moves or self.reversing
        said = self.dead_man
        self.stop()
        self.dead_man = str(reason) if stopped else said
        return stopped

    def halt(self) -> None:
        """:meth:`stop`, and ignore commands until :meth:`resume` (:meth:`reverse` too)."""
        self.stop()
        self.halted = True

    def resume(self) -> None:
        """Accept commands again after :meth:`halt`."""
        self.halted = False
        self.dead_man = ""
        self.plant_fault = ""

    def reset(self, q: object = None) -> None:
        """Back to ``q`` (default ``robot.home()``) at once: command, record and reversal
        cleared, the controller's memory too (:meth:`Controller.reset`); a new segment starts
        at ``q``. The halt and a recording in progress are kept. InputError for a bad ``q``,
        one outside the position limits the controller keeps among them (nothing changes then)."""
        start = self.robot.home() if q is None else self.robot.check_q(q)
        self.controller.check_inside_limits(start)
        self.stop()
        self.q = start
        if self.plant is not None:
            self.measurement = self.plant.reset(start)
        self._way_back.clear()
        self.controller.reset()
        self.last = None

    def mark(self) -> None:
        """Start a new segment here: a later :meth:`reverse` stops at this configuration.

        During a reversal the mark waits for the reversal's end, and the robot keeps
        retracing (a mark is bookkeeping, not a motion command: it neither stops the robot
        nor forgets the way back it is taking). The new segment then starts where the
        reversal ended: at the old segment's start when it ran to completion, where the robot
        was when a command or :meth:`stop` ended it.
        """
        self._way_back.mark()

    @property
    def reversing(self) -> bool:
        """True while a reversal retraces the record."""
        return self._way_back.playback is not None

    def reverse(self, now: object = None) -> bool:
        """From the next tick on, retrace the recorded motion (the last ``history`` seconds
        of it, or back to the last :meth:`mark`) backwards at the recorded pace, through the
        controller's step (every limit applies), until its start or until a non-zero
        command dated after ``now`` arrives. The held command is dropped. False (and
        nothing changes) when there is no motion to retrace. During a reversal it goes on
        (True), only commands dated after this ``now`` end it. InputError for a bad ``now``,
        and while :attr:`halted` ("halted: resume first": a halted robot does not move; nothing
        changes)."""
        stamp = check_time(now)
        if self.halted:
            raise InputError("halted: resume first")
        way_back = self._way_back
        if way_back.playback is not None:
            self._command = STILL
            way_back.reversed_at = stamp
            return True
        if len(self.recorder) < 2:
            return False
        self._command = STILL
        way_back.playback = self.recorder.playback(self.controller)
        way_back.reversed_at = stamp
        self.dead_man = ""
        return True

    # ------------------------------------------------------------------ the loop
    def current_command(self, now: object = None) -> tuple[np.ndarray, np.ndarray]:
        """(linear, angular) in m/s and rad/s, :attr:`frame` axes, that a tick at ``now``
        would command: zero when older than ``timeout`` or while halted (and for a jog; in
        the uncoupled mode, the wrist centre's velocity and the wrist joints' rates)."""
        held = self._live(check_time(now))
        if held.mode == "jog":
            return np.zeros(3), np.zeros(3)
        return held.linear, held.angular

    def _live(self, stamp: float) -> Held:
        """The command a tick at ``stamp`` serves: the held one, or none (still) when it is
        older than ``timeout`` or while halted."""
        held = self._command
        if self.halted or stamp - held.stamp > self.timeout:
            return STILL
        return held

    def tick(self, now: object = None) -> Step:
        """One controller step of dt from :attr:`q` with the current command (a reversal's
        step while one runs); :attr:`q` becomes the step's. ``now``: s, default
        ``time.monotonic()``; it ages the command (dead man), it does not set the step's dt,
        and it is the tick's time in a recording. A fresh non-zero command dated after the
        reversal's ``now`` ends a reversal before the step; so does reaching the segment's
        start after it. A non-zero command older than ``timeout`` counts as zero and sets
        :attr:`dead_man`. InputError for a bad ``now`` (nothing changes then)."""
        stamp = check_time(now)
        held = self._live(stamp)
        commanded = held.moves
        way_back = self._way_back
        expired = not (commanded or self.halted or self.dead_man) and way_back.playback is None
        if expired and self._command.moves:
            self.dead_man = f"no input for {self.timeout:g} s"  # a non-zero command expired: the dead man
        if way_back.playback is not None and commanded and held.stamp > way_back.reversed_at:
            way_back.end(self.q)
        if way_back.playback is not None:
            step = way_back.step(self.q)
            self._move(step)
        else:
            step = self._operator_step(held)
        self.last = step
        if self._recording is not None:  # what the plant measured, when there is one
            self._recording.add(stamp, step, None if self.measurement is None else self.measurement.q)
        return step

    def _operator_step(self, held: Held) -> Step:
        """One controller step of the held command (a twist, an uncoupled command, a jog)."""
        controller = self.controller
        observation = controller.observe_unchecked(self.q)
        command = held.command(controller, observation, self._frame, self.max_linear_speed)
        step = controller.step(self.q, command, observation=observation)
        before = self.q
        self._move(step)
        if step.joint_rates.any():
            self._way_back.record(before, self.q, controller.dt)
        return step

    def _move(self, step: Step) -> None:
        """:attr:`q` after ``step``: its own, or the plant's measurement after dt (a joint past a
        limit by more than the plant's tolerance: put on it, a halt, :attr:`plant_fault`)."""
        if self.plant is None:
            self.q = step.q
            return
        self.measurement = self.plant.advance(step.joint_rates, self.controller.dt)
        self.q, beyond = onto_limits(self.controller, self.measurement.q, self.plant.limit_tolerance, clip=True)
        if beyond:
            self.halt()
            self.plant_fault = f"the plant went past a position limit: {beyond}"

    # ------------------------------------------------------------------ a run for saving
    @property
    def recording(self) -> bool:
        """True between :meth:`start_recording` and :meth:`stop_recording`."""
        return self._recording is not None

    def start_recording(self, max_samples: int = 2_000_000) -> None:
        """Keep every tick from now on (at most ``max_samples``: the oldest go first), the
        recording's start being :attr:`q` now; also :meth:`mark` a new segment. During a
        reversal the robot keeps retracing and the recording keeps its ticks; the mark
        applies when the reversal ends (see :meth:`mark`). InputError (and nothing changes)
        when already recording, so that a run is never dropped unsaved, or for a bad
        ``max_samples``."""
        if self._recording is not None:
            raise InputError("already recording: call stop_recording() first")
        recording = Recording(self.robot, self.controller.dt, max_samples=max_samples)
        recording.add_start(self.q)
        self.mark()
        self._recording = recording

    def stop_recording(self) -> Recording:
        """The ticks since :meth:`start_recording`, the last ``max_samples`` of them (zero
        ticks is a valid recording); InputError when not recording."""
        if self._recording is None:
            raise InputError("not recording: call start_recording() first")
        recording, self._recording = self._recording, None
        return recording


__all__ = ["FRAMES", "MODES", "Teleop"]
