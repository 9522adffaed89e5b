"""One control step, the seam that the servo and teleoperation share.

Each step at configuration q (Shoham & Koren §2, Fig. 3):

1. kinematics at q, one Pinocchio pass: the sensor-frame Jacobian J (eq. 1-8), the tip and
   sensor poses, and ρ of the smaller of G and H (eq. 32, 50) — an :class:`Observation`;
2. the command becomes a twist in the sensor frame's axes (m/s, rad/s): a twist is taken as
   it is; a :class:`PoseGoal` commands ``gain`` times the pose error, position error
   R_s^T (p_target - p_tip) and rotation error R_s^T log3(R_target R_tip^T);
3. the linear and the angular parts are each scaled down, direction kept, to at most
   ``max_linear_speed`` and ``max_angular_speed``;
4. the algorithm turns the twist into joint rates (:mod:`pinrate.solvers`);
5. position limits: a joint whose commanded rate would carry it past a limit within dt is
   *blocked*: the rates are solved again without it (the others serve the command as well as
   they can), and it moves at most onto the limit. A joint on its limit whose command points
   away is not blocked: motion away is always executed. The test is on the commanded rate,
   never on a measured one, so a joint held at a limit does not cycle between stop and go
   (MoveIt Servo issue #2898);
6. velocity limits: when a rate exceeds its joint's limit, every rate is scaled by the same
   factor, the largest that meets every limit, so the direction of motion is kept;
7. q is integrated over dt on the configuration space (``pin.integrate``) and clamped to
   the limits (a guard against rounding: step 5 already keeps q inside).

:meth:`Controller.step` returns a :class:`Step`: the next q, the rates applied, and a
:class:`~pinrate.control.status.Status` saying what limited the step.
"""

from __future__ import annotations

import math
import weakref
from collections.abc import Callable, Collection
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
import pinocchio as pin

from ..checks import check_positive, check_vector
from ..compiled import CoreServo, ServoSettings, backend, core_kinematics, core_servo
from ..errors import InputError, SingularBlockError, UnsupportedByCoreError
from ..kinematics.axes import Axis, wrist_axes, wrist_centre
from ..kinematics.home import generic_ranks
from ..kinematics.manipulator import Robot
from ..kinematics.partition import Partition, PartitionIndex, partition_for
from ..kinematics.spatial import norm, pose_error, saturate
from ..solvers import closed_form
from ..solvers.conditioning import (
    characteristic_length,
    inverse_condition,
    inverse_condition_bound,
    row_scale,
    truncated_pinv,
)
from ..solvers.generalized import damped_inverter, filtered_rates, generalized_inverter
from ..solvers.rates import partition_rates, partition_spectral_radius
from ..solvers.reference import DLS_DAMPING, EXACT_RCOND, Inverter
from ..solvers.registry import check_algorithm
from .collision import CollisionMonitor
from .commands import JointJog, PoseGoal, Uncoupled, joint_rate_vector
from .elbow import ELBOW_REGION, EXTENDED, Elbow, arm_frame, elbow_rate, find_elbow, remaining_rates
from .posture import PostureJoints, null_space_motion, posture_joints
from .posture import gradient as posture_gradient
from .singularity import (
    SINGULAR_THRESHOLD,
    SLOW_THRESHOLD,
    STRATEGIES,
    WRIST_STRATEGIES,
    ColumnMap,
    Conditioning,
    adaptive_damping,
    block_of,
    carrying_joints,
    check_strategy,
    check_thresholds,
    conditioning,
    deceleration,
    halts,
    measured_blocks,
    wrist_pair,
)
from .status import Status, ranked

MAX_LINEAR_SPEED = 0.5
"""Default speed limit of the commanded TCP velocity (m/s)."""

MAX_ANGULAR_SPEED = 1.0
"""Default speed limit of the commanded angular velocity (rad/s)."""


@dataclass(slots=True)  # a record, read-only by convention: frozen dataclasses cost ~1 µs per step
class Observation:
    """What the controller sees at q, from one kinematics pass.

    Attributes:
        q: the configuration (nq,).
        jacobian: the sensor-frame Jacobian (6, nv).
        world_T_tip, world_T_sensor: the tip and sensor poses in the world.
        blocks: A, B, U, W as nested lists when the closed-form kernels apply, else None.
        algorithm: the controller's algorithm (ρ is that of its error map where it differs).
        index: the controller's resolved partition.
        goal: the pose goal ``error`` was measured against, if any.
        error: the controlled pose error (m + k,) in partition order, sensor axes (m, rad).
    """

    q: np.ndarray
    jacobian: np.ndarray
    world_T_tip: pin.SE3
    world_T_sensor: pin.SE3
    blocks: closed_form.Blocks | None
    algorithm: str
    index: PartitionIndex
    goal: PoseGoal | None = None
    error: np.ndarray | None = None
    _spectral_radius: float | None = None
    _inverses: dict[str, closed_form.Matrix | SingularBlockError] | None = None

    @property
    def spectral_radius(self) -> float:
        """ρ of the smaller of G and H (eq. 32, 50; inf where A or W is singular), computed on
        first use: a control step that does not report it does not pay for it."""
        if self._spectral_radius is None:
            inverses = None
            if self.blocks is not None:
                try:
                    inverses = (self.block_inverse("A"), self.block_inverse("W"))
                except SingularBlockError:
                    self._spectral_radius = math.inf
                    return self._spectral_radius
            self._spectral_radius = partition_spectral_radius(
                self.jacobian, self.index, self.blocks, self.algorithm, inverses
            )
        return self._spectral_radius

    def block_inverse(self, name: str) -> closed_form.Matrix:
        """A^-1 or W^-1 (``name`` "A" or "W") in closed form, computed once for ρ and the
        conditioning bound alike (``blocks`` must be set). Raises SingularBlockError."""
        if self._inverses is None:
            self._inverses = {}
        if name not in self._inverses:
            assert self.blocks is not None
            try:
                self._inverses[name] = closed_form.inverse(self.blocks[0 if name == "A" else 3], name)
            except SingularBlockError as singular:
                self._inverses[name] = singular
        inverse = self._inverses[name]
        if isinstance(inverse, SingularBlockError):
            raise inverse
        return inverse


@dataclass(slots=True)  # a record, read-only by convention
class Step:
    """The outcome of one control step from ``observation.q``.

    Attributes:
        q: the next configuration (nq,): the rates integrated over dt, clamped to the limits.
        joint_rates: the rates applied (nv,), 0 for joints outside the partition.
        status: the most severe condition met in this step.
        frozen: names of the joints held still in this step.
        twist: the twist commanded after saturation (m + k,), partition order, sensor axes.
        observation: what the controller saw at the start of the step.
        detail: why the status is not OK, in words ("" when OK): which joint, which block,
            what conditioning, what scale.
        conditions: every condition met in this step, least severe first (``status`` is
            the last; empty when OK).
    """

    q: np.ndarray
    joint_rates: np.ndarray
    status: Status
    frozen: tuple[str, ...]
    twist: np.ndarray
    observation: Observation
    detail: str = ""
    conditions: tuple[Status, ...] = ()


class _Limit(NamedTuple):  # a tuple: the per-step test reads it on Python floats
    joint: str
    q_index: int  # into q
    velocity: int  # into v
    lower: float
    upper: float

    def onto_the_limit(self, q: np.ndarray, rate: float, dt: float) -> float:
        """The rate, cut so that the joint ends the step on its limit at most."""
        value = q[self.q_index]
        return min(max(rate, (self.lower - value) / dt), (self.upper - value) / dt)


WATCH_FACTOR = 3.0
"""A decelerating controller looks one step ahead from a conditioning bound under this many
times ``slow_threshold`` when the step is big (:data:`WATCHED_STEP`)."""

WATCHED_STEP = 0.02
"""rad (or m): a step moving some joint further than this, near the singular region, is
judged one step ahead."""

DECELERATING = ("decelerate", "auxiliary_elbow")
"""The strategies that decelerate in the singular region (auxiliary_elbow outside its elbow
region), judging a big step near it one step ahead."""

VELOCITY_LIMIT_UNLIMITED = 1e6
"""A URDF velocity limit of 0 (what converters write for "unknown") or above this (rad/s or
m/s) means no limit."""


class _Facts(NamedTuple):
    """What a controller needs of its robot and partition that no option changes."""

    limits: tuple[_Limit, ...]  # every 1-DOF joint with finite position limits (a jog may move any)
    urdf_velocity_limits: np.ndarray  # (nv,), inf where the URDF gives none
    characteristic_length: float  # L of J at home
    ranks: tuple[int, int, int]  # generic ranks of J, A, W
    velocity_of: dict[str, int]  # joint name -> its first velocity index
    joggable: tuple[str, ...]  # the 1-DOF joints
    wrist_axes: tuple[Axis, ...]  # the wrist's first two rotating joints
    wrist_body: int  # the joint whose body carries the wrist centre


_FACTS: weakref.WeakKeyDictionary[Robot, dict[Partition, tuple[tuple[bytes, ...], _Facts]]] = (
    weakref.WeakKeyDictionary()
)


def _facts(robot: Robot, partition: Partition) -> _Facts:
    """The :class:`_Facts` of ``robot`` and ``partition``, computed once (a servo call builds a
    controller, and these cost more than the run's loop), and again when the model's limits or
    the home configuration they depend on were edited since."""
    model = robot.model
    home_q = robot.home()
    edited = (
        np.asarray(model.lowerPositionLimit).tobytes(),
        np.asarray(model.upperPositionLimit).tobytes(),
        np.asarray(model.velocityLimit).tobytes(),
        home_q.tobytes(),
    )
    cache = _FACTS.setdefault(robot, {})
    if partition not in cache or cache[partition][0] != edited:
        index = partition.resolve(robot)
        limits = []
        for joint in robot.joint_names:
            bounds = robot.joint_limits(joint)
            if bounds is not None:
                joint_model = model.joints[robot.joint_id(joint)]
                limits.append(_Limit(joint, joint_model.idx_q, joint_model.idx_v, *bounds))
        urdf = np.array(model.velocityLimit, dtype=float)
        home = robot.jacobian_unchecked(home_q)[np.ix_(index.rows, index.columns)]
        wrist_ids = [robot.joint_id(name) for name in partition.wrist]
        cache[partition] = (
            edited,
            _Facts(
                limits=tuple(limits),
                urdf_velocity_limits=np.where((urdf > 0) & (urdf < VELOCITY_LIMIT_UNLIMITED), urdf, np.inf),
                characteristic_length=characteristic_length(home, index.m),
                ranks=generic_ranks(robot, partition),
                velocity_of={name: model.joints[robot.joint_id(name)].idx_v for name in robot.joint_names},
                joggable=tuple(name for name in robot.joint_names if model.joints[robot.joint_id(name)].nv == 1),
                wrist_axes=wrist_axes(model, wrist_ids),
                # The wrist centre rides on the body that carries the first wrist joint of the
                # chain (or the tip's body without a wrist).
                wrist_body=model.parents[min(wrist_ids)] if wrist_ids else model.frames[robot.tip_id].parentJoint,
            ),
        )
    return cache[partition][1]


class _Plan(NamedTuple):
    """How a step in the singular region solves: the change of variables of the wrist and the
    frozen joints, the inversion used, and what to report."""

    columns: ColumnMap  # the variables the step solves for (wrist pair merged or held, frozen dropped)
    dropped: frozenset[int]  # partition positions held still by the plan (a held wrist joint, frozen joints)
    merged: tuple[int, int, float] | None  # the wrist pair moving as one (split)
    released_by: tuple[int, int] | None  # (held, last): last_then_first releases held when last is blocked
    invert: Inverter
    value: float  # c of the solved system at q
    block: str
    decelerate: bool
    statuses: tuple[Status, ...]
    details: tuple[str, ...]
    frozen: tuple[str, ...]


class _Auxiliary(NamedTuple):
    """A step under Barker's auxiliary elbow control (:mod:`.elbow`)."""

    bend: float  # elbow - straight (rad)
    outward: float  # the command's component along the upper arm (m/s)
    directions: np.ndarray  # p and, when commanded, n: world directions over the sensor's linear axes (r, m)
    targets: np.ndarray  # TVEL along them (m/s)
    dropped: frozenset[int]  # the wrist rule's held joint
    merged: tuple[int, int, float] | None
    released_by: tuple[int, int] | None
    statuses: tuple[Status, ...]
    details: tuple[str, ...]


CONTROLLED_SHARE = 0.5
"""A world direction counts as commanded when the partition's linear components carry at
least this share of it (a planar arm's twist has no component normal to its plane)."""


class Controller:
    """The resolved-rate control step of a robot (one Robot per controller and thread).

    Args:
        robot: the robot; its tip and sensor frames fix what twists mean.
        algorithm: a name of :data:`pinrate.ALGORITHMS`.
        partition: which joints and twist rows take part; None means ``Partition.auto(robot)``.
        dt: control period in seconds.
        singularity: what a step in the singular region does, a name of
            :data:`~pinrate.control.singularity.STRATEGIES` (see that module).
        wrist: how two aligned wrist axes share a rotation, a name of
            :data:`~pinrate.control.singularity.WRIST_STRATEGIES`.
        velocity_limits: None for the URDF's ``<limit velocity>`` of each joint (none where it
            gives 0 or none), a number for every joint, or one per velocity component (nv,),
            in rad/s or m/s; inf for none. When one binds, all rates are scaled alike.
        position_limits: keep q within the joints' position limits (see the module docstring).
        singular_threshold, slow_threshold: inverse condition numbers σ_min/σ_max of the
            inverted blocks (dimensionless, 0 <= singular < slow <= 1): under ``slow`` a step
            is in the singular region, under ``singular`` a block counts as singular.
        max_linear_speed, max_angular_speed: saturation of the commanded twist (m/s, rad/s;
            inf for none).
        elbow_region: rad; with ``singularity="auxiliary_elbow"``, Barker's elbow control acts
            while the elbow is closer than this to full extension (:mod:`.elbow`). None: the
            bend at which c of the measured block reaches ``slow_threshold`` at home (the
            elbow's whole singular region; 0.15 rad on the UR5), at most
            :data:`~pinrate.control.elbow.ELBOW_REGION`.
        posture: None (off), ``"home"`` or a configuration (nq,): a secondary task for
            redundant partitions moves the joints toward it and away from their limits in
            the null space of the twist (:mod:`.posture`), outside the singular region. Off
            by default, so the step's rates are the algorithm's.
        posture_gain: k (1/s) of the secondary task.
        acceleration_limits: None (the default: a URDF states none; MoveIt keeps them in
            ``joint_limits.yaml``), a number for every joint or one per velocity component
            (nv,), in rad/s² or m/s². With limits, the controller remembers the rates it
            applied last (:meth:`reset` forgets them) and moves each step's rates from those
            toward the new ones by at most a·dt per joint, one factor for all joints, so the
            change keeps its direction (``Status.RATE_LIMITED``). Position limits, the
            collision monitor and halts act at once, whatever the acceleration.
        collision: False (the default), True, or a
            :class:`~pinrate.control.collision.CollisionMonitor`: self-collision in the loop,
            from the URDF's collision geometry less the SRDF's disabled pairs. A step that
            brings two links closer is scaled down under the safety distance and halts before
            the stop distance; motion that separates them is always executed
            (``Status.DECELERATE_FOR_COLLISION``, ``Status.HALT_FOR_COLLISION``). A robot
            without collision geometry is not monitored (a warning says so, once).

    Raises:
        InputError: an unknown algorithm or strategy (the message lists the valid ones), a
            bad partition, a dt or speed that is not positive, thresholds out of order,
            velocity limits that are not positive or of the wrong length.
    """

    def __init__(
        self,
        robot: Robot,
        *,
        algorithm: str = "exact",
        partition: Partition | None = None,
        dt: float = 0.01,
        singularity: str = "decelerate",
        wrist: str = "split",
        velocity_limits: object = None,
        position_limits: bool = True,
        singular_threshold: float = SINGULAR_THRESHOLD,
        slow_threshold: float = SLOW_THRESHOLD,
        max_linear_speed: float = MAX_LINEAR_SPEED,
        max_angular_speed: float = MAX_ANGULAR_SPEED,
        elbow_region: float | None = None,
        posture: object = None,
        posture_gain: float = 1.0,
        acceleration_limits: object = None,
        collision: object = False,
    ) -> None:
        self.robot = robot
        self.algorithm = check_algorithm(algorithm)
        self.partition = partition_for(robot, partition)
        self.index = self.partition.resolve(robot)
        self.dt = check_positive(dt, "dt")
        self.singularity = check_strategy(singularity, STRATEGIES, "singularity strategy")
        self.wrist = check_strategy(wrist, WRIST_STRATEGIES, "wrist strategy")
        self.singular_threshold, self.slow_threshold = check_thresholds(singular_threshold, slow_threshold)
        self.max_linear_speed = check_positive(max_linear_speed, "max_linear_speed", allow_inf=True)
        self.max_angular_speed = check_positive(max_angular_speed, "max_angular_speed", allow_inf=True)
        if not isinstance(position_limits, bool):
            raise InputError(f"position_limits must be True or False, not {position_limits!r}")
        self.position_limits = position_limits
        facts = _facts(robot, self.partition)
        self._limits = facts.limits
        self.velocity_limits = self._velocity_limits(velocity_limits, facts.urdf_velocity_limits)
        self.acceleration_limits = (
            None if acceleration_limits is None else self._per_joint(acceleration_limits, "acceleration_limits")
        )
        self._previous_rates = np.zeros(robot.nv)
        self.collision = self._collision_monitor(collision)
        """The self-collision monitor, or None."""
        self._rate_limit_rows = [
            (velocity, float(limit)) for velocity, limit in enumerate(self.velocity_limits) if math.isfinite(limit)
        ]
        index = self.index
        self._names = self.partition.arm + self.partition.wrist  # partition order
        self._positions = {name: position for position, name in enumerate(self._names)}
        self._measured = measured_blocks(self.algorithm)
        self.characteristic_length = facts.characteristic_length
        """L (m): J's linear rows are divided by it before J is measured or pseudo-inverted."""
        self._row_scale = row_scale(index.m, index.k, self.characteristic_length)
        self._row_scale_column = self._row_scale[:, None]
        ranks = facts.ranks
        self._ranks = {"J": ranks[0], "A": ranks[1], "W": ranks[2]}
        self._square_j = index.rows.size == index.columns.size == ranks[0]
        self._velocity_of = facts.velocity_of
        self.joggable: tuple[str, ...] = facts.joggable
        self._wrist_axes = facts.wrist_axes
        self._wrist_body = facts.wrist_body
        self._centre_data: pin.Data | None = None  # Uncoupled commands' own, made on first use
        self.posture_gain = check_positive(posture_gain, "posture_gain")
        self._posture = self._posture_joints(posture)
        self.elbow: Elbow | None = None
        """The arm's elbow and shoulder when ``singularity="auxiliary_elbow"`` found one."""
        self.elbow_region = 0.0 if elbow_region is None else check_positive(elbow_region, "elbow_region")
        if self.singularity == "auxiliary_elbow":
            self._elbow_data = robot.model.createData()
            self.elbow = find_elbow(robot, self.partition, self._singular_with)
            if self.elbow is not None:
                bent = float(robot.home()[self.elbow.q_index]) - self.elbow.straight
                self._first_bend_sign = -1.0 if bent < 0.0 else 1.0  # the first bend goes the home's way
                self._bend_sign = self._first_bend_sign
                if elbow_region is None:
                    self.elbow_region = self._slow_bend(self.elbow)

    def compiled(self) -> CoreServo | None:
        """The compiled twin of this controller (:mod:`pinrate.compiled`) with its settings as
        they are now; None where the Python path is chosen or the configuration is one the
        core does not cover (:meth:`compiled_reason` says which)."""
        if self.compiled_reason() is not None:
            return None
        # Everything _compiled_settings reads: a servo call builds a controller afresh, and the
        # same settings come back.
        key = (
            self.partition,
            self.algorithm,
            self.dt,
            self.max_linear_speed,
            self.max_angular_speed,
            self.slow_threshold,
            self.singularity,
            self.position_limits,
            self.velocity_limits.tobytes(),
            self._limits,
            self.characteristic_length,
            self._square_j,
            tuple(self._ranks.values()),
        )
        try:
            return core_servo(self.robot, key, self._compiled_settings)
        except UnsupportedByCoreError:
            return None

    def compiled_reason(self) -> str | None:
        """Why this controller's loops run on Python though the core may be there (None when
        nothing in the configuration stops the core)."""
        try:
            if core_kinematics(self.robot) is None:
                return backend().reason
        except UnsupportedByCoreError as unsupported:
            return str(unsupported)
        if self.elbow is not None:
            return "auxiliary elbow control runs on the Python path"
        if self._posture is not None:
            return "a posture task runs on the Python path"
        if self.acceleration_limits is not None:
            return "acceleration limits run on the Python path"
        if self.collision is not None:
            return "the collision monitor runs on the Python path"
        if not self.index.small and not self.index.pseudo_g:
            return "a tall A or a wide W (rho is then the error map's) runs on the Python path"
        return None

    def _compiled_settings(self) -> ServoSettings:
        index = self.index
        return ServoSettings(
            rows=tuple(index.rows.tolist()),
            columns=tuple(index.columns.tolist()),
            m=index.m,
            n_arm=int(index.arm_columns.size),
            algorithm=self.algorithm,
            measured=self._measured,
            row_scale=tuple(self._row_scale.tolist()),
            slow_threshold=self.slow_threshold,
            watch=self.singularity in DECELERATING,
            watch_factor=WATCH_FACTOR,
            watched_step=WATCHED_STEP,
            max_linear_speed=self.max_linear_speed,
            max_angular_speed=self.max_angular_speed,
            dt=self.dt,
            position_limits=self.position_limits,
            limits=tuple((limit.q_index, limit.velocity, limit.lower, limit.upper) for limit in self._limits),
            rate_limits=tuple(self._rate_limit_rows),
            exact_rcond=EXACT_RCOND,
            dls_damping=DLS_DAMPING,
            small=index.small,
            ranks=(self._ranks["J"], self._ranks["A"], self._ranks["W"]),
        )

    def position_limit(self, number: int) -> _Limit:
        """The ``number``-th position limit the controller keeps (the compiled core names a
        clamped joint by it)."""
        return self._limits[number]

    def _posture_joints(self, posture: object) -> PostureJoints | None:
        """The secondary task's joints and preferred posture, or None when it is off."""
        if posture is None:
            return None
        if isinstance(posture, str):
            if posture != "home":
                raise InputError(f"posture must be None, 'home' or a configuration ({self.robot.nq},), not {posture!r}")
            preferred = self.robot.home()
        else:
            preferred = self.robot.check_q(posture)
        model = self.robot.model
        positions, q_indices = [], []
        for position, name in enumerate(self._names):
            joint = model.joints[self.robot.joint_id(name)]
            if joint.nq == 1:
                positions.append(position)
                q_indices.append(joint.idx_q)
        lower, upper = (np.array(bounds)[q_indices] for bounds in self.robot.position_limits())
        return posture_joints(positions, q_indices, lower, upper, preferred[q_indices])

    def _null_motion(self, observation: Observation, left_out: frozenset[str]) -> np.ndarray:
        """Rates (nv,) of the secondary task: -k ∇H projected onto the null space of the
        partition's J without the ``left_out`` joints (:mod:`.posture`)."""
        joints = self._posture
        assert joints is not None
        index = self.index
        descent = np.zeros(index.columns.size)
        descent[joints.positions] = -self.posture_gain * posture_gradient(joints, observation.q)
        kept = [position for position, name in enumerate(self._names) if name not in left_out]
        scaled = self._reduced(observation.jacobian)[:, kept] * self._row_scale_column
        rates = np.zeros(self.robot.nv)
        rates[index.columns[kept]] = null_space_motion(scaled, descent[kept], self.singular_threshold)
        return rates

    def _null_room(self, task: np.ndarray, null: np.ndarray) -> float:
        """The largest α in [0, 1] keeping task + α null within the velocity limits (0 when the
        task alone exceeds one): the secondary motion gives way before a velocity limit can
        scale the commanded twist."""
        room = 1.0
        task_values, null_values = task.tolist(), null.tolist()
        for velocity, limit in self._rate_limit_rows:
            rate, extra = task_values[velocity], null_values[velocity]
            if extra == 0.0:
                continue
            if abs(rate) >= limit:
                return 0.0
            room = min(room, (limit - math.copysign(1.0, extra) * rate) / abs(extra))
        return max(room, 0.0)

    def _slow_bend(self, elbow: Elbow) -> float:
        """The bend from full extension (rad, toward home's side, others at home) at which c of
        the measured blocks reaches ``slow_threshold``, by bisection; at most ELBOW_REGION."""
        q = self.robot.home()
        sense = self._bend_sign

        def slow_at(bend: float) -> bool:
            q[elbow.q_index] = elbow.straight + sense * bend
            return self.conditioning(q).value < self.slow_threshold

        if slow_at(ELBOW_REGION):
            return ELBOW_REGION
        low, high = 0.0, ELBOW_REGION
        for _ in range(30):
            middle = 0.5 * (low + high)
            low, high = (middle, high) if slow_at(middle) else (low, middle)
        return high

    def _singular_with(self, q: np.ndarray, position: int) -> bool:
        """Whether a measured block is singular at q with the joint at ``position`` carrying
        the lost motion."""
        weakest = self.conditioning(q)
        return weakest.value < self.singular_threshold and position in carrying_joints(weakest)

    def _velocity_limits(self, limits: object, urdf: np.ndarray) -> np.ndarray:
        """Per velocity component (nv,), inf where there is none."""
        if limits is None:
            return urdf.copy()
        return self._per_joint(limits, "velocity_limits")

    def _per_joint(self, limits: object, what: str) -> np.ndarray:
        """One positive limit per velocity component (nv,) from a number or an (nv,) array."""
        if np.ndim(limits) == 0:  # type: ignore[arg-type]  # any object: check_positive names a bad one
            value = check_positive(limits, what, allow_inf=True)
            return np.full(self.robot.nv, value)
        try:
            values = np.array(limits, dtype=float)
        except (TypeError, ValueError):
            raise InputError(f"{what} must be numbers, not {type(limits).__name__}") from None
        if values.shape != (self.robot.nv,):
            raise InputError(
                f"{what} must be one number or {self.robot.nv} (one per velocity component of "
                f"{self.robot.name!r}), got shape {values.shape}"
            )
        if np.isnan(values).any() or (values <= 0).any():
            raise InputError(f"{what} must be positive (inf for none), got {values}")
        return values

    def _collision_monitor(self, collision: object) -> CollisionMonitor | None:
        if isinstance(collision, CollisionMonitor):
            if collision.robot is not self.robot:
                raise InputError("the CollisionMonitor was built for another Robot object; build it on this one")
            return collision if collision.active else None
        if collision is False or collision is None:
            return None
        if collision is True:
            monitor = CollisionMonitor(self.robot)
            return monitor if monitor.active else None
        raise InputError(f"collision must be True, False or a CollisionMonitor, not {collision!r}")

    def reset(self) -> None:
        """Forget what earlier steps left: the rates applied last (an acceleration-limited
        motion starts at rest) and the side of the elbow's last bend (the next bend from full
        extension goes the home's way)."""
        self._previous_rates = np.zeros(self.robot.nv)
        if self.elbow is not None:
            self._bend_sign = self._first_bend_sign

    # ------------------------------------------------------------------ seeing
    def observe(self, q: object, goal: PoseGoal | None = None) -> Observation:
        """Kinematics and blocks at q (one Pinocchio pass); the pose error to ``goal`` too
        when given. q is checked (:meth:`Robot.check_q`)."""
        if goal is not None and not isinstance(goal, PoseGoal):
            raise InputError(f"goal must be a PoseGoal (PoseGoal.of(target, gain)), not {type(goal).__name__}")
        return self.observe_unchecked(self.robot.check_q(q), goal)

    def observe_unchecked(self, q: np.ndarray, goal: PoseGoal | None = None) -> Observation:
        """:meth:`observe` at a q that already went through :meth:`Robot.check_q` (or came out
        of a step): the servo's hot path."""
        index = self.index
        jacobian, world_T_tip, world_T_sensor = self.robot.kinematics(q)
        error = None if goal is None else pose_error(world_T_tip, world_T_sensor, goal.target)[index.rows]
        parts = closed_form.blocks(jacobian, index.selectors) if index.small else None
        return Observation(q, jacobian, world_T_tip, world_T_sensor, parts, self.algorithm, index, goal, error)

    def conditioning(self, q: object) -> Conditioning:
        """The least inverse condition number σ_r/σ_1 of the blocks the algorithm inverts at q,
        which block, and its weakest joint motion (:mod:`pinrate.control.singularity`)."""
        return self.observed_conditioning(self.observe(q))

    def observed_conditioning(self, observation: Observation) -> Conditioning:
        """:meth:`conditioning` from an observation already made: no kinematics, so another
        thread (a display) may call it beside the control loop."""
        return self._conditioning(self._reduced(observation.jacobian), self.index.arm_columns.size)

    def _reduced(self, jacobian: np.ndarray) -> np.ndarray:
        """J restricted to the partition (m + k, n), partition order."""
        index = self.index
        return jacobian if index.all_rows and index.all_columns else jacobian[np.ix_(index.rows, index.columns)]

    def _conditioning(self, reduced: np.ndarray, n_arm: int) -> Conditioning:
        return conditioning(reduced, self.index.m, n_arm, self._measured, self._row_scale, self._ranks)

    def _conditioning_bound(self, observation: Observation) -> float:
        """A cheap lower bound of the least c of the measured blocks (0.0 where none is cheap):
        1 / (||M||_F ||M^-1||_F) from the closed-form inverses of A, W and numpy's of J."""
        bound = math.inf
        for name in self._measured:
            if name == "J":
                if not self._square_j:
                    return 0.0
                scaled = self._reduced(observation.jacobian) * self._row_scale_column
                try:
                    bound = min(bound, inverse_condition_bound(scaled, np.linalg.inv(scaled)))
                except np.linalg.LinAlgError:
                    return 0.0
                continue
            parts = observation.blocks
            if parts is None:
                return 0.0
            block = parts[0] if name == "A" else parts[3]
            if not block or not block[0]:
                continue
            try:
                bound = min(bound, inverse_condition_bound(block, observation.block_inverse(name)))
            except SingularBlockError:
                return 0.0
        return bound

    # ------------------------------------------------------------------ acting
    def command_twist(self, observation: Observation, command: np.ndarray | PoseGoal) -> tuple[np.ndarray, bool]:
        """(twist, saturated): the command as a saturated twist in partition order, sensor axes."""
        m = self.index.m
        if isinstance(command, PoseGoal):
            error = observation.error if observation.goal is command else None
            if error is None:
                error = pose_error(observation.world_T_tip, observation.world_T_sensor, command.target)[self.index.rows]
            wanted = command.gain * error
        else:
            wanted = command
        linear, saturated_linear = saturate(wanted[:m], self.max_linear_speed)
        angular, saturated_angular = saturate(wanted[m:], self.max_angular_speed)
        return np.concatenate([linear, angular]), saturated_linear or saturated_angular

    def step(self, q: object, command: object, *, observation: Observation | None = None) -> Step:
        """One control step from q: command -> twist -> joint rates -> next q.

        Args:
            q: the configuration (nq,); checked unless ``observation`` (taken at q) is given.
            command: a twist (m + k,) in partition order, sensor axes (m/s, rad/s), a
                :class:`PoseGoal`, a :class:`JointJog` or an :class:`Uncoupled` command
                (:mod:`pinrate.control.commands`).
            observation: :meth:`observe` at q, when the caller already has it (the servo
                measures its stop rules on it): it is reused, not recomputed.

        In the singular region the ``singularity=`` and ``wrist=`` strategies decide
        (:mod:`pinrate.control.singularity`); joints that the command would carry past a
        position limit are held at it while the others serve the command
        (``Status.JOINT_LIMIT``, ``frozen``); rates over a velocity limit are all scaled alike
        (``Status.RATE_LIMITED``). Never raises for what the robot does, and never returns
        NaN or inf.
        """
        if observation is None:
            observation = self.observe(q)
        if isinstance(command, JointJog):
            return self._jog(observation, command)
        if isinstance(command, Uncoupled):
            return self._uncoupled(observation, command)
        if not isinstance(command, PoseGoal):
            command = check_vector(command, self.index.rows.size, "twist (linear then angular components)")
        twist, saturated = self.command_twist(observation, command)
        statuses = [Status.TWIST_SATURATED] if saturated else []
        details: list[str] = []
        bound = self._conditioning_bound(observation)
        auxiliary = self._auxiliary(observation, twist) if self.elbow is not None else None
        plan = self._plan(observation, twist) if auxiliary is None and bound < self.slow_threshold else None
        frozen: tuple[str, ...] = ()
        if auxiliary is not None:

            def solve(left_out: frozenset[str]) -> np.ndarray:
                return self._solve_auxiliary(observation, twist, auxiliary, left_out)

            statuses.extend(auxiliary.statuses)
            details.extend(auxiliary.details)
        elif plan is None:

            def solve(left_out: frozenset[str]) -> np.ndarray:
                return self._solve_without(observation, twist, left_out)

        else:

            def solve(left_out: frozenset[str]) -> np.ndarray:
                return self._solve_planned(observation, twist, plan, left_out)

            statuses.extend(plan.statuses)
            details.extend(plan.details)
            frozen = plan.frozen
        if self._posture is not None and plan is None and auxiliary is None:
            task = solve

            def solve(left_out: frozenset[str]) -> np.ndarray:
                rates = task(left_out)
                null = self._null_motion(observation, left_out)
                return rates + self._null_room(rates, null) * null

        try:
            rates = solve(frozenset())
            rates, frozen = self._hold_at_position_limits(observation, rates, solve, statuses, details, frozen)
        except SingularBlockError as singular:
            return self._halt(observation, twist, str(singular))
        watched = None if auxiliary is not None else self._watched(observation, plan, bound, rates)
        if watched is not None:
            scale, status, detail = self._decelerate(observation, rates, *watched)
            if status is Status.HALT_FOR_SINGULARITY:
                return self._halt(observation, twist, detail)
            if status is not Status.OK:
                rates = rates * scale
                statuses.append(status)
                details.append(detail)  # NEAR_SINGULARITY: a way out, scale 1
        return self._finish(observation, twist, rates, statuses, details, frozen)

    # ------------------------------------------------------------------ other commands
    def _jog(self, observation: Observation, jog: JointJog) -> Step:
        """A joint jog: the named joints at their rates, the others still; then the limits.
        ``Step.twist`` is the twist the jog produces at q (partition rows, sensor axes)."""
        requested = joint_rate_vector(jog.rates, self.joggable, self._velocity_of, self.robot.nv, "JointJog")
        statuses: list[Status] = []
        details: list[str] = []

        def solve(left_out: frozenset[str]) -> np.ndarray:
            rates = requested.copy()
            for name in left_out:
                rates[self._velocity_of[name]] = 0.0
            return rates

        rates, frozen = self._hold_at_position_limits(observation, requested.copy(), solve, statuses, details, ())
        step = self._finish(observation, np.zeros(self.index.rows.size), rates, statuses, details, frozen)
        step.twist = self._reduced_rows(observation.jacobian) @ step.joint_rates
        return step

    def _uncoupled(self, observation: Observation, command: Uncoupled) -> Step:
        """Barker's uncoupled mode: the wrist joints at the rates named, the arm joints moving
        the wrist centre (a point of the arm's last body) with the linear command, by the
        generalized inverse of its arm Jacobian (:mod:`pinrate.control.commands`)."""
        index = self.index
        m = index.m
        if command.linear.size != m:
            raise InputError(
                f"Uncoupled.linear must have the partition's {m} linear components ({self.partition.linear}), "
                f"got {command.linear.size}"
            )
        wrist = joint_rate_vector(
            command.wrist, self.partition.wrist, self._velocity_of, self.robot.nv, "Uncoupled.wrist"
        )
        centre_jacobian = self._wrist_centre_jacobian(observation)  # (m, n_arm): sensor axes
        value = 1.0
        statuses: list[Status] = []
        details: list[str] = []
        if centre_jacobian.size:
            value, _ = inverse_condition(centre_jacobian, min(centre_jacobian.shape))
            if value < self.slow_threshold:
                statuses.append(Status.NEAR_SINGULARITY)
                details.append(f"the arm's wrist-centre block is near singular (c = {value:.2g}): generalized inverse")

        def solve(left_out: frozenset[str]) -> np.ndarray:
            rates = wrist.copy()
            for name in left_out:
                rates[self._velocity_of[name]] = 0.0
            kept = [position for position, name in enumerate(self.partition.arm) if name not in left_out]
            if kept:
                arm = truncated_pinv(centre_jacobian[:, kept], self.singular_threshold) @ command.linear
                rates[index.arm_columns[kept]] = arm
            return rates

        rates, frozen = self._hold_at_position_limits(observation, solve(frozenset()), solve, statuses, details, ())
        step = self._finish(observation, np.zeros(index.rows.size), rates, statuses, details, frozen)
        step.twist = self._reduced_rows(observation.jacobian) @ step.joint_rates
        return step

    def _wrist_centre_jacobian(self, observation: Observation) -> np.ndarray:
        """(m, n_arm): the wrist centre's velocity per arm joint rate, in the sensor frame's
        controlled linear axes (m/s per rad/s): a point of the body that carries the first
        wrist joint, so the wrist joints do not move it."""
        model = self.robot.model
        if self._centre_data is None:
            self._centre_data = model.createData()
        data = self._centre_data
        q = observation.q
        index = self.index
        pin.computeJointJacobians(model, data, q)
        pin.updateFramePlacements(model, data)
        centre = wrist_centre(data, self._wrist_axes, np.array(data.oMf[self.robot.tip_id].translation))
        body = self._wrist_body
        jacobian = pin.getJointJacobian(model, data, body, pin.ReferenceFrame.LOCAL_WORLD_ALIGNED)
        lever = centre - np.array(data.oMi[body].translation)
        linear = jacobian[:3] - np.cross(lever, jacobian[3:].T).T  # v_p = v_i + ω_i x (p - o_i)
        sensor = observation.world_T_sensor.rotation
        return (sensor.T @ linear)[index.rows[:m]][:, index.arm_columns] if (m := index.m) else np.zeros((0, 0))

    def _reduced_rows(self, jacobian: np.ndarray) -> np.ndarray:
        """J's controlled rows (m + k, nv)."""
        return jacobian[self.index.rows]

    def _hold_at_position_limits(
        self,
        observation: Observation,
        rates: np.ndarray,
        solve: Callable[[frozenset[str]], np.ndarray],
        statuses: list[Status],
        details: list[str],
        frozen: tuple[str, ...],
    ) -> tuple[np.ndarray, tuple[str, ...]]:
        """(rates, frozen) after step 5 of the module docstring: joints that ``rates`` would
        carry past a position limit are held at it and ``solve`` runs without them; the
        condition is appended to ``statuses`` and ``details``. Raises SingularBlockError as
        ``solve`` does."""
        passing = self._passing(observation.q, rates, ()) if self.position_limits else []
        if not passing:
            return rates, frozen
        try:
            rates, blocked = self._respect_position_limits(observation, rates, passing, solve)
        except SingularBlockError as singular:
            raise SingularBlockError(f"{singular}, with the joints at their limits left out") from None
        if blocked:
            statuses.append(Status.JOINT_LIMIT)
            details.append(f"held at a position limit: {', '.join(blocked)}")
            frozen = frozen + tuple(name for name in blocked if name not in frozen)
        return rates, frozen

    def _finish(
        self,
        observation: Observation,
        twist: np.ndarray,
        rates: np.ndarray,
        statuses: list[Status],
        details: list[str],
        frozen: tuple[str, ...],
    ) -> Step:
        """The end of every step: velocity limits (one scale factor), integration over dt,
        the clamp to the position limits, the status."""
        scale = self._rate_scale(rates)
        if scale < 1.0:
            rates = rates * scale
            statuses.append(Status.RATE_LIMITED)
            details.append(f"rates scaled by {scale:.3g} to meet the velocity limits")
        if self.acceleration_limits is not None:
            rates = self._limit_acceleration(observation.q, rates, frozen, statuses, details)
        if self.collision is not None:
            verdict = self.collision.limit(observation.q, rates, self.dt)
            if verdict.status is Status.HALT_FOR_COLLISION:
                return self._halt(observation, twist, verdict.detail, Status.HALT_FOR_COLLISION)
            if verdict.scale < 1.0:
                rates = rates * verdict.scale
                statuses.append(verdict.status)
                details.append(verdict.detail)
        if self.acceleration_limits is not None:
            self._previous_rates = rates.copy()  # the rates applied, after every scaling
        next_q = self.robot.integrate(observation.q, rates, self.dt)
        if self.elbow is not None:
            self._reach_extension(observation.q, next_q)
        if self.position_limits:
            hit = self._clamp(next_q)
            if hit and Status.JOINT_LIMIT not in statuses:
                statuses.append(Status.JOINT_LIMIT)
                details.append(hit)
        conditions = ranked(statuses)
        status = conditions[-1] if conditions else Status.OK
        return Step(next_q, rates, status, frozen, twist, observation, "; ".join(details), conditions)

    def _halt(
        self, observation: Observation, twist: np.ndarray, detail: str, status: Status = Status.HALT_FOR_SINGULARITY
    ) -> Step:
        self._previous_rates = np.zeros(self.robot.nv)
        return Step(observation.q.copy(), np.zeros(self.robot.nv), status, (), twist, observation, detail, (status,))

    # ------------------------------------------------------------------ singular region
    def _watched(
        self, observation: Observation, plan: _Plan | None, bound: float, rates: np.ndarray
    ) -> tuple[ColumnMap, float, str] | None:
        """(columns, c, block) when ``singularity="decelerate"`` must judge this step one step
        ahead: every step in the singular region, and a step from just outside it (bound
        under :data:`WATCH_FACTOR` x slow) that moves some joint more than
        :data:`WATCHED_STEP` rad, which could enter the region or cross a singularity in one
        step (a servo's big steps do). None otherwise."""
        if self.singularity not in DECELERATING:
            return None
        if plan is not None:
            return (plan.columns, plan.value, plan.block) if plan.decelerate else None
        if (
            bound >= WATCH_FACTOR * self.slow_threshold
            or float(np.abs(rates).max(initial=0.0)) * self.dt <= WATCHED_STEP
        ):
            return None
        index = self.index
        columns = ColumnMap.of(index.arm_columns.size, index.wrist_columns.size, frozenset(), None)
        here = self._conditioning(self._reduced(observation.jacobian), index.arm_columns.size)
        return columns, here.value, here.block

    def _plan(self, observation: Observation, twist: np.ndarray) -> _Plan | None:
        """How to solve at a q whose cheap bound fell under ``slow_threshold``; None when the
        exact c of every measured block is above it after all."""
        reduced = self._reduced(observation.jacobian)
        n_arm, n_wrist = self.index.arm_columns.size, self.index.wrist_columns.size
        weakest = self._conditioning(reduced, n_arm)
        if weakest.value >= self.slow_threshold:
            return None
        statuses: list[Status] = []
        details: list[str] = []
        dropped: frozenset[int] = frozenset()
        merged = released_by = None
        rule = self._wrist_rule(weakest, n_arm)
        if rule is not None:
            dropped, merged, released_by, detail = rule
            statuses.append(Status.WRIST_SINGULARITY)
            details.append(detail)
            columns = ColumnMap.of(n_arm, n_wrist, dropped, merged)
            weakest = self._conditioning(reduced @ columns.matrix, columns.n_arm)
        generalized = generalized_inverter(self.singular_threshold)
        columns = ColumnMap.of(n_arm, n_wrist, dropped, merged)
        if weakest.value >= self.slow_threshold:
            return _Plan(
                columns,
                dropped,
                merged,
                released_by,
                generalized,
                weakest.value,
                weakest.block,
                False,
                tuple(statuses),
                tuple(details),
                (),
            )
        where = f"block {weakest.block} near singular (c = {weakest.value:.2g} < {self.slow_threshold:g})"
        frozen: tuple[str, ...] = ()
        invert, decelerate = generalized, False
        if self.singularity in DECELERATING:  # outside the elbow's region
            decelerate = True
        elif self.singularity == "generalized_inverse":
            statuses.append(Status.NEAR_SINGULARITY)
            cut = "directions cut" if weakest.value < self.singular_threshold else "no direction cut"
            details.append(f"{where}: generalized inverse, {cut}")
        elif self.singularity == "adaptive_dls":
            damping = adaptive_damping(weakest.value, self.slow_threshold)
            invert = damped_inverter(damping)
            statuses.append(Status.NEAR_SINGULARITY)
            details.append(f"{where}: damped least squares, λ = {damping:.2g} σ_1")
        else:  # freeze
            plan = _Plan(
                columns, dropped, merged, released_by, generalized, weakest.value, weakest.block, False, (), (), ()
            )
            free = self._solve_planned(observation, twist, plan, frozenset())
            ahead, crossed = self._lookahead(observation, free, columns)
            if crossed or ahead <= weakest.value:  # the free step would not raise c: freeze
                carrying = {
                    position
                    for variable in carrying_joints(weakest)
                    for position in np.flatnonzero(columns.matrix[:, variable]).tolist()
                }
                dropped = dropped | frozenset(carrying)
                frozen = tuple(self._names[position] for position in sorted(carrying))
                columns = ColumnMap.of(n_arm, n_wrist, dropped, merged)
                statuses.append(Status.FROZEN)
                details.append(f"{where}: {', '.join(frozen)} held still")
            else:
                statuses.append(Status.NEAR_SINGULARITY)
                details.append(f"{where}: the step of all joints raises c, none frozen")
        return _Plan(
            columns,
            dropped,
            merged,
            released_by,
            invert,
            weakest.value,
            weakest.block,
            decelerate,
            tuple(statuses),
            tuple(details),
            frozen,
        )

    def _auxiliary(self, observation: Observation, twist: np.ndarray) -> _Auxiliary | None:
        """Barker's auxiliary elbow control at this q, or None: the elbow is outside its region,
        or the upper arm's direction is not among the commanded linear components."""
        elbow = self.elbow
        assert elbow is not None
        q = observation.q
        bend = float(q[elbow.q_index]) - elbow.straight
        if abs(bend) >= self.elbow_region:
            return None
        pin.forwardKinematics(self.robot.model, self._elbow_data, q)
        frame = arm_frame(elbow, self._elbow_data, np.array(observation.world_T_tip.translation))
        if frame is None:
            return None
        index = self.index
        m = index.m
        sensor_rotation = observation.world_T_sensor.rotation
        axes = index.rows[:m]  # the sensor's linear axes the twist commands
        commanded = sensor_rotation[:, axes]  # their world directions (3, m)
        if np.linalg.norm(commanded.T @ frame.outward) < CONTROLLED_SHARE:
            return None
        world_linear = commanded @ twist[:m]  # TVEL in the world (m/s)
        directions = [
            world for world in (frame.pitch, frame.normal) if np.linalg.norm(commanded.T @ world) >= CONTROLLED_SHARE
        ]
        n_arm = index.arm_columns.size
        dropped: frozenset[int] = frozenset()
        merged = released_by = None
        statuses = [Status.AUXILIARY_ELBOW]
        outward = float(frame.outward @ world_linear)
        way = "retracts" if outward < 0.0 else "straightens" if abs(bend) > EXTENDED else "holds (outward command)"
        details = [f"{elbow.joint} {abs(bend):.3g} rad from full extension: auxiliary elbow control, the elbow {way}"]
        rows = np.array([commanded.T @ world for world in directions]).reshape(len(directions), m)
        # The rows left to the joints other than the elbow: near singular, they are the wrist's
        # (two aligned axes: the wrist rule) or another block's (the generalized inverse cuts).
        others = ColumnMap.of(n_arm, index.wrist_columns.size, frozenset([elbow.position]), None).matrix
        left = self._auxiliary_rows(observation, rows) @ others
        if left.size:
            value, motion = inverse_condition(left, min(left.shape))
            if value < self.slow_threshold:
                weakest = Conditioning(value, "rows left to the other joints", others @ motion)
                rule = self._wrist_rule(weakest, n_arm)
                if rule is not None:
                    dropped, merged, released_by, detail = rule
                    statuses.append(Status.WRIST_SINGULARITY)
                    details.append(detail)
                else:
                    statuses.append(Status.NEAR_SINGULARITY)
                    details.append(f"the rows left to the other joints are near singular (c = {value:.2g})")
        return _Auxiliary(
            bend,
            outward,
            rows,
            np.array([float(world @ world_linear) for world in directions]),
            dropped,
            merged,
            released_by,
            tuple(statuses),
            tuple(details),
        )

    def _solve_auxiliary(
        self, observation: Observation, twist: np.ndarray, auxiliary: _Auxiliary, left_out: frozenset[str]
    ) -> np.ndarray:
        """Rates (nv,) under auxiliary elbow control: the elbow by eq. 45; the shoulder and the
        other joints (less ``left_out`` and the wrist rule's held joint) by the generalized
        inverse of the pitch row (eq. 46's coefficients for shoulder and elbow), the normal
        row and the angular rows, less what the elbow produces there (:mod:`.elbow`)."""
        elbow = self.elbow
        assert elbow is not None
        index = self.index
        m = index.m
        partition_rates = np.zeros(index.columns.size)
        if elbow.joint not in left_out:
            partition_rates[elbow.position] = elbow_rate(
                elbow, auxiliary.bend, self._bend_sign, auxiliary.outward, self.elbow_region, self.dt
            )
        dropped = auxiliary.dropped | {self._positions[name] for name in left_out}
        if auxiliary.released_by is not None and auxiliary.released_by[1] in dropped:
            dropped = dropped - {auxiliary.released_by[0]}
        columns = ColumnMap.of(
            index.arm_columns.size, index.wrist_columns.size, dropped | {elbow.position}, auxiliary.merged
        )
        matrix = self._auxiliary_rows(observation, auxiliary.directions)
        target = np.concatenate([auxiliary.targets / self.characteristic_length, twist[m:]])
        partition_rates += remaining_rates(
            matrix, target - matrix @ partition_rates, columns.matrix, self.singular_threshold
        )
        rates = np.zeros(self.robot.nv)
        rates[index.columns] = partition_rates
        return rates

    def _auxiliary_rows(self, observation: Observation, directions: np.ndarray) -> np.ndarray:
        """The rows solved under auxiliary elbow control (r + k, n): the velocities along
        ``directions`` (p, and n when commanded; over the sensor's linear axes) per joint rate,
        over the characteristic length as the generalized inverse's rows, then J's angular rows."""
        reduced = self._reduced(observation.jacobian)
        linear = directions @ reduced[: self.index.m]
        return np.vstack([linear / self.characteristic_length, reduced[self.index.m :]])

    def _reach_extension(self, q: np.ndarray, next_q: np.ndarray) -> None:
        """After any step (a twist, a jog, a playback): a step that brings the elbow to full
        extension puts it exactly there, and one that reaches or crosses it makes the next bend
        from full extension go the other way (Barker: K3 changes sign each time)."""
        elbow = self.elbow
        assert elbow is not None
        bend = float(q[elbow.q_index]) - elbow.straight
        after = float(next_q[elbow.q_index]) - elbow.straight
        if abs(bend) > EXTENDED and (abs(after) <= EXTENDED or after * bend < 0.0):
            if abs(after) <= EXTENDED:
                next_q[elbow.q_index] = elbow.straight
            self._bend_sign = -math.copysign(1.0, bend)

    def _wrist_rule(
        self, weakest: Conditioning, n_arm: int
    ) -> tuple[frozenset[int], tuple[int, int, float] | None, tuple[int, int] | None, str] | None:
        """(dropped, merged, released_by, detail) of the ``wrist=`` rule when the weakest
        motion is a wrist pair's (two aligned axes), else None."""
        pair = wrist_pair(weakest, n_arm)
        if pair is None:
            return None
        first, last, _ = pair
        names = f"{self._names[first]} and {self._names[last]}"
        dropped: frozenset[int] = frozenset()
        merged = released_by = None
        if self.wrist == "split":
            merged = pair
            how = "they share the rotation about the common axis"
        else:
            dropped = frozenset([first])
            released_by = (first, last) if self.wrist == "last_then_first" else None
            how = f"{self._names[first]} holds, {self._names[last]} takes the rotation"
        return (
            dropped,
            merged,
            released_by,
            f"wrist axes of {names} aligned (c({weakest.block}) = {weakest.value:.2g}): {how}",
        )

    def _solve_planned(
        self, observation: Observation, twist: np.ndarray, plan: _Plan, left_out: frozenset[str]
    ) -> np.ndarray:
        """Rates (nv,) by the plan's change of variables and inversion, ``left_out`` joints
        (blocked at a limit) held too. Finite for every J."""
        index = self.index
        dropped = plan.dropped | {self._positions[name] for name in left_out}
        if plan.released_by is not None and plan.released_by[1] in dropped:
            dropped = dropped - {plan.released_by[0]}  # last_then_first: the last is held, the first turns
        columns = (
            plan.columns
            if dropped == plan.dropped
            else ColumnMap.of(index.arm_columns.size, index.wrist_columns.size, dropped, plan.merged)
        )
        reduced = self._reduced(observation.jacobian) @ columns.matrix
        solved = filtered_rates(reduced, index.m, columns.n_arm, twist, self.algorithm, plan.invert, self._row_scale)
        rates = np.zeros(self.robot.nv)
        rates[index.columns] = columns.matrix @ solved
        return rates

    def _signs(self, reduced: np.ndarray, n_arm: int) -> tuple[float, ...]:
        """Signs of the determinants of the measured blocks that are square: a step that
        flips one has crossed a singularity, whatever c is at its two ends."""
        blocks = (block_of(name, reduced, self.index.m, n_arm, self._row_scale) for name in self._measured)
        return tuple(float(np.sign(np.linalg.det(M))) for M in blocks if M.size and M.shape[0] == M.shape[1])

    def _lookahead(self, observation: Observation, rates: np.ndarray, columns: ColumnMap) -> tuple[float, bool]:
        """(c, crossed): c of the system ``columns`` solves one step of ``rates`` ahead (one
        kinematics pass), and whether the step crosses a singularity of a square block."""
        here = self._reduced(observation.jacobian) @ columns.matrix
        ahead = self._reduced(self.robot.kinematics(self.robot.integrate(observation.q, rates, self.dt))[0])
        ahead = ahead @ columns.matrix
        signs = zip(self._signs(here, columns.n_arm), self._signs(ahead, columns.n_arm), strict=True)
        crossed = any(now * then < 0.0 for now, then in signs)  # leaving det = 0 is no crossing
        return self._conditioning(ahead, columns.n_arm).value, crossed

    def _decelerate(
        self, observation: Observation, rates: np.ndarray, columns: ColumnMap, value: float, block: str
    ) -> tuple[float, Status, str]:
        """(scale, status, detail) of a step at c = ``value``, judged one step ahead: unscaled
        when it raises c (without crossing a singularity); a halt when the unscaled step
        would cross a singularity or carry c under singular_threshold (with the margin of
        :func:`~pinrate.control.singularity.halts`); else scaled by
        (c - singular) / (slow - singular), c the lesser of now and ahead."""
        ahead, crossed = self._lookahead(observation, rates, columns)
        where = f"block {block} near singular (c = {min(value, ahead):.2g})"
        crossed = crossed and value >= self.singular_threshold  # sign(det) next to det = 0 is noise
        if ahead > value and not crossed:
            if value >= self.slow_threshold:
                return 1.0, Status.OK, ""
            return 1.0, Status.NEAR_SINGULARITY, f"{where}: the step raises c, executed unscaled"
        if crossed or halts(ahead, self.singular_threshold, self.slow_threshold):
            return 0.0, Status.HALT_FOR_SINGULARITY, f"{where}: halted, the step would make it singular"
        scale = deceleration(min(value, ahead), self.singular_threshold, self.slow_threshold)
        if scale >= 1.0:
            return 1.0, Status.OK, ""
        return scale, Status.DECELERATE_FOR_SINGULARITY, f"{where}: command scaled by {scale:.2g}"

    # ------------------------------------------------------------------ limits
    def _passing(self, q: np.ndarray, rates: np.ndarray, skipped: Collection[_Limit]) -> list[_Limit]:
        """The limits, less ``skipped``, that the commanded rates carry their joints past
        within dt. On Python floats: numpy's per-call cost exceeds the arithmetic for a
        handful of joints, and this runs every step."""
        q_values, rate_values, dt = q.tolist(), rates.tolist(), self.dt
        passing = []
        for limit in self._limits:
            value = q_values[limit.q_index] + rate_values[limit.velocity] * dt
            if (value > limit.upper or value < limit.lower) and limit not in skipped:
                passing.append(limit)
        return passing

    def _respect_position_limits(
        self,
        observation: Observation,
        rates: np.ndarray,
        passing: list[_Limit],
        solve: Callable[[frozenset[str]], np.ndarray],
    ) -> tuple[np.ndarray, tuple[str, ...]]:
        """(rates, blocked joints), from the limits ``passing`` at ``rates``: those joints are
        left out and the rates solved again by ``solve``, until no remaining joint passes a
        limit; each blocked joint goes on at its commanded rate up to its limit, and stops there."""
        q = observation.q
        blocked: dict[_Limit, float] = {}  # each blocked joint's rate when it was blocked
        while passing:
            blocked.update((limit, float(rates[limit.velocity])) for limit in passing)
            rates = solve(frozenset(limit.joint for limit in blocked))
            passing = self._passing(q, rates, blocked)
        for limit, commanded in blocked.items():
            rates[limit.velocity] = limit.onto_the_limit(q, commanded, self.dt)
        return rates, tuple(limit.joint for limit in blocked)

    def _solve_without(self, observation: Observation, twist: np.ndarray, left_out: frozenset[str]) -> np.ndarray:
        """The algorithm's rates with the ``left_out`` joints removed from the partition (they
        get rate 0 here). Raises SingularBlockError as the algorithm does."""
        if not left_out:
            return partition_rates(observation.jacobian, self.index, twist, self.algorithm, observation.blocks)
        partition = self.partition
        reduced = Partition(
            [joint for joint in partition.arm if joint not in left_out],
            [joint for joint in partition.wrist if joint not in left_out],
            linear=partition.linear,
            angular=partition.angular,
        )
        return partition_rates(observation.jacobian, reduced.resolve(self.robot), twist, self.algorithm)

    def _limit_acceleration(
        self, q: np.ndarray, rates: np.ndarray, held: tuple[str, ...], statuses: list[Status], details: list[str]
    ) -> np.ndarray:
        """previous + s (rates - previous) on the joints not ``held`` (at a limit, frozen), s the
        largest factor <= 1 keeping every change within a·dt; the held joints keep their rates,
        and a joint the blend would carry past a limit stops on it. Between two rate vectors
        within the velocity limits, the result is within them too. (The step remembers what
        it applies in the end.)"""
        assert self.acceleration_limits is not None
        change = rates - self._previous_rates
        for name in held:
            change[self._velocity_of[name]] = 0.0  # position limits act at once
        largest = np.abs(change) / (self.acceleration_limits * self.dt)
        worst = float(largest.max(initial=0.0))
        if worst <= 1.0:
            return rates
        blended = self._previous_rates + change / worst
        for name in held:
            blended[self._velocity_of[name]] = rates[self._velocity_of[name]]
        for limit in self._passing(q, blended, ()):
            blended[limit.velocity] = limit.onto_the_limit(q, blended[limit.velocity], self.dt)
        statuses.append(Status.RATE_LIMITED)
        details.append(f"rates changed by {1.0 / worst:.3g} of the step's change to meet the acceleration limits")
        return blended

    def _rate_scale(self, rates: np.ndarray) -> float:
        """The largest factor <= 1 that brings every rate within its velocity limit."""
        scale = 1.0
        rate_values = rates.tolist()
        for velocity, limit in self._rate_limit_rows:
            magnitude = abs(rate_values[velocity])
            if magnitude * scale > limit:
                scale = limit / magnitude
        return scale

    def _clamp(self, q: np.ndarray) -> str:
        """Clamp q in place to the limits; describe the first joint that was past one ('' if none)."""
        hit = ""
        for limit in self._limits:
            value = q[limit.q_index]
            if value < limit.lower or value > limit.upper:
                side, bound = ("lower", limit.lower) if value < limit.lower else ("upper", limit.upper)
                q[limit.q_index] = bound
                hit = hit or f"{limit.joint} reached its {side} limit {bound:.4g}"
        return hit


def error_norms(observation: Observation, m: int) -> tuple[float, float]:
    """(position error in m, rotation error in rad) of an observation taken against a goal."""
    assert observation.error is not None
    return norm(observation.error[:m]), norm(observation.error[m:])


__all__ = [
    "MAX_ANGULAR_SPEED",
    "MAX_LINEAR_SPEED",
    "Controller",
    "Observation",
    "PoseGoal",
    "Step",
    "error_norms",
]
