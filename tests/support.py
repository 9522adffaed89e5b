"""Independent reference computations and paths shared by the tests (on sys.path: ``pythonpath`` in pyproject)."""

from __future__ import annotations

import contextlib
import ctypes
import math
import os
import re
import struct
import subprocess
import sys
import textwrap
import threading
import time
import zipfile
import zlib
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


# Corrupted files: what the loaders of saved files (pinrate.files) must refuse with an
# InputError naming the file, never another exception, a hang or a huge allocation.


STRUCTURES = (b"PK\x01\x02", b"PK\x03\x04", b"PK\x05\x06", b"\x93NUMPY")
"""Where a zip's headers and an .npy header start: half the damage of :func:`corrupt_bytes`
falls in the 64 bytes after one of them."""


def corrupt_bytes(data: bytes, rng: np.random.Generator) -> tuple[str, bytes]:
    """``data`` damaged one way, at random: truncated, bits flipped, a run of bytes
    overwritten (with bytes, digits or punctuation: an .npy header is text) or zeroed, a
    stretch repeated or cut out; half the time in a zip or .npy header (:data:`STRUCTURES`).
    With a label for the message."""
    kind = str(rng.choice(["truncate", "flip", "overwrite", "text", "zero", "repeat", "cut"]))
    size = len(data)
    starts = [match.start() for marker in STRUCTURES for match in re.finditer(re.escape(marker), data)]
    if starts and rng.random() < 0.5:
        at = min(size - 1, int(rng.choice(starts)) + int(rng.integers(0, 64)))
    else:
        at = int(rng.integers(0, size))
    length = int(rng.integers(1, min(8 if rng.random() < 0.7 else 64, size - at) + 1))
    damaged = bytearray(data)
    if kind == "truncate":
        return f"truncated at {at}", data[:at]
    if kind == "flip":
        for _ in range(int(rng.integers(1, 4))):
            spot = min(size - 1, at + int(rng.integers(0, length)))
            damaged[spot] ^= 1 << int(rng.integers(0, 8))
        return f"bits flipped from {at}", bytes(damaged)
    if kind == "overwrite":
        damaged[at : at + length] = rng.integers(0, 256, length, dtype=np.uint8).tobytes()
    elif kind == "text":
        damaged[at : at + length] = bytes(rng.choice(list(b"0123456789()[]{},:'\" -9eLU<>|"), length).tolist())
    elif kind == "zero":
        damaged[at : at + length] = bytes(length)
    elif kind == "repeat":
        damaged[at:at] = data[at : at + length]
    else:
        del damaged[at : at + length]
    return f"{kind} {length} bytes at {at}", bytes(damaged)


MUTATIONS = (
    "drop", "extra", "rename", "object", "bytes", "complex", "as text", "as number", "nan", "inf",
    "-inf", "huge", "negate", "zero", "float32", "int", "add a dimension", "drop a row", "empty name",
    "transpose", "scalar as a list",
)  # fmt: skip
"""The ways :func:`mutate` changes one field of a saved file."""


def mutate(entries: dict[str, np.ndarray], rng: np.random.Generator) -> tuple[str, str, dict[str, np.ndarray]]:
    """``entries`` (a saved file's arrays by name) with one field changed one way of
    :data:`MUTATIONS`: (the way, the field, the new entries)."""
    kind = str(rng.choice(MUTATIONS))
    name = str(rng.choice(sorted(entries)))
    value = np.asarray(entries[name])
    changed = dict(entries)
    numeric = value.dtype.kind in "iuf"
    if kind == "drop":
        del changed[name]
    elif kind == "extra":
        changed["extra_field"] = np.zeros(3)
    elif kind == "rename":
        changed[name + "_renamed"] = changed.pop(name)
    elif kind == "object":
        changed[name] = np.array([value.tolist(), None], dtype=object)
    elif kind == "bytes":
        changed[name] = np.array(b"bytes")
    elif kind == "complex":
        changed[name] = value.astype(complex) if numeric else np.array(1j)
    elif kind == "as text":
        changed[name] = value.astype(str)
    elif kind == "as number":
        changed[name] = np.array(1.0)
    elif kind in ("nan", "inf", "-inf", "huge", "negate", "zero") and value.dtype.kind == "f" and value.size:
        spoilt = value.copy()
        spot = np.unravel_index(int(rng.integers(0, value.size)), value.shape)
        if kind == "negate":
            spoilt = -spoilt
        else:
            spoilt[spot] = {"nan": np.nan, "inf": np.inf, "-inf": -np.inf, "huge": 1e300, "zero": 0.0}[kind]
        changed[name] = spoilt
    elif kind == "float32" and numeric:
        changed[name] = value.astype(np.float32)
    elif kind == "int" and numeric:
        changed[name] = value.astype(np.int64)
    elif kind == "add a dimension":
        changed[name] = value[None]
    elif kind == "drop a row" and value.ndim and len(value):
        changed[name] = value[:-1]
    elif kind == "empty name" and value.dtype.kind == "U" and value.size:
        spoilt = value.copy()
        spoilt.reshape(-1)[int(rng.integers(0, value.size))] = ""
        changed[name] = spoilt
    elif kind == "transpose" and value.ndim == 2:
        changed[name] = value.T
    elif kind == "scalar as a list" and value.ndim == 0:
        changed[name] = value[None]
    else:
        return mutate(entries, rng)  # that way does not apply to that field: another
    return kind, name, changed


def npy(shape: tuple[int, ...], descr: object = "<f8", data: bytes = b"") -> bytes:
    """The bytes of an .npy array (format 1.0) whose header declares ``shape`` and ``descr``,
    followed by ``data`` (which need not hold that shape: a header may lie)."""
    header = repr({"descr": descr, "fortran_order": False, "shape": shape}).encode("latin1")
    header += b" " * (63 - (10 + len(header)) % 64) + b"\n"
    return b"\x93NUMPY\x01\x00" + struct.pack("<H", len(header)) + header + data


def raw_zip(members: list[tuple[str, bytes, int, int, int]]) -> bytes:
    """A zip archive written byte by byte, its members given as (name, data as stored in
    the zip, method: 0 stored or 8 deflated, crc32, declared uncompressed size): what a
    damaged or hostile file may declare, which zipfile would not write."""
    body, directory = b"", b""
    for name, data, method, crc, size in members:
        encoded = name.encode()
        fields = struct.pack("<HHHHHIII", 20, 0, method, 0, 0, crc, len(data), size)
        directory += (
            b"PK\x01\x02"
            + struct.pack("<H", 20)
            + fields
            + struct.pack("<HHHHHII", len(encoded), 0, 0, 0, 0, 0, len(body))
            + encoded
        )
        body += b"PK\x03\x04" + fields + struct.pack("<HH", len(encoded), 0) + encoded + data
    end = struct.pack("<HHHHIIH", 0, 0, len(members), len(members), len(directory), len(body), 0)
    return body + directory + b"PK\x05\x06" + end


def deflated_zeros(prefix: bytes, mebibytes: int) -> tuple[bytes, int, int]:
    """``prefix`` then ``mebibytes`` MiB of zeros, deflated (about 1000 to 1, built fast from
    one repeated block): (the raw deflate stream, its crc32, its uncompressed size)."""
    zeros = bytes(1 << 20)
    compressor = zlib.compressobj(9, zlib.DEFLATED, -15)
    head = compressor.compress(prefix + zeros) + compressor.flush(zlib.Z_FULL_FLUSH)
    block = compressor.compress(zeros) + compressor.flush(zlib.Z_FULL_FLUSH)
    stream = head + block * (mebibytes - 1) + compressor.flush()
    crc = zlib.crc32(prefix)
    for _ in range(mebibytes):
        crc = zlib.crc32(zeros, crc)
    return stream, crc, len(prefix) + (mebibytes << 20)


def npz_members(path: Path) -> list[tuple[str, bytes, int, int, int]]:
    """The members of an .npz numpy wrote, as :func:`raw_zip` takes them (to rewrite one)."""
    with zipfile.ZipFile(path) as archive:
        members = []
        for info in archive.infolist():
            data = archive.read(info)
            stored = data if info.compress_type == zipfile.ZIP_STORED else zlib.compress(data)[2:-4]
            members.append((info.filename, stored, info.compress_type, zlib.crc32(data), len(data)))
        return members


def outcome(load: Callable[[Path], object], path: Path, label: str = "") -> str:
    """ "loaded" or "refused": ``load(path)`` either returns, or raises an InputError whose
    message names the file; any other exception fails the test (the label says what file)."""
    try:
        load(path)
    except pinrate.InputError as error:
        assert str(path) in str(error), f"{label}: the message does not name the file: {error}"
        return "refused"
    except Exception as error:
        raise AssertionError(f"{label}: {type(error).__name__} instead of an InputError: {error}") from error
    return "loaded"


def load_with_timeout(load: Callable[[Path], object], path: Path, timeout: float = 10.0) -> BaseException | None:
    """What ``load(path)`` raised (None when it returned), run on a thread; AssertionError
    if it is still running after ``timeout`` s (a FIFO opened for reading blocks until a
    writer comes: one is opened then, so that the thread ends)."""
    result: list[BaseException | None] = []

    def run() -> None:
        try:
            load(path)
            result.append(None)
        except BaseException as error:
            result.append(error)

    thread = threading.Thread(target=run, daemon=True)
    thread.start()
    thread.join(timeout)
    if thread.is_alive():
        with contextlib.suppress(OSError):  # a writer lets a blocked open of a FIFO return
            os.close(os.open(path, os.O_WRONLY | os.O_NONBLOCK))
        thread.join(5.0)
        raise AssertionError(f"loading {path} still ran after {timeout:g} s")
    return result[0]


def run_python(code: str, timeout: float = 120.0) -> subprocess.CompletedProcess[str]:
    """``code`` run by this interpreter in a fresh process that imports this pinrate."""
    source = str(Path(pinrate.__file__).parents[1])
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([source, os.environ.get("PYTHONPATH", "")])}
    return subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, timeout=timeout, env=env, check=False
    )


def peak_memory_of_load(owner: str, path: Path) -> tuple[int, str]:
    """The growth of the peak resident memory (bytes, Linux) of a fresh process while it
    runs ``owner.load(path)`` (``owner`` a dotted name: "pinrate.Trajectory"), and what the
    load did: "loaded", or the exception's type and message."""
    module, _, name = owner.rpartition(".")
    code = textwrap.dedent(f"""
        import importlib, resource
        load = getattr(importlib.import_module({module!r}), {name!r}).load
        before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
        try:
            load({str(path)!r})
            what = "loaded"
        except BaseException as error:
            what = type(error).__name__ + ": " + str(error)
        after = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
        print((after - before) * 1024)
        print(what)
    """)
    result = run_python(code)
    assert result.returncode == 0, result.stderr[-3000:]
    growth, what = result.stdout.split("\n", 1)
    return int(growth), what.strip()


def save_under_a_file_size_limit(setup: str, path: Path, limit: int) -> str:
    """Run ``setup`` (code that leaves an object with a ``save`` method in ``saved``) in a
    fresh process, then ``saved.save(path)`` with RLIMIT_FSIZE at ``limit`` bytes and
    SIGXFSZ ignored, so a write past it fails with EFBIG part-way; what the save did:
    "saved", or the exception's type and message."""
    code = textwrap.dedent(setup) + textwrap.dedent(f"""
        import resource, signal
        signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
        resource.setrlimit(resource.RLIMIT_FSIZE, ({limit}, {limit}))
        try:
            saved.save({str(path)!r})
            print("saved")
        except BaseException as error:
            print(type(error).__name__ + ": " + str(error))
    """)
    result = run_python(code)
    assert result.returncode == 0, result.stderr[-3000:]
    return result.stdout.strip()


def special_files(folder: Path) -> list[tuple[str, Path, str]]:
    """Paths that are no regular file, or one that cannot be read, with what a loader's
    message must say of each: (label, path, a regular expression of the message)."""
    fifo = folder / "fifo.npz"
    os.mkfifo(fifo)
    subfolder = folder / "folder.npz"
    subfolder.mkdir()
    unreadable = folder / "unreadable.npz"
    unreadable.write_bytes(b"PK\x05\x06" + bytes(18))
    unreadable.chmod(0)
    cases = [("a FIFO", fifo, "FIFO"), ("a folder", subfolder, "folder"), ("a device", Path("/dev/null"), "device")]
    if os.access(unreadable, os.R_OK):  # root reads it; not a file of /proc/sys it may only write
        unreadable = Path("/proc/sys/vm/compact_memory")
    if unreadable.exists():
        cases.append(("an unreadable file", unreadable, "cannot be read: Permission denied"))
    return cases


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


TRIANGLE_STL = """solid t
facet normal 0 0 1
outer loop
vertex 0 0 0
vertex 0.1 0 0
vertex 0 0.1 0
endloop
endfacet
endsolid t
"""
"""One triangle as an ASCII STL file: the smallest mesh Pinocchio reads (tests that write meshes)."""


def flat_plate(robot: pinrate.Robot, name: str) -> pin.GeometryObject:
    """A flat 10 cm square plate of two triangles, 0.2 m out along wrist_3_link's z axis: a
    mesh qhull cannot hull (no 3-D hull; coal 3.0's convexHull would end the process on it),
    so the collision monitor keeps it as a mesh. Added to ``robot``'s collision model under
    ``name`` (the monitor warns once per robot and geometry name) and returned."""
    import coal

    plate = coal.BVHModelOBBRSS()
    plate.beginModel(2, 4)
    plate.addVertices(np.array([[-0.05, -0.05, 0.0], [0.05, -0.05, 0.0], [0.05, 0.05, 0.0], [-0.05, 0.05, 0.0]]))
    plate.addTriangles(np.array([[0, 1, 2], [0, 2, 3]]))
    plate.endModel()
    frame = robot.model.getFrameId("wrist_3_link")
    joint = robot.model.frames[frame].parentJoint
    placement = pin.SE3(np.eye(3), np.array([0.0, 0.0, 0.2]))
    geometry = pin.GeometryObject(name, joint, frame, placement, plate)
    robot.collision_model.addGeometryObject(geometry)
    return geometry
