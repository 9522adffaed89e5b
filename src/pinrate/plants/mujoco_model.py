"""A MuJoCo model of a pinrate :class:`~pinrate.kinematics.manipulator.Robot`, built from
its Pinocchio model (the one the controller uses, so the two cannot disagree on a joint, an
axis or a frame).

Each moving joint of the Pinocchio model becomes a MuJoCo body at the joint's placement in its
parent joint's frame (``model.jointPlacements``), with one hinge or slide joint on the same
axis, the joint's position limits (none for a continuous joint; a stiff stop), and the mass, centre of mass
and rotational inertia Pinocchio merged onto that joint from the URDF's links
(``model.inertias``: every link rigidly attached to it, fixed joints included). The URDF's
``<dynamics damping friction>`` become the joint's damping and friction loss; its armature
(``model.armature``) is kept where it is given, else :data:`DEFAULT_ARMATURE` (a URDF has no
rotor inertia; a drive has one, and it keeps a light distal link's dynamics from being stiff
at a 1 ms step).

A servo on every joint of the model (the controller's step gives every joint a rate, 0 for
those it does not drive, so a gripper's fingers are held still), in N m or N:

- **velocity** (default), a drive's PI velocity loop: ``τ_j = k_v,j (q̇_cmd,j - q̇_j) +
  k_i,j (q_ref,j - q_j)``, q_ref the command integrated (so k_i multiplies the integral of
  the velocity error): a joint comes to rest under a load (gravity, its neighbours'
  reactions), at τ_load / k_i from its reference, where a P-only loop would drift. Two MuJoCo
  actuators: a velocity one (damping taken implicitly) and the integral, a position one on
  q_ref (actuator ``"<joint> integral"``);
- **position**: ``τ_j = k_p,j (q_ref,j - q_j) - k_v,j q̇_j``, no velocity feed-forward.

The gains are set per joint from the joint space inertia at the model's home configuration
(:func:`set_servo_gains`), so that every joint's loop has the same time constant whatever the
robot's size. The URDF's effort limit, where it gives one, bounds the joint's total actuator
force (the joint's ``actfrcrange``); its velocity limit bounds the velocity command.

A URDF inertia that breaks the triangle inequality (not a rigid body's, as on the xArm5's
second link) is balanced by MuJoCo (``balanceinertia``). Gravity acts (0, 0, -9.81 m/s² in
the world), and by default the drives compensate it (``gravcomp`` on every body, as a real
arm's joint controllers do); the integrator is
``implicitfast`` (the velocity servo's damping taken implicitly: with MuJoCo's default
explicit Euler the panda's light fingers diverged in the design's prototype). Contacts are
off: the plant simulates the arm's joint dynamics, and self-collision is the controller's
concern (``Controller(collision=True)``), so the URDF's meshes are not needed here (the
viewer draws the simulated robot from them).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
import pinocchio as pin

from ..errors import PlantError
from ..kinematics.manipulator import Robot

DEFAULT_ARMATURE = 0.01
"""kg m² (rad joints) or kg (prismatic joints): the armature a joint gets when the model gives
none (a URDF cannot; a small geared drive's rotor inertia reflected through its gear is of this
order or larger)."""

GRAVITY = (0.0, 0.0, -9.81)
"""m/s², world frame."""

MIN_MASS = 1e-9
"""kg: a moving body lighter than this has no inertia for MuJoCo (its ``mjMINVAL`` is 1e-15 on
the mass and the inertia; a body below this is what a URDF without ``<inertial>`` gives)."""

_AXES = {"X": (1.0, 0.0, 0.0), "Y": (0.0, 1.0, 0.0), "Z": (0.0, 0.0, 1.0)}


@dataclass(frozen=True)
class JointLayout:
    """Where each moving joint's coordinates sit in Pinocchio's q and in MuJoCo's qpos.

    Attributes:
        names: the moving joints, in velocity order (:attr:`Robot.joint_names`).
        idx_q: each joint's first index in Pinocchio's q.
        idx_v: each joint's index in Pinocchio's v (and the actuator's index in MuJoCo).
        continuous: each joint's kind: True for a continuous joint, whose Pinocchio q holds
            (cos θ, sin θ) and MuJoCo's qpos θ.
        qpos: each joint's index in MuJoCo's qpos; qvel: in MuJoCo's qvel; actuator: its
            servo's index in MuJoCo's actuators (and ctrl); integral: its velocity servo's
            integral actuator, -1 for a position servo.
    """

    names: tuple[str, ...]
    idx_q: np.ndarray
    idx_v: np.ndarray
    continuous: np.ndarray
    qpos: np.ndarray
    qvel: np.ndarray
    actuator: np.ndarray
    integral: np.ndarray

    def to_mujoco(self, q: np.ndarray) -> np.ndarray:
        """MuJoCo's qpos (nq_mujoco,) for Pinocchio's q (nq,): θ = atan2(sin, cos) for a
        continuous joint, the value itself otherwise (rad or m)."""
        qpos = np.empty(self.qpos.size)
        first = q[self.idx_q]
        second = q[np.minimum(self.idx_q + 1, q.size - 1)]
        qpos[self.qpos] = np.where(self.continuous, np.arctan2(second, first), first)
        return qpos

    def from_mujoco(self, qpos: np.ndarray, nq: int) -> np.ndarray:
        """Pinocchio's q (nq,) for MuJoCo's qpos: (cos θ, sin θ) for a continuous joint."""
        q = np.empty(nq)
        value = qpos[self.qpos]
        q[self.idx_q] = np.where(self.continuous, np.cos(value), value)
        continuous = self.idx_q[self.continuous]
        q[continuous + 1] = np.sin(value[self.continuous])
        return q


def build_spec(
    robot: Robot,
    *,
    timestep: float,
    actuator: str = "velocity",
    gravity_compensation: bool = True,
    missing_mass: float | None = None,
) -> Any:
    """The ``mujoco.MjSpec`` of ``robot`` (see the module docstring): its ``actuator``
    servos (``"velocity"`` or ``"position"``) with unit gains (:func:`set_servo_gains` sets
    them on the compiled model), and a site named ``"tip"`` at the robot's tip frame.

    Raises:
        PlantError: naming the joints whose bodies have no mass (a URDF link without
            ``<inertial>``; ``missing_mass`` (kg) gives each of them that mass, as a solid
            sphere of radius 5 cm at the joint), or a joint kind MuJoCo's hinge and slide
            joints cannot represent.
    """
    import mujoco

    model = robot.model
    spec = mujoco.MjSpec()
    spec.modelname = robot.name or "pinrate robot"
    spec.option.timestep = timestep
    spec.option.integrator = mujoco.mjtIntegrator.mjINT_IMPLICITFAST
    spec.option.gravity = GRAVITY
    spec.option.disableflags |= mujoco.mjtDisableBit.mjDSBL_CONTACT
    spec.compiler.autolimits = True
    spec.compiler.degree = False  # joint ranges in radians, as the URDF gives them
    # An inertia that breaks the triangle inequality (A + B >= C; xArm5's URDF has one) is
    # not a rigid body's: MuJoCo then raises its smallest moment to the bound, as it may.
    spec.compiler.balanceinertia = True
    massless = [model.names[index] for index in range(1, model.njoints) if model.inertias[index].mass < MIN_MASS]
    if massless and missing_mass is None:
        raise PlantError(
            f"robot {robot.name!r}: MuJoCo needs a mass on every moving body, and the links moved by "
            f"{', '.join(massless)} have none (no <inertial> in the URDF): add <inertial> elements, or "
            "give each such body a mass as a 5 cm solid sphere at its joint (MujocoPlant(missing_mass=kg); "
            "pinrate demo/teleop: --missing-mass KG)"
        )
    bodies: dict[int, Any] = {0: spec.worldbody}
    for index in range(1, model.njoints):
        joint = model.joints[index]
        if joint.nv != 1:
            raise PlantError(
                f"robot {robot.name!r}: joint {model.names[index]!r} is a {joint.shortname()} "
                "(more than one degree of freedom): the MuJoCo plant takes revolute, continuous "
                "and prismatic joints"
            )
        placement = model.jointPlacements[index]
        body = bodies[model.parents[index]].add_body(
            name=model.names[index],
            pos=placement.translation,
            quat=pin.Quaternion(placement.rotation).coeffs()[[3, 0, 1, 2]],
        )
        body.gravcomp = 1.0 if gravity_compensation else 0.0
        _set_inertia(body, model.inertias[index], missing_mass)
        bodies[index] = body
        _add_servo(mujoco, spec, _add_joint(mujoco, body, robot, index, timestep), robot, index, actuator)
    tip = model.frames[robot.tip_id]
    placement = tip.placement
    bodies[tip.parentJoint].add_site(
        name="tip", pos=placement.translation, quat=pin.Quaternion(placement.rotation).coeffs()[[3, 0, 1, 2]]
    )
    return spec


def _set_inertia(body: Any, inertia: pin.Inertia, missing_mass: float | None) -> None:
    """The body's mass (kg), centre of mass (m, body frame) and inertia about it (kg m²)."""
    body.explicitinertial = True
    if inertia.mass < MIN_MASS:
        mass = float(missing_mass)  # type: ignore[arg-type]  # build_spec refused None
        body.mass = mass
        body.ipos = [0.0, 0.0, 0.0]
        body.inertia = [0.4 * mass * 0.05**2] * 3  # 2/5 m r², a solid sphere
        return
    rotational = inertia.inertia
    body.mass = inertia.mass
    body.ipos = inertia.lever
    # MuJoCo's fullinertia: (Ixx, Iyy, Izz, Ixy, Ixz, Iyz) about the centre of mass.
    body.fullinertia = [
        rotational[0, 0],
        rotational[1, 1],
        rotational[2, 2],
        rotational[0, 1],
        rotational[0, 2],
        rotational[1, 2],
    ]


def _add_joint(mujoco: Any, body: Any, robot: Robot, index: int, timestep: float) -> Any:
    """The hinge or slide of Pinocchio joint ``index`` on ``body``: axis, limits, damping,
    friction loss and armature (see the module docstring)."""
    model = robot.model
    joint = model.joints[index]
    kind = joint.shortname().removeprefix("JointModel")
    if kind.startswith("R"):
        joint_type = mujoco.mjtJoint.mjJNT_HINGE
    elif kind.startswith("P"):
        joint_type = mujoco.mjtJoint.mjJNT_SLIDE
    else:
        raise PlantError(
            f"robot {robot.name!r}: joint {model.names[index]!r} is a {kind}, not a revolute or prismatic joint"
        )
    axis = _AXES.get(kind[-1]) if kind[-1] in _AXES else tuple(np.asarray(joint.extract().axis, dtype=float))
    added = body.add_joint(name=model.names[index], type=joint_type, axis=axis)
    v, q = joint.idx_v, joint.idx_q
    if joint.nq == 1:
        lower, upper = float(model.lowerPositionLimit[q]), float(model.upperPositionLimit[q])
        if np.isfinite(lower) and np.isfinite(upper) and lower < upper:
            added.limited = mujoco.mjtLimited.mjLIMITED_TRUE
            added.range = [lower, upper]
            # A stiff stop at the limit: the stiffest MuJoCo keeps stable, a time constant of
            # two sub-steps, critically damped (its default, 20 ms, let a servo moving at
            # 2 rad/s press 3 mrad past it; this, 0.24 mrad).
            added.solref_limit = [2.0 * timestep, 1.0]
    damping = float(model.damping[v])
    try:
        added.damping = damping
    except TypeError:  # MuJoCo 4: the linear term first, then its polynomial's
        added.damping = [damping, 0.0, 0.0]
    added.frictionloss = float(model.friction[v])
    armature = float(model.armature[v])
    added.armature = armature if armature > 0 else DEFAULT_ARMATURE
    return added


def _add_servo(mujoco: Any, spec: Any, joint: Any, robot: Robot, index: int, kind: str) -> None:
    """Joint ``index``'s servo (``joint``: its MuJoCo joint): ``kind`` ``"velocity"`` (a
    velocity actuator and the integral, a position actuator on q_ref) or ``"position"`` (a
    position actuator on q_ref), every command q̇_cmd bounded by the velocity limit. q_ref is
    the actuator's own activation, which MuJoCo integrates from the command (an
    ``intvelocity`` actuator: act' = q̇_cmd, taken the sub-step it changes, ``actearly``),
    bounded by the position limits; the joint's total actuator force by the effort limit."""
    model = robot.model
    pinocchio_joint = model.joints[index]
    effort = float(model.effortLimit[pinocchio_joint.idx_v])
    if np.isfinite(effort) and effort > 0:
        joint.actfrclimited = mujoco.mjtLimited.mjLIMITED_TRUE
        joint.actfrcrange = [-effort, effort]
    name = model.names[index]
    speed = float(model.velocityLimit[pinocchio_joint.idx_v])
    actuators = [_add_actuator(mujoco, spec, name, name)] if kind == "velocity" else []
    reference = _add_actuator(mujoco, spec, f"{name} integral" if kind == "velocity" else name, name)
    actuators.append(reference)
    reference.dyntype = mujoco.mjtDyn.mjDYN_INTEGRATOR
    reference.actearly = True
    if np.isfinite(speed) and speed > 0:
        for actuator in actuators:
            actuator.ctrllimited = mujoco.mjtLimited.mjLIMITED_TRUE
            actuator.ctrlrange = [-speed, speed]
    if pinocchio_joint.nq == 1:
        q_index = pinocchio_joint.idx_q
        lower, upper = float(model.lowerPositionLimit[q_index]), float(model.upperPositionLimit[q_index])
        if np.isfinite(lower) and np.isfinite(upper) and lower < upper:
            reference.actlimited = mujoco.mjtLimited.mjLIMITED_TRUE
            reference.actrange = [lower, upper]


def _add_actuator(mujoco: Any, spec: Any, name: str, joint: str) -> Any:
    """An actuator on ``joint`` with a fixed gain and an affine bias (set by :func:`set_servo_gains`)."""
    actuator = spec.add_actuator(name=name, target=joint)
    actuator.trntype = mujoco.mjtTrn.mjTRN_JOINT
    actuator.gaintype = mujoco.mjtGain.mjGAIN_FIXED
    actuator.biastype = mujoco.mjtBias.mjBIAS_AFFINE
    return actuator


def set_servo_gains(
    mujoco: Any, mj_model: Any, layout: JointLayout, home: np.ndarray, kind: str, time_constant: float
) -> np.ndarray:
    """Set every servo's gains for a loop of time constant T = ``time_constant`` (s) at the
    configuration ``home`` (Pinocchio's q), from the joint space inertia's diagonal there,
    M_jj (armature included; kg m² or kg):

        velocity servo:  k_v = M_jj / T,  k_i = M_jj / (4 T²)
        position servo:  k_p = M_jj / T², k_v = 2 M_jj / T

    Both are critically damped: the PI loop's error obeys M ë + k_v ė + k_i e = 0, a double
    pole at -1 / (2 T) (without the integral, k_v alone: q̇ reaches q̇_cmd as
    1 - exp(-t / T)); the position loop's, a double pole at -1 / T. The other joints' coupling
    is neglected (M's diagonal dominates a serial arm's). Returns the M_jj, velocity order."""
    data = mujoco.MjData(mj_model)
    data.qpos[:] = layout.to_mujoco(home)
    mujoco.mj_forward(mj_model, data)
    diagonal = np.diag(joint_space_inertia(mujoco, mj_model, data))[layout.qvel]
    for actuator, integral, m_jj in zip(layout.actuator, layout.integral, diagonal, strict=True):
        if kind == "velocity":
            _set_gains(mj_model, actuator, m_jj / time_constant, 0.0, m_jj / time_constant)
            stiffness = m_jj / (4.0 * time_constant**2)
            _set_gains(mj_model, integral, stiffness, stiffness, 0.0)
        else:
            stiffness = m_jj / time_constant**2
            _set_gains(mj_model, actuator, stiffness, stiffness, 2.0 * m_jj / time_constant)
    return diagonal


def joint_space_inertia(mujoco: Any, mj_model: Any, data: Any) -> np.ndarray:
    """MuJoCo's joint space inertia M (nv, nv; kg m² or kg, armature included) at ``data``'s
    configuration, after ``mj_forward``, whichever of MuJoCo 3's and 4's signatures of
    ``mj_fullM`` the installed release has."""
    inertia = np.zeros((mj_model.nv, mj_model.nv))
    try:
        mujoco.mj_fullM(mj_model, data, inertia)
    except TypeError:  # MuJoCo 3: (model, destination, qM)
        mujoco.mj_fullM(mj_model, inertia, data.qM)
    return inertia


def _set_gains(mj_model: Any, actuator: int, gain: float, stiffness: float, damping: float) -> None:
    """force = gain u - stiffness q - damping q̇, u the actuator's command, or its activation
    q_ref when it has one (MuJoCo's fixed gain and affine bias)."""
    mj_model.actuator_gainprm[actuator, 0] = gain
    mj_model.actuator_biasprm[actuator, :3] = (0.0, -stiffness, -damping)


def joint_layout(robot: Robot, mj_model: Any) -> JointLayout:
    """The :class:`JointLayout` of ``robot`` in ``mj_model`` (built by :func:`build_spec`)."""
    import mujoco

    model = robot.model
    ids = [model.getJointId(name) for name in robot.joint_names]
    mj_joints = [mujoco.mj_name2id(mj_model, mujoco.mjtObj.mjOBJ_JOINT, name) for name in robot.joint_names]
    return JointLayout(
        names=tuple(robot.joint_names),
        idx_q=np.array([model.joints[index].idx_q for index in ids]),
        idx_v=np.array([model.joints[index].idx_v for index in ids]),
        continuous=np.array([model.joints[index].nq == 2 for index in ids]),
        qpos=np.array([mj_model.jnt_qposadr[joint] for joint in mj_joints]),
        qvel=np.array([mj_model.jnt_dofadr[joint] for joint in mj_joints]),
        actuator=np.array(
            [mujoco.mj_name2id(mj_model, mujoco.mjtObj.mjOBJ_ACTUATOR, name) for name in robot.joint_names]
        ),
        integral=np.array(
            [
                mujoco.mj_name2id(mj_model, mujoco.mjtObj.mjOBJ_ACTUATOR, f"{name} integral")
                for name in robot.joint_names
            ]
        ),
    )


__all__ = [
    "DEFAULT_ARMATURE",
    "GRAVITY",
    "MIN_MASS",
    "JointLayout",
    "build_spec",
    "joint_layout",
    "joint_space_inertia",
    "set_servo_gains",
]
