"""The ``pinrate`` command line: ``list``, ``demo``, ``analyze``, ``paper`` and ``teleop``.

``main`` is the console script's entry point; this package imports nothing heavy until a
subcommand runs, so ``--help`` answers at once (see :mod:`.entry` and :mod:`.parser`).
"""

from .entry import main

__all__ = ["main"]
