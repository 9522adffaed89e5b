"""The ``pinrate`` command line: ``list``, ``demo``, ``analyze``, ``paper`` and ``teleop``.

``main`` runs it in a program (``pinrate.cli.main(["demo", "ur5"])``); the console script
enters by :func:`.console.main`, which owns the signals first. This package imports nothing
until asked: ``main`` loads :mod:`.entry` on first use, so the console script's way to its
signal handlers is short, and ``--help`` answers before anything heavy loads (see
:mod:`.entry` and :mod:`.parser`).
"""

from __future__ import annotations

TYPE_CHECKING = False  # typing.TYPE_CHECKING without importing typing (milliseconds on the console script's way)
if TYPE_CHECKING:
    from .entry import main

__all__ = ["main"]


def __getattr__(name: str) -> object:
    if name == "main":
        from .entry import main

        return main
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
