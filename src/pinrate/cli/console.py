"""The ``pinrate`` console script's entry point (``[project.scripts]``), and ``python -m pinrate.cli``'s.

It does the least Python can before SIGINT and SIGTERM are pinrate's: the console script
imports ``pinrate`` and ``pinrate.cli`` (both light: nothing below them loads) and this
module, and :func:`main`'s first act is to install handlers that only record a signal. Then
it imports the command line (:mod:`.entry`: argparse, logging, the parser) and runs it; a
signal recorded meanwhile ends the run at once, as one during the run would (exit 130 for
SIGINT, 143 for SIGTERM, no traceback).

What no code of pinrate can guard is what runs before it: CPython's start-up and its
``site`` module (the environment's ``.pth`` files; some tens of milliseconds). SIGINT there
ends the process by the signal itself (shells report 130) or, inside ``site``, with CPython's
own "Fatal Python error: init_import_site" (exit 1); see docs/cli.md.

A program that imports :func:`pinrate.cli.main` to call it keeps its own handlers until
``main`` runs (and gets them back when it returns): only this entry point installs its
recorders, and only when called.
"""

from __future__ import annotations

import signal
from types import FrameType


def main() -> int:
    """Run the command line of ``sys.argv``; returns the exit code (see :mod:`.entry`)."""
    arrived: list[int] = []

    def record(signum: int, frame: FrameType | None) -> None:
        arrived.append(signum)

    signal.signal(signal.SIGINT, record)
    signal.signal(signal.SIGTERM, record)
    from .entry import run_console  # what the command line needs, with the signals recorded

    return run_console(arrived)
