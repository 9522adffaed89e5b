"""Which path runs: the compiled core where it is importable, else pure Python.

The core is a separate extension module, ``pinrate_core`` (``core/`` in the source tree:
nanobind on Pinocchio's header-only templates). ``pip install ./core`` builds it;
``make demo`` and ``make test`` do so where a C++ compiler works, and go on without it where
none does. Nothing in pinrate requires it: every result has a pure-Python path.
"""

from __future__ import annotations

import importlib
import os
from dataclasses import dataclass
from types import ModuleType

from ..errors import InputError
from .boundary import disagreements

ENVIRONMENT = "PINRATE_BACKEND"
"""``auto`` (the default: the core where it is importable), ``python`` (never the core) or
``compiled`` (the core, or an error where it cannot be imported)."""

CHOICES = ("auto", "python", "compiled")

CORE_MODULE = "pinrate_core"
"""The extension module's name."""

CORE_ABI = 7
"""The ``pinrate_core.ABI`` this pinrate speaks; a core of another ABI is not used, nor one
whose constants or settings' fields differ from this pinrate's (:mod:`.boundary`)."""

_choice: str | None = None  # set by use(); None: the environment decides
_loaded: tuple[ModuleType | None, str] | None = None


@dataclass(frozen=True)
class Backend:
    """The path pinrate's loops take (``pinrate.backend()``).

    Attributes:
        name: ``"compiled"`` or ``"python"``.
        reason: why, in words (the core's version and headers, or why it is not used).
        choice: what was asked for: ``"auto"``, ``"python"`` or ``"compiled"``.
    """

    name: str
    reason: str
    choice: str

    def __str__(self) -> str:
        return f"{self.name} ({self.reason})"


def _requested() -> str:
    choice = _choice if _choice is not None else os.environ.get(ENVIRONMENT, "auto").strip().lower() or "auto"
    if choice not in CHOICES:
        raise InputError(f"{ENVIRONMENT} must be one of {', '.join(CHOICES)}, not {choice!r}")
    return choice


def _import_core() -> tuple[ModuleType | None, str]:
    global _loaded
    if _loaded is None:
        try:
            # The core links libcoal.so (the collision monitor) without a path to it: the coal
            # binding loads the one pin runs, and the core's reference resolves to it.
            importlib.import_module("coal")
            module = importlib.import_module(CORE_MODULE)
        except ImportError as error:
            _loaded = (
                None,
                f"the compiled core is not installed ({error}); `pip install ./core` in pinrate's source builds it",
            )
        else:
            abi = getattr(module, "ABI", None)
            if abi != CORE_ABI:
                why = f"pinrate_core speaks ABI {abi}, this pinrate {CORE_ABI}: rebuild it (pip install ./core)"
                _loaded = (None, why)
            elif found := disagreements(module):
                why = (
                    f"pinrate_core disagrees with this pinrate: {'; '.join(found)}: "
                    "rebuild it from this pinrate's core/ (pip install ./core)"
                )
                _loaded = (None, why)
            else:
                _loaded = (module, f"pinrate_core on Pinocchio {module.PINOCCHIO_VERSION}'s headers")
    return _loaded


def core_module() -> ModuleType | None:
    """The ``pinrate_core`` module when the compiled path is chosen and importable, else None.

    Raises:
        InputError: ``compiled`` was asked for and the core cannot be imported.
    """
    choice = _requested()
    if choice == "python":
        return None
    module, reason = _import_core()
    if module is None and choice == "compiled":
        raise InputError(f"{ENVIRONMENT}=compiled, but {reason}")
    return module


def backend() -> Backend:
    """Which path pinrate's servo loops and ρ maps take, and why.

    ``compiled`` where ``pinrate_core`` imports; a configuration the core does not cover (a
    joint type it does not rebuild, auxiliary elbow control, a posture task, acceleration
    limits, blocks larger than 3x3, a collision monitor where the coal that runs is not the
    one the core was built on) still runs on Python, per call.
    """
    choice = _requested()
    if choice == "python":
        return Backend("python", f"{ENVIRONMENT}=python", choice)
    module, reason = _import_core()
    if module is None:
        if choice == "compiled":
            raise InputError(f"{ENVIRONMENT}=compiled, but {reason}")
        return Backend("python", reason, choice)
    return Backend("compiled", reason, choice)


def chosen() -> str | None:
    """What :func:`use` chose for this process (None: ``PINRATE_BACKEND`` decides): a per-call
    step's cheap test of whether the path may have changed (reading the environment costs
    more than the step's own checks)."""
    return _choice


def use(choice: str | None) -> None:
    """Choose the path for this process: ``"auto"``, ``"python"``, ``"compiled"``, or None to
    follow ``PINRATE_BACKEND`` again."""
    global _choice
    if choice is not None and choice not in CHOICES:
        raise InputError(f"backend must be one of {', '.join(CHOICES)} or None, not {choice!r}")
    _choice = choice
    if choice == "compiled":
        core_module()  # fail here, not in the first loop
