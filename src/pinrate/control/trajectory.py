"""The record of a servo run: saved and loaded as ``.npz``, and reversed (Barker's
"recording and reversing a motion")."""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ..checks import PHYSICAL_BOUND
from ..errors import PinrateError
from ..files import MAX_LOAD_BYTES, NUMBERS, Npz, open_npz, replace_file
from ..kinematics.partition import Partition
from .status import Status

_ARRAYS = ("q", "position_error", "orientation_error", "spectral_radius", "joint_rates")
_TEXTS = ("reason", "algorithm", "linear", "angular")
FORMAT = "pinrate-trajectory-2"
"""The ``format`` entry of a saved trajectory: what :meth:`Trajectory.load` reads (and
``pinrate-trajectory-1``, whose step words it renames by :data:`RENAMED_WORDS`)."""

_FIRST_FORMAT = "pinrate-trajectory-1"

RENAMED_WORDS = {
    "saturated": Status.TWIST_SATURATED.word,
    "joint limit": Status.JOINT_LIMIT.word,
    "decelerating": Status.DECELERATE_FOR_SINGULARITY.word,
    "slowing for collision": Status.DECELERATE_FOR_COLLISION.word,
    "auxiliary elbow": Status.AUXILIARY_ELBOW.word,
    "frozen": Status.FROZEN.word,
}
"""Step words of release 0.1.0 (format ``pinrate-trajectory-1``) that :data:`~pinrate.control.status.WORDS`
renamed, old to new; its other words are unchanged."""


@dataclass(frozen=True)
class PlantRecord:
    """What the plant did beside what the controller commanded, step by step (a run on a
    plant: ``servo(..., plant=...)``; :mod:`pinrate.plants`).

    Attributes:
        name: the plant, in words (``Plant.name``).
        measured_rates: the joints' velocities the plant measured at the end of each step,
            (N - 1, nv), rad/s or m/s; the commanded ones are ``Trajectory.joint_rates``.
        tracking_error: per step, the distance (m) between the tip where the step's command
            would have put it (q[i] integrated by joint_rates[i] over dt) and where the plant
            measured it (at q[i + 1]), (N - 1,).
        saturated: per step and joint, True when the joint's actuator reached its effort
            limit during the step, (N - 1, nv).
    """

    name: str
    measured_rates: np.ndarray
    tracking_error: np.ndarray
    saturated: np.ndarray


_PLANT_FIELDS = ("plant", "measured_rates", "tracking_error", "saturated")


@dataclass
class Trajectory:
    """A servo run: value i of every per-configuration array is taken at ``q[i]``.

    Attributes:
        q: configurations (N, nq), q[0] = q0.
        position_error: norm of the controlled position error (m), (N,).
        orientation_error: norm of the controlled rotation error (rad), (N,).
        spectral_radius: ρ of the smaller of G and H (inf where A or W is singular), (N,).
        status: per configuration, the status of the step taken from it in words
            (:attr:`Status.word <pinrate.Status.word>`: "moving", "speed limited", "at a joint
            limit", "rate limited", …, the words the console shows), and for the last the
            run's outcome ("converged", "diverging", "stalled", "singular", "collision", "max
            steps", "plant"; see :mod:`pinrate.control.servo_loop`; "reversed" for a
            reversed run).
        joint_rates: the rates applied after each configuration but the last, (N - 1, nv).
        converged: both errors below tol at the last configuration.
        reason: why the run stopped, in words.
        detail: per configuration, what limited the step taken from it, in words (which
            joint, which block, what conditioning or distance; "" when nothing did); the last
            is ``reason``. Empty for trajectories saved before it existed.
        plant: what the plant measured beside the commands (:class:`PlantRecord`), for a run
            on a plant; None for a kinematic run (its q are the integrated rates).
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
    detail: list[str] = field(default_factory=list, repr=False)
    plant: PlantRecord | None = field(default=None, repr=False)

    @property
    def steps(self) -> int:
        """Number of integration steps taken (N - 1)."""
        return self.q.shape[0] - 1

    @property
    def time(self) -> np.ndarray:
        """Time stamps (N,) in seconds."""
        return np.arange(self.q.shape[0]) * self.dt

    def reversed(self) -> Trajectory:
        """The motion backwards at the recorded pace: configurations in reverse order and each
        step's rates negated, so integrating ``joint_rates[i]`` over ``dt`` from ``q[i]``
        gives ``q[i + 1]`` (exactly on every joint's own group: q exp(v) exp(-v) = q). Every
        configuration is one the run went through, so the reversal stays within every limit
        the run kept. Per-configuration arrays are reversed alike; ``converged`` is False and
        ``reason`` says what was reversed. A reversal is a plan, not a measurement: it has
        no :attr:`plant` record."""
        return Trajectory(
            q=self.q[::-1].copy(),
            position_error=self.position_error[::-1].copy(),
            orientation_error=self.orientation_error[::-1].copy(),
            spectral_radius=self.spectral_radius[::-1].copy(),
            status=[*self.status[-2::-1], "reversed"] if self.status else [],
            joint_rates=-self.joint_rates[::-1],
            converged=False,
            reason=f"reversed: {self.reason}",
            algorithm=self.algorithm,
            dt=self.dt,
            partition=self.partition,
            detail=[*self.detail[-2::-1], f"reversed: {self.reason}"] if self.detail else [],
        )

    def save(self, path: str | os.PathLike[str]) -> Path:
        """Write the trajectory to ``path`` as an uncompressed ``.npz`` of plain arrays (no
        pickles: :meth:`load` reads no object); returns the path. The file is written whole
        or not at all (:func:`~pinrate.files.replace_file`): a save that fails leaves the
        file it was replacing as it was. InputError naming the file for a path that cannot
        be written or a write that fails."""
        arrays = {name: np.asarray(getattr(self, name), dtype=float) for name in _ARRAYS}
        texts = {
            name: np.array(value)
            for name, value in (
                ("reason", self.reason),
                ("algorithm", self.algorithm),
                ("linear", self.partition.linear),
                ("angular", self.partition.angular),
            )
        }
        entries: dict[str, Any] = {
            "format": np.array(FORMAT),
            "status": np.array(self.status, dtype=str),
            "detail": np.array(self.detail, dtype=str),
            "arm": np.array(self.partition.arm, dtype=str),
            "wrist": np.array(self.partition.wrist, dtype=str),
            "converged": np.array(self.converged),
            "dt": np.array(self.dt),
            **arrays,
            **texts,
        }
        if self.plant is not None:
            entries.update(
                plant=np.array(self.plant.name),
                measured_rates=np.asarray(self.plant.measured_rates, dtype=float),
                tracking_error=np.asarray(self.plant.tracking_error, dtype=float),
                saturated=np.asarray(self.plant.saturated, dtype=bool),
            )
        # To a stream: numpy would append ".npz" to a name.
        return replace_file(path, "trajectory file", lambda stream: np.savez(stream, **entries))

    @classmethod
    def load(cls, path: str | os.PathLike[str], *, max_bytes: int = MAX_LOAD_BYTES) -> Trajectory:
        """A trajectory written by :meth:`save` (format ``pinrate-trajectory-2``, or ``-1``
        with its step words renamed by :data:`RENAMED_WORDS`).

        Read by :func:`~pinrate.files.open_npz`: a regular file only, every array's header
        checked before anything is read, and refused when reading it would take more than
        ``max_bytes`` (:data:`~pinrate.files.MAX_LOAD_BYTES`, 2 GiB). Then every field is
        checked: q floats (N, nq) with N, nq >= 1; position_error, orientation_error (N,)
        and spectral_radius (N,) floats >= 0 (ρ may be inf); joint_rates floats (N - 1, nv);
        every number finite within ±:data:`~pinrate.checks.PHYSICAL_BOUND` but ρ; status
        (N,) text; detail (N,) text or empty (absent in ``-1``); converged a boolean; dt a
        positive finite number up to PHYSICAL_BOUND; reason, algorithm, linear, angular one
        text each; arm and wrist lists of joint names (non-empty, printable) that make a
        :class:`~pinrate.kinematics.partition.Partition`; a run on a plant adds its
        :class:`PlantRecord` (``plant`` one text, ``measured_rates`` floats (N - 1, nv),
        ``tracking_error`` floats >= 0 (N - 1,), ``saturated`` booleans (N - 1, nv): all four
        or none). A field more or fewer is refused.

        Raises:
            InputError: naming the file (and the field): a missing file or one that is not
                a regular file, not a saved pinrate trajectory, too big, damaged, or whose
                fields do not hold what they must or do not fit together.
        """
        with open_npz(path, "trajectory file", max_bytes=max_bytes) as npz:
            version = _version(npz)
            npz.fields((*_FIELDS, "detail") if version == FORMAT else _FIELDS, ("detail", *_PLANT_FIELDS))
            rows, nq = npz.shape("q", NUMBERS, 2)
            if rows < 1 or nq < 1:
                raise npz.refuse(f"has shape {(rows, nq)}: a trajectory holds its start at least", "q")
            for name in _ARRAYS[1:4]:
                if npz.shape(name, NUMBERS, 1) != (rows,):
                    raise npz.refuse(f"has shape {npz.members[name].shape}, not ({rows},) as q's rows", name)
            steps = npz.shape("joint_rates", NUMBERS, 2)[0]
            if steps != rows - 1:
                raise npz.refuse(f"has {steps} rows for {rows} configurations, not {rows - 1}", "joint_rates")
            for name, allowed in (("status", (rows,)), ("detail", (rows, 0))):
                if name in npz.members and npz.shape(name, "U", 1)[0] not in allowed:
                    raise npz.refuse(f"has {npz.members[name].shape[0]} entries for {rows} configurations", name)
            arrays = {name: npz.floats(name, 2) for name in ("q", "joint_rates")}
            arrays.update({name: npz.floats(name, 1) for name in _ARRAYS[1:3]})
            arrays["spectral_radius"] = npz.floats("spectral_radius", 1, finite=False)
            for name in _ARRAYS[1:4]:
                if (arrays[name] < 0).any():
                    raise npz.refuse(f"holds a negative value at {int(np.argmax(arrays[name] < 0))}", name)
            status = npz.texts("status")
            if version == _FIRST_FORMAT:
                status = [RENAMED_WORDS.get(word, word) for word in status]
            detail = npz.texts("detail") if "detail" in npz.members else []
            dt = npz.number("dt")
            if not 0 < dt <= PHYSICAL_BOUND:
                raise npz.refuse(f"is {dt!r}: not a positive finite number up to {PHYSICAL_BOUND:g} s", "dt")
            converged = npz.flag("converged")
            texts = {name: npz.text(name) for name in _TEXTS}
            arm, wrist = npz.names("arm"), npz.names("wrist")
            try:
                partition = Partition(arm, wrist, linear=texts["linear"], angular=texts["angular"])
            except PinrateError as error:
                raise npz.refuse(f"holds no partition in 'arm', 'wrist', 'linear', 'angular': {error}") from None
            plant = _plant_record(npz, arrays["joint_rates"].shape)
        return cls(
            status=status,
            converged=converged,
            reason=texts["reason"],
            algorithm=texts["algorithm"],
            dt=dt,
            partition=partition,
            detail=detail,
            plant=plant,
            **arrays,
        )


def _plant_record(npz: Npz, shape: tuple[int, ...]) -> PlantRecord | None:
    """The file's :class:`PlantRecord` (its four fields, or none of them), checked against
    the joint rates' ``shape`` (N - 1, nv)."""
    present = [name for name in _PLANT_FIELDS if name in npz.members]
    if not present:
        return None
    if len(present) < len(_PLANT_FIELDS):
        missing = [name for name in _PLANT_FIELDS if name not in npz.members]
        raise npz.refuse(f"holds {', '.join(present)} without {', '.join(missing)}: a plant record has all four")
    measured = npz.floats("measured_rates", 2)
    tracking = npz.floats("tracking_error", 1)
    for name, values, wanted in (("measured_rates", measured, shape), ("tracking_error", tracking, shape[:1])):
        if values.shape != wanted:
            raise npz.refuse(f"has shape {values.shape}, not {wanted} as the joint rates'", name)
    if (tracking < 0).any():
        raise npz.refuse(f"holds a negative value at {int(np.argmax(tracking < 0))}", "tracking_error")
    if npz.shape("saturated", "b", 2) != shape:
        raise npz.refuse(f"has shape {npz.members['saturated'].shape}, not {shape} as the joint rates'", "saturated")
    saturated = npz.array("saturated")
    if not np.isin(saturated.view(np.uint8), (0, 1)).all():
        raise npz.refuse("holds a byte that is not a boolean", "saturated")
    return PlantRecord(npz.text("plant"), measured, tracking, saturated.astype(bool))


_FIELDS = ("format", *_ARRAYS, *_TEXTS, "status", "arm", "wrist", "converged", "dt")


def _version(npz: Npz) -> str:
    """The file's format, if it is one :meth:`Trajectory.load` reads; InputError otherwise."""
    if "format" not in npz.members:
        raise npz.refuse(f"is not a pinrate trajectory (no format {FORMAT!r})")
    version = npz.text("format")
    if version not in (FORMAT, _FIRST_FORMAT):
        raise npz.refuse(f"is not a pinrate trajectory: format {version[:80]!r}, not {FORMAT!r}")
    return version
