"""The arm/wrist partition of the sensor-frame Jacobian (Shoham & Koren eq. 17-19).

    [ v ]   [ A  B ] [ qdot_arm   ]
    [ Ω ] = [ U  W ] [ qdot_wrist ]                                        (eq. 17, 19)

v holds the controlled linear components and Ω the controlled angular components of the
TCP twist, both in the sensor frame's axes. A maps arm rates to TCP velocity, W wrist rates
to angular velocity, B (wrist → velocity) and U (arm → angular velocity) are the couplings
the motion control algorithms neglect.
"""

from __future__ import annotations

import weakref
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..errors import InputError
from .kinematic_model import KinematicModel, check_model

_AXES = "xyz"
_ZERO_TOL = 1e-9  # a Jacobian entry counts as zero below this times (1 + max |J|)

# Per-robot caches kept here, not on the robot: they go when the robot goes.
_INDEX_CACHE: weakref.WeakKeyDictionary[KinematicModel, dict[Partition, PartitionIndex]] = weakref.WeakKeyDictionary()
_AUTO_CACHE: weakref.WeakKeyDictionary[KinematicModel, Partition] = weakref.WeakKeyDictionary()

Selector = tuple[Any, Any]
"""An index of J[rows, columns]: two slices, or ``np.ix_`` index arrays."""


def _selector(rows: list[int], columns: list[int]) -> Selector:
    """Index of J[rows, columns]: two slices when both are contiguous (one cheap view)."""

    def as_slice(indices: list[int]) -> slice | None:
        if not indices:
            return slice(0, 0)
        if indices == list(range(indices[0], indices[-1] + 1)):
            return slice(indices[0], indices[-1] + 1)
        return None

    row_slice, column_slice = as_slice(rows), as_slice(columns)
    if row_slice is not None and column_slice is not None:
        return (row_slice, column_slice)
    row_index, column_index = np.ix_(rows, columns)
    return (row_index, column_index)


def square_and_small(m: int, n_arm: int, k: int, n_wrist: int) -> bool:
    """A and W square, A of size 1 to 3, W of size 0 to 3: the closed-form kernels apply."""
    return m == n_arm and k == n_wrist and 0 < m <= 3 and k <= 3


def pseudo_g_is_exact(m: int, n_arm: int, k: int, n_wrist: int) -> bool:
    """A not tall (m <= its columns) and W not wide (k >= its columns): of full rank, A A^+ = I
    and W^+ W = I, so the pseudo-inverse G has the spectrum of the algorithms' error map
    (:mod:`pinrate.solvers.error_map`) and the cheap G may stand for it."""
    return m <= n_arm and k >= n_wrist


def position_first_applies(m: int, n_arm: int, k: int, n_wrist: int) -> bool:
    """A square and not empty, W tall (fewer wrist joints than angular rows: a 5-DOF arm's
    3x2 W, an arm with no wrist for rows of Ω): no joint rates make every twist, and the
    linear rows come first. Position is made exactly through A and the angular rows in least
    squares over the wrist rates that leave it (:func:`pinrate.solvers.reference.position_first`)."""
    return 0 < m == n_arm and k > n_wrist


@dataclass(frozen=True)
class PartitionIndex:
    """A partition resolved against one robot: row and column indices into J (6, nv)."""

    rows: np.ndarray  # controlled twist components, linear then angular (0-5)
    arm_columns: np.ndarray
    wrist_columns: np.ndarray
    m: int  # number of linear rows
    k: int  # number of angular rows
    nv: int  # the robot's velocity dimension
    columns: np.ndarray = field(init=False)
    all_columns: bool = field(init=False)  # the columns are 0 .. nv-1 in order
    all_rows: bool = field(init=False)  # the rows are 0 .. 5 in order
    small: bool = field(init=False)  # square blocks of size <= 3: closed-form kernels apply
    square: bool = field(init=False)  # A and W square, as the Theorem assumes (else the error map)
    pseudo_g: bool = field(init=False)  # pseudo_g_is_exact for these blocks
    position_first: bool = field(init=False)  # position_first_applies for these blocks
    selectors: tuple[Selector, ...] = field(init=False)  # A, B, U, W in J

    def __post_init__(self) -> None:
        columns = np.concatenate([self.arm_columns, self.wrist_columns])
        set_ = object.__setattr__
        set_(self, "columns", columns)
        linear, angular = self.rows[: self.m].tolist(), self.rows[self.m :].tolist()
        arm, wrist = self.arm_columns.tolist(), self.wrist_columns.tolist()
        set_(self, "selectors", tuple(_selector(r, c) for r in (linear, angular) for c in (arm, wrist)))
        set_(self, "small", square_and_small(self.m, self.arm_columns.size, self.k, self.wrist_columns.size))
        set_(self, "square", self.m == self.arm_columns.size and self.k == self.wrist_columns.size)
        set_(self, "pseudo_g", pseudo_g_is_exact(self.m, self.arm_columns.size, self.k, self.wrist_columns.size))
        set_(
            self,
            "position_first",
            position_first_applies(self.m, self.arm_columns.size, self.k, self.wrist_columns.size),
        )
        set_(self, "all_columns", columns.tolist() == list(range(self.nv)))
        set_(self, "all_rows", self.rows.tolist() == list(range(6)))


@dataclass(frozen=True, init=False)
class Partition:
    """Which joints form the arm and the wrist, and which twist components are controlled.

    Args:
        arm: names of the arm joints (columns of A and U), in the order their rates are used.
        wrist: names of the wrist joints (columns of B and W).
        linear: sensor-frame axes of the controlled linear velocity (rows of A, B), e.g. "xy".
        angular: sensor-frame axes of the controlled angular velocity (rows of U, W), e.g. "z".
    """

    arm: tuple[str, ...]
    wrist: tuple[str, ...]
    linear: str
    angular: str

    def __init__(self, arm: object, wrist: object, *, linear: str = "xyz", angular: str = "xyz") -> None:
        arm_names = _names(arm, "arm")
        wrist_names = _names(wrist, "wrist")
        for group, names in (("arm", arm_names), ("wrist", wrist_names)):
            repeated = sorted({name for name in names if names.count(name) > 1})
            if repeated:
                raise InputError(f"partition {group} lists joint(s) {repeated} more than once")
        overlap = sorted(set(arm_names) & set(wrist_names))
        if overlap:
            raise InputError(f"partition arm and wrist overlap: joint(s) {overlap} are in both")
        object.__setattr__(self, "arm", arm_names)
        object.__setattr__(self, "wrist", wrist_names)
        object.__setattr__(self, "linear", _axes(linear, "linear"))
        object.__setattr__(self, "angular", _axes(angular, "angular"))

    @property
    def m(self) -> int:
        """Number of controlled linear components (rows of A)."""
        return len(self.linear)

    @property
    def k(self) -> int:
        """Number of controlled angular components (rows of W)."""
        return len(self.angular)

    @property
    def joints(self) -> tuple[str, ...]:
        """Arm joints then wrist joints."""
        return self.arm + self.wrist

    def rows(self) -> list[int]:
        """Row indices into the 6-row twist: linear axes (0-2) then angular axes (3-5)."""
        return [_AXES.index(a) for a in self.linear] + [3 + _AXES.index(a) for a in self.angular]

    def resolve(self, robot: KinematicModel) -> PartitionIndex:
        """Row and column indices of this partition in ``robot``'s Jacobian (cached per robot).

        Raises:
            InputError: a joint the robot does not have, one off the chain from the base to
                the tip (it cannot move the tip: its column of J is zero), or a mimic joint
                (its leader moves it: its column is folded into the leader's).
        """
        cache = _INDEX_CACHE.setdefault(check_model(robot), {})
        index = cache.get(self)
        if index is None:
            chain = robot.tip_chain()
            for joint in self.joints:
                robot.joint_id(joint)  # an unknown name: InputError with the closest names
                relation = robot.mimics.relations.get(joint)
                if relation is not None:
                    raise InputError(
                        f"joint {joint!r} of robot {robot.name!r} mimics {relation.leader!r} (it moves at "
                        f"{relation.multiplier:g} times its rate): put {relation.leader!r} in the partition instead"
                    )
                if joint not in chain:
                    raise InputError(
                        f"joint {joint!r} is not on the chain from the base to the tip {robot.tip!r} of robot "
                        f"{robot.name!r}: it cannot move the tip. The chain's joints: {', '.join(chain)}"
                    )
            arm_columns = [c for joint in self.arm for c in robot.velocity_indices(joint)]
            wrist_columns = [c for joint in self.wrist for c in robot.velocity_indices(joint)]
            index = PartitionIndex(
                rows=np.array(self.rows(), dtype=np.intp),
                arm_columns=np.array(arm_columns, dtype=np.intp),
                wrist_columns=np.array(wrist_columns, dtype=np.intp),
                m=self.m,
                k=self.k,
                nv=robot.nv,
            )
            cache[self] = index
        return index

    def blocks(self, robot: KinematicModel, J: object) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """(A, B, U, W) of eq. 19: A = J[linear, arm], B = J[linear, wrist],
        U = J[angular, arm], W = J[angular, wrist]."""
        index = self.resolve(robot)
        try:
            jacobian = np.asarray(J, dtype=float)
        except (TypeError, ValueError):
            raise InputError(f"J must be a (6, {robot.nv}) array of numbers, got {type(J).__name__}") from None
        if jacobian.shape != (6, robot.nv):
            raise InputError(f"J must have shape (6, {robot.nv}) for robot {robot.name!r}, got {jacobian.shape}")
        if not np.isfinite(jacobian).all():
            raise InputError("J contains NaN or inf")
        return split_blocks(jacobian[np.ix_(index.rows, index.columns)], index.m, len(index.arm_columns))

    def __str__(self) -> str:
        return self.describe()

    def describe(self, robot: KinematicModel | None = None) -> str:
        """The partition in three lines; with ``robot``, the block shapes count velocity
        components, so a multi-DOF joint (planar: 3, floating: 6) counts as many columns."""

        def joints(names: tuple[str, ...]) -> str:
            return ", ".join(names) if names else "none"

        if robot is None:
            n_arm, n_wrist = len(self.arm), len(self.wrist)
        else:
            index = self.resolve(robot)
            n_arm, n_wrist = len(index.arm_columns), len(index.wrist_columns)
        square = self.m == n_arm and self.k == n_wrist
        test = (
            f"G = U A^-1 B W^-1 is {self.k}x{self.k}, H = B W^-1 U A^-1 is {self.m}x{self.m}"
            if square
            else "not square: A^+ and W^+ are pseudo-inverses, and convergence is judged by the error map "
            "I - J K (the Theorem assumes square blocks)"
        )
        if position_first_applies(self.m, n_arm, self.k, n_wrist):
            test += (
                f"; position first: {n_arm + n_wrist} joints for {self.m + self.k} twist components, so the "
                "linear rows are made exactly and the angular ones in least squares over the motions that keep "
                "them (exact, schur, dls)"
            )
        lines = [
            f"arm ({len(self.arm)} joints, drive linear {self.linear or 'none'} through A): {joints(self.arm)}",
            f"wrist ({len(self.wrist)} joints, drive angular {self.angular or 'none'} through W): {joints(self.wrist)}",
            f"A is {self.m}x{n_arm}, W is {self.k}x{n_wrist}; {test}",
        ]
        return "\n".join(lines)

    @classmethod
    def auto(cls, robot: KinematicModel) -> Partition:
        """The default partition of ``robot`` (cached on the robot).

        Only joints of the tip's chain whose Jacobian column is non-zero somewhere take part,
        less the gripper and hand joints (zero-range, mimic groups at the end of the chain;
        :attr:`~pinrate.kinematics.manipulator.Robot.hand_joints`), less the mimic joints
        that follow an arm joint (:attr:`~pinrate.kinematics.manipulator.Robot.arm_mimics`: a
        joint that parallelogram links mimic stays, its links do not), and less multi-DOF
        joints (a ``planar`` or ``floating`` base: the paper's arm and wrist are the
        manipulator's 1-DOF joints; a :class:`Partition` naming one includes it); twist
        components whose rows are zero at every sampled configuration are dropped.
        With n joints, m linear and k angular components, the wrist is the last
        min(k, max(n - m, 0)) joints and the arm the ones before them.
        """
        cached = _AUTO_CACHE.get(check_model(robot))
        if cached is not None:
            return cached
        samples = np.vstack([robot.generic_configurations(), robot.home()])
        magnitude = np.zeros((6, robot.nv))
        for q in samples:
            magnitude = np.maximum(magnitude, np.abs(robot.jacobian(q)))
        tol = _ZERO_TOL * (1.0 + magnitude.max())
        moving = magnitude > tol
        joints = [
            j
            for j in robot.tip_chain()
            if j not in robot.hand_joints
            and j not in robot.arm_mimics
            and len(robot.velocity_indices(j)) == 1
            and any(moving[:, c].any() for c in robot.velocity_indices(j))
        ]
        columns = [c for j in joints for c in robot.velocity_indices(j)]
        active_rows = moving[:, columns].any(axis=1) if columns else np.zeros(6, dtype=bool)
        linear = "".join(a for i, a in enumerate(_AXES) if active_rows[i])
        angular = "".join(a for i, a in enumerate(_AXES) if active_rows[3 + i])
        n_wrist = min(len(angular), max(len(joints) - len(linear), 0))
        split = len(joints) - n_wrist
        partition = cls(joints[:split], joints[split:], linear=linear, angular=angular)
        _AUTO_CACHE[robot] = partition
        return partition


def partition_for(robot: KinematicModel, partition: object) -> Partition:
    """``partition``, or the robot's automatic one when it is None; InputError for anything
    else (a string such as "auto" included) and for a robot that is not a Robot."""
    check_model(robot)
    if partition is None:
        return Partition.auto(robot)
    if not isinstance(partition, Partition):
        raise InputError(f"partition must be a pinrate.Partition or None (automatic), not {partition!r}")
    return partition


def split_blocks(jacobian: np.ndarray, m: int, n_arm: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(A, B, U, W) of a Jacobian already restricted to the partition's rows and columns."""
    return (jacobian[:m, :n_arm], jacobian[:m, n_arm:], jacobian[m:, :n_arm], jacobian[m:, n_arm:])


def _names(value: object, what: str) -> tuple[str, ...]:
    if isinstance(value, str):
        return (value,)
    try:
        names: tuple[object, ...] = tuple(value)  # type: ignore[arg-type]
    except TypeError:
        raise InputError(f"partition {what} must be a sequence of joint names") from None
    for name in names:
        if not isinstance(name, str):
            raise InputError(f"partition {what} must hold joint names (str), got {name!r}")
    return tuple(str(name) for name in names)


def _axes(value: object, what: str) -> str:
    if not isinstance(value, str):
        raise InputError(f"{what} must be a string of axis letters from 'xyz', got {value!r}")
    unknown = sorted({a for a in value if a not in _AXES})
    if unknown:
        raise InputError(f"{what} axes {value!r}: unknown letter(s) {unknown}; valid letters: x, y, z")
    repeated = sorted({a for a in value if value.count(a) > 1})
    if repeated:
        raise InputError(f"{what} axes {value!r}: letter(s) {repeated} appear more than once")
    return value
