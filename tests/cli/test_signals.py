"""The process owns its signals: Ctrl-C at any moment after start-up ends with exit 130 and no
traceback, also when SIGINT was inherited ignored; SIGTERM cleans up; a closed pipe is quiet
(pinrate.cli.entry)."""

from __future__ import annotations

import os
import re
import signal
import subprocess
import sys
import time
from collections.abc import Callable

import pytest

from support import ROOT

pytestmark = pytest.mark.skipif(not os.path.exists("/proc/self/status"), reason="needs Linux /proc")

COMMAND = [sys.executable, "-m", "pinrate.cli"]


def ignore_sigint() -> None:
    # What a background job of a non-interactive shell inherits (`bash -c "cmd &"`).
    signal.signal(signal.SIGINT, signal.SIG_IGN)


def catches(pid: int, signum: int) -> bool:
    """Whether the process has a handler installed for ``signum`` (its SigCgt mask)."""
    with open(f"/proc/{pid}/status", encoding="ascii") as status:
        for line in status:
            if line.startswith("SigCgt:"):
                return bool(int(line.split()[1], 16) >> (signum - 1) & 1)
    return False


def start(argv: list[str], preexec: Callable[[], None] | None = None) -> subprocess.Popen[str]:
    """The CLI in a child, returned once its entry point owns the signals: Python catches
    SIGINT from start-up on, SIGTERM only once pinrate's main runs. What comes before that
    is CPython's own site initialisation, which no program can guard."""
    process = subprocess.Popen(
        [*COMMAND, *argv], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, preexec_fn=preexec
    )
    deadline = time.monotonic() + 30
    while not catches(process.pid, signal.SIGTERM):
        assert process.poll() is None and time.monotonic() < deadline, process.communicate()
        time.sleep(0.001)
    return process


@pytest.mark.parametrize("inherited", ["default", "ignored"])
@pytest.mark.parametrize("delay", [0.0, 0.05, 0.15, 0.3, 0.6, 1.2])
def test_ctrl_c_at_any_moment_exits_130_without_a_traceback(inherited: str, delay: float) -> None:
    # From the entry point on: importing Pinocchio and matplotlib (about a second), loading,
    # the servo runs; 40 targets take far longer than the longest delay.
    process = start(
        ["demo", "ur5", "--no-viewer", "--targets", "1000"], ignore_sigint if inherited == "ignored" else None
    )
    time.sleep(delay)
    process.send_signal(signal.SIGINT)
    _, err = process.communicate(timeout=30)
    # 130, or death by SIGINT (what shells also show as 130): CPython ends a process so when
    # the interrupt surfaced inside code an extension module ran (Pinocchio's import).
    assert process.returncode in (130, -signal.SIGINT), err[-2000:]
    assert "Traceback" not in err and err.strip().splitlines()[-1] == "pinrate: interrupted"


@pytest.mark.parametrize("delay", [0.0, 0.1, 0.3, 0.5, 1.2])
def test_sigterm_ends_the_run_and_says_so(delay: float) -> None:
    process = start(["demo", "ur5", "--no-viewer", "--targets", "1000"])
    time.sleep(delay)
    process.terminate()
    _, err = process.communicate(timeout=30)
    assert process.returncode == 143 and "Traceback" not in err, err[-2000:]


def test_a_closed_output_pipe_is_quiet() -> None:
    # `pinrate list | head -0`: the reader is gone before the first line is written.
    process = subprocess.Popen([*COMMAND, "list"], stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    process.stdout.close()
    err = process.stderr.read().decode()
    process.stderr.close()
    assert process.wait(timeout=30) == 141
    assert "Traceback" not in err and "BrokenPipeError" not in err, err


SWALLOWED = """
import signal, sys, time, weakref
from pinrate.cli import entry

class Thing:
    pass

def callback(reference):
    # The signal lands inside a weak-reference callback, whose exception CPython can only
    # report as "Exception ignored in ..." (what an import lock's callback did in CI).
    signal.raise_signal(signal.SIG{name})
    for _ in range(1000):
        pass

entry._own_signals()
thing = Thing()
reference = weakref.ref(thing, callback)
try:
    del thing
    deadline = time.monotonic() + 5
    while time.monotonic() < deadline:
        # Not a bare `pass`: CPython 3.13 raises a signal's exception in a tight loop's
        # condition outside the enclosing try (python/cpython#130279).
        time.sleep(0.001)
    print("not delivered")
except (KeyboardInterrupt, entry.Terminated) as delivered:
    print(type(delivered).__name__)
"""


@pytest.mark.parametrize(("name", "exception"), [("TERM", "Terminated"), ("INT", "KeyboardInterrupt")])
def test_a_signal_swallowed_by_a_callback_is_delivered_again(name: str, exception: str) -> None:
    result = subprocess.run(
        [sys.executable, "-c", SWALLOWED.replace("{name}", name)], capture_output=True, text=True, timeout=30
    )
    assert result.stdout.strip() == exception and "Traceback" not in result.stderr, result.stderr


CONSOLE_SCRIPT = """
import signal, sys

class Ring:
    # Sends the signal when the command line's own modules start loading: the moment between
    # the console script's first line and pinrate's handlers (Ctrl-C a few ms after start).
    def find_spec(self, name, path=None, target=None):
        if name == "pinrate.cli.entry":
            signal.raise_signal(signal.SIG{name})
        return None

sys.meta_path.insert(0, Ring())
from {module} import {function} as main
assert signal.getsignal(signal.SIGINT) is signal.default_int_handler, "importing it took SIGINT"
sys.argv[1:] = ["list"]
sys.exit(main())
"""


@pytest.mark.parametrize(("name", "code", "said"), [("INT", 130, "interrupted"), ("TERM", 143, "terminated")])
def test_a_signal_before_the_command_line_loads_ends_the_console_script_quietly(
    name: str, code: int, said: str
) -> None:
    # The console script as pip writes it, for the entry point pyproject.toml declares.
    declared = re.search(r'^pinrate = "([\w.]+):(\w+)"', (ROOT / "pyproject.toml").read_text(encoding="utf-8"), re.M)
    assert declared is not None
    module, function = declared.groups()
    script = CONSOLE_SCRIPT.replace("{name}", name).replace("{module}", module).replace("{function}", function)
    result = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=60, check=False)
    assert result.returncode == code and "Traceback" not in result.stderr, result.stderr[-2000:]
    assert result.stderr.strip() == f"pinrate: {said}" and not result.stdout
