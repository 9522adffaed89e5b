"""The kinematics of a manipulator with a tool centre point (tip) and a sensor frame.

The one quantity everything else builds on is the Jacobian of the TCP twist expressed in the
sensor frame (Shoham & Koren 1987, eq. 1-8): with ``J_w`` the Jacobian in world axes and
``C`` the rotation of the sensor frame in the world, ``J = C^-1 J_w`` (eq. 8). Pinocchio
gives the tip Jacobian in the tip's own axes (``LOCAL``: velocity of the tip origin and
angular velocity, both in tip axes), so

    J_sensor = blockdiag(R, R) J_local,   R = R_world_sensor^T R_world_tip.

Kinematics are Pinocchio's throughout: URDF parsing, frame placements, Jacobians and
integration on the configuration space (continuous joints have nq = 2, nv = 1). Mimic joints
(URDF ``<mimic>``, q_follower = m q_leader + o) follow their leaders (:mod:`.mimic`): J is
folded, ``J[:, leader] += m J[:, follower]`` and ``J[:, follower] = 0``, for the followers
between the base and the tip, and the configurations made here keep the relation.
"""

from __future__ import annotations

import functools
import logging
import math
from collections.abc import Mapping, Sequence
from pathlib import Path

import numpy as np
import pinocchio as pin

from ..checks import MAX_SAMPLES, PHYSICAL_BOUND, RngLike, as_rng, check_count, check_name, check_vector
from ..errors import InputError, LoadError, choices_hint
from .frames import default_tip_frame, resolve_frame
from .mimic import Mimic, MimicCoupling, coupled_interval, fold

logger = logging.getLogger("pinrate")


UNIT_TOLERANCE = 1e-6
"""How far from 1 the norm of a continuous joint's (cos, sin) pair (or a quaternion) in q may be."""


GENERIC_SAMPLES = 32
"""Configurations drawn for :meth:`KinematicModel.generic_configurations` (besides neutral)."""

GENERIC_SEED = 20260101
"""Their seed: the tests of what holds almost everywhere are deterministic."""


def not_a_robot(robot: object) -> InputError:
    """The InputError for a ``robot`` argument that is not a :class:`~pinrate.kinematics.manipulator.Robot`
    (a name or a path included)."""
    hint = " (load it first: pinrate.load(...))" if isinstance(robot, str | Path) else ""
    return InputError(f"robot must be a pinrate.Robot{hint}, not {type(robot).__name__}")


def check_model(robot: object) -> KinematicModel:
    """``robot`` if it is a :class:`KinematicModel` (every Robot is); InputError otherwise."""
    if not isinstance(robot, KinematicModel):
        raise not_a_robot(robot)
    return robot


class KinematicModel:
    """A Pinocchio model with a tip (TCP) frame and a sensor frame: sizes and names,
    configurations, the tip pose and the sensor-frame Jacobian (eq. 1, 8). What the partition
    and the home search need; :class:`~pinrate.kinematics.manipulator.Robot` adds its home, its
    geometry and its spec (its docstring lists the attributes)."""

    def __init__(
        self,
        model: pin.Model,
        *,
        tip: str | None = None,
        sensor: str | None = None,
        name: str = "",
        reference_configurations: Mapping[str, np.ndarray] | None = None,
        mimic: Mapping[str, str | Mimic] | None = None,
    ) -> None:
        if not isinstance(model, pin.Model):
            raise InputError(f"model must be a pinocchio.Model (or use pinrate.load), not {type(model).__name__}")
        self.model = model
        try:
            self.data = model.createData()
        except MemoryError:
            raise LoadError(
                f"robot {name or model.name!r}: Pinocchio's data for {model.nv} joints does not fit in memory"
            ) from None
        self.name = name or model.name
        self.joint_names: tuple[str, ...] = tuple(
            model.names[j] for j in range(1, model.njoints) if model.joints[j].nv > 0
        )
        # Plain attributes, not properties: read on every call of the hot path.
        self._single_column = model.nv == 1
        self._has_unit_pairs = model.nq != model.nv
        if not self.joint_names:
            raise LoadError(f"robot {self.name!r} has no moving joint: every joint is fixed, nothing to control")
        self.mimics = MimicCoupling(model, mimic)  # the mimic joints' relations (Robot's docstring)
        choice = default_tip_frame(model, self.mimics.leaders)
        self.hand_joints, self.arm_mimics = choice.hand_joints, choice.arm_mimics
        if tip is None:
            self.tip_id = choice.frame_id
            self.tip_choice = choice.reason
            logger.info("%s: no tip given, %s: %r", self.name, self.tip_choice, model.frames[self.tip_id].name)
        else:
            self.tip_id = resolve_frame(model, tip, role="tip", robot=self.name)
            self.tip_choice = "given"
        self.tip = model.frames[self.tip_id].name
        if not self.tip_chain():
            raise LoadError(
                f"robot {self.name!r}: tip frame {self.tip!r} has no moving joint between it and the world, "
                "so no joint rate can move it; choose a frame on the arm"
            )
        self._folded = self.mimics.folded_columns(self.tip_chain())
        self.sensor_id = self.tip_id if sensor is None else resolve_frame(model, sensor, role="sensor", robot=self.name)
        self.sensor = model.frames[self.sensor_id].name
        self._joint_ids = {model.names[j]: j for j in range(1, model.njoints)}
        self.reference_configurations: dict[str, np.ndarray] = {
            key: np.array(value, dtype=float) for key, value in (reference_configurations or {}).items()
        }
        self.home_choice = (
            "the 'home' reference configuration" if "home" in self.reference_configurations else "neutral"
        )
        if "home" in self.reference_configurations:  # its mimic joints where their leaders put them
            self.follow_leaders(self.reference_configurations["home"])

    # ------------------------------------------------------------------ sizes and names
    @property
    def nq(self) -> int:
        return int(self.model.nq)

    @property
    def nv(self) -> int:
        return int(self.model.nv)

    def joint_id(self, joint: str) -> int:
        """Pinocchio joint index of a moving joint, or an InputError listing the joints."""
        joint_id = self._joint_ids.get(check_name(joint, "joint"))
        if joint_id is None or self.model.joints[joint_id].nv == 0:
            raise InputError(
                f"robot {self.name!r} has no moving joint {joint!r}." + choices_hint(joint, self.joint_names)
            )
        return joint_id

    def velocity_indices(self, joint: str) -> list[int]:
        """Indices of a joint's components in the velocity vector (one for 1-DOF joints)."""
        joint_model = self.model.joints[self.joint_id(joint)]
        return list(range(joint_model.idx_v, joint_model.idx_v + joint_model.nv))

    def tip_chain(self) -> tuple[str, ...]:
        """The moving joints that support the tip, base to tip."""
        parent = self.model.frames[self.tip_id].parentJoint
        return tuple(self.model.names[j] for j in self.model.supports[parent] if j > 0 and self.model.joints[j].nv > 0)

    # ------------------------------------------------------------------ configurations
    def neutral(self) -> np.ndarray:
        """Pinocchio's neutral configuration (nq,)."""
        return np.array(pin.neutral(self.model))

    def home(self) -> np.ndarray:
        """The start pose (nq,): the ``home`` reference configuration, else neutral;
        ``home_choice`` says which (a :class:`~pinrate.kinematics.manipulator.Robot` finds
        one inside the limits and non-singular)."""
        if "home" in self.reference_configurations:
            return self.reference_configurations["home"].copy()
        return self.follow_leaders(self.neutral())

    def follow_leaders(self, configurations: np.ndarray, leader: str | None = None) -> np.ndarray:
        """Configurations (nq,) or (N, nq) with every mimic joint (of ``leader``, or all) at
        m q_leader + o, then inside its own limits (:meth:`.mimic.MimicCoupling.follow`), in
        place; returned."""
        if not self.mimics:
            return configurations
        followers = self.mimics.followers if leader is None else self.mimics.of_leader(leader)
        limits = {follower.name: self.joint_limits(follower.name) for follower in followers}
        return self.mimics.follow(configurations, limits, leader)

    def coupled_limits(self, joint: str) -> tuple[float, float] | None:
        """:meth:`joint_limits`, for a leader of mimic joints narrowed to where each of them is
        inside its own limits too (:func:`.mimic.coupled_interval`): how far the joint may go."""
        own = self.joint_limits(joint)
        followers = self.mimics.of_leader(joint)
        if not followers or self.model.joints[self.joint_id(joint)].nq != 1:
            return own
        return coupled_interval(own, [(follower.relation, self.joint_limits(follower.name)) for follower in followers])

    def position_limits(self) -> tuple[np.ndarray, np.ndarray]:
        """Lower and upper limits of q (nq,), as Pinocchio stores them."""
        return np.array(self.model.lowerPositionLimit), np.array(self.model.upperPositionLimit)

    def sample_configurations(
        self, count: int, rng: RngLike = None, *, joints: Sequence[str] | None = None
    ) -> np.ndarray:
        """``count`` configurations (count, nq) drawn uniformly within the joint limits.

        Only ``joints`` (default: all moving joints) are drawn; the others stay at neutral.
        A 1-DOF joint without finite limits is drawn in [-pi, pi]; a continuous joint
        (nq = 2: cos, sin) by its angle in [-pi, pi]; other multi-DOF joints stay neutral.
        Mimic joints are not drawn: they follow their leaders (:meth:`follow_leaders`).
        """
        generator = as_rng(rng)
        samples = np.tile(self.follow_leaders(self.neutral()), (check_count(count, "count", maximum=MAX_SAMPLES), 1))
        for joint in self.joint_names if joints is None else joints:
            if self.model.joints[self.joint_id(joint)].nv == 1 and joint not in self.mimics.relations:
                self.set_joint_values(samples, joint, generator.uniform(*self.joint_range(joint), count))
        return samples

    def generic_configurations(self, joints: Sequence[str] | None = None) -> np.ndarray:
        """Where pinrate tests what holds at almost every configuration (a Jacobian entry or
        row that is zero everywhere, a block's generic rank): neutral, then
        :data:`~pinrate.kinematics.kinematic_model.GENERIC_SAMPLES` configurations drawn with
        the fixed seed :data:`~pinrate.kinematics.kinematic_model.GENERIC_SEED` within the limits
        of ``joints`` (all moving joints by default; the others at neutral). One set for every
        such test, so they agree."""
        return np.vstack(
            [
                self.follow_leaders(self.neutral()),
                self.sample_configurations(GENERIC_SAMPLES, GENERIC_SEED, joints=joints),
            ]
        )

    def joint_limits(self, joint: str) -> tuple[float, float] | None:
        """The finite position limits of a 1-DOF joint with one coordinate, else None
        (continuous and multi-DOF joints, and limits wider than 1e6)."""
        joint_model = self.model.joints[self.joint_id(joint)]
        if joint_model.nq != 1:
            return None
        i = joint_model.idx_q
        lower, upper = float(self.model.lowerPositionLimit[i]), float(self.model.upperPositionLimit[i])
        if not (math.isfinite(lower) and math.isfinite(upper)) or upper - lower > 1e6:
            return None
        return lower, upper

    def joint_range(self, joint: str) -> tuple[float, float]:
        """The range a 1-DOF joint is drawn or swept over: its limits (a leader's narrowed by
        its mimic joints', :meth:`coupled_limits`), else [-pi, pi]."""
        return self.coupled_limits(joint) or (-math.pi, math.pi)

    def set_joint_values(self, configurations: np.ndarray, joint: str, values: np.ndarray) -> None:
        """Write a 1-DOF joint's values (angles for a continuous joint: cos, sin) into the
        rows of ``configurations`` (N, nq), in place; the joints that mimic it follow
        (:meth:`follow_leaders`)."""
        joint_model = self.model.joints[self.joint_id(joint)]
        if joint_model.nv != 1:
            raise InputError(f"joint {joint!r} has {joint_model.nv} DOF; only 1-DOF joints can be set by value")
        if not isinstance(configurations, np.ndarray) or configurations.ndim != 2 or configurations.shape[1] != self.nq:
            raise InputError(f"configurations must be an (N, {self.nq}) array, got {np.shape(configurations)}")
        values = np.asarray(values, dtype=float)
        if values.shape not in ((), (configurations.shape[0],)):
            raise InputError(f"values must be one per configuration ({configurations.shape[0]}), got {values.shape}")
        i = joint_model.idx_q
        if joint_model.nq == 2:
            configurations[:, i], configurations[:, i + 1] = np.cos(values), np.sin(values)
        else:
            configurations[:, i] = values
        self.follow_leaders(configurations, joint)

    def random_configuration(self, rng: RngLike = None) -> np.ndarray:
        """One configuration (nq,) drawn uniformly within the joint limits."""
        return self.sample_configurations(1, rng)[0]

    def check_q(self, q: object) -> np.ndarray:
        """q as a float array of shape (nq,); InputError on a wrong length, NaN/inf, a
        magnitude past :data:`~pinrate.checks.PHYSICAL_BOUND`, or a continuous joint's
        (cos, sin) pair (or a quaternion) whose norm is off 1 by more than
        :data:`~pinrate.kinematics.kinematic_model.UNIT_TOLERANCE`."""
        q = check_vector(q, self.nq, "q", names=self._q_names)
        if self._has_unit_pairs and not pin.isNormalized(self.model, q, UNIT_TOLERANCE):
            self._refuse_unnormalised(q, "q")
        return q

    def check_configurations(self, configurations: object) -> np.ndarray:
        """Configurations (N, nq) as floats, each row checked as :meth:`check_q` checks q; the
        InputError names the first bad row."""
        try:
            array = np.asarray(configurations, dtype=float)
        except (TypeError, ValueError):
            raise InputError(f"configurations must be an (N, {self.nq}) array of numbers") from None
        if array.ndim != 2 or array.shape[1] != self.nq:
            raise InputError(f"configurations must have shape (N, {self.nq}), got {array.shape}")
        if array.size and not float(np.abs(array).max()) <= PHYSICAL_BOUND:
            row = int(np.flatnonzero(~(np.abs(array) <= PHYSICAL_BOUND).all(axis=1))[0])
            check_vector(array[row], self.nq, f"configurations[{row}]", names=self._q_names)
        if self._has_unit_pairs:
            for row, q in enumerate(array):
                if not pin.isNormalized(self.model, q, UNIT_TOLERANCE):
                    self._refuse_unnormalised(q, f"configurations[{row}]")
        return array

    def _refuse_unnormalised(self, q: np.ndarray, what: str) -> None:
        neutral = self.neutral()
        for joint_id in range(1, self.model.njoints):
            joint_model = self.model.joints[joint_id]
            if joint_model.nq == joint_model.nv:
                continue
            block = slice(joint_model.idx_q, joint_model.idx_q + joint_model.nq)
            probe = neutral.copy()
            probe[block] = q[block]
            if not pin.isNormalized(self.model, probe, UNIT_TOLERANCE):
                raise InputError(
                    f"{what}[{block.start}:{block.stop}] of joint {self.model.names[joint_id]!r} = {q[block]} must "
                    "hold a unit (cos, sin) pair (or unit quaternion); write an angle a as (cos a, sin a)"
                )

    @functools.cached_property
    def _q_names(self) -> list[str]:
        names = [""] * self.nq
        for joint_id in range(1, self.model.njoints):
            joint_model = self.model.joints[joint_id]
            for offset in range(joint_model.nq):
                names[joint_model.idx_q + offset] = self.model.names[joint_id]
        return names

    def integrate(self, q: np.ndarray, joint_rates: np.ndarray, dt: float) -> np.ndarray:
        """q moved by joint_rates (nv,) for dt seconds on the configuration space (the rates
        as given: a step drives the mimic joints first, :meth:`.mimic.MimicCoupling.drive`)."""
        return np.array(pin.integrate(self.model, q, joint_rates * dt))

    # ------------------------------------------------------------------ kinematics
    def pose(self, q: object) -> np.ndarray:
        """The tip frame in the world, a 4x4 homogeneous matrix."""
        q = self.check_q(q)
        pin.forwardKinematics(self.model, self.data, q)
        return np.array(pin.updateFramePlacement(self.model, self.data, self.tip_id).homogeneous)

    def frame_pose(self, q: object, frame: str) -> np.ndarray:
        """Any frame in the world, a 4x4 homogeneous matrix."""
        q = self.check_q(q)
        frame_id = resolve_frame(self.model, frame, role="frame", robot=self.name)
        pin.forwardKinematics(self.model, self.data, q)
        return np.array(pin.updateFramePlacement(self.model, self.data, frame_id).homogeneous)

    def jacobian(self, q: object) -> np.ndarray:
        """The sensor-frame Jacobian (6, nv) at q (Shoham & Koren eq. 1, 8).

        Rows [vx vy vz wx wy wz]: the velocity of the tip frame's origin and the angular
        velocity, both expressed in the sensor frame's axes.
        """
        return self.jacobian_unchecked(self.check_q(q))

    def jacobian_unchecked(self, q: np.ndarray) -> np.ndarray:
        """:meth:`jacobian` without the input check, for a q that already went through
        :meth:`check_q` (or was drawn by pinrate): the hot path of loops over configurations.

        With the sensor at the tip this is one Pinocchio call (the LOCAL frame Jacobian), and
        the fold of the mimic joints between the base and the tip (:func:`.mimic.fold`).
        """
        if self.sensor_id == self.tip_id:
            jacobian = pin.computeFrameJacobian(self.model, self.data, q, self.tip_id, pin.LOCAL)
            # eigenpy hands a one-column matrix back as a vector: keep (6, nv) for one joint.
            jacobian = jacobian.reshape(6, 1) if self._single_column else jacobian
            return fold(jacobian, self._folded) if self._folded else jacobian
        return self.kinematics(q)[0]

    @property
    def folds_mimics(self) -> bool:
        """Whether a mimic joint lies between the base and the tip, so that J is folded
        (:func:`.mimic.fold`): a loop that makes J itself must fold it too."""
        return bool(self._folded)

    def kinematics(self, q: np.ndarray) -> tuple[np.ndarray, pin.SE3, pin.SE3]:
        """(J_sensor, world_T_tip, world_T_sensor) at a checked q, in one kinematics pass.

        ``computeJointJacobians`` runs the forward kinematics too, so the frame placements
        updated afterwards are fresh for this q.
        """
        model, data = self.model, self.data
        pin.computeJointJacobians(model, data, q)
        jacobian_local = pin.getFrameJacobian(model, data, self.tip_id, pin.LOCAL)
        if self._single_column:  # eigenpy's one-column matrix is a vector
            jacobian_local = jacobian_local.reshape(6, 1)
        if self._folded:
            jacobian_local = fold(jacobian_local, self._folded)
        world_T_tip = pin.updateFramePlacement(model, data, self.tip_id)
        if self.sensor_id == self.tip_id:
            return jacobian_local, world_T_tip, world_T_tip
        world_T_sensor = pin.updateFramePlacement(model, data, self.sensor_id)
        sensor_R_tip = world_T_sensor.rotation.T @ world_T_tip.rotation
        jacobian = np.empty_like(jacobian_local)
        jacobian[:3] = sensor_R_tip @ jacobian_local[:3]
        jacobian[3:] = sensor_R_tip @ jacobian_local[3:]
        return jacobian, world_T_tip, world_T_sensor
