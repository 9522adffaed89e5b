"""Joint rates from a sensor-frame twist at a configuration: the algorithms of the
registry applied to a robot's partitioned Jacobian (the contract's ``pinrate.joint_rates``)."""

from __future__ import annotations

import math

import numpy as np

from ..checks import check_vector
from ..errors import SingularBlockError
from ..kinematics.manipulator import Robot
from ..kinematics.partition import Partition, PartitionIndex, partition_for, position_first_applies, split_blocks
from . import closed_form, reference
from .error_map import THEOREM_ALGORITHMS, error_map
from .registry import REGISTRY, check_algorithm


def position_first_rates(
    J: np.ndarray, m: int, n_arm: int, twist: np.ndarray, algorithm: str, invert: reference.Inverter | None = None
) -> np.ndarray:
    """Rates (n,) of :func:`~pinrate.solvers.reference.position_first` for a J (m + k, n) in
    partition order with a square A (``n_arm`` = m arm columns) and a tall W, the blocks
    inverted by ``invert`` (None: the algorithm's own, ``position_first`` of :class:`~.registry.Algorithm`).
    Where A is singular, ``exact`` falls back to its least squares over the whole J (it never
    raises); schur raises SingularBlockError as it does for a singular square block."""
    if invert is None:
        invert = REGISTRY[algorithm].position_first
        assert invert is not None
    try:
        arm, wrist = reference.position_first(*split_blocks(J, m, n_arm), twist[:m], twist[m:], invert=invert)
    except SingularBlockError:
        if algorithm != "exact":
            raise
        return reference.exact(J, twist)
    return np.concatenate([arm, wrist])


def position_first_solves(algorithm: str, m: int, n_arm: int, k: int, n_wrist: int) -> bool:
    """Whether ``algorithm`` solves these block shapes by
    :func:`~pinrate.solvers.reference.position_first` (``position_first`` of :class:`~.registry.Algorithm`)."""
    return REGISTRY[algorithm].position_first is not None and position_first_applies(m, n_arm, k, n_wrist)


def partition_rates(
    J: np.ndarray,
    index: PartitionIndex,
    twist: np.ndarray,
    algorithm: str,
    parts: closed_form.Blocks | None = None,
    position_first: bool | None = None,
) -> np.ndarray:
    """Joint rates (nv,) from a sensor-frame Jacobian (6, nv) and a twist in partition order.

    Joints outside the partition get rate 0. ``parts`` may hold the blocks as nested lists
    already taken from J (when ``index.small``). On a partition with a square A and a tall W,
    exact, schur and dls put position first (:func:`position_first_rates`); ``position_first``
    False keeps them from it (a controller's partition with joints held at a limit solves as
    the partition it came from: a 6-DOF arm with a wrist joint held keeps its least squares).
    Raises SingularBlockError (without q: the caller adds it) when a block algorithm meets a
    singular square block.
    """
    entry = REGISTRY[algorithm]
    if index.small and entry.closed_form is not None:
        if parts is None:
            parts = closed_form.blocks(J, index.selectors)
        floats = closed_form.block_rates(entry.closed_form, parts, twist)
        if index.all_columns:
            return np.array(floats)
        rates = np.zeros(J.shape[1])
        rates[index.columns] = floats
        return rates
    if index.columns.size == 0:
        return np.zeros(J.shape[1])
    reduced = J if index.all_rows and index.all_columns else J[np.ix_(index.rows, index.columns)]
    first = index.position_first and position_first is not False
    if first and entry.position_first is not None:
        solved = position_first_rates(reduced, index.m, index.arm_columns.size, twist, algorithm)
    elif entry.whole is not None:
        solved = entry.whole(reduced, twist)
    else:
        assert entry.blocks is not None
        blocks = split_blocks(reduced, index.m, index.arm_columns.size)
        arm, wrist = entry.blocks(*blocks, twist[: index.m], twist[index.m :])
        rates = np.zeros(J.shape[1])
        rates[index.arm_columns] = arm
        rates[index.wrist_columns] = wrist
        return rates
    if index.all_columns:  # solved is a new array of every column, in order
        return solved
    rates = np.zeros(J.shape[1])
    rates[index.columns] = solved
    return rates


def partition_spectral_radius(
    J: np.ndarray,
    index: PartitionIndex,
    parts: closed_form.Blocks | None = None,
    algorithm: str = "mca1",
    inverses: tuple[closed_form.Matrix, closed_form.Matrix] | None = None,
) -> float:
    """ρ of the smaller of G and H (eq. 32, 50) from a sensor-frame Jacobian (6, nv); inf
    where A or W is singular. Closed form on ``parts`` when given (square blocks <= 3), with
    their ``inverses`` (A^-1, W^-1) when at hand.
    Where A is tall or W wide, ρ of the error map of ``algorithm`` (an MCA; MCA1 for the
    others), :mod:`pinrate.solvers.error_map`; a wide A or a tall W keeps the pseudo-inverse G,
    whose spectrum is the map's."""
    try:
        if parts is not None:
            return closed_form.spectral_radius(parts, inverses)
        reduced = J[np.ix_(index.rows, index.columns)]
        arm = index.arm_columns.size
        if index.pseudo_g:
            return reference.spectral_radius(*split_blocks(reduced, index.m, arm))
        mca = algorithm if algorithm in THEOREM_ALGORITHMS else "mca1"
        return error_map(reduced, index.m, arm, mca).spectral_radius
    except SingularBlockError:
        return math.inf


def joint_rates(
    robot: Robot, q: object, twist: object, *, algorithm: str = "mca1", partition: Partition | None = None
) -> np.ndarray:
    """Joint rates (nv,) that realise a sensor-frame twist command at configuration q.

    Args:
        robot: the robot (its tip and sensor frames fix what the twist means).
        q: configuration (nq,).
        twist: the controlled components in partition order, linear then angular (m + k,),
            in the sensor frame's axes: m/s and rad/s.
        algorithm: a name of :data:`pinrate.ALGORITHMS`: "exact", "schur" (eq. 20), "mca1"
            (eq. 24-25), "mca2" (eq. 44-45), "mca3" (eq. 51-52) or "dls".
        partition: which joints and rows take part; None means ``Partition.auto(robot)``.

    Returns:
        Joint rates in velocity-vector order (rad/s or m/s); joints outside the partition get 0.

    Raises:
        InputError: q or twist of the wrong length or with NaN/inf; unknown algorithm or
            partition joints.
        SingularBlockError: an MCA or schur meets a singular square block (never NaN/inf).
    """
    algorithm = check_algorithm(algorithm)
    partition = partition_for(robot, partition)
    q = robot.check_q(q)
    index = partition.resolve(robot)
    twist = check_vector(twist, index.rows.size, "twist (linear then angular components of the partition)")
    jacobian = robot.jacobian_unchecked(q)
    try:
        return partition_rates(jacobian, index, twist, algorithm)
    except SingularBlockError as error:
        raise error.at(robot.name, q, f" with {algorithm}") from None
