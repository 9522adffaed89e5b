"""The ``pinrate`` process: who owns its signals, how it ends, what it exits with.

Exit codes: 0 done (the demo converged), 1 the demo did not converge, 2 a refused input
(one line ``pinrate: error: ...`` on stderr), 130 interrupted (Ctrl-C, at any moment,
start-up included; when the interrupt landed inside Pinocchio's import, CPython itself ends
the process by SIGINT after pinrate's cleanup, which shells also report as 130), 143
terminated (SIGTERM), 141 its output pipe closed (``| head``).

The CLI owns SIGINT: CPython raises KeyboardInterrupt only when SIGINT was at its default
disposition at start-up, and a background job of a non-interactive shell inherits it
ignored, so a ``pinrate demo`` started that way would never hear Ctrl-C. Heavy imports
(Pinocchio, matplotlib) happen inside the guarded region, so an interrupt while they load
ends as cleanly as one during the run.
"""

from __future__ import annotations

import contextlib
import os
import signal
import sys
import threading
from collections.abc import Sequence
from types import FrameType

INTERRUPTED = 130
TERMINATED = 143
BROKEN_PIPE = 141


class _Interrupts:
    """Whether SIGINT arrived: an extension module that clears Python errors (Boost.Python
    code run while Pinocchio imports) can swallow the KeyboardInterrupt, so the flag is
    checked again once the imports are done."""

    seen = False

    @classmethod
    def handle(cls, signum: int, frame: FrameType | None) -> None:
        cls.seen = True
        raise KeyboardInterrupt


class Terminated(SystemExit):
    """Raised in the main thread on SIGTERM, so ``finally`` blocks (the viewer's server) run."""


def _terminate(signum: int, frame: FrameType | None) -> None:
    raise Terminated(TERMINATED)


def main(argv: Sequence[str] | None = None) -> int:
    """Run the command line; returns the exit code (see the module docstring)."""
    previous = _own_signals()
    try:
        from .commands import run  # inside the guard: importing Pinocchio takes a second

        if _Interrupts.seen:  # interrupted while importing, and something swallowed it
            raise KeyboardInterrupt
        return run(argv)
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


def _own_signals() -> dict[int, object]:
    """SIGINT raises KeyboardInterrupt and SIGTERM :class:`Terminated`, whatever was
    inherited; the previous handlers are returned for :func:`_restore_signals` (so a test
    calling ``main`` in-process keeps its own)."""
    if threading.current_thread() is not threading.main_thread():
        return {}
    previous = {}
    _Interrupts.seen = False
    for signum, handler in ((signal.SIGINT, _Interrupts.handle), (signal.SIGTERM, _terminate)):
        previous[signum] = signal.signal(signum, handler)
    return previous


def _restore_signals(previous: dict[int, object]) -> None:
    for signum, handler in previous.items():
        signal.signal(signum, handler)  # type: ignore[arg-type]


def _quiet_print(message: str) -> None:
    with contextlib.suppress(OSError, ValueError):  # stderr may be closed too
        print(message, file=sys.stderr, flush=True)
