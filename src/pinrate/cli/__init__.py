"""The ``pinrate`` command line: ``list``, ``demo``, ``analyze`` and ``paper``."""

from .commands import build_parser, main

__all__ = ["build_parser", "main"]
