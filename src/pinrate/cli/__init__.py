"""The ``pinrate`` command line: ``list``, ``demo``, ``analyze``, ``paper`` and ``teleop``.

``main`` is the console script's entry point; this package imports nothing heavy until it
runs (see :mod:`.entry`).
"""

from .entry import main

__all__ = ["main"]
