"""Reading a saved ``.npz`` without trust: :func:`open_npz`, then field by field (:class:`Npz`).

:func:`open_npz` opens the file and checks it and every member's header before any array is
read (:mod:`~pinrate.files.npz_members` lists the checks). Only then are the arrays read, a
piece at a time into arrays of that size, each member's checksum checked at its end, and each
field through one check of its kind and shape. Every failure is an InputError naming the file
and, where there is one, the field.

The cap on what reading one file may take: :data:`MAX_LOAD_BYTES` (2 GiB): what the arrays of
one file take in memory together, a text array counted with the Python strings it becomes
(:data:`~pinrate.files.npz_members.STR_OBJECT_BYTES` more per string), and what the loader
declares it builds from them (:meth:`Npz.reserve`), by default (the loaders' ``max_bytes``
keyword raises it for a bigger file one trusts). The other caps, on what a file may declare,
are checked by :mod:`~pinrate.files.npz_members`.
"""

from __future__ import annotations

import math
import os
import zipfile
from collections.abc import Iterable
from pathlib import Path
from types import TracebackType
from typing import IO

import numpy as np

from ..checks import PHYSICAL_BOUND, as_path
from ..errors import InputError
from .npz_members import (
    CORRUPT,
    KINDS,
    Member,
    named,
    open_regular,
    over_max_bytes,
    read_exactly,
    read_members,
    reason,
)

MAX_LOAD_BYTES = 2 << 30
"""Most bytes reading one ``.npz`` may take (2 GiB), counted from its headers before any
array is read: the arrays, the Python strings of their text
(:data:`~pinrate.files.npz_members.STR_OBJECT_BYTES` each beyond the text) and what the
loader builds per row (:meth:`Npz.reserve`). About a teleop
recording of 2 M ticks of a 6-joint arm with 60-character details (the console's longest by
default: ``max_samples``), or a servo trajectory of 3 M steps of a 7-joint arm. A file
declaring more is refused unread, unless the loader is given a larger ``max_bytes``."""

CHUNK_BYTES = 1 << 20
"""Bytes read from a member at a time."""

NUMBERS = "iuf"
"""The kinds :meth:`Npz.floats` and :meth:`Npz.number` accept (read as float64)."""


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
        return InputError(f"{named(self.path, self.what)}{field} {problem}")

    def reserve(self, nbytes: int) -> None:
        """Count ``nbytes`` more that the loader will build from the arrays (its objects per
        row) against ``max_bytes``; refuse the file if they do not fit."""
        self.cost += nbytes
        if self.cost > self.max_bytes:
            raise self.refuse(over_max_bytes(self.max_bytes))

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
                read_exactly(stream, member.offset)
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
            raise self.refuse(f"cannot be read: {reason(error)}", name) from None
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
            raise self.refuse(f"holds text that is not valid Unicode ({reason(error)})", name) from None
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


def open_npz(path: str | os.PathLike[str], what: str, *, max_bytes: int = MAX_LOAD_BYTES) -> Npz:
    """An ``.npz`` opened for reading, every member's header checked (the checks:
    :mod:`~pinrate.files.npz_members`) and nothing of the arrays read yet: close it (``with``).

    Raises:
        InputError: naming ``what`` and the path, and the field where there is one: not a
            regular file, not a zip, a member that is not a sane ``.npy`` header of a plain
            dtype, or arrays declaring more than ``max_bytes`` together or more than the file
            can hold.
    """
    if isinstance(max_bytes, bool) or not isinstance(max_bytes, int) or max_bytes < 0:
        raise InputError(f"max_bytes must be a non-negative integer, got {max_bytes!r}")
    stream = open_regular(path, what)
    source = as_path(path, what)
    where = named(source, what)
    try:
        size = os.fstat(stream.fileno()).st_size
        if stream.read(4) not in (b"PK\x03\x04", b"PK\x05\x06"):  # numpy would take other bytes for a pickle
            raise InputError(f"{where} is not an .npz archive")
        stream.seek(0)
        try:
            archive = zipfile.ZipFile(stream)
        except CORRUPT as error:
            raise InputError(f"{where} is not a readable .npz archive: {reason(error)}") from None
        try:
            members = read_members(archive, size, max_bytes, where)
        except BaseException:
            archive.close()
            raise
    except BaseException:
        stream.close()
        raise
    return Npz(source, what, stream, archive, members, max_bytes)


__all__ = ["MAX_LOAD_BYTES", "NUMBERS", "Npz", "open_npz"]
