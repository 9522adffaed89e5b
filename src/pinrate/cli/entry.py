"""The ``pinrate`` process: who owns its signals, how it ends, what it exits with.

Exit codes: 0 done (the demo converged), 1 the demo did not converge, 2 a refused input
(one line ``pinrate: error: ...`` on stderr), 130 interrupted (Ctrl-C, at any moment from
the console script's first call on, :mod:`.console`; when the interrupt landed inside
Pinocchio's import, CPython itself ends the process by SIGINT after pinrate's cleanup, which
shells also report as 130), 143 terminated (SIGTERM), 141 its output pipe closed (``| head``).

The CLI owns SIGINT: CPython raises KeyboardInterrupt only when SIGINT was at its default
disposition at start-up, and a background job of a non-interactive shell inherits it
ignored, so a ``pinrate demo`` started that way would never hear Ctrl-C. The arguments are
parsed first, with nothing heavy loaded (:mod:`.parser`: ``--help`` and a refused argument
answer in a few tens of milliseconds); then the subcommand's module is imported, and with
it what the command needs (numpy and Pinocchio, matplotlib for ``analyze`` and ``paper``).
Those heavy imports happen inside the guarded region with signals deferred: an interrupt
while they load is recorded and raised as soon as they end (within about a second), as
cleanly as one during the run.
"""

from __future__ import annotations

import argparse
import contextlib
import logging
import os
import signal
import sys
import threading
from collections.abc import Callable, Iterator, Sequence
from types import FrameType
from typing import ClassVar

from .. import __version__
from .parser import build_parser

INTERRUPTED = 130
TERMINATED = 143
BROKEN_PIPE = 141
REDELIVERY_DELAY = 0.01
"""Seconds before a swallowed signal is sent again (see ``_Signals``)."""


class Terminated(SystemExit):
    """Raised in the main thread on SIGTERM, so ``finally`` blocks (the viewer's server) run."""


class _Signals:
    """Which of SIGINT and SIGTERM arrived, and their delivery as exceptions.

    Two places in CPython can swallow the exception a handler raises: an extension module
    that clears Python errors (Boost.Python code run while Pinocchio imports), and a callback
    whose exception CPython can only report as "Exception ignored in ..." (the weak-reference
    callback of an import lock, run by the garbage collector at any moment). The first is
    caught by checking :attr:`seen` once the imports are done; the second by
    :meth:`unraisable`, which reports nothing and has the signal sent again a moment later
    (:data:`REDELIVERY_DELAY`, from another thread: sent from the hook itself, it would be
    handled inside the hook and swallowed once more), so it surfaces in ordinary code.
    """

    seen: int | None = None
    deferring = False
    """While True (the heavy imports), a signal is only recorded and raised when they end: an
    exception raised inside a pybind11 module's initialisation (matplotlib's ft2font) becomes
    "ImportError: initialization failed" and can abort the process."""
    default_unraisable: ClassVar[Callable[[sys.UnraisableHookArgs], object]] = sys.__unraisablehook__
    """The hook :meth:`unraisable` hands other reports to (the one it replaced)."""

    @classmethod
    def handle(cls, signum: int, frame: FrameType | None) -> None:
        cls.seen = signum
        if not cls.deferring:
            raise cls.exception(signum)

    @staticmethod
    def exception(signum: int) -> BaseException:
        return KeyboardInterrupt() if signum == signal.SIGINT else Terminated(TERMINATED)

    @classmethod
    def unraisable(cls, report: sys.UnraisableHookArgs) -> None:
        if cls.seen is not None and isinstance(report.exc_value, (KeyboardInterrupt, Terminated)):
            redelivery = threading.Timer(REDELIVERY_DELAY, os.kill, (os.getpid(), cls.seen))
            redelivery.daemon = True
            redelivery.start()
            return
        cls.default_unraisable(report)

    @classmethod
    def raise_swallowed(cls) -> None:
        """Raise the signal's exception if it arrived but something swallowed it."""
        if cls.seen is not None:
            raise cls.exception(cls.seen)


def main(argv: Sequence[str] | None = None) -> int:
    """Run the command line; returns the exit code (see the module docstring)."""
    return _run(argv, ())


def run_console(arrived: Sequence[int]) -> int:
    """:func:`main` on ``sys.argv``, for the console script (:mod:`.console`): ``arrived`` holds
    the signals its recorders caught before pinrate's own handlers were installed, the first of
    which ends the run at once (130 or 143)."""
    return _run(None, arrived)


def _run(argv: Sequence[str] | None, arrived: Sequence[int]) -> int:
    previous = _own_signals()
    try:
        if arrived:  # read once pinrate's handlers are in place: no signal falls between
            raise _Signals.exception(arrived[0])
        try:
            args = build_parser(_version).parse_args(argv)  # light: --help answers here
        except SystemExit as finished:  # --help, --version, or a usage error already printed on one line
            return finished.code if isinstance(finished.code, int) else 2
        logging.basicConfig(level=logging.INFO if args.verbose else logging.WARNING, format="pinrate: %(message)s")
        with _signals_deferred():  # importing Pinocchio (and matplotlib) takes a second
            from ..errors import PinrateError

            run = _command(args.command)
        try:
            return int(run(args))
        except PinrateError as error:  # a refused input: one line
            print(f"pinrate: error: {error}", file=sys.stderr)
            return 2
    except KeyboardInterrupt:
        _quiet_print("pinrate: interrupted")
        return INTERRUPTED
    except Terminated:
        _quiet_print("pinrate: terminated")
        return TERMINATED
    except BrokenPipeError:
        # The reader went away (`pinrate list | head`): stop writing, and keep the
        # interpreter's final flush from failing on the closed pipe again.
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        os.close(devnull)
        return BROKEN_PIPE
    finally:
        _restore_signals(previous)


def _command(name: str) -> Callable[[argparse.Namespace], int]:
    """The function that runs subcommand ``name``. Only here does its module load, and with it
    what the command needs: numpy and Pinocchio for all, matplotlib for ``analyze`` and
    ``paper``; the parser imports none of them."""
    if name == "list":
        from .robot_list import list_robots

        return list_robots
    if name == "demo":
        from .demo import demo

        return demo
    if name == "analyze":
        from .analyze import analyze

        return analyze
    if name == "paper":
        from .paper_results import paper

        return paper
    if name == "teleop":
        from .teleop import run

        return run
    raise KeyError(name)  # the parser offers no other name


def _version() -> str:
    """``--version``'s text: the version, and the path pinrate's loops take. Which path is
    :mod:`pinrate.compiled`'s to say, and that package loads numpy and Pinocchio."""
    with _signals_deferred():
        from ..compiled import backend

    return f"pinrate {__version__}\nbackend: {backend()}"


@contextlib.contextmanager
def _signals_deferred() -> Iterator[None]:
    """A block of heavy imports: a signal that arrives meanwhile is recorded and raised when
    the block ends (see :attr:`_Signals.deferring`), also when an extension swallowed it."""
    _Signals.deferring = True
    try:
        yield
    finally:
        _Signals.deferring = False
    _Signals.raise_swallowed()


def _own_signals() -> dict[int, object]:
    """SIGINT raises KeyboardInterrupt and SIGTERM :class:`Terminated`, whatever was
    inherited; the previous handlers (and unraisable hook) are returned for
    :func:`_restore_signals`, so a test calling ``main`` in-process keeps its own."""
    if threading.current_thread() is not threading.main_thread():
        return {}
    _Signals.seen = None
    previous: dict[int, object] = {
        signum: signal.signal(signum, _Signals.handle) for signum in (signal.SIGINT, signal.SIGTERM)
    }
    _Signals.default_unraisable = sys.unraisablehook
    sys.unraisablehook = _Signals.unraisable
    return previous


def _restore_signals(previous: dict[int, object]) -> None:
    if not previous:
        return
    for signum, handler in previous.items():
        signal.signal(signum, handler)  # type: ignore[arg-type]
    sys.unraisablehook = _Signals.default_unraisable


def _quiet_print(message: str) -> None:
    with contextlib.suppress(OSError, ValueError):  # stderr may be closed too
        print(message, file=sys.stderr, flush=True)
