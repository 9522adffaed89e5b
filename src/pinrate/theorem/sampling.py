"""The Theorem over the work volume: ρ at many configurations, sampled or given.

Jacobians come from Pinocchio one configuration at a time; the block algebra and the
eigenvalues run batched in closed form (:mod:`pinrate.solvers.batched`), in chunks that
can go to worker processes or a Dask cluster (:mod:`.parallel`). The compiled core, where
installed, runs Jacobians and closed forms in one C++ loop, on threads of its own.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from ..checks import MAX_SAMPLES, RngLike, check_count
from ..compiled import CoreServo, rho_map
from ..errors import InputError
from ..kinematics.manipulator import Robot, RobotSpec
from ..kinematics.partition import Partition, partition_for
from ..kinematics.urdf import robot_from_spec
from ..solvers import batched
from .parallel import check_workers, map_chunks

_Z95 = 1.959963984540054  # two-sided 95 % normal quantile


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
    if not 0 <= successes <= trials:
        raise InputError(f"successes must lie in [0, trials]: got {successes} of {trials}")
    if trials == 0:
        return (0.0, 1.0)
    p = successes / trials
    denominator = 1.0 + z * z / trials
    centre = (p + z * z / (2 * trials)) / denominator
    half = z * math.sqrt(p * (1 - p) / trials + z * z / (4 * trials * trials)) / denominator
    return (max(0.0, centre - half), min(1.0, centre + half))


def _partition_jacobians(robot: Robot, configurations: np.ndarray, partition: Partition) -> np.ndarray:
    """Sensor-frame Jacobians restricted to the partition, a stack (N, m + k, n)."""
    index = partition.resolve(robot)
    if configurations.shape[0] == 0:
        return np.zeros((0, index.rows.size, index.columns.size))
    if robot.sensor_id == robot.tip_id and not robot.folds_mimics:
        # The hot loop: Robot.jacobian_unchecked's sensor-at-tip branch, inlined (one Pinocchio
        # call per q, collected in a list, stacked once): 15 % faster than calling the method.
        compute, model, data, tip, local = pin.computeFrameJacobian, robot.model, robot.data, robot.tip_id, pin.LOCAL
        full = np.stack([compute(model, data, q, tip, local) for q in list(configurations)])
        full = full.reshape(len(full), 6, robot.nv)  # eigenpy gives one column as a vector
    else:
        full = np.stack([robot.jacobian_unchecked(q) for q in list(configurations)])
    if index.all_rows and index.all_columns:
        return full
    return full[:, index.rows][:, :, index.columns]


CHUNK = 20_000
"""Configurations per chunk of work in :func:`sample_convergence` on the Python path."""

CORE_CHUNK = 250_000
"""Configurations per call of the compiled ρ map (a few tenths of a second each): the
progress bar moves and Ctrl-C is heard between calls."""


def _spectral_radius_of_chunk(spec: RobotSpec, partition: Partition, configurations: np.ndarray) -> np.ndarray:
    """ρ at each configuration of one chunk (N, nq), runnable in any process."""
    return _spectral_radius(robot_from_spec(spec), partition, configurations)


def _core_map(robot: Robot, partition: Partition) -> CoreServo | None:
    """The compiled ρ map of ``robot`` and ``partition``, or None where the Python path runs."""
    index = partition.resolve(robot)
    return rho_map(
        robot, tuple(index.rows.tolist()), tuple(index.columns.tolist()), index.m, int(index.arm_columns.size)
    )


def _core_chunk(core: CoreServo, threads: int, configurations: np.ndarray) -> np.ndarray:
    """ρ at each configuration of one chunk (N, nq) on the compiled map's ``threads``."""
    return core.spectral_radius_at(configurations, threads=threads)


def _spectral_radius(robot: Robot, partition: Partition, configurations: np.ndarray) -> np.ndarray:
    """ρ at each configuration (N, nq) of ``robot``: in the compiled core where it covers the
    robot and partition (Jacobians and closed forms in one C++ loop), else Pinocchio
    Jacobians and the batched block algebra."""
    core = _core_map(robot, partition)
    if core is not None:
        return core.spectral_radius_at(configurations)
    index = partition.resolve(robot)
    jacobians = _partition_jacobians(robot, configurations, partition)
    m, n_arm = index.m, index.arm_columns.size
    return batched.spectral_radius(
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
    """ρ of the smaller of G and H at each configuration (N, nq), in chunks, in parallel if asked.

    ``workers``: threads inside the compiled core where it maps this robot and partition
    (each with its own Pinocchio Data; the result is the same for any count), else worker
    processes; ``scheduler``: a Dask cluster instead (:func:`.parallel.map_chunks`).
    """
    partition = partition_for(robot, partition)
    partition.resolve(robot)  # unknown joints fail here, not in a worker
    configurations = robot.check_configurations(configurations)
    workers = check_workers(workers)
    core = _core_map(robot, partition) if scheduler is None else None
    description = f"{robot.name}: rho"
    if core is not None:
        # Threads, not processes: a process rebuilds the robot and ships its chunk both ways,
        # which costs about as much as the compiled map of the chunk itself.
        if configurations.shape[0] <= CORE_CHUNK:
            return core.spectral_radius_at(configurations, threads=workers)
        starts = range(0, configurations.shape[0], CORE_CHUNK)
        parts = map_chunks(
            _core_chunk,
            [configurations[start : start + CORE_CHUNK] for start in starts],
            core,
            workers,
            progress=progress,
            description=description,
        )
        return np.concatenate(parts)
    if workers == 1 and scheduler is None and configurations.shape[0] <= CHUNK:
        return _spectral_radius(robot, partition, configurations)
    chunks = [configurations[start : start + CHUNK] for start in range(0, configurations.shape[0], CHUNK)]
    parts = map_chunks(
        _spectral_radius_of_chunk,
        chunks,
        robot.spec(),
        partition,
        workers=workers,
        scheduler=scheduler,
        progress=progress,
        description=description,
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
    and the eigenvalues are batched in closed form (:mod:`pinrate.solvers.batched`); the
    compiled core, where installed, runs both in one C++ loop. ``workers`` spreads the work
    over that many threads inside the core (else over processes), ``scheduler`` over a Dask
    cluster (the result is the same either way: configurations are drawn here first). ``progress``: a bar (None:
    on a terminal only).
    """
    samples = check_count(samples, "samples", minimum=1, maximum=MAX_SAMPLES)
    partition = partition_for(robot, partition)
    configurations = robot.sample_configurations(samples, rng, joints=partition.joints)
    radii = spectral_radius_at(
        robot, configurations, partition=partition, workers=workers, scheduler=scheduler, progress=progress
    )
    return ConvergenceSample(q=configurations, spectral_radius=radii, partition=partition)
