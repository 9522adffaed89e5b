"""The files pinrate writes and reads back: written whole or not at all, read without trust.

Writing (:func:`replace_file`): the bytes go to a temporary file in the target's own folder,
are flushed to the disk, and the temporary file is then renamed over the target in one step
(``os.replace``). A write that fails part-way (disk full, a file-size limit, an interrupt)
leaves the file it was replacing as it was and removes the temporary file; the failure is an
:class:`~pinrate.errors.InputError` naming the file, never a bare ``OSError``.

Reading (:func:`open_npz`): a saved ``.npz`` is a zip of ``.npy`` members. Before any array
is read, the file must be a regular file (a folder, a FIFO, a device or a socket is refused
from ``os.stat``, and the file is opened non-blocking and checked again, so a FIFO swapped in
meanwhile cannot block the reader), a zip archive of at most :data:`MAX_MEMBERS` stored or
deflated, unencrypted, uniquely named ``.npy`` members, and every member's header must be
sane: a plain dtype (booleans, integers, floats or text: never objects, so never a pickle),
a shape whose byte size is exactly what the member declares, and declared sizes within the
caps below. Only then are the arrays read, a piece at a time into arrays of that size, each
member's checksum checked at its end. Every failure is an InputError naming the file and,
where there is one, the field.

The caps on what a file may make pinrate allocate:

* :data:`MAX_LOAD_BYTES` (2 GiB): what the arrays of one file take in memory together, a
  text array counted with the Python strings it becomes (:data:`STR_OBJECT_BYTES` more per
  string), and what the loader declares it builds from them (:meth:`Npz.reserve`), by
  default (the loaders' ``max_bytes`` keyword raises it for a bigger file one trusts);
* the file's own size: a stored member cannot hold more than the file, and a deflated one
  not more than :data:`DEFLATE_RATIO` times its compressed size (deflate cannot do better, so
  a member that declares more is a lie: a zip bomb);
* :data:`MAX_HEADER_BYTES` per ``.npy`` header (numpy's own limit for untrusted files).
"""

from __future__ import annotations

import ast
import contextlib
import io
import math
import os
import re
import secrets
import stat
import struct
import tokenize
import zipfile
import zlib
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from pathlib import Path
from types import TracebackType
from typing import IO, Any

import numpy as np

from .checks import PHYSICAL_BOUND, check_output_file
from .errors import InputError

MAX_LOAD_BYTES = 2 << 30
"""Most bytes reading one ``.npz`` may take (2 GiB), counted from its headers before any
array is read: the arrays, the Python strings of their text (:data:`STR_OBJECT_BYTES` each
beyond the text) and what the loader builds per row (:meth:`Npz.reserve`). About a teleop
recording of 2 M ticks of a 6-joint arm with 60-character details (the console's longest by
default: ``max_samples``), or a servo trajectory of 3 M steps of a 7-joint arm. A file
declaring more is refused unread, unless the loader is given a larger ``max_bytes``."""

STR_OBJECT_BYTES = 80
"""Bytes a Python str takes beyond its characters (about 50 for ASCII, 76 for the widest),
rounded up: counted per entry of a text array against :data:`MAX_LOAD_BYTES`."""

DEFLATE_RATIO = 1032
"""The most deflate can shrink data (1032 to 1, runs of one byte): a deflated member that
declares more bytes than this times its compressed size (plus :data:`DEFLATE_SLACK`) is
refused unread."""

DEFLATE_SLACK = 1024
"""Bytes a tiny deflated member may declare beyond :data:`DEFLATE_RATIO` (a stream's fixed
overhead)."""

MAX_MEMBERS = 64
"""Most members (arrays) a ``.npz`` pinrate reads may hold."""

MAX_HEADER_BYTES = 10_000
"""Longest ``.npy`` header read (numpy's default ``max_header_size``)."""

MAX_DIMENSIONS = 8
"""Most dimensions of an array read."""

CHUNK_BYTES = 1 << 20
"""Bytes read from a member at a time."""

KINDS = {"b": "booleans", "i": "integers", "u": "integers", "f": "floats", "U": "text"}
"""The dtype kinds an array read may have (numpy's ``dtype.kind``), in words."""

NUMBERS = "iuf"
"""The kinds :meth:`Npz.floats` and :meth:`Npz.number` accept (read as float64)."""

CORRUPT: tuple[type[BaseException], ...] = (
    OSError,
    EOFError,
    ValueError,
    TypeError,
    KeyError,
    IndexError,
    NotImplementedError,
    RuntimeError,  # zipfile: "File is encrypted"; RecursionError
    OverflowError,
    SyntaxError,
    struct.error,
    zlib.error,
    tokenize.TokenError,
    zipfile.BadZipFile,
)
"""What reading a damaged archive may raise from zipfile, zlib and numpy's header parser:
each is an InputError naming the file."""


def _where(path: Path, what: str) -> str:
    return f"{what} {str(path)!r}"


def replace_file(
    path: str | os.PathLike[str],
    what: str,
    write: Callable[[IO[Any]], object],
    *,
    encoding: str | None = None,
) -> Path:
    """Write a file whole or not at all; returns its path.

    ``write(stream)`` writes the content to a temporary file beside the target (binary, or
    text in ``encoding``); it is flushed to the disk and renamed over the target in one step,
    so the target is the old file or the new one, never a part. A symbolic link is followed:
    the file it points to is replaced. The new file gets the mode of the file it replaces
    (the umask's default when there was none).

    Raises:
        InputError: naming ``what`` and the path: a folder or another non-regular file at the
            path, a folder that is missing or not writable (:func:`~pinrate.checks.check_output_file`),
            or a write that failed (the old file is then intact and the temporary one removed).
            What ``write`` raises otherwise goes up as it is, the temporary file removed.
    """
    target = check_output_file(path, what)
    final = Path(os.path.realpath(target))  # a link: the file it points to
    try:
        existing: os.stat_result | None = os.stat(final)
    except FileNotFoundError:
        existing = None
    except OSError as error:
        raise InputError(f"{_where(target, what)} cannot be written: {error.strerror or error}") from None
    if existing is not None and not stat.S_ISREG(existing.st_mode):
        raise InputError(f"{_where(target, what)} exists and is not a regular file")
    temporary, descriptor = _create_beside(final, target, what)
    try:
        if existing is not None and hasattr(os, "fchmod"):
            os.fchmod(descriptor, stat.S_IMODE(existing.st_mode))
        mode = "w" if encoding else "wb"
        with os.fdopen(descriptor, mode, encoding=encoding) as stream:
            descriptor = -1  # the stream closes it
            write(stream)
            stream.flush()
            os.fsync(stream.fileno())
        os.replace(temporary, final)
    except BaseException as error:
        if descriptor >= 0:
            with contextlib.suppress(OSError):
                os.close(descriptor)
        with contextlib.suppress(OSError):
            os.unlink(temporary)
        if isinstance(error, OSError):
            reason = error.strerror or str(error) or type(error).__name__
            kept = "the file it was replacing is as it was" if existing is not None else "nothing was written"
            raise InputError(f"{_where(target, what)} could not be written ({reason}); {kept}") from error
        raise
    _sync_folder(final.parent)
    return target


def _create_beside(final: Path, target: Path, what: str) -> tuple[Path, int]:
    """A new, empty temporary file in ``final``'s folder (hidden, a random name), opened."""
    flags = os.O_WRONLY | os.O_CREAT | os.O_EXCL | getattr(os, "O_CLOEXEC", 0) | getattr(os, "O_BINARY", 0)
    for _ in range(100):
        temporary = final.parent / f".{final.name}.{secrets.token_hex(6)}.tmp"
        try:
            return temporary, os.open(temporary, flags, 0o666)
        except FileExistsError:
            continue
        except OSError as error:
            raise InputError(f"{_where(target, what)} cannot be written: {error.strerror or error}") from None
    raise InputError(f"{_where(target, what)} cannot be written: no free temporary name in its folder")


def _sync_folder(folder: Path) -> None:
    """Flush the folder's entry of the renamed file to the disk, where the system allows."""
    with contextlib.suppress(OSError, AttributeError):
        descriptor = os.open(folder, os.O_RDONLY | getattr(os, "O_DIRECTORY", 0))
        try:
            os.fsync(descriptor)
        finally:
            os.close(descriptor)


@dataclass(frozen=True)
class Member:
    """One ``.npy`` member of an archive, from its header: nothing of its data read yet."""

    name: str  # the field's name: the member's name without ".npy"
    info: zipfile.ZipInfo
    shape: tuple[int, ...]
    dtype: np.dtype
    fortran_order: bool
    offset: int  # bytes of the .npy header before the data

    @property
    def nbytes(self) -> int:
        """The bytes of its data."""
        return math.prod(self.shape) * self.dtype.itemsize

    @property
    def cost(self) -> int:
        """The bytes reading it takes: its data, and a text array's strings besides."""
        return self.nbytes + (math.prod(self.shape) * STR_OBJECT_BYTES if self.dtype.kind == "U" else 0)


def open_regular(path: str | os.PathLike[str], what: str) -> IO[bytes]:
    """``path`` opened for reading in binary, if it is a regular file; InputError naming
    ``what`` and the path otherwise (missing, unreadable, a folder, a FIFO, a device, a
    socket). It is opened non-blocking, so a FIFO put there after the check cannot block."""
    source = _as_source(path, what)
    where = _where(source, what)
    try:
        status = os.stat(source)
        if not stat.S_ISREG(status.st_mode):
            raise InputError(f"{where} {_not_regular(status.st_mode)}")
        flags = os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_CLOEXEC", 0) | getattr(os, "O_BINARY", 0)
        descriptor = os.open(source, flags)
    except FileNotFoundError:
        raise InputError(f"{where} does not exist") from None
    except OSError as error:
        raise InputError(f"{where} cannot be read: {error.strerror or error}") from None
    try:
        status = os.fstat(descriptor)
        if not stat.S_ISREG(status.st_mode):  # swapped since the check
            raise InputError(f"{where} {_not_regular(status.st_mode)}")
        return os.fdopen(descriptor, "rb")
    except BaseException:
        os.close(descriptor)
        raise


def _not_regular(mode: int) -> str:
    if stat.S_ISDIR(mode):
        return "is a folder, not a file"
    kind = "a FIFO" if stat.S_ISFIFO(mode) else "a device" if stat.S_ISCHR(mode) or stat.S_ISBLK(mode) else "a socket"
    return f"is not a regular file ({kind})"


def _as_source(path: object, what: str) -> Path:
    if not isinstance(path, str | os.PathLike) or str(path) == "":
        raise InputError(f"{what} must be a path, got {path!r}")
    try:
        return Path(path).expanduser()
    except RuntimeError as error:  # ~unknownuser
        raise InputError(f"{what} {str(path)!r}: {error}") from None


class Npz:
    """A ``.npz`` opened for reading (:func:`open_npz`): its members' headers checked, their
    arrays read on demand, each through one check of its kind and shape.

    Attributes:
        path: the file.
        what: what the file is, in the messages ("trajectory file").
        members: the arrays' headers by field name.
        max_bytes: the most reading it may take (:data:`MAX_LOAD_BYTES` by default).
        cost: what reading it takes, as counted so far (the members' :attr:`Member.cost`,
            and what :meth:`reserve` added).
    """

    def __init__(
        self,
        path: Path,
        what: str,
        stream: IO[bytes],
        archive: zipfile.ZipFile,
        members: dict[str, Member],
        max_bytes: int,
    ) -> None:
        self.path = path
        self.what = what
        self.members = members
        self.max_bytes = max_bytes
        self.cost = sum(member.cost for member in members.values())
        self._stream = stream
        self._archive = archive

    def close(self) -> None:
        self._archive.close()
        self._stream.close()

    def __enter__(self) -> Npz:
        return self

    def __exit__(
        self, kind: type[BaseException] | None, error: BaseException | None, trace: TracebackType | None
    ) -> None:
        self.close()

    def refuse(self, problem: str, name: str | None = None) -> InputError:
        """The InputError of this file (and the field ``name``): raise it."""
        field = f": field {name!r}" if name else ""
        return InputError(f"{_where(self.path, self.what)}{field} {problem}")

    def reserve(self, nbytes: int) -> None:
        """Count ``nbytes`` more that the loader will build from the arrays (its objects per
        row) against ``max_bytes``; refuse the file if they do not fit."""
        self.cost += nbytes
        if self.cost > self.max_bytes:
            raise self.refuse(_over(self.max_bytes))

    def fields(self, required: Iterable[str], optional: Iterable[str] = ()) -> None:
        """Refuse a file that lacks a ``required`` field or holds one in neither list."""
        required = list(required)
        missing = [name for name in required if name not in self.members]
        if missing:
            raise self.refuse(f"lacks the field(s) {', '.join(missing)}")
        known = {*required, *optional}
        extra = [name for name in self.members if name not in known]
        if extra:
            raise self.refuse(f"holds unknown field(s) {', '.join(repr(name) for name in extra)}")

    def shape(self, name: str, kinds: str, ndim: int) -> tuple[int, ...]:
        """The shape of field ``name``, from its header, once its dtype's kind is one of
        ``kinds`` (numpy kinds: "f", "iuf", "b", "U") and it has ``ndim`` dimensions."""
        member = self.members.get(name)
        if member is None:
            raise self.refuse("is missing", name)
        if member.dtype.kind not in kinds:
            wanted = " or ".join(dict.fromkeys(KINDS[kind] for kind in kinds))
            raise self.refuse(f"holds {KINDS.get(member.dtype.kind, member.dtype.str)}, not {wanted}", name)
        if len(member.shape) != ndim:
            raise self.refuse(f"has {len(member.shape)} dimensions (shape {member.shape}), not {ndim}", name)
        return member.shape

    def array(self, name: str) -> np.ndarray:
        """Field ``name``'s array, read a piece at a time into an array of its declared size
        (native byte order); InputError when the member is damaged (short, its checksum
        wrong)."""
        member = self.members[name]
        flat = np.empty(math.prod(member.shape), dtype=member.dtype)
        try:
            with self._archive.open(member.info) as stream:
                _read_exactly(stream, member.offset)
                view = flat.view(np.uint8).data if flat.nbytes else memoryview(b"")
                position = 0
                while position < flat.nbytes:
                    piece = stream.read(min(CHUNK_BYTES, flat.nbytes - position))
                    if not piece:
                        raise EOFError(f"{flat.nbytes - position} bytes short")
                    view[position : position + len(piece)] = piece
                    position += len(piece)
                if stream.read(1):
                    raise ValueError("data beyond the array")
        except CORRUPT as error:
            raise self.refuse(f"cannot be read: {_reason(error)}", name) from None
        array = flat.reshape(member.shape[::-1]).T if member.fortran_order else flat.reshape(member.shape)
        if not array.dtype.isnative:
            array = array.astype(array.dtype.newbyteorder("="))
        return array

    def floats(self, name: str, ndim: int, *, finite: bool = True) -> np.ndarray:
        """Field ``name`` as float64 with ``ndim`` dimensions (from numbers of any width);
        with ``finite``, refused if it holds NaN or inf (which entry, in the message)."""
        self.shape(name, NUMBERS, ndim)
        values = np.asarray(self.array(name), dtype=float)
        if finite:
            self.finite(name, values)
        elif np.isnan(values).any():
            raise self.refuse(f"holds NaN at {_first(np.isnan(values))}", name)
        return values

    def finite(self, name: str, values: np.ndarray, bound: float = PHYSICAL_BOUND) -> None:
        """Refuse ``values`` (field ``name``) unless every entry is finite and within ±``bound``."""
        bad = ~(np.abs(values) <= bound)
        if bad.any():
            entry = _first(bad)
            raise self.refuse(f"holds {float(values[entry])!r} at {entry}: not a finite number within ±{bound:g}", name)

    def number(self, name: str) -> float:
        """Field ``name``: one number (a 0-d array), as a float (finite or not: the caller judges)."""
        return float(self.floats(name, 0, finite=False))

    def flag(self, name: str) -> bool:
        """Field ``name``: one boolean (a 0-d array of numpy bool holding 0 or 1)."""
        self.shape(name, "b", 0)
        byte = int(self.array(name).view(np.uint8))
        if byte not in (0, 1):
            raise self.refuse(f"holds the byte {byte}, not a boolean", name)
        return bool(byte)

    def texts(self, name: str, ndim: int = 1) -> list[str]:
        """Field ``name``: text with ``ndim`` dimensions (0 or 1), as a list of str; refused
        when an entry is not valid Unicode."""
        self.shape(name, "U", ndim)
        values = self.array(name).reshape(-1)
        try:
            words = values.tolist()
            "".join(words).encode("utf-8")
        except (ValueError, UnicodeError) as error:
            raise self.refuse(f"holds text that is not valid Unicode ({_reason(error)})", name) from None
        return [str(word) for word in words]

    def names(self, name: str) -> list[str]:
        """Field ``name``: a list of names (joints), each non-empty and printable."""
        names = self.texts(name)
        for entry in names:
            if not entry or not entry.isprintable():
                raise self.refuse(f"holds the name {entry[:80]!r}: not a non-empty printable name", name)
        return names

    def text(self, name: str) -> str:
        """Field ``name``: one string (a 0-d text array)."""
        return self.texts(name, 0)[0]


def _first(mask: np.ndarray) -> tuple[int, ...] | int:
    index = tuple(int(i) for i in np.unravel_index(int(np.argmax(mask)), mask.shape))
    return index[0] if len(index) == 1 else index


def _reason(error: BaseException) -> str:
    text = str(error).splitlines()[0] if str(error) else ""
    return f"{type(error).__name__}: {text[:200]}" if text else type(error).__name__


def _read_exactly(stream: IO[bytes], size: int) -> bytes:
    data = stream.read(size)
    if len(data) != size:
        raise EOFError(f"expected {size} bytes, got {len(data)}")
    return data


def open_npz(path: str | os.PathLike[str], what: str, *, max_bytes: int = MAX_LOAD_BYTES) -> Npz:
    """An ``.npz`` opened for reading, every member's header checked (the module's
    docstring lists the checks) and nothing of the arrays read yet: close it (``with``).

    Raises:
        InputError: naming ``what`` and the path, and the field where there is one: not a
            regular file, not a zip, a member that is not a sane ``.npy`` header of a plain
            dtype, or arrays declaring more than ``max_bytes`` together or more than the file
            can hold.
    """
    if isinstance(max_bytes, bool) or not isinstance(max_bytes, int) or max_bytes < 0:
        raise InputError(f"max_bytes must be a non-negative integer, got {max_bytes!r}")
    stream = open_regular(path, what)
    source = _as_source(path, what)
    where = _where(source, what)
    try:
        size = os.fstat(stream.fileno()).st_size
        if stream.read(4) not in (b"PK\x03\x04", b"PK\x05\x06"):  # numpy would take other bytes for a pickle
            raise InputError(f"{where} is not an .npz archive")
        stream.seek(0)
        try:
            archive = zipfile.ZipFile(stream)
        except CORRUPT as error:
            raise InputError(f"{where} is not a readable .npz archive: {_reason(error)}") from None
        try:
            members = _members(archive, size, max_bytes, where)
        except BaseException:
            archive.close()
            raise
    except BaseException:
        stream.close()
        raise
    return Npz(source, what, stream, archive, members, max_bytes)


def _members(archive: zipfile.ZipFile, size: int, max_bytes: int, where: str) -> dict[str, Member]:
    infos = archive.infolist()
    if len(infos) > MAX_MEMBERS:
        raise InputError(f"{where} holds {len(infos)} members, more than {MAX_MEMBERS}")
    if sum(info.compress_size for info in infos) > size:
        raise InputError(f"{where} is damaged: its members declare more bytes than the file holds")
    members: dict[str, Member] = {}
    total = 0
    for info in infos:
        name = info.filename.removesuffix(".npy")
        if not info.filename.endswith(".npy") or not name or name in members:
            raise InputError(f"{where} holds the member {info.filename[:80]!r}: not one .npy array of a unique name")
        member = _member(archive, info, name, where)
        total += member.cost
        if total > max_bytes:
            raise InputError(f"{where}: {_over(max_bytes)}")
        members[name] = member
    return members


def _over(max_bytes: int) -> str:
    return f"reading it would take more than {max_bytes:,} bytes (max_bytes): refused unread"


def _member(archive: zipfile.ZipFile, info: zipfile.ZipInfo, name: str, where: str) -> Member:
    field = f"{where}: field {name!r}"
    if info.flag_bits & 0x1:
        raise InputError(f"{field} is encrypted")
    if info.compress_type == zipfile.ZIP_STORED:
        if info.file_size != info.compress_size:
            raise InputError(f"{field} is damaged: stored, yet {info.file_size:,} bytes in {info.compress_size:,}")
    elif info.compress_type == zipfile.ZIP_DEFLATED:
        if info.file_size > DEFLATE_RATIO * info.compress_size + DEFLATE_SLACK:
            raise InputError(
                f"{field} declares {info.file_size:,} bytes in {info.compress_size:,} compressed: "
                f"more than deflate can hold ({DEFLATE_RATIO} to 1), a zip bomb"
            )
    else:
        raise InputError(f"{field} is compressed by method {info.compress_type}, not stored or deflated")
    try:
        with archive.open(info) as stream:
            shape, fortran_order, dtype, offset = _header(stream)
    except CORRUPT as error:
        raise InputError(f"{field} has no readable .npy header: {_reason(error)}") from None
    if dtype.kind not in KINDS or dtype.hasobject or dtype.fields is not None or dtype.subdtype is not None:
        raise InputError(f"{field} holds {dtype.str}: not booleans, integers, floats or text")
    if dtype.itemsize == 0:
        raise InputError(f"{field} holds {dtype.str}: items of no bytes")
    if len(shape) > MAX_DIMENSIONS or any(isinstance(n, bool) or not isinstance(n, int) or n < 0 for n in shape):
        raise InputError(f"{field} declares the shape {str(shape)[:80]}")
    member = Member(name, info, shape, dtype, fortran_order, offset)
    if offset + member.nbytes != info.file_size:
        raise InputError(
            f"{field} declares shape {shape} of {dtype.str} ({member.nbytes:,} bytes) "
            f"in a member of {info.file_size - offset:,} bytes of data"
        )
    return member


_HEADER_TEXT = re.compile(rb"[\x20-\x5b\x5d-\x7e\n]*")
"""What an .npy header of a plain dtype holds: printable ASCII (no backslash) and newlines."""


def _header(stream: IO[bytes]) -> tuple[tuple[int, ...], bool, np.dtype, int]:
    """The shape, order and dtype of an .npy stream and its header's length in bytes, from
    a header of at most :data:`MAX_HEADER_BYTES` (read whole only after its length is known)."""
    magic = _read_exactly(stream, 8)
    if magic[:6] != b"\x93NUMPY":
        raise ValueError("not an .npy array (no magic string)")
    version = (magic[6], magic[7])
    if version == (1, 0):
        length_bytes = _read_exactly(stream, 2)
        (length,) = struct.unpack("<H", length_bytes)
    elif version == (2, 0):
        length_bytes = _read_exactly(stream, 4)
        (length,) = struct.unpack("<I", length_bytes)
    else:
        raise ValueError(f".npy format version {version[0]}.{version[1]}, not 1.0 or 2.0")
    if length > MAX_HEADER_BYTES:
        raise ValueError(f"a header of {length:,} bytes, over {MAX_HEADER_BYTES:,}")
    header = _read_exactly(stream, length)
    if not _HEADER_TEXT.fullmatch(header):  # what parsing it would warn of (an escape)
        raise ValueError("a header that is not printable ASCII without backslashes")
    ast.literal_eval(header.decode("ascii"))  # a SyntaxError: numpy would filter it as Python 2's, and warn
    text = io.BytesIO(length_bytes + header)
    reader = np.lib.format.read_array_header_1_0 if version == (1, 0) else np.lib.format.read_array_header_2_0
    shape, fortran_order, dtype = reader(text, max_header_size=MAX_HEADER_BYTES)
    return tuple(shape), bool(fortran_order), np.dtype(dtype), 8 + len(length_bytes) + length


__all__ = [
    "DEFLATE_RATIO",
    "MAX_LOAD_BYTES",
    "MAX_MEMBERS",
    "STR_OBJECT_BYTES",
    "Member",
    "Npz",
    "open_npz",
    "open_regular",
    "replace_file",
]
