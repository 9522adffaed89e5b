"""The output folders of ``analyze`` (``--out``) and ``teleop`` (``--record-dir``): checked, and
made, before the work starts, and taken away again when the command ends without writing
into them, so a refused or interrupted command leaves no empty folder behind.

Importing this module loads numpy and Pinocchio (:mod:`pinrate.checks`), as the subcommands'
modules do.
"""

from __future__ import annotations

import contextlib
import os
from collections.abc import Iterator
from pathlib import Path

from ..checks import check_output_folder


@contextlib.contextmanager
def output_folder(path: str, what: str) -> Iterator[Path]:
    """:func:`~pinrate.checks.check_output_folder`'s folder for the block; when the block
    raises (a refused argument, Ctrl-C), the folders the check created are removed again,
    deepest first, as long as they are empty (nothing the block wrote is removed)."""
    made = _missing_folders(path)
    folder = check_output_folder(path, what)
    try:
        yield folder
    except BaseException:
        for created in made:
            try:
                created.rmdir()
            except OSError:  # not empty (something was written), or gone
                break
        raise


def _missing_folders(path: str) -> list[Path]:
    """The folders of ``path`` that do not exist yet, deepest first ([] when it cannot tell:
    the check then refuses the path)."""
    try:
        folder = Path(os.path.abspath(Path(path).expanduser()))
        return [parent for parent in (folder, *folder.parents) if not parent.exists()] if path else []
    except (OSError, RuntimeError, ValueError):
        return []
