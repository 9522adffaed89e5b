"""The compiled core for the tests: which tests need it, and the two paths side by side.

A test that needs the core is skipped with a reason when ``pinrate_core`` is not installed
(a pure-Python install), unless PINRATE_REQUIRE_CORE=1 (CI sets it), which turns a missing
core into a failure.
"""

from __future__ import annotations

import contextlib
import importlib.util
import os
from collections.abc import Iterator

import pytest

from pinrate.compiled import use

REQUIRED = os.environ.get("PINRATE_REQUIRE_CORE") == "1"
MISSING = "" if importlib.util.find_spec("pinrate_core") else "pinrate_core is not installed (make core)"
if MISSING and REQUIRED:
    raise RuntimeError(f"PINRATE_REQUIRE_CORE=1 but {MISSING}")
needs_core = pytest.mark.skipif(bool(MISSING), reason=MISSING or "core available")


@contextlib.contextmanager
def path(choice: str) -> Iterator[None]:
    """Run the block on one path ("python" or "compiled"), then follow PINRATE_BACKEND again."""
    use(choice)
    try:
        yield
    finally:
        use(None)
