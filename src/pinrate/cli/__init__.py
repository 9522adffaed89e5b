"""The ``pinrate`` command line: ``list``, ``demo``, ``analyze`` and ``paper``."""

from .main import build_parser, main

__all__ = ["build_parser", "main"]
