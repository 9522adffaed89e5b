"""The convergence Theorem of Shoham & Koren (1987, §4) and its work-volume statistics.

With P = U A^-1 (k x m) and Q = B W^-1 (m x k),

    G = P Q = U A^-1 B W^-1   (k x k, eq. 32)      H = Q P = B W^-1 U A^-1   (m x m, eq. 50)

The error of MCA1 obeys e(i+1) = β G e(i) + G Ω(i) (eq. 40); freezing G along the
trajectory, it dies out when every eigenvalue of G lies inside the unit circle (Result 1);
MCA2 needs the same of H (Result 2). PQ and QP share their non-zero eigenvalues, so the
smaller of G and H decides for all three algorithms (the Theorem).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from . import batched
from .algorithms import inverse
from .errors import InputError, SingularBlockError
from .parallel import map_chunks, robot_from_spec
from .partition import Partition
from .robot import RngLike, Robot, RobotSpec

_Z95 = 1.959963984540054  # two-sided 95 % normal quantile


@dataclass(frozen=True)
class Convergence:
    """The Theorem's test at one configuration."""

    G: np.ndarray
    H: np.ndarray
    eigenvalues: np.ndarray
    spectral_radius: float
    converges: bool


def convergence_matrices(A: np.ndarray, B: np.ndarray, U: np.ndarray, W: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(G, H) = (U A^-1 B W^-1, B W^-1 U A^-1) (eq. 32, 50); pseudo-inverses for non-square blocks."""
    P = U @ inverse(A, "A")
    Q = B @ inverse(W, "W")
    return P @ Q, Q @ P


def convergence_from_blocks(A: np.ndarray, B: np.ndarray, U: np.ndarray, W: np.ndarray) -> Convergence:
    """The Theorem's test from the blocks of eq. 19."""
    G, H = convergence_matrices(A, B, U, W)
    smaller = G if G.shape[0] <= H.shape[0] else H
    eigenvalues = np.linalg.eigvals(smaller) if smaller.size else np.zeros(0, dtype=complex)
    radius = float(np.max(np.abs(eigenvalues))) if eigenvalues.size else 0.0
    return Convergence(G=G, H=H, eigenvalues=eigenvalues, spectral_radius=radius, converges=radius < 1.0)


def convergence(robot: Robot, q: object, *, partition: Partition | None = None) -> Convergence:
    """The Theorem's test at configuration q: G, H, eigenvalues of the smaller, ρ, ρ < 1.

    Raises:
        SingularBlockError: A or W is square and singular at q (G and H do not exist).
    """
    q = robot.check_q(q)
    partition = Partition.auto(robot) if partition is None else partition
    try:
        return convergence_from_blocks(*partition.blocks(robot, robot.kinematics(q)[0]))
    except SingularBlockError as error:
        raise error.at(robot.name, q, " (G and H are undefined there)") from None


def spectral_radii(A: np.ndarray, B: np.ndarray, U: np.ndarray, W: np.ndarray) -> np.ndarray:
    """ρ of the smaller of G and H for stacks of blocks (N, ., .); inf where A or W is singular."""
    A_inv, singular_A = batched.inverse(A)
    W_inv, singular_W = batched.inverse(W)
    P = U @ A_inv
    Q = B @ W_inv
    radii = batched.spectral_radius(P @ Q if P.shape[1] <= Q.shape[1] else Q @ P)
    radii[singular_A | singular_W] = np.inf
    return radii


@dataclass(frozen=True)
class ConvergenceSample:
    """The Theorem's test over configurations drawn uniformly in the joint limits."""

    q: np.ndarray
    spectral_radius: np.ndarray
    partition: Partition

    @property
    def fraction(self) -> float:
        """Share of the samples with spectral radius < 1."""
        return float(np.mean(self.spectral_radius < 1.0)) if self.spectral_radius.size else math.nan

    @property
    def interval(self) -> tuple[float, float]:
        """95 % Wilson score confidence interval of :attr:`fraction`."""
        return wilson_interval(int(np.sum(self.spectral_radius < 1.0)), int(self.spectral_radius.size))


def wilson_interval(successes: int, trials: int, z: float = _Z95) -> tuple[float, float]:
    """Wilson score interval of a binomial proportion (good near 0 and 1, unlike Wald's)."""
    if trials == 0:
        return (0.0, 1.0)
    p = successes / trials
    denominator = 1.0 + z * z / trials
    centre = (p + z * z / (2 * trials)) / denominator
    half = z * math.sqrt(p * (1 - p) / trials + z * z / (4 * trials * trials)) / denominator
    return (max(0.0, centre - half), min(1.0, centre + half))


def partition_jacobians(robot: Robot, configurations: np.ndarray, partition: Partition) -> np.ndarray:
    """Sensor-frame Jacobians restricted to the partition, a stack (N, m + k, n)."""
    index = partition.resolve(robot)
    if configurations.shape[0] == 0:
        return np.zeros((0, index.rows.size, index.columns.size))
    if robot.sensor_id == robot.tip_id:
        # The hot loop: Robot.sensor_jacobian's sensor-at-tip branch, inlined (one Pinocchio
        # call per q, collected in a list, stacked once): 15 % faster than calling the method.
        compute, model, data, tip, local = pin.computeFrameJacobian, robot.model, robot.data, robot.tip_id, pin.LOCAL
        full = np.stack([compute(model, data, q, tip, local) for q in list(configurations)])
    else:
        full = np.stack([robot.sensor_jacobian(q) for q in list(configurations)])
    if index.all_rows and index.all_columns:
        return full
    return full[:, index.rows][:, :, index.columns]


CHUNK = 20_000
"""Configurations per chunk of work in :func:`sample_convergence`."""


def radii_of_configurations(spec: RobotSpec, partition: Partition, configurations: np.ndarray) -> np.ndarray:
    """ρ at each configuration (N, nq): one chunk of work, runnable in any process."""
    return radii_for_robot(robot_from_spec(spec), partition, configurations)


def radii_for_robot(robot: Robot, partition: Partition, configurations: np.ndarray) -> np.ndarray:
    """ρ at each configuration (N, nq) of ``robot``: Pinocchio Jacobians, batched block algebra."""
    index = partition.resolve(robot)
    jacobians = partition_jacobians(robot, configurations, partition)
    m, n_arm = index.m, index.arm_columns.size
    return spectral_radii(
        jacobians[:, :m, :n_arm], jacobians[:, :m, n_arm:], jacobians[:, m:, :n_arm], jacobians[:, m:, n_arm:]
    )


def spectral_radius_at(
    robot: Robot,
    configurations: np.ndarray,
    *,
    partition: Partition | None = None,
    workers: int = 1,
    scheduler: object = None,
    progress: bool | None = None,
) -> np.ndarray:
    """ρ of the smaller of G and H at each configuration (N, nq), in chunks, in parallel if asked."""
    partition = Partition.auto(robot) if partition is None else partition
    partition.resolve(robot)  # unknown joints fail here, not in a worker
    configurations = np.asarray(configurations, dtype=float)
    if configurations.ndim != 2 or configurations.shape[1] != robot.nq:
        raise InputError(f"configurations must have shape (N, {robot.nq}), got {configurations.shape}")
    if workers == 1 and scheduler is None and configurations.shape[0] <= CHUNK:
        return radii_for_robot(robot, partition, configurations)
    chunks = [configurations[start : start + CHUNK] for start in range(0, configurations.shape[0], CHUNK)]
    parts = map_chunks(
        radii_of_configurations,
        chunks,
        robot.spec(),
        partition,
        workers=workers,
        scheduler=scheduler,
        progress=progress,
        description=f"{robot.name}: rho",
    )
    return np.concatenate(parts) if parts else np.zeros(0)


def sample_convergence(
    robot: Robot,
    samples: int,
    *,
    partition: Partition | None = None,
    rng: RngLike = None,
    workers: int = 1,
    scheduler: object = None,
    progress: bool | None = None,
) -> ConvergenceSample:
    """The Theorem's test at ``samples`` configurations drawn uniformly in the joint limits.

    Only the partition's joints are drawn (others stay at neutral; joints without limits in
    [-pi, pi]). Jacobians come from Pinocchio one configuration at a time; the block algebra
    and the eigenvalues are batched in closed form (:mod:`pinrate.batched`). ``workers``
    spreads the chunks over processes, ``scheduler`` over a Dask cluster (the result is
    the same either way: configurations are drawn here first). ``progress``: a bar (None:
    on a terminal only).
    """
    if isinstance(samples, bool) or not isinstance(samples, int | np.integer) or samples < 1:
        raise InputError(f"samples must be a positive integer, got {samples!r}")
    partition = Partition.auto(robot) if partition is None else partition
    configurations = robot.sample_configurations(int(samples), rng, joints=partition.joints)
    radii = spectral_radius_at(
        robot, configurations, partition=partition, workers=workers, scheduler=scheduler, progress=progress
    )
    return ConvergenceSample(q=configurations, spectral_radius=radii, partition=partition)
