"""Writing a file whole or not at all (:func:`replace_file`).

The bytes go to a temporary file in the target's own folder, are flushed to the disk, and the
temporary file is then renamed over the target in one step (``os.replace``). A write that
fails part-way (disk full, a file-size limit, an interrupt) leaves the file it was replacing
as it was and removes the temporary file; the failure is an
:class:`~pinrate.errors.InputError` naming the file, never a bare ``OSError``.
"""

from __future__ import annotations

import contextlib
import os
import secrets
import stat
from collections.abc import Callable
from pathlib import Path
from typing import IO, Any

from ..checks import check_output_file
from ..errors import InputError


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


__all__ = ["replace_file"]
