"""The compiled servo loop and ρ map: a controller's settings, set by name on a
``pinrate_core.Settings`` and handed to ``pinrate_core.Servo`` (see ``core/src/servo.hpp`` for
what the loop does and hands back)."""

from __future__ import annotations

import dataclasses
import math
import weakref
from collections.abc import Callable, Hashable
from types import ModuleType
from typing import Any

import numpy as np

from ..errors import UnsupportedByCoreError
from ..kinematics.manipulator import Robot
from ..kinematics.partition import pseudo_g_is_exact, square_and_small
from .boundary import KERNELS, ServoSettings
from .core import core_module
from .kinematics import core_kinematics


def core_settings(core: ModuleType, settings: ServoSettings) -> Any:
    """A ``pinrate_core.Settings`` with each field of ``settings`` set by its name.

    Raises:
        UnsupportedByCoreError: the core's Settings has no field of that name (a core built
            from other sources; the check at load names these too).
    """
    filled = core.Settings()
    for field in dataclasses.fields(settings):
        try:
            setattr(filled, field.name, getattr(settings, field.name))
        except AttributeError:
            raise UnsupportedByCoreError(
                f"pinrate_core.Settings has no field {field.name!r} (ServoSettings.{field.name}): "
                "rebuild it (pip install ./core)"
            ) from None
    return filled


class CoreServo:
    """A controller's compiled twin: ``run`` is the servo loop, ``spectral_radius_at`` the
    ρ map, both in C++ (the GIL released); ``step_functions`` one control step per call."""

    def __init__(self, robot: Robot, settings: ServoSettings) -> None:
        kinematics = core_kinematics(robot)
        core = core_module()
        if kinematics is None or core is None:
            raise UnsupportedByCoreError("the Python path is chosen")
        if settings.algorithm not in KERNELS:
            raise UnsupportedByCoreError(f"the compiled core has no kernel {settings.algorithm!r}")
        if settings.small and (len(settings.rows) - settings.m > 3 or settings.m > 3 or settings.n_arm > 3):
            raise UnsupportedByCoreError("the closed forms take blocks of at most 3x3")
        self.core = core
        self.settings = settings  # no reference to the robot: the caches keyed by it must let it go
        self._servo = core.Servo(kinematics, core_settings(core, settings))
        self.nq, self.nv = kinematics.nq, kinematics.nv

    def step_functions(self) -> tuple[Callable[..., Any], Callable[..., Any]]:
        """The core's one control step per call, called with no wrapper between (see
        ``core/src/module.cpp``): ``step_at(q, twist, target, gain)`` from q (the checks,
        the kinematics pass, a twist or, with a (4, 4) target, gain times the pose error) and
        ``step_given(q, jacobian, twist)`` from the caller's J. Each returns None where
        Python must check the inputs, False where the step is Python's, else (flags, scale,
        hit, next q, rates, twist saturated, what the kinematics pass saw or None)."""
        return self._servo.step_at, self._servo.step_given

    def run(self, **arguments: Any) -> tuple[int, int, float, float, int]:
        """The servo loop, every argument by its name (see ``core/src/module.cpp``'s
        ``run_servo``): (outcome, step number, best, progress, progress step)."""
        return self._servo.run(**arguments)

    def spectral_radius_at(self, configurations: np.ndarray, *, threads: int = 1) -> np.ndarray:
        """ρ of the smaller of G and H at each configuration (N, nq); inf where A or W is singular.

        ``threads``: the configurations split into that many contiguous chunks, each mapped on
        a thread of the core's own (the GIL released); the result does not depend on it.
        """
        radii = np.empty(configurations.shape[0])
        self._servo.spectral_radius_at(np.ascontiguousarray(configurations, dtype=float), radii, threads)
        return radii

    def jacobian_seconds(self, configurations: np.ndarray, *, threads: int = 1) -> float:
        """Wall-clock seconds of the ρ map's Jacobians alone at each configuration (N, nq),
        split over ``threads`` as :meth:`spectral_radius_at` splits them: the map's bound."""
        return self._servo.jacobian_timing(np.ascontiguousarray(configurations, dtype=float), threads)

    def solve_seconds(self, q: np.ndarray, twist: np.ndarray, algorithm: str, repeats: int) -> float:
        """Seconds per call of ``algorithm``'s solve alone (exact, mca1 or mca2) at q, in C++."""
        return self._servo.solve_timing(q, np.ascontiguousarray(twist, dtype=float), algorithm, repeats)


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
