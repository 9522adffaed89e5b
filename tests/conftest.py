"""Shared fixtures and independent reference computations for the tests."""

from __future__ import annotations

import faulthandler
import os
import sys
import threading

import pytest

import pinrate
from support import DATA

EXIT_GRACE = 60.0
"""Seconds the interpreter may take to exit after the last test."""


def pytest_sessionfinish(session: pytest.Session, exitstatus: int) -> None:
    """Leave within EXIT_GRACE seconds of the session's end, whatever hangs at exit.

    Once CI spent its 90 minutes after every test had passed and pytest had printed its
    summary: something (a library's atexit handler or a non-daemon thread) never returned.
    A daemon watchdog prints every thread's stack, so the culprit shows in the log, and
    exits with the session's own status.
    """

    def leave() -> None:
        print(f"\npytest did not exit within {EXIT_GRACE:g} s of the session's end; the threads:", file=sys.__stderr__)
        faulthandler.dump_traceback(file=sys.__stderr__, all_threads=True)
        sys.__stderr__.flush()
        os._exit(int(exitstatus))

    watchdog = threading.Timer(EXIT_GRACE, leave)
    watchdog.daemon = True
    watchdog.start()


@pytest.fixture(scope="session")
def ur5() -> pinrate.Robot:
    return pinrate.load("ur5")


@pytest.fixture(scope="session")
def panda() -> pinrate.Robot:
    return pinrate.load("panda")


@pytest.fixture(scope="session")
def mixed() -> pinrate.Robot:
    """Negative and non-z axes, a prismatic and a continuous joint; sensor mid-chain."""
    return pinrate.load(DATA / "mixed_joints.urdf", tip="tool", sensor="link2")
