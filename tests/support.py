"""Independent reference computations and paths shared by the tests (on sys.path: ``pythonpath`` in pyproject)."""

from __future__ import annotations

import contextlib
import ctypes
import math
import os
import struct
import sys
import time
from collections.abc import Callable, Iterator
from pathlib import Path

import numpy as np
import pinocchio as pin

import pinrate

ROOT = Path(__file__).resolve().parents[1]
"""The repository root."""

DATA = Path(__file__).parent / "data"


def finite_difference_jacobian(robot: pinrate.Robot, q: np.ndarray, step: float = 1e-6) -> np.ndarray:
    """The sensor-frame TCP Jacobian from central differences of robot.pose alone.

    Column i: the tip origin's velocity and the angular velocity (from log3 of the relative
    rotation) when joint velocity i is 1, rotated into the sensor frame's axes at q.
    """
    sensor_rotation = robot.frame_pose(q, robot.sensor)[:3, :3]
    columns = []
    for i in range(robot.nv):
        tangent = np.zeros(robot.nv)
        tangent[i] = step
        ahead = robot.pose(pin.integrate(robot.model, q, tangent))
        behind = robot.pose(pin.integrate(robot.model, q, -tangent))
        velocity = (ahead[:3, 3] - behind[:3, 3]) / (2 * step)
        angular = pin.log3(ahead[:3, :3] @ behind[:3, :3].T) / (2 * step)
        columns.append(np.concatenate([sensor_rotation.T @ velocity, sensor_rotation.T @ angular]))
    return np.column_stack(columns)


def fuzz_count(base: int) -> int:
    """How many cases a fuzz test runs: ``base`` in ``make test`` (seeded, bounded), times
    ``PINRATE_FUZZ_SCALE`` for a longer hunt (``PINRATE_FUZZ_SCALE=100 pytest tests/fuzz``)."""
    import os

    return base * max(1, int(os.environ.get("PINRATE_FUZZ_SCALE", "1")))


def partition_rows_and_columns(robot: pinrate.Robot, partition: pinrate.Partition) -> tuple[list[int], list[int]]:
    """Rows (twist components, linear then angular) and columns (joints, arm then wrist) of
    a partition in J (6, nv), written here from the contract rather than taken from pinrate."""
    rows = ["xyz".index(a) for a in partition.linear] + [3 + "xyz".index(a) for a in partition.angular]
    columns = [c for joint in partition.joints for c in robot.velocity_indices(joint)]
    return rows, columns


EPS = float(np.finfo(float).eps)


def spectral_radius_tolerance(
    robot: pinrate.Robot, partition: pinrate.Partition, configurations: np.ndarray, *, jacobian_ulps: float = 64.0
) -> np.ndarray:
    """How far two honest computations of ρ (eq. 32, 50) may differ at each configuration,
    from a bound rather than a machine's luck: where their G = U A^-1 B W^-1 (or H) differ
    by at most ΔG in the 2-norm, Elsner's theorem (Linear Algebra Appl. 66, 1985) bounds the
    distance between the two spectra, hence between the two spectral radii, by

        (‖G₁‖ + ‖G₂‖)^(1 - 1/n) ‖ΔG‖^(1/n),     n = the size of the matrix whose ρ is taken.

    The 1/n-th root is real: an eigenvalue of a defective (or nilpotent, ρ = 0) G moves by the
    n-th root of a perturbation, so ρ of a G made of rounding noise is a cube root of noise.

    ΔG is bounded to first order from the blocks of the sensor-frame Jacobian J (6, nv), the
    two sides' J taken to differ by η = ``jacobian_ulps`` · ε · ‖J‖ (the same kinematics in
    another order of operations) and their inverses of A and W by a further κ · ε relatively
    (a backward-stable inversion): with P = U A^-1 and Q = B W^-1,

        ‖ΔG‖ <= η (‖A^-1‖ ‖Q‖ + ‖P‖ ‖A^-1‖ ‖Q‖ + ‖P‖ ‖W^-1‖ + ‖P‖ ‖Q‖ ‖W^-1‖)
                + 8 n ε (κ(A) + κ(W) + 1) ‖P‖ ‖Q‖,

    the last term also covering the products and the closed-form eigenvalue routine's own
    rounding (backward error about ε ‖G‖). Configurations where A or W loses rank get inf;
    a wide A or a tall W is pseudo-inverted (the pseudo-inverse G), its smallest nonzero
    singular value in place of 1 / ‖A^-1‖.
    """
    rows, columns = partition_rows_and_columns(robot, partition)
    m, n_arm = len(partition.linear), sum(len(robot.velocity_indices(joint)) for joint in partition.arm)
    jacobians = np.stack([robot.jacobian(q) for q in configurations])
    reduced = jacobians[:, rows][:, :, columns]
    A, B = reduced[:, :m, :n_arm], reduced[:, :m, n_arm:]
    U, W = reduced[:, m:, :n_arm], reduced[:, m:, n_arm:]

    def singular_values(matrices: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The largest and the smallest of min(shape) singular values, per matrix."""
        values = np.linalg.svd(matrices, compute_uv=False)
        return values[:, 0], values[:, -1]

    def norm(matrices: np.ndarray) -> np.ndarray:
        return singular_values(matrices)[0] if min(matrices.shape[1:]) else np.zeros(len(matrices))

    # Pseudo-inverses where A is wide or W tall (the pseudo-inverse G); inf where rank is lost.
    a_largest, a_smallest = singular_values(A)
    w_largest, w_smallest = singular_values(W)
    singular = (a_smallest <= EPS * a_largest * max(A.shape[1:])) | (w_smallest <= EPS * w_largest * max(W.shape[1:]))
    with np.errstate(divide="ignore", invalid="ignore"):
        a_inv, w_inv = 1.0 / a_smallest, 1.0 / w_smallest
        P = U @ np.linalg.pinv(A)
        Q = B @ np.linalg.pinv(W)
    n = min(P.shape[1:])
    if n == 0:
        return np.zeros(len(configurations))
    p, q_norm = norm(P), norm(Q)
    eta = jacobian_ulps * EPS * norm(jacobians)
    conditioning = a_largest * a_inv + w_largest * w_inv + 1.0
    delta = eta * (a_inv * q_norm + p * a_inv * q_norm + p * w_inv + p * q_norm * w_inv)
    delta += 8 * n * EPS * conditioning * p * q_norm
    size = p * q_norm + delta  # >= ‖G‖ for either side
    with np.errstate(invalid="ignore", over="ignore"):
        tolerances = (2.0 * size) ** (1.0 - 1.0 / n) * delta ** (1.0 / n)
    return np.where(singular | ~np.isfinite(tolerances), np.inf, tolerances)


def wait_for(condition: Callable[[], object], timeout: float = 5.0) -> bool:
    """Poll ``condition`` every 10 ms until it holds or ``timeout`` s pass; whether it held
    (for tests of threads and servers that act on their own time)."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if condition():
            return True
        time.sleep(0.01)
    return bool(condition())


KINDS = ("revolute", "prismatic", "continuous", "fixed")


def numbers(values: np.ndarray) -> str:
    return " ".join(f"{value:.6g}" for value in values)


def random_urdf(rng: np.random.Generator) -> str:
    """A tree of 2-12 links: mostly a chain, with branches; revolute, prismatic, continuous
    and fixed joints; odd axes (any direction, any length); zero-length links."""
    count = int(rng.integers(2, 13))
    links = [f'<link name="link{i}"/>' for i in range(count)]
    joints = []
    for child in range(1, count):
        parent = child - 1 if rng.random() < 0.75 else int(rng.integers(0, child))
        kind = "revolute" if child == 1 else KINDS[int(rng.choice(4, p=[0.4, 0.2, 0.2, 0.2]))]
        xyz = np.zeros(3) if rng.random() < 0.2 else rng.normal(0.0, 0.3, 3)
        rpy = np.zeros(3) if rng.random() < 0.4 else rng.uniform(-math.pi, math.pi, 3)
        axis = np.eye(3)[int(rng.integers(3))] * rng.choice([-1.0, 1.0]) if rng.random() < 0.5 else rng.normal(0, 1, 3)
        if np.linalg.norm(axis) < 1e-3:
            axis = np.array([0.0, 0.0, 1.0])
        inner = f'<origin xyz="{numbers(xyz)}" rpy="{numbers(rpy)}"/><axis xyz="{numbers(axis)}"/>'
        if kind == "revolute":
            lower = rng.uniform(-3.0, 0.0)
            inner += f'<limit lower="{lower:.6g}" upper="{lower + rng.uniform(0.2, 3.0):.6g}" effort="1" velocity="1"/>'
        elif kind == "prismatic":
            inner += '<limit lower="-0.4" upper="0.6" effort="1" velocity="1"/>'
        joints.append(
            f'<joint name="joint{child}" type="{kind}"><parent link="link{parent}"/>'
            f'<child link="link{child}"/>{inner}</joint>'
        )
    return '<robot name="random">' + "".join(links) + "".join(joints) + "</robot>"


IN_OPEN = 0x20
"""inotify's event: a file (or the folder) was opened."""


@contextlib.contextmanager
def files_opened_in(folder: Path) -> Iterator[list[str]]:
    """The names of the files in ``folder`` opened during the block, by any code of any process
    (Python's, or C++ such as Pinocchio's mesh loaders): Linux inotify's IN_OPEN events,
    filled in when the block ends."""
    libc = ctypes.CDLL(None, use_errno=True)
    descriptor = libc.inotify_init1(os.O_NONBLOCK | os.O_CLOEXEC)
    if descriptor < 0:
        raise OSError(ctypes.get_errno(), "inotify_init1")
    names: list[str] = []
    try:
        if libc.inotify_add_watch(descriptor, os.fsencode(folder), IN_OPEN) < 0:
            raise OSError(ctypes.get_errno(), f"inotify_add_watch {folder}")
        yield names
        try:
            events = os.read(descriptor, 1 << 16)
        except BlockingIOError:
            events = b""
        offset = 0
        while offset < len(events):
            _, _, _, length = struct.unpack_from("iIII", events, offset)
            names.append(events[offset + 16 : offset + 16 + length].rstrip(b"\0").decode())
            offset += 16 + length
    finally:
        os.close(descriptor)


_OPENED: list[str] | None = None
"""Where :func:`python_opens` records while a block runs (None: not recording)."""


def _record_open(event: str, arguments: tuple[object, ...]) -> None:
    if event == "open" and _OPENED is not None and isinstance(arguments[0], str | bytes | os.PathLike):
        _OPENED.append(os.fsdecode(arguments[0]))


@contextlib.contextmanager
def python_opens() -> Iterator[list[str]]:
    """Every path Python code opens during the block ("open" audit events; a hook cannot be
    removed, so one hook is added per process and records only inside these blocks)."""
    global _OPENED
    if not getattr(sys, "_pinrate_open_hook", False):
        sys.addaudithook(_record_open)
        sys._pinrate_open_hook = True  # type: ignore[attr-defined]
    _OPENED = []
    try:
        yield _OPENED
    finally:
        _OPENED = None
