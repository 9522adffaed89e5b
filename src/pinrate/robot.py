"""A URDF manipulator with a tool centre point (tip) and a sensor frame.

The one quantity everything else builds on is the Jacobian of the TCP twist expressed in the
sensor frame (Shoham & Koren 1987, eq. 1-8): with ``J_w`` the Jacobian in world axes and
``C`` the rotation of the sensor frame in the world, ``J = C^-1 J_w`` (eq. 8). Pinocchio
gives the tip Jacobian in the tip's own axes (``LOCAL``: velocity of the tip origin and
angular velocity, both in tip axes), so

    J_sensor = blockdiag(R, R) J_local,   R = R_world_sensor^T R_world_tip.

Kinematics are Pinocchio's throughout: URDF parsing, frame placements, Jacobians and
integration on the configuration space (continuous joints have nq = 2, nv = 1).
"""

from __future__ import annotations

import functools
import logging
import math
import os
import warnings
import xml.etree.ElementTree as ET
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pinocchio as pin

from .catalog import EXAMPLE_ROBOTS, CatalogEntry, example_robot_data_share, example_robot_path
from .errors import FrameError, InputError, LoadError, PinrateError, choices_hint

logger = logging.getLogger("pinrate")

RngLike = np.random.Generator | int | None

# Frame types in the order a name is resolved: a link wins over a joint of the same name.
_FRAME_PREFERENCE = (
    pin.FrameType.BODY,
    pin.FrameType.OP_FRAME,
    pin.FrameType.SENSOR,
    pin.FrameType.JOINT,
    pin.FrameType.FIXED_JOINT,
)


def as_rng(rng: RngLike) -> np.random.Generator:
    """A numpy Generator from a Generator, an int seed, or None (fresh entropy)."""
    if isinstance(rng, np.random.Generator):
        return rng
    if rng is None or isinstance(rng, int | np.integer):
        return np.random.default_rng(rng)
    raise InputError(f"rng must be a numpy Generator, an int seed or None, not {type(rng).__name__}")


@dataclass(frozen=True)
class RobotSpec:
    """What a worker needs to rebuild a robot's kinematics: URDF text, tip, sensor, name."""

    urdf_text: str
    tip: str
    sensor: str
    name: str

    def build(self) -> Robot:
        return robot_from_urdf(self.urdf_text, label=self.name, tip=self.tip, sensor=self.sensor, name=self.name)


class Robot:
    """A Pinocchio model with a tip (TCP) frame and a sensor frame.

    Attributes:
        model, data: the Pinocchio model and its data (the data is scratch space reused by
            every call, so a Robot is not thread-safe; use one Robot per thread).
        tip: name of the frame whose origin is the TCP.
        tip_choice: how the tip was picked ("given", or how pinrate chose it).
        sensor: name of the frame whose axes twists are expressed in.
        joint_names: the moving joints, in velocity-vector order.
        reference_configurations: named configurations (from the SRDF, plus ``"home"``).
    """

    def __init__(
        self,
        model: pin.Model,
        *,
        tip: str | None = None,
        sensor: str | None = None,
        name: str = "",
        urdf_path: Path | None = None,
        urdf_text: str | None = None,
        package_dirs: Sequence[str] = (),
        reference_configurations: Mapping[str, np.ndarray] | None = None,
    ) -> None:
        self.model = model
        self.data = model.createData()
        self.name = name or model.name
        self._urdf_path = urdf_path
        self._urdf_text = urdf_text
        self._package_dirs = list(package_dirs)
        self._visual_model: pin.GeometryModel | None = None

        if tip is None:
            self.tip_id = default_tip_frame(model)
            self.tip_choice = "chosen: the deepest frame at the end of the longest chain of moving joints"
            logger.info("%s: no tip given, %s: %r", self.name, self.tip_choice, model.frames[self.tip_id].name)
        else:
            self.tip_id = resolve_frame(model, tip, role="tip", robot=self.name)
            self.tip_choice = "given"
        self.tip = model.frames[self.tip_id].name
        self.sensor_id = self.tip_id if sensor is None else resolve_frame(model, sensor, role="sensor", robot=self.name)
        self.sensor = model.frames[self.sensor_id].name

        self.joint_names: tuple[str, ...] = tuple(
            model.names[j] for j in range(1, model.njoints) if model.joints[j].nv > 0
        )
        self._joint_ids = {model.names[j]: j for j in range(1, model.njoints)}
        self.reference_configurations: dict[str, np.ndarray] = {
            key: np.array(value, dtype=float) for key, value in (reference_configurations or {}).items()
        }
        self._auto_partition = None  # filled by Partition.auto, keyed on nothing: tip is fixed

    # ------------------------------------------------------------------ sizes and names
    @property
    def nq(self) -> int:
        return int(self.model.nq)

    @property
    def nv(self) -> int:
        return int(self.model.nv)

    def joint_id(self, joint: str) -> int:
        """Pinocchio joint index of a moving joint, or an InputError listing the joints."""
        joint_id = self._joint_ids.get(joint)
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

    def spec(self) -> RobotSpec:
        """A picklable recipe of this robot's kinematics (for worker processes and Dask)."""
        if self._urdf_text is None:
            raise PinrateError(f"robot {self.name!r} was built from a model, not URDF text: it has no spec")
        return RobotSpec(urdf_text=self._urdf_text, tip=self.tip, sensor=self.sensor, name=self.name)

    def __repr__(self) -> str:
        return f"Robot({self.name!r}, nq={self.nq}, nv={self.nv}, tip={self.tip!r}, sensor={self.sensor!r})"

    # ------------------------------------------------------------------ configurations
    def neutral(self) -> np.ndarray:
        """Pinocchio's neutral configuration (nq,)."""
        return np.array(pin.neutral(self.model))

    def home(self) -> np.ndarray:
        """A non-singular start pose: the ``home`` reference configuration, else neutral."""
        if "home" in self.reference_configurations:
            return self.reference_configurations["home"].copy()
        return self.neutral()

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
        """
        generator = as_rng(rng)
        samples = np.tile(self.neutral(), (count, 1))
        for joint in self.joint_names if joints is None else joints:
            if self.model.joints[self.joint_id(joint)].nv == 1:
                self.set_joint_values(samples, joint, generator.uniform(*self.joint_range(joint), count))
        return samples

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
        """The range a 1-DOF joint is drawn or swept over: its limits, else [-pi, pi]."""
        return self.joint_limits(joint) or (-math.pi, math.pi)

    def set_joint_values(self, configurations: np.ndarray, joint: str, values: np.ndarray) -> None:
        """Write a 1-DOF joint's values (angles for a continuous joint: cos, sin) into the
        rows of ``configurations`` (N, nq), in place."""
        joint_model = self.model.joints[self.joint_id(joint)]
        if joint_model.nv != 1:
            raise InputError(f"joint {joint!r} has {joint_model.nv} DOF; only 1-DOF joints can be set by value")
        i = joint_model.idx_q
        if joint_model.nq == 2:
            configurations[:, i], configurations[:, i + 1] = np.cos(values), np.sin(values)
        else:
            configurations[:, i] = values

    def random_configuration(self, rng: RngLike = None) -> np.ndarray:
        """One configuration (nq,) drawn uniformly within the joint limits."""
        return self.sample_configurations(1, rng)[0]

    def check_q(self, q: object) -> np.ndarray:
        """q as a float array of shape (nq,); InputError on a wrong length or NaN/inf."""
        return check_vector(q, self.nq, "q", names=self._q_names)

    @functools.cached_property
    def _q_names(self) -> list[str]:
        names = [""] * self.nq
        for joint_id in range(1, self.model.njoints):
            joint_model = self.model.joints[joint_id]
            for offset in range(joint_model.nq):
                names[joint_model.idx_q + offset] = self.model.names[joint_id]
        return names

    def integrate(self, q: np.ndarray, joint_rates: np.ndarray, dt: float) -> np.ndarray:
        """q moved by joint_rates (nv,) for dt seconds on the configuration space."""
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
        return self.sensor_jacobian(self.check_q(q))

    def sensor_jacobian(self, q: np.ndarray) -> np.ndarray:
        """:meth:`jacobian` at an already checked q: the hot path of a control loop.

        With the sensor at the tip this is one Pinocchio call (the LOCAL frame Jacobian).
        """
        if self.sensor_id == self.tip_id:
            return pin.computeFrameJacobian(self.model, self.data, q, self.tip_id, pin.LOCAL)
        return self.kinematics(q)[0]

    def kinematics(self, q: np.ndarray) -> tuple[np.ndarray, pin.SE3, pin.SE3]:
        """(J_sensor, world_T_tip, world_T_sensor) at a checked q, in one kinematics pass.

        ``computeJointJacobians`` runs the forward kinematics too, so the frame placements
        updated afterwards are fresh for this q.
        """
        model, data = self.model, self.data
        pin.computeJointJacobians(model, data, q)
        jacobian_local = pin.getFrameJacobian(model, data, self.tip_id, pin.LOCAL)
        world_T_tip = pin.updateFramePlacement(model, data, self.tip_id)
        if self.sensor_id == self.tip_id:
            return jacobian_local, world_T_tip, world_T_tip
        world_T_sensor = pin.updateFramePlacement(model, data, self.sensor_id)
        sensor_R_tip = world_T_sensor.rotation.T @ world_T_tip.rotation
        jacobian = np.empty_like(jacobian_local)
        jacobian[:3] = sensor_R_tip @ jacobian_local[:3]
        jacobian[3:] = sensor_R_tip @ jacobian_local[3:]
        return jacobian, world_T_tip, world_T_sensor

    # ------------------------------------------------------------------ visuals
    @property
    def visual_model(self) -> pin.GeometryModel:
        """Visual geometries, loaded on first use; an empty model (with a warning) on failure."""
        if self._visual_model is None:
            self._visual_model = self._load_visuals()
        return self._visual_model

    def _load_visuals(self) -> pin.GeometryModel:
        try:
            if self._urdf_path is None and self._urdf_text is not None:
                return pin.buildGeomFromUrdfString(
                    self.model, self._urdf_text, pin.GeometryType.VISUAL, package_dirs=self._package_dirs
                )
            if self._urdf_path is not None:
                return pin.buildGeomFromUrdf(
                    self.model, str(self._urdf_path), pin.GeometryType.VISUAL, package_dirs=self._package_dirs
                )
        except (RuntimeError, ValueError, OSError) as error:
            warnings.warn(f"{self.name}: visual meshes not loaded ({error}); kinematics unaffected", stacklevel=2)
        return pin.GeometryModel()


# ---------------------------------------------------------------------- helpers
def check_vector(value: object, length: int, what: str, *, names: Sequence[str] | None = None) -> np.ndarray:
    """A float vector of the given length; InputError naming ``what`` otherwise."""
    try:
        array = np.asarray(value, dtype=float)
    except (TypeError, ValueError) as error:
        raise InputError(f"{what} must be a vector of {length} numbers: {error}") from None
    if array.shape != (length,):
        raise InputError(f"{what} must have shape ({length},), got shape {array.shape}")
    # A finite sum proves every entry finite (the cheap test on the hot path); an overflowing
    # sum of finite entries falls through to the entry-wise test.
    if not math.isfinite(array.sum()) and not np.isfinite(array).all():
        bad = np.flatnonzero(~np.isfinite(array))
        where = ", ".join(f"{what}[{i}]" + (f" ({names[int(i)]})" if names and names[int(i)] else "") for i in bad)
        raise InputError(f"{what} contains NaN or inf at {where}")
    return array


def resolve_frame(model: pin.Model, name: str, *, role: str, robot: str = "") -> int:
    """Index of the frame called ``name``; a link wins over a joint of the same name."""
    if not isinstance(name, str):
        raise InputError(f"{role} must be a frame name (str), not {type(name).__name__}")
    for frame_type in _FRAME_PREFERENCE:
        if model.existFrame(name, frame_type):
            return int(model.getFrameId(name, frame_type))
    frames = list(dict.fromkeys(frame.name for frame in model.frames))
    raise FrameError(
        f"robot {robot or model.name!r} has no frame {name!r} (asked as {role})."
        + choices_hint(name, frames, limit=200)
    )


def default_tip_frame(model: pin.Model) -> int:
    """The deepest frame at the end of the longest chain of moving joints (ties: model order).

    The longest chain ends at the moving joint with the most moving joints in its support;
    among the frames attached to it, the one with the most ancestor frames wins, links
    preferred over joint frames.
    """

    def moving_depth(joint_id: int) -> int:
        return sum(1 for j in model.supports[joint_id] if j > 0 and model.joints[j].nv > 0)

    moving = [j for j in range(1, model.njoints) if model.joints[j].nv > 0]
    if not moving:
        return len(model.frames) - 1
    end_joint = max(moving, key=lambda j: (moving_depth(j), -j))

    def frame_depth(frame_id: int) -> int:
        depth = 0
        while frame_id != 0 and model.frames[frame_id].parentJoint == end_joint:
            frame_id = model.frames[frame_id].parentFrame
            depth += 1
        return depth

    attached = [f for f, frame in enumerate(model.frames) if frame.parentJoint == end_joint]
    return max(attached, key=lambda f: (frame_depth(f), model.frames[f].type == pin.FrameType.BODY, -f))


# ---------------------------------------------------------------------- loading
def _read_urdf(path: Path) -> str:
    if not path.exists():
        raise LoadError(f"URDF file not found: {path}")
    if not path.is_file():
        raise LoadError(f"URDF path is not a file: {path}")
    return path.read_text(encoding="utf-8", errors="replace")


def _check_urdf_text(text: str, label: str) -> ET.Element:
    """The URDF's root element; LoadError naming ``label`` for malformed XML or a non-URDF."""
    try:
        root = ET.fromstring(text)
    except ET.ParseError as error:
        raise LoadError(f"{label}: malformed XML ({error})") from None
    if root.tag != "robot":
        raise LoadError(f"{label}: not a URDF (root element is <{root.tag}>, expected <robot>)")
    return root


def _build_model(text: str, label: str) -> pin.Model:
    try:
        return pin.buildModelFromXML(text)
    except (ValueError, RuntimeError) as error:
        detail = " ".join(str(error).split())
        raise LoadError(f"{label}: Pinocchio could not build a model: {detail}") from None


def robot_from_urdf(
    text: str,
    *,
    label: str,
    tip: str | None = None,
    sensor: str | None = None,
    urdf_path: Path | None = None,
    package_dirs: Sequence[str] = (),
    srdf_path: Path | None = None,
    home: str | None = None,
    home_values: Mapping[str, float] | None = None,
    name: str | None = None,
) -> Robot:
    """A Robot from URDF text: the common path of every way of loading."""
    root = _check_urdf_text(text, label)
    model = _build_model(text, label)
    references: dict[str, np.ndarray] = {}
    if srdf_path is not None and srdf_path.is_file():
        try:
            pin.loadReferenceConfigurations(model, str(srdf_path), False)
            references = {entry.key(): np.array(entry.data()) for entry in model.referenceConfigurations}
        except (RuntimeError, ValueError) as error:
            warnings.warn(f"{label}: reference configurations not read from {srdf_path}: {error}", stacklevel=3)
    if home is not None and home in references:
        references["home"] = references[home].copy()
    if home_values:
        configuration = references.get("home", np.array(pin.neutral(model)))
        for joint, value in home_values.items():
            if model.existJointName(joint):
                configuration[model.joints[model.getJointId(joint)].idx_q] = value
        references["home"] = configuration
    if "home" in references:
        references["home"] = _into_limits(model, references["home"])
    robot_name = name or root.get("name") or label
    return Robot(
        model,
        tip=tip,
        sensor=sensor,
        name=robot_name,
        urdf_path=urdf_path,
        urdf_text=text,
        package_dirs=package_dirs,
        reference_configurations=references,
    )


def _into_limits(model: pin.Model, q: np.ndarray) -> np.ndarray:
    """q with each 1-DOF joint brought inside its limits: revolute ones by whole turns when
    that suffices (an SRDF pose may be written in another turn), else clamped."""
    q = q.copy()
    for joint_id in range(1, model.njoints):
        joint_model = model.joints[joint_id]
        if joint_model.nq != 1:
            continue
        i = joint_model.idx_q
        lower, upper = model.lowerPositionLimit[i], model.upperPositionLimit[i]
        if lower <= q[i] <= upper:
            continue
        if joint_model.shortname().startswith("JointModelR"):
            turned = q[i] + 2 * math.pi * math.ceil((lower - q[i]) / (2 * math.pi))
            if lower <= turned <= upper:
                q[i] = turned
                continue
        q[i] = min(max(q[i], lower), upper)
    return q


def load(source: str | os.PathLike[str], *, tip: str | None = None, sensor: str | None = None) -> Robot:
    """Load a robot from a URDF path, a papers'-robot name or an example-robot-data name.

    Args:
        source: a path to a ``.urdf`` file; or a name from :func:`pinrate.catalog.known_names`
            (the papers' robots such as ``"scara"``, and ``"ur5"``, ``"panda"``, ...).
        tip: the frame whose origin is the TCP (a link, joint or fixed frame; a name that is
            both a link and a joint means the link). Default: the name table's tip; for any
            other URDF, the deepest frame at the end of the longest chain of moving joints.
        sensor: the frame whose axes twists are expressed in. Default: the tip.

    Raises:
        LoadError: missing file, malformed XML, not a URDF, unknown robot name.
        FrameError: unknown tip or sensor frame (the message lists the frames).
    """
    from . import robots  # the papers' robots; imported here to avoid a cycle

    if isinstance(source, os.PathLike) or (isinstance(source, str) and _looks_like_path(source)):
        path = Path(source).expanduser().resolve()
        text = _read_urdf(path)
        return robot_from_urdf(
            text,
            label=str(path),
            tip=tip,
            sensor=sensor,
            urdf_path=path,
            package_dirs=_package_dirs_for(path),
        )
    if not isinstance(source, str):
        raise InputError(f"source must be a URDF path or a robot name, not {type(source).__name__}")
    if source in robots.ROBOT_NAMES:
        return robots.build(source, tip=tip, sensor=sensor)
    entry = EXAMPLE_ROBOTS.get(source)
    if entry is None:
        from .catalog import known_names

        raise LoadError(f"unknown robot name {source!r}." + choices_hint(source, known_names()))
    return _load_example_robot(entry, tip=tip, sensor=sensor)


def _looks_like_path(source: str) -> bool:
    return source.endswith((".urdf", ".xml")) or os.sep in source or "/" in source


def _package_dirs_for(path: Path) -> list[str]:
    """Folders ``package://`` URIs may resolve against: the file's ancestors, example-robot-data."""
    dirs = [str(parent) for parent in list(path.parents)[:4]]
    share = example_robot_data_share()
    if share is not None:
        dirs.append(str(share))
    return dirs


def _load_example_robot(entry: CatalogEntry, *, tip: str | None, sensor: str | None) -> Robot:
    path = example_robot_path(entry.urdf)
    srdf = example_robot_path(entry.srdf) if entry.srdf else None
    share = example_robot_data_share()
    return robot_from_urdf(
        _read_urdf(path),
        label=entry.name,
        tip=tip or entry.tip,
        sensor=sensor,
        urdf_path=path,
        package_dirs=[str(share)] if share else [],
        srdf_path=srdf,
        home=entry.home,
        home_values=entry.home_values,
        name=entry.name,
    )
