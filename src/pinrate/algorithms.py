"""Resolved-rate solutions: joint rates from a sensor-frame twist command.

Every function here is pure mathematics over the partitioned Jacobian of eq. 19,

    J = [[A, B], [U, W]],   twist = [v; Ω],   rates = [qdot_arm; qdot_wrist],

with v (the m controlled linear components) and Ω (the k controlled angular components)
expressed in the sensor frame's axes, exactly as the rows of J. Blocks that are not square
are inverted with the Moore-Penrose pseudo-inverse. A square block is *singular* when
|det M| <= SINGULAR_RATIO * prod_j ||M[:, j]|| (Hadamard's bound makes this scale-free);
the MCA algorithms then raise :class:`SingularBlockError` naming the block, while ``exact``
falls back to the minimum-norm least-squares solution and ``dls`` is always finite.

:func:`joint_rates` is the public entry point (the contract's ``pinrate.joint_rates``).
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from . import _small
from .errors import InputError, SingularBlockError, choices_hint
from .partition import Partition, PartitionIndex, split_blocks
from .robot import Robot, check_vector

SINGULAR_RATIO = _small.SINGULAR_RATIO
"""A square block M is singular when |det M| <= SINGULAR_RATIO * prod of its column norms."""

EXACT_RCOND = 1e-10
"""``exact`` falls back to the pseudo-inverse when J's condition number exceeds 1 / EXACT_RCOND."""

PINV_RCOND = 1e-10
"""Relative cut-off of singular values in every pseudo-inverse."""

DLS_DAMPING = 1e-2
"""Damping λ of :func:`dls` (in the twist's mixed units: m/s and rad/s per unit rate)."""

Blocks = tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]


def hadamard_ratio(M: np.ndarray) -> float:
    """|det M| / prod ||M[:, j]||, in [0, 1]: 1 for orthogonal columns, 0 when singular."""
    n = M.shape[0]
    if n == 0:
        return 1.0
    norms = np.linalg.norm(M, axis=0)
    scale = float(np.prod(norms))
    if scale == 0.0 or not math.isfinite(scale):
        return 0.0
    return abs(float(np.linalg.det(M))) / scale


def inverse(M: np.ndarray, block: str) -> np.ndarray:
    """M^-1 for a non-singular square block, M^+ for a rectangular one.

    Raises:
        SingularBlockError: a square block whose Hadamard ratio is below SINGULAR_RATIO.
    """
    rows, cols = M.shape
    if rows == 0 or cols == 0:
        return np.zeros((cols, rows))
    if rows != cols:
        return np.linalg.pinv(M, rcond=PINV_RCOND)
    if hadamard_ratio(M) <= SINGULAR_RATIO:
        raise SingularBlockError(f"block {block} ({rows}x{cols}) is singular", block=block)
    return np.linalg.inv(M)


def exact(J: np.ndarray, twist: np.ndarray) -> np.ndarray:
    """The exact resolved-rate solution qdot = J^-1 s (eq. 4, 18).

    Square: one LAPACK solve, no error. Since ||J||_F ||qdot|| <= cond(J) ||s||, a solution
    with ||J||_F ||qdot|| > ||s|| / EXACT_RCOND betrays a (numerically) singular J; it and
    every non-square J get the minimum-norm least-squares solution J^+ s instead, whose
    twist error (I - J J^+) s is the part of the command the joints cannot produce.
    """
    rows, cols = J.shape
    if rows == cols and rows > 0:
        try:
            rates = np.linalg.solve(J, twist)
        except np.linalg.LinAlgError:
            rates = None
        if rates is not None:
            flat = J.ravel()
            growth = float(flat @ flat) * float(rates @ rates) * EXACT_RCOND**2
            if growth <= float(twist @ twist):  # also False for NaN/inf rates
                return rates
    return np.linalg.pinv(J, rcond=PINV_RCOND) @ twist if J.size else np.zeros(cols)


def schur(
    A: np.ndarray, B: np.ndarray, U: np.ndarray, W: np.ndarray, v: np.ndarray, omega: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """The exact inverse by blocks (eq. 20), through the Schur complement of W:

        K = (A - B W^-1 U)^-1,  N = (W - U A^-1 B)^-1,  L = -A^-1 B N,  M = -W^-1 U K
        qdot_arm   = K v + L Ω = K (v - B W^-1 Ω)
        qdot_wrist = M v + N Ω = W^-1 (Ω - U qdot_arm)

    The last form follows from Woodbury's identity N = W^-1 + W^-1 U K B W^-1 and needs
    neither A^-1 nor N: one complement and W^-1. With a wide arm (A is m x n, n > m) K is
    the pseudo-inverse of the m x n complement and the result still solves J q̇ = s exactly
    (a particular solution, not the minimum-norm one). Error: none when W and K exist.
    (The OCR'd eq. 20 prints "U = -A^-1 B N" for L.)
    """
    W_inv = inverse(W, "W")
    arm = inverse(A - B @ W_inv @ U, "A - B W^-1 U") @ (v - B @ (W_inv @ omega))
    return arm, W_inv @ (omega - U @ arm)


def mca1(
    A: np.ndarray, B: np.ndarray, U: np.ndarray, W: np.ndarray, v: np.ndarray, omega: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """First motion control algorithm (eq. 23-25): J^-1 with U taken as 0.

        qdot_arm = A^-1 v - A^-1 B W^-1 Ω        (eq. 24)
        qdot_wrist = W^-1 Ω                       (eq. 25)

    Error: the velocity is exact, v' = v (eq. 28); the angular velocity is off by
    e = Ω - Ω' = -U qdot_arm = -U A^-1 v + G Ω (eq. 30-31), G = U A^-1 B W^-1 (eq. 32).
    Exact when U = 0 (a Cartesian arm).
    """
    A_inv, W_inv = inverse(A, "A"), inverse(W, "W")
    wrist = W_inv @ omega
    return A_inv @ (v - B @ wrist), wrist


def mca2(
    A: np.ndarray, B: np.ndarray, U: np.ndarray, W: np.ndarray, v: np.ndarray, omega: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Second motion control algorithm (eq. 22, 44-45): J^-1 with B taken as 0.

        qdot_arm = A^-1 v                          (eq. 44)
        qdot_wrist = -W^-1 U A^-1 v + W^-1 Ω        (eq. 45)

    Error: the angular velocity is exact, Ω' = Ω (eq. 47); the velocity is off by
    e_v = v - v' = -B qdot_wrist = H v - B W^-1 Ω (eq. 48-49), H = B W^-1 U A^-1 (eq. 50).
    Exact when B = 0: the wrist axes meet at the TCP (eq. 22).
    """
    A_inv, W_inv = inverse(A, "A"), inverse(W, "W")
    arm = A_inv @ v
    return arm, W_inv @ (omega - U @ arm)


def mca3(
    A: np.ndarray, B: np.ndarray, U: np.ndarray, W: np.ndarray, v: np.ndarray, omega: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Third (general) motion control algorithm (eq. 21, 51-52): K ≈ A^-1, N ≈ W^-1.

        qdot_arm = A^-1 v - A^-1 B W^-1 Ω           (eq. 51)
        qdot_wrist = -W^-1 U A^-1 v + W^-1 Ω         (eq. 52)

    Error: e_v = H v (eq. 53) and e_Ω = G Ω (eq. 54).
    """
    A_inv, W_inv = inverse(A, "A"), inverse(W, "W")
    return A_inv @ (v - B @ (W_inv @ omega)), W_inv @ (omega - U @ (A_inv @ v))


def dls(J: np.ndarray, twist: np.ndarray, damping: float = DLS_DAMPING) -> np.ndarray:
    """Damped least squares: qdot = J^T (J J^T + λ² I)^-1 s, λ = ``damping``.

    The singularity-robust baseline (Nakamura & Hanafusa 1986; Wampler 1986): finite
    everywhere, with a twist error λ² (J J^T + λ² I)^-1 s that grows near singularities and
    vanishes as the command goes to zero.
    """
    rows = J.shape[0]
    if J.size == 0:
        return np.zeros(J.shape[1])
    return J.T @ np.linalg.solve(J @ J.T + damping**2 * np.eye(rows), twist)


BlockAlgorithm = Callable[..., tuple[np.ndarray, np.ndarray]]
BLOCK_ALGORITHMS: dict[str, BlockAlgorithm] = {"schur": schur, "mca1": mca1, "mca2": mca2, "mca3": mca3}
ALGORITHMS: tuple[str, ...] = ("exact", "schur", "mca1", "mca2", "mca3", "dls")


def check_algorithm(algorithm: object) -> str:
    """The algorithm name, or an InputError listing the valid ones."""
    if algorithm not in ALGORITHMS:
        raise InputError(f"unknown algorithm {algorithm!r}." + choices_hint(str(algorithm), ALGORITHMS))
    return str(algorithm)


def partition_rates(
    J: np.ndarray,
    index: PartitionIndex,
    twist: np.ndarray,
    algorithm: str,
    parts: _small.Blocks | None = None,
) -> np.ndarray:
    """Joint rates (nv,) from a sensor-frame Jacobian (6, nv) and a twist in partition order.

    Joints outside the partition get rate 0. ``parts`` may hold the blocks as nested lists
    already taken from J (when ``index.small``). Raises SingularBlockError (without q: the
    caller adds it) when an MCA meets a singular square block.
    """
    if index.small and algorithm in _small.KERNELS:
        if parts is None:
            parts = _small.blocks(J, index.selectors)
        solved = _small.block_rates(algorithm, parts, twist)
        if index.all_columns:
            return np.array(solved)
        rates = np.zeros(J.shape[1])
        rates[index.columns] = solved
        return rates
    rates = np.zeros(J.shape[1])
    if index.columns.size == 0:
        return rates
    reduced = J if index.all_rows and index.all_columns else J[np.ix_(index.rows, index.columns)]
    if algorithm == "exact":
        rates[index.columns] = exact(reduced, twist)
    elif algorithm == "dls":
        rates[index.columns] = dls(reduced, twist)
    else:
        blocks = split_blocks(reduced, index.m, index.arm_columns.size)
        arm, wrist = BLOCK_ALGORITHMS[algorithm](*blocks, twist[: index.m], twist[index.m :])
        rates[index.arm_columns] = arm
        rates[index.wrist_columns] = wrist
    return rates


def joint_rates(
    robot: Robot, q: object, twist: object, *, algorithm: str = "mca1", partition: Partition | None = None
) -> np.ndarray:
    """Joint rates (nv,) that realise a sensor-frame twist command at configuration q.

    Args:
        robot: the robot (its tip and sensor frames fix what the twist means).
        q: configuration (nq,).
        twist: the controlled components in partition order, linear then angular (m + k,),
            in the sensor frame's axes: m/s and rad/s.
        algorithm: "exact", "schur" (eq. 20), "mca1" (eq. 24-25), "mca2" (eq. 44-45),
            "mca3" (eq. 51-52) or "dls" (damped least squares).
        partition: which joints and rows take part; None means ``Partition.auto(robot)``.

    Returns:
        Joint rates in velocity-vector order; joints outside the partition get 0.

    Raises:
        InputError: q or twist of the wrong length or with NaN/inf; unknown algorithm or
            partition joints.
        SingularBlockError: an MCA or schur meets a singular square block (never NaN/inf).
    """
    algorithm = check_algorithm(algorithm)
    q = robot.check_q(q)
    partition = Partition.auto(robot) if partition is None else partition
    index = partition.resolve(robot)
    twist = check_vector(twist, index.rows.size, "twist (linear then angular components of the partition)")
    jacobian = robot.sensor_jacobian(q)
    try:
        return partition_rates(jacobian, index, twist, algorithm)
    except SingularBlockError as error:
        raise error.at(robot.name, q, f" with {algorithm}") from None
