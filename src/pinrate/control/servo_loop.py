"""Closed-loop servo of the TCP to a target pose: a loop over :meth:`Controller.step` and
its stop rules.

Each step the sensor sees the pose error and commands (Shoham & Koren §2, Fig. 3)

    v = gain * R_s^T (p_target - p_tip)                 (position error, sensor axes)
    Ω = gain * R_s^T log3(R_target R_tip^T)             (rotation error, sensor axes)

saturated to ``max_linear_speed`` (m/s) and ``max_angular_speed`` (rad/s), turned into
joint rates by the algorithm and integrated over ``dt`` (see :mod:`.controller`).

On the Theorem: with ``gain * dt = 1`` the sensor commands the whole error each sample and
the error of MCA1 maps as e <- G e (eq. 40 with β = 1), so ``|λ(G)|`` < 1 is the exact test.
With smaller ``gain * dt`` the step is e <- (I - gain dt (I - G)) e: ``|λ|`` < 1 remains
sufficient, and only Re λ < 1 is needed as gain dt -> 0.

Stop rules, on the error measure e = ``|position error|`` + ``|rotation error|`` (m + rad, the two
norms ``tol`` applies to):

- **converged**: both norms below ``tol``.
- **diverging**: e > DIVERGENCE_FACTOR × min(e so far) + tol. Near the target the error maps
  linearly, e_k+1 ≈ M e_k; with ρ(M) > 1 it grows geometrically, so it passes 3× its minimum
  after ln 3 / ln ρ steps (12 steps at ρ = 1.1). With ρ(M) < 1 it can still grow for a while
  (M is not normal; far from the target the map is not linear), by at most the condition
  number of M's eigenvectors: a factor of 3 over the best error is past what a convergent run
  shows in pinrate's robots and tests, and cheap to detect early.
- **stalled**: e has not fallen below (1 - STALL_IMPROVEMENT) × its value at the last
  improvement for ``stall_time`` seconds of simulated time (default: max(1 s, 5 / gain), five
  time constants of the first-order error decay e(t) = e0 exp(-gain t) that an exact solver
  gives), or for STALL_MAX_STEPS steps, whichever is fewer. Every continuing window improves
  e by 1 %, and e cannot fall below ``tol`` without converging, so a run ends after at most
  ln(e0 / tol) / ln(1 / 0.99) windows. That bounds a run, not usefully: an error that
  improves slowly (``gain=2e-5``) goes on for tens of millions of steps.
- **singular**: the step halted for a singularity (``singularity="decelerate"``: the next
  step would have made a block singular; or the algorithm met a singular block).
- **collision**: the step halted before two links would come within the collision monitor's
  stop distance (``Controller(collision=True)``).
- **plant** (a run on a plant): the plant measured a joint past a position limit by more
  than its ``limit_tolerance`` (:mod:`.measured`).
- **max steps**: ``max_steps`` ran out. ``max_steps`` is at most MAX_STEPS (one million; an
  InputError names it beyond): the run records every step, so this bounds its memory.

A joint limit does not stop the run: the step holds the joint on its limit while the others
go on serving the error (a target the held joint was needed for then ends as "stalled").
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable
from typing import Any

from ..checks import check_count, check_positive
from ..errors import InputError
from ..kinematics.manipulator import Robot
from ..kinematics.partition import Partition
from ..plants import Plant
from .commands import PoseGoal
from .controller import (
    CONTROLLER_OPTIONS,
    MAX_ANGULAR_SPEED,
    MAX_LINEAR_SPEED,
    Controller,
)
from .measured import onto_limits
from .servo_run import DIVERGENCE_FACTOR, STALL_IMPROVEMENT, ServoRun
from .trajectory import Trajectory

STALL_TIME_CONSTANTS = 5.0
"""Default stall window in time constants (1 / gain) of the error's decay; at least 1 s."""

STALL_MAX_STEPS = 100_000
"""Most steps in a stall window, whatever ``stall_time / dt``: an error that needs more steps
than this to fall 1 % is not progressing at a useful rate (and a tiny dt would otherwise
make the window, and the run, endless in wall-clock time)."""


MAX_STEPS = 1_000_000
"""Most steps one servo run may take (``max_steps`` beyond it is an InputError), which bounds its
memory: a run records every step (q, joint rates, error norms, ρ, status; the run's arrays and
the Trajectory's copies), about 16 (nq + nv) + 100 bytes a step, and 150 more for a step taken
on Python. Measured on a 6-joint arm: 285 bytes a step compiled, 430 on Python, so at most
0.3-0.45 GB (a 100-joint model: about 3.5 GB). At dt = 0.01 a million steps is 2.8 hours of
motion; servo again from ``trajectory.q[-1]`` for more."""

MIN_TOL = 1e-12
"""Smallest ``tol`` (m and rad): finer than double precision resolves a pose of a 1 m arm."""


def _options_from_one_place(function: Callable[..., Trajectory]) -> Callable[..., Trajectory]:
    """With ``controller=`` given, any Controller option passed beside it is an InputError
    (whatever its value: an option equal to servo's default is refused too, never ignored)."""

    @functools.wraps(function)
    def checked(*arguments: Any, **keywords: Any) -> Trajectory:
        if keywords.get("controller") is not None:
            given = sorted(set(keywords) & set(CONTROLLER_OPTIONS))
            if given:
                raise InputError(
                    f"servo(controller=...) takes its options from the controller: drop {', '.join(given)} "
                    "(or build the controller with them)"
                )
        return function(*arguments, **keywords)

    return checked


@_options_from_one_place
def servo(
    robot: Robot,
    q0: object,
    target: object,
    *,
    algorithm: str = "mca1",
    partition: Partition | None = None,
    dt: float = 0.01,
    gain: float = 1.0,
    max_steps: int = 2000,
    tol: float = 1e-4,
    max_linear_speed: float = MAX_LINEAR_SPEED,
    max_angular_speed: float = MAX_ANGULAR_SPEED,
    stall_time: float | None = None,
    velocity_limits: object = math.inf,
    singularity: str = "decelerate",
    wrist: str = "turn",
    controller: Controller | None = None,
    plant: Plant | None = None,
    **controller_options: Any,
) -> Trajectory:
    """Servo the tip from q0 to ``target`` (4x4 pose in the world, or pinocchio.SE3).

    Stops when the norms of the controlled position error (m) and rotation error (rad) are
    both below ``tol`` (converged), or with a reason (see the module's stop rules): the error
    grew past DIVERGENCE_FACTOR times its best (diverging), it has not improved by
    STALL_IMPROVEMENT for ``stall_time`` seconds (stalled; default max(1 s, 5 / gain)), a
    step halted for a singularity, or ``max_steps`` ran out (at most MAX_STEPS, a million: the
    run records every step, 285-430 bytes each for a 6-joint arm). Joints are held at their
    position limits while the others go on (:class:`Controller`). ``velocity_limits``, ``singularity``
    and ``wrist`` as for :class:`Controller`: the default velocity limits, none, keep the
    papers' simulations as they were; None takes the URDF's.

    Every other :class:`Controller` option is taken by keyword (``collision=True``,
    ``acceleration_limits=2.0``, ``posture="home"``, ...), or a ``controller`` built on this
    ``robot`` is used as it is (then no controller option may be given here; its state, such
    as acceleration-limited rates, carries over from earlier steps). An unknown option is an
    InputError listing the valid ones.

    ``plant`` (:mod:`pinrate.plants`, e.g. ``MujocoPlant(robot)``) closes the loop on a
    simulated robot: it is reset to q0, each step is taken from the configuration it measured
    after the step before (never the controller's own integration; Shoham & Koren Fig. 3),
    and the trajectory's q are the measured ones, with what the plant did beside the commands
    in ``trajectory.plant`` (measured rates, the tip's tracking error, saturated actuators).
    Such a run steps on Python, each step per call (compiled per call where the core covers
    the controller). None (the default): the kinematic loop, q the integrated rates.
    """
    if controller is None:
        unknown = sorted(set(controller_options) - set(CONTROLLER_OPTIONS))
        if unknown:
            raise InputError(
                f"servo() has no option {', '.join(map(repr, unknown))}; its own are gain, max_steps, tol, "
                f"stall_time, controller, plant, and the Controller's: {', '.join(CONTROLLER_OPTIONS)}"
            )
        controller = Controller(
            robot,
            algorithm=algorithm,
            partition=partition,
            dt=dt,
            max_linear_speed=max_linear_speed,
            max_angular_speed=max_angular_speed,
            velocity_limits=velocity_limits,
            singularity=singularity,
            wrist=wrist,
            **controller_options,
        )
    elif not isinstance(controller, Controller):
        raise InputError(f"controller must be a pinrate.Controller, not {type(controller).__name__}")
    elif controller.robot is not robot:
        raise InputError("the controller was built for another Robot object: servo it on that one")
    q = robot.check_q(q0)
    if plant is not None:  # a plant's last measurement may sit past a limit by its tolerance
        plant = _check_plant(plant, robot)
        q, beyond = onto_limits(controller, q, plant.limit_tolerance)
        if beyond:
            raise InputError(f"q0 is past a position limit by more than the plant's tolerance: {beyond}")
    controller.check_inside_limits(q)
    goal = PoseGoal.of(target, gain)
    tol = check_positive(tol, "tol")
    if tol < MIN_TOL:
        raise InputError(f"tol must be at least {MIN_TOL:g} (m and rad), got {tol!r}")
    max_steps = check_count(max_steps, "max_steps")
    if max_steps > MAX_STEPS:
        raise InputError(
            f"max_steps must be at most {MAX_STEPS:,} (a run records every step: servo again from "
            f"trajectory.q[-1] for a longer one), got {max_steps:,}"
        )
    if stall_time is None:  # STALL_MAX_STEPS caps the window anyway: a tiny gain is no error of stall_time's
        stall_time = max(1.0, STALL_TIME_CONSTANTS / goal.gain)  # inf for a subnormal gain
    else:
        check_positive(stall_time, "stall_time")
    stall_steps = math.ceil(min(stall_time / controller.dt, STALL_MAX_STEPS))
    run = ServoRun(controller, goal, q, tol, stall_steps, max_steps)
    if plant is not None:
        run.on_plant(plant)
        return run.trajectory()
    core = controller.compiled()
    if core is None:
        run.python()
    else:
        run.compiled(core)
    return run.trajectory()


def _check_plant(plant: object, robot: Robot) -> Plant:
    """``plant`` when it is a :class:`~pinrate.plants.Plant` of ``robot``; InputError otherwise."""
    if not isinstance(plant, Plant):
        raise InputError(f"plant must be a pinrate.plants.Plant, not {type(plant).__name__}")
    if plant.robot is not robot:
        raise InputError("the plant was built for another Robot object: servo it on that one")
    return plant


__all__ = [
    "DIVERGENCE_FACTOR",
    "MAX_STEPS",
    "MIN_TOL",
    "STALL_IMPROVEMENT",
    "STALL_MAX_STEPS",
    "STALL_TIME_CONSTANTS",
    "servo",
]
