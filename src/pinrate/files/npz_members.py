"""The members of a saved ``.npz``, checked from their headers before any array is read.

A saved ``.npz`` is a zip of ``.npy`` members. Before any array is read
(:class:`~pinrate.files.Npz` reads them), the file must be a regular file (:func:`open_regular`:
a folder, a FIFO, a device or a socket is refused from ``os.stat``, and the file is opened
non-blocking and checked again, so a FIFO swapped in meanwhile cannot block the reader), a zip
archive of at most :data:`MAX_MEMBERS` stored or deflated, unencrypted, uniquely named
``.npy`` members (:func:`read_members`), and every member's header must be sane: a plain dtype
(booleans, integers, floats or text: never objects, so never a pickle), a shape whose byte
size is exactly what the member declares, and declared sizes within the caps below. Every
failure is an InputError naming the file and, where there is one, the field.

The caps on what a file may make pinrate allocate, checked here:

* ``max_bytes`` (:data:`~pinrate.files.MAX_LOAD_BYTES`, 2 GiB, by default): what the arrays of
  one file take in memory together (:attr:`Member.cost`), a text array counted with the Python
  strings it becomes (:data:`STR_OBJECT_BYTES` more per string);
* the file's own size: a stored member cannot hold more than the file, and a deflated one
  not more than :data:`DEFLATE_RATIO` times its compressed size (deflate cannot do better, so
  a member that declares more is a lie: a zip bomb);
* :data:`MAX_HEADER_BYTES` per ``.npy`` header (numpy's own limit for untrusted files).
"""

from __future__ import annotations

import ast
import io
import math
import os
import re
import stat
import struct
import tokenize
import zipfile
import zlib
from dataclasses import dataclass
from pathlib import Path
from typing import IO

import numpy as np

from ..checks import as_path
from ..errors import InputError

STR_OBJECT_BYTES = 80
"""Bytes a Python str takes beyond its characters (about 50 for ASCII, 76 for the widest),
rounded up: counted per entry of a text array against :data:`~pinrate.files.MAX_LOAD_BYTES`."""

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

KINDS = {"b": "booleans", "i": "integers", "u": "integers", "f": "floats", "U": "text"}
"""The dtype kinds an array read may have (numpy's ``dtype.kind``), in words."""

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
    source = as_path(path, what)
    where = named(source, what)
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


def named(path: Path, what: str) -> str:
    """What a message about the file starts with: ``what`` and the path ("trajectory file '/tmp/t.npz'")."""
    return f"{what} {str(path)!r}"


def read_members(archive: zipfile.ZipFile, size: int, max_bytes: int, where: str) -> dict[str, Member]:
    """The members of ``archive`` (a file of ``size`` bytes) by field name, each from its
    header checked (the module's docstring lists the checks), their :attr:`Member.cost`
    within ``max_bytes`` together; InputError starting with ``where`` (:func:`named`) otherwise."""
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
            raise InputError(f"{where}: {over_max_bytes(max_bytes)}")
        members[name] = member
    return members


def over_max_bytes(max_bytes: int) -> str:
    """Why a file that would take more than ``max_bytes`` to read is refused, in words."""
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
        raise InputError(f"{field} has no readable .npy header: {reason(error)}") from None
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
    magic = read_exactly(stream, 8)
    if magic[:6] != b"\x93NUMPY":
        raise ValueError("not an .npy array (no magic string)")
    version = (magic[6], magic[7])
    if version == (1, 0):
        length_bytes = read_exactly(stream, 2)
        (length,) = struct.unpack("<H", length_bytes)
    elif version == (2, 0):
        length_bytes = read_exactly(stream, 4)
        (length,) = struct.unpack("<I", length_bytes)
    else:
        raise ValueError(f".npy format version {version[0]}.{version[1]}, not 1.0 or 2.0")
    if length > MAX_HEADER_BYTES:
        raise ValueError(f"a header of {length:,} bytes, over {MAX_HEADER_BYTES:,}")
    header = read_exactly(stream, length)
    if not _HEADER_TEXT.fullmatch(header):  # what parsing it would warn of (an escape)
        raise ValueError("a header that is not printable ASCII without backslashes")
    ast.literal_eval(header.decode("ascii"))  # a SyntaxError: numpy would filter it as Python 2's, and warn
    text = io.BytesIO(length_bytes + header)
    reader = np.lib.format.read_array_header_1_0 if version == (1, 0) else np.lib.format.read_array_header_2_0
    shape, fortran_order, dtype = reader(text, max_header_size=MAX_HEADER_BYTES)
    return tuple(shape), bool(fortran_order), np.dtype(dtype), 8 + len(length_bytes) + length


def read_exactly(stream: IO[bytes], size: int) -> bytes:
    """The next ``size`` bytes of ``stream``; EOFError when it holds fewer."""
    data = stream.read(size)
    if len(data) != size:
        raise EOFError(f"expected {size} bytes, got {len(data)}")
    return data


def reason(error: BaseException) -> str:
    """What went wrong, for a message: ``error``'s type and the first line of what it says."""
    text = str(error).splitlines()[0] if str(error) else ""
    return f"{type(error).__name__}: {text[:200]}" if text else type(error).__name__


__all__ = [
    "CORRUPT",
    "DEFLATE_RATIO",
    "KINDS",
    "MAX_MEMBERS",
    "STR_OBJECT_BYTES",
    "Member",
    "named",
    "open_regular",
    "over_max_bytes",
    "read_exactly",
    "read_members",
    "reason",
]
