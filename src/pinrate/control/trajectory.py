"""The record of a servo run: saved and loaded as ``.npz``, and reversed (Barker's
"recording and reversing a motion")."""

from __future__ import annotations

import os
import zipfile
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ..checks import check_output_file
from ..errors import InputError, PinrateError
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
            steps"; see :mod:`pinrate.control.servo_loop`; "reversed" for a reversed run).
        joint_rates: the rates applied after each configuration but the last, (N - 1, nv).
        converged: both errors below tol at the last configuration.
        reason: why the run stopped, in words.
        detail: per configuration, what limited the step taken from it, in words (which
            joint, which block, what conditioning or distance; "" when nothing did); the last
            is ``reason``. Empty for trajectories saved before it existed.
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
        ``reason`` says what was reversed."""
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
        pickles: :meth:`load` reads it with ``allow_pickle=False``); returns the path."""
        target = check_output_file(path, "trajectory file")
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
        with target.open("wb") as stream:  # a file object: numpy would append ".npz" to a name
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
            np.savez(stream, **entries)
        return target

    @classmethod
    def load(cls, path: str | os.PathLike[str]) -> Trajectory:
        """A trajectory written by :meth:`save`.

        Raises:
            InputError: a missing file, a file that is not a saved pinrate trajectory, or one
                whose arrays do not fit together.
        """
        source = Path(path)
        if not source.is_file():
            raise InputError(f"trajectory file {str(source)!r} does not exist")
        if not zipfile.is_zipfile(source):  # numpy would take any other bytes for a pickle
            raise InputError(f"{str(source)!r} is not a pinrate trajectory (not an .npz archive)")
        try:
            with np.load(source, allow_pickle=False) as data:
                version = str(data["format"]) if "format" in data.files else ""
                if version not in (FORMAT, _FIRST_FORMAT):
                    raise InputError(f"{str(source)!r} is not a pinrate trajectory (no format {FORMAT!r})")
                missing = [
                    name
                    for name in (*_ARRAYS, *_TEXTS, "status", "arm", "wrist", "converged", "dt")
                    if name not in data.files
                ]
                if missing:
                    raise InputError(f"trajectory file {str(source)!r} lacks {', '.join(missing)}")
                arrays = {name: np.array(data[name], dtype=float) for name in _ARRAYS}
                texts = {name: str(data[name]) for name in _TEXTS}
                status = [str(word) for word in data["status"]]
                if version == _FIRST_FORMAT:
                    status = [RENAMED_WORDS.get(word, word) for word in status]
                detail = [str(words) for words in data["detail"]] if "detail" in data.files else []
                arm, wrist = [str(j) for j in data["arm"]], [str(j) for j in data["wrist"]]
                converged, dt = bool(data["converged"]), float(data["dt"])
        except (OSError, ValueError, zipfile.BadZipFile) as error:
            raise InputError(f"trajectory file {str(source)!r} cannot be read: {error}") from None
        count = arrays["q"].shape[0]
        if any(arrays[name].shape != (count,) for name in _ARRAYS[1:4]) or arrays["joint_rates"].shape[0] != max(
            count - 1, 0
        ):
            raise InputError(f"trajectory file {str(source)!r}: its arrays do not fit together")
        if detail and len(detail) != count:
            raise InputError(f"trajectory file {str(source)!r}: {len(detail)} details for {count} configurations")
        try:
            partition = Partition(arm, wrist, linear=texts["linear"], angular=texts["angular"])
        except PinrateError as error:
            raise InputError(f"trajectory file {str(source)!r}: {error}") from None
        return cls(
            status=status,
            converged=converged,
            reason=texts["reason"],
            algorithm=texts["algorithm"],
            dt=dt,
            partition=partition,
            detail=detail,
            **arrays,
        )
