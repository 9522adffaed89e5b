"""Argument types for the command line: every value is checked as it is parsed, so a bad one
ends in one line ``pinrate: error: ...`` (exit 2) before any work starts."""

from __future__ import annotations

import argparse
import math
import sys
from typing import NoReturn


class Parser(argparse.ArgumentParser):
    """argparse, with its usage errors on one line: ``pinrate: error: <command>: <message>``."""

    def error(self, message: str) -> NoReturn:
        command = self.prog.removeprefix("pinrate").strip()
        where = f"{command}: " if command else ""
        self.exit(2, f"pinrate: error: {where}{message} (see `{self.prog} --help`)\n")


def count(minimum: int, maximum: int | None = None) -> type[int]:
    """An argparse type: an integer >= ``minimum`` (and <= ``maximum``)."""

    def parse(text: str) -> int:
        try:
            value = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected an integer, got {text!r}") from None
        if value < minimum:
            raise argparse.ArgumentTypeError(f"must be at least {minimum}, got {value}")
        if maximum is not None and value > maximum:
            raise argparse.ArgumentTypeError(f"must be at most {maximum:,}, got {value:,}")
        return value

    parse.__name__ = f"integer >= {minimum}" if maximum is None else f"integer in [{minimum}, {maximum}]"
    return parse  # type: ignore[return-value]


def positive(text: str) -> float:
    """An argparse type: a finite number > 0."""
    value = finite(text)
    if value <= 0:
        raise argparse.ArgumentTypeError(f"must be positive, got {text}")
    return value


def within(low: float, high: float) -> type[float]:
    """An argparse type: a number in [``low``, ``high``]."""

    def parse(text: str) -> float:
        value = finite(text)
        if not low <= value <= high:
            raise argparse.ArgumentTypeError(f"must be from {low:g} to {high:g}, got {text}")
        return value

    parse.__name__ = f"number in [{low:g}, {high:g}]"
    return parse  # type: ignore[return-value]


def finite(text: str) -> float:
    """An argparse type: a finite number."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from None
    if not math.isfinite(value):
        raise argparse.ArgumentTypeError(f"must be a finite number, got {text}")
    return value


def xacro_argument(text: str) -> tuple[str, str]:
    """An argparse type: ``NAME:=VALUE``, a xacro:arg's value (as ``xacro file name:=value``)."""
    name, separator, value = text.partition(":=")
    if not separator or not name.strip() or name != name.strip():
        raise argparse.ArgumentTypeError(f"expected NAME:=VALUE (e.g. ur_type:=ur10e), got {text!r}")
    return name, value


xacro_argument.__name__ = "NAME:=VALUE"


def warn(message: str) -> None:
    """One line ``pinrate: warning: ...`` on stderr."""
    print(f"pinrate: warning: {message}", file=sys.stderr, flush=True)
