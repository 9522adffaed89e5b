"""The record of a servo run."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..kinematics.partition import Partition


@dataclass
class Trajectory:
    """A servo run: value i of every per-configuration array is taken at ``q[i]``.

    Attributes:
        q: configurations (N, nq), q[0] = q0.
        position_error: norm of the controlled position error (m), (N,).
        orientation_error: norm of the controlled rotation error (rad), (N,).
        spectral_radius: ρ of the smaller of G and H (inf where A or W is singular), (N,).
        status: per configuration, "moving", "saturated" (TCP speed limit active), "joint
            limit" (a joint held at a position limit), "rate limited" (a velocity limit bound)
            or the final state ("converged", "diverging", "stalled", "singular", "max steps";
            see :mod:`pinrate.control.servo_loop`).
        joint_rates: the rates applied after each configuration but the last, (N - 1, nv).
        converged: both errors below tol at the last configuration.
        reason: why the run stopped, in words.
    """

    q: np.ndarray
    position_error: np.ndarray
    orientation_error: np.ndarray
    spectral_radius: np.ndarray
    status: list[str]
    joint_rates: np.ndarray
    converged: bool
    reason: str
    algorithm: str
    dt: float
    partition: Partition = field(repr=False)

    @property
    def steps(self) -> int:
        """Number of integration steps taken (N - 1)."""
        return self.q.shape[0] - 1

    @property
    def time(self) -> np.ndarray:
        """Time stamps (N,) in seconds."""
        return np.arange(self.q.shape[0]) * self.dt
