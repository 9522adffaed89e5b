"""A MuJoCo simulation of the robot as the plant (``pip install "pinrate[mujoco]"``).

The model is built from the robot's Pinocchio model (:mod:`.mujoco_model`: same joints,
axes, limits and inertias; a servo on every joint; gravity, compensated by the drives by
default; ``implicitfast``; no contacts). An advance holds the commanded joint rates for the
duration in sub-steps of at most ``timestep`` (the controller's dt and the simulation's step
are independent: n = ceil(duration / timestep) sub-steps of duration / n each):

- each sub-step moves the reference q_ref by q̇_cmd times the sub-step, from the reference of
  the sub-step before (not from the measured q, which lags: starting each advance from the
  measured q would lose the lag every time, an effective gain of about 0.8/s for a commanded
  2/s in the design's prototype), within the position limits: MuJoCo integrates it, as the
  activation of an ``intvelocity`` actuator;
- **velocity servo** (default): the PI loop drives q̇ toward q̇_cmd and, through its
  integral, q toward q_ref (:func:`.mujoco_model.set_servo_gains`: critically damped, time
  constant T); the command, and so the reference's rate, saturates at the URDF's velocity
  limit (a controller that drives it keeps those limits: ``velocity_limits=None``);
- **position servo**: the servo pulls q toward q_ref, critically damped with time constant T.

The measurement is MuJoCo's qpos and qvel at the end of the advance, in Pinocchio's layout.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from ..checks import check_positive
from ..errors import InputError, PlantError
from ..kinematics.manipulator import Robot
from .abstract_plant import Measurement, Plant
from .mujoco_model import build_spec, joint_layout, set_servo_gains

ACTUATORS = ("velocity", "position")
"""The values of ``MujocoPlant(actuator=...)``."""

TIMESTEP = 0.001
"""s: the simulation's longest sub-step (MuJoCo's default is 2 ms; 1 ms resolves a servo of
a few ms)."""

TIME_CONSTANT = 0.005
"""s: each servo's time constant T at home (velocity: q̇ reaches 63 % of a step in its command
after T; position: critically damped at ω = 1 / T)."""

LIMIT_SOFTNESS = 1e-4
"""rad or m: how far MuJoCo's joint limit (a stiff stop: a critically damped spring of time
constant two sub-steps, :mod:`.mujoco_model`) lets a joint its servo holds there press past
it (measured: 1e-5 on the panda's joints at rest, 2.4e-4 arriving at 2 rad/s)."""

UNLIMITED_SPEED = 3.0
"""rad/s or m/s: the speed assumed for a joint whose URDF gives no velocity limit, in its
``limit_tolerance``."""


def _mujoco() -> Any:
    try:
        import mujoco
    except ImportError:
        raise PlantError(
            'the MuJoCo plant needs MuJoCo: pip install "pinrate[mujoco]" (or pip install mujoco)'
        ) from None
    return mujoco


class MujocoPlant(Plant):
    """The robot simulated by MuJoCo (see the module docstring).

    Args:
        robot: the robot (its Pinocchio model is simulated; any URDF pinrate loads whose
            moving joints are revolute, continuous or prismatic, each moving body with a mass).
        actuator: ``"velocity"`` (default) or ``"position"`` servos.
        timestep: s, the longest simulation sub-step (default :data:`TIMESTEP`).
        time_constant: s, each servo's time constant T (default :data:`TIME_CONSTANT`).
        gravity_compensation: the drives cancel gravity (default True, as a real arm's joint
            controllers do); False lets gravity pull against the servos.
        missing_mass: kg given to each moving body the URDF gives no mass (a 5 cm sphere at
            its joint); None (default) refuses such a robot naming the joints.

    Attributes:
        model, data: MuJoCo's ``MjModel`` and ``MjData``.
        limit_tolerance: per joint, T times its velocity limit (:data:`UNLIMITED_SPEED`
            without one) plus :data:`LIMIT_SOFTNESS`: the overshoot of a servo that was
            moving at its limit speed when its command stopped.
        layout: where each joint sits in both q (:class:`~.mujoco_model.JointLayout`).
        inertia: each joint's M_jj at home (kg m² or kg, velocity order), the servo gains' base.

    Raises:
        PlantError: MuJoCo is not installed, or the robot lacks what it needs (the message
            names the joint and the repair).
        InputError: a bad option (naming it and its choices).
    """

    def __init__(
        self,
        robot: Robot,
        *,
        actuator: str = "velocity",
        timestep: float = TIMESTEP,
        time_constant: float = TIME_CONSTANT,
        gravity_compensation: bool = True,
        missing_mass: float | None = None,
    ) -> None:
        if actuator not in ACTUATORS:
            raise InputError(f"actuator must be one of {', '.join(map(repr, ACTUATORS))}, got {actuator!r}")
        self.timestep = check_positive(timestep, "timestep", maximum=1.0)
        self.time_constant = check_positive(time_constant, "time_constant", maximum=10.0)
        if missing_mass is not None:
            check_positive(missing_mass, "missing_mass")
        mujoco = self._mujoco = _mujoco()
        self.robot = robot
        self.actuator = actuator
        spec = build_spec(
            robot,
            timestep=self.timestep,
            actuator=actuator,
            gravity_compensation=bool(gravity_compensation),
            missing_mass=missing_mass,
        )
        try:
            self.model = spec.compile()
        except ValueError as error:
            raise PlantError(f"robot {robot.name!r}: MuJoCo could not compile its model: {error}") from None
        self.data = mujoco.MjData(self.model)
        self.layout = joint_layout(robot, self.model)
        self.inertia = set_servo_gains(mujoco, self.model, self.layout, robot.home(), actuator, self.time_constant)
        kind = "PI velocity" if actuator == "velocity" else "position"
        self.name = f"MuJoCo {mujoco.__version__}, {kind} servos (T = {self.time_constant * 1e3:g} ms)"
        joints = self.model.dof_jntid[self.layout.qvel]
        limited = self.model.jnt_actfrclimited[joints].astype(bool)
        # A joint's actuator force at its effort limit, to rounding (1e-9 relative): saturated.
        self._force_limit = np.where(limited, np.abs(self.model.jnt_actfrcrange[joints, 1]) * (1.0 - 1e-9), math.inf)
        self._force_limited = bool(limited.any())
        # Where q_ref lives: the activation of the velocity servo's integral, or of the position servo.
        referenced = self.layout.integral if actuator == "velocity" else self.layout.actuator
        self._reference_state = self.model.actuator_actadr[referenced]
        # The fastest each joint is commanded: its servo's command bound (the URDF's velocity
        # limit, as the model set it). A servo of time constant T moving at q̇ comes to rest
        # about q̇ T past where its command stopped.
        bounded = self.model.actuator_ctrllimited[self.layout.actuator].astype(bool)
        speeds = np.full(robot.nv, UNLIMITED_SPEED)
        speeds[self.layout.idx_v] = np.where(
            bounded, self.model.actuator_ctrlrange[self.layout.actuator, 1], UNLIMITED_SPEED
        )
        self.limit_tolerance = self.time_constant * speeds + LIMIT_SOFTNESS
        self._time = 0.0
        self.reset(robot.home())

    def reset(self, q: np.ndarray) -> Measurement:
        mujoco, data = self._mujoco, self.data
        q = self.robot.check_q(q)
        mujoco.mj_resetData(self.model, data)
        data.qpos[:] = self.layout.to_mujoco(q)
        data.act[self._reference_state] = data.qpos[self.layout.qpos]  # q_ref starts where q is
        mujoco.mj_forward(self.model, data)
        self._time = 0.0
        return self._measure(())

    def advance(self, joint_rates: np.ndarray, duration: float) -> Measurement:
        rates, seconds = self.check_command(joint_rates, duration)
        mujoco, model, data, layout = self._mujoco, self.model, self.data, self.layout
        substeps = max(1, math.ceil(seconds / self.timestep - 1e-9))
        model.opt.timestep = seconds / substeps
        command = rates[layout.idx_v]
        data.ctrl[layout.actuator] = command  # MuJoCo bounds it by the velocity limit
        if self.actuator == "velocity":
            data.ctrl[layout.integral] = command  # the integral's q_ref moves at the same rate
        saturated = np.zeros(layout.actuator.size, dtype=bool)
        if self._force_limited:  # looked at after every sub-step
            for _ in range(substeps):
                mujoco.mj_step(model, data)
                saturated |= np.abs(data.qfrc_actuator[layout.qvel]) >= self._force_limit
        else:
            mujoco.mj_step(model, data, nstep=substeps)
        self._time += seconds
        if not np.isfinite(data.qpos).all() or not np.isfinite(data.qvel).all():
            raise PlantError(
                f"the MuJoCo simulation of {self.robot.name!r} diverged (non-finite state) at t = {self._time:g} s"
            )
        return self._measure(tuple(name for name, hit in zip(layout.names, saturated, strict=True) if hit))

    def _measure(self, saturated: tuple[str, ...]) -> Measurement:
        layout, data = self.layout, self.data
        q = layout.from_mujoco(data.qpos, self.robot.nq)
        joint_rates = np.zeros(self.robot.nv)
        joint_rates[layout.idx_v] = data.qvel[layout.qvel]
        return Measurement(q, joint_rates, self._time, saturated)


__all__ = ["ACTUATORS", "LIMIT_SOFTNESS", "TIMESTEP", "TIME_CONSTANT", "UNLIMITED_SPEED", "MujocoPlant"]
