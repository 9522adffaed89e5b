"""What a control step sees and what it did: :class:`Observation` (kinematics at q, one
Pinocchio pass) and :class:`Step` (the next q, the rates applied, the status)."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from ..errors import SingularBlockError
from ..kinematics.partition import PartitionIndex
from ..kinematics.spatial import norm
from ..solvers import closed_form
from ..solvers.rates import partition_spectral_radius
from .commands import PoseGoal
from .status import Status


@dataclass(slots=True)  # a record, read-only by convention: frozen dataclasses cost ~1 µs per step
class Observation:
    """What the controller sees at q, from one kinematics pass.

    Attributes:
        q: the configuration (nq,).
        jacobian: the sensor-frame Jacobian (6, nv).
        world_T_tip, world_T_sensor: the tip and sensor poses in the world.
        algorithm: the controller's algorithm (ρ is that of its error map where it differs).
        index: the controller's resolved partition.
        goal: the pose goal ``error`` was measured against, if any.
        error: the controlled pose error (m + k,) in partition order, sensor axes (m, rad).
    """

    q: np.ndarray
    jacobian: np.ndarray
    world_T_tip: pin.SE3
    world_T_sensor: pin.SE3
    algorithm: str
    index: PartitionIndex
    goal: PoseGoal | None = None
    error: np.ndarray | None = None
    _blocks: closed_form.Blocks | None = None
    _blocks_made: bool = False
    _spectral_radius: float | None = None
    _inverses: dict[str, closed_form.Matrix | SingularBlockError] | None = None

    @property
    def blocks(self) -> closed_form.Blocks | None:
        """A, B, U, W of J (eq. 19) as nested lists when the closed-form kernels apply, else
        None; made on first use (a step the compiled core takes reads J alone)."""
        if not self._blocks_made:
            self._blocks = closed_form.blocks(self.jacobian, self.index.selectors) if self.index.small else None
            self._blocks_made = True
        return self._blocks

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


def error_norms(observation: Observation, m: int) -> tuple[float, float]:
    """(position error in m, rotation error in rad) of an observation taken against a goal."""
    assert observation.error is not None
    return norm(observation.error[:m]), norm(observation.error[m:])


__all__ = ["Observation", "Step", "error_norms"]
