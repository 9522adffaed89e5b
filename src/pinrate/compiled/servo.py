"""The compiled servo loop and ρ map: a controller's settings as plain numbers, handed to
``pinrate_core.Servo`` (see ``core/src/servo.hpp`` for what the loop does and hands back)."""

from __future__ import annotations

import math
import weakref
from collections.abc import Callable, Hashable
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..errors import UnsupportedByCoreError
from ..kinematics.manipulator import Robot
from ..kinematics.partition import pseudo_g_is_exact, square_and_small
from ..solvers.singular import PINV_RCOND
from .core import core_module
from .kinematics import core_kinematics

KERNELS = ("exact", "schur", "mca1", "mca2", "mca3", "dls")
"""The algorithms in the core's order (``pinrate_core.KERNELS``)."""


@dataclass(frozen=True)
class ServoSettings:
    """What the compiled step needs of a :class:`~pinrate.control.Controller`.

    Attributes:
        rows: J's rows of the twist, partition order (m linear first), indices 0-5.
        columns: velocity indices of the partition's joints, arm then wrist.
        m, n_arm: linear rows, arm joints.
        algorithm: a name of :data:`KERNELS`.
        measured: the blocks the conditioning bound measures ("A", "W", "J").
        row_scale: 1/L on linear rows, 1 on angular (m + k,).
        slow_threshold: c under which a step is in the singular region (handed back).
        watch, watch_factor, watched_step: the decelerate rule's one-step-ahead test.
        max_linear_speed, max_angular_speed: m/s, rad/s (inf for none).
        dt: s.
        position_limits: keep q within the limits.
        limits: rows (q index, v index, lower, upper) of the position limits (rad or m).
        rate_limits: rows (v index, limit) of the velocity limits (rad/s or m/s).
        exact_rcond, dls_damping: :mod:`pinrate.solvers.reference`'s constants.
        small: A and W square of size <= 3 (the closed forms); else pseudo-inverses, which
            needs A not tall and W not wide (ρ of the pseudo-inverse G is then the error map's).
        ranks: the generic ranks of J, A and W (c is σ_rank / σ_1).
        pinv_rcond: the pseudo-inverses' relative cut-off.
    """

    rows: tuple[int, ...]
    columns: tuple[int, ...]
    m: int
    n_arm: int
    algorithm: str
    measured: tuple[str, ...]
    row_scale: tuple[float, ...]
    slow_threshold: float
    watch: bool
    watch_factor: float
    watched_step: float
    max_linear_speed: float
    max_angular_speed: float
    dt: float
    position_limits: bool
    limits: tuple[tuple[int, int, float, float], ...]
    rate_limits: tuple[tuple[int, float], ...]
    exact_rcond: float
    dls_damping: float
    small: bool = True
    ranks: tuple[int, int, int] = (6, 3, 3)
    pinv_rcond: float = PINV_RCOND


class CoreServo:
    """A controller's compiled twin: ``run`` is the servo loop, ``spectral_radius_at`` the
    ρ map, both in C++ (the GIL released)."""

    def __init__(self, robot: Robot, settings: ServoSettings) -> None:
        kinematics = core_kinematics(robot)
        core = core_module()
        if kinematics is None or core is None:
            raise UnsupportedByCoreError("the Python path is chosen")
        if settings.small and (len(settings.rows) - settings.m > 3 or settings.m > 3 or settings.n_arm > 3):
            raise UnsupportedByCoreError("the closed forms take blocks of at most 3x3")
        self.core = core
        self.settings = settings  # no reference to the robot: the caches keyed by it must let it go
        self._servo = core.Servo(
            kinematics,
            list(settings.rows),
            list(settings.columns),
            settings.m,
            settings.n_arm,
            KERNELS.index(settings.algorithm),
            list(settings.measured),
            list(settings.row_scale),
            settings.slow_threshold,
            settings.watch,
            settings.watch_factor,
            settings.watched_step,
            settings.max_linear_speed,
            settings.max_angular_speed,
            settings.dt,
            settings.position_limits,
            np.array(settings.limits, dtype=float).reshape(-1, 4),
            np.array(settings.rate_limits, dtype=float).reshape(-1, 2),
            settings.exact_rcond,
            settings.dls_damping,
            settings.small,
            list(settings.ranks),
            settings.pinv_rcond,
        )

    def run(self, q: np.ndarray, target: np.ndarray, *arguments: Any) -> tuple[int, int, float, float, int]:
        """The servo loop from ``q`` (see ``core/src/module.cpp``'s ``run_servo``):
        (outcome, step number, best, progress, progress step)."""
        return self._servo.run(q, target, *arguments)

    def spectral_radius_at(self, configurations: np.ndarray) -> np.ndarray:
        """ρ of the smaller of G and H at each configuration (N, nq); inf where A or W is singular."""
        radii = np.empty(configurations.shape[0])
        self._servo.spectral_radius_at(np.ascontiguousarray(configurations, dtype=float), radii)
        return radii

    def solve_seconds(self, q: np.ndarray, twist: np.ndarray, algorithm: str, repeats: int) -> float:
        """Seconds per call of ``algorithm``'s solve alone (exact, mca1 or mca2) at q, in C++."""
        return self._servo.solve_timing(q, np.ascontiguousarray(twist, dtype=float), KERNELS.index(algorithm), repeats)


_servos: weakref.WeakKeyDictionary[Robot, dict[Hashable, CoreServo]] = weakref.WeakKeyDictionary()

MAX_CACHED_SERVOS = 64
"""Compiled servos (and ρ maps) kept per robot (a servo call builds its controller afresh;
the same settings come back, and building the core's twin costs as much as a few dozen
steps)."""


def core_servo(robot: Robot, key: Hashable, settings: Callable[[], ServoSettings]) -> CoreServo:
    """The :class:`CoreServo` of ``robot`` for a controller whose settings ``key`` stands for
    (a cheap tuple of everything that ``settings()`` reads), built once and kept.

    Raises:
        UnsupportedByCoreError: as :class:`CoreServo` does.
    """
    if core_module() is None:
        raise UnsupportedByCoreError("the Python path is chosen")
    servos = _servos.setdefault(robot, {})
    servo = servos.get(key)
    if servo is None:
        if len(servos) >= MAX_CACHED_SERVOS:
            servos.clear()
        servo = servos[key] = CoreServo(robot, settings())
    return servo


def rho_map(robot: Robot, rows: tuple[int, ...], columns: tuple[int, ...], m: int, n_arm: int) -> CoreServo | None:
    """A compiled ρ map of ``robot`` for a partition's rows and columns (kept as the servos
    are), or None where the Python path is chosen or the core does not cover it (a joint it
    does not rebuild; a tall A or a wide W, whose ρ is the error map's)."""
    k, n_wrist = len(rows) - m, len(columns) - n_arm
    if core_module() is None or not pseudo_g_is_exact(m, n_arm, k, n_wrist):
        return None

    def settings() -> ServoSettings:  # only the partition matters to a ρ map
        return ServoSettings(
            rows=rows,
            columns=columns,
            m=m,
            n_arm=n_arm,
            algorithm="mca1",
            measured=(),
            row_scale=(1.0,) * len(rows),
            slow_threshold=0.0,
            watch=False,
            watch_factor=0.0,
            watched_step=0.0,
            max_linear_speed=math.inf,
            max_angular_speed=math.inf,
            dt=1.0,
            position_limits=False,
            limits=(),
            rate_limits=(),
            exact_rcond=0.0,
            dls_damping=0.0,
            small=square_and_small(m, n_arm, k, n_wrist),
        )

    try:
        return core_servo(robot, ("rho map", rows, columns, m, n_arm), settings)
    except UnsupportedByCoreError:
        return None
