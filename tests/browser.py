"""Real headless Chromium for the browser tests (Debian's /usr/bin/chromium, driven by Playwright).

A test module using it is skipped with a reason when Chromium or Playwright is missing,
unless PINRATE_REQUIRE_BROWSER=1 (CI sets it), which turns a missing browser into a failure.
"""

from __future__ import annotations

import contextlib
import os
import shutil
import tempfile
from collections.abc import Iterator
from pathlib import Path

import pytest

CHROMIUM = os.environ.get("PINRATE_CHROMIUM", "/usr/bin/chromium")
REQUIRED = os.environ.get("PINRATE_REQUIRE_BROWSER") == "1"
SOFTWARE_GL = {
    # The tests' default: SwiftShader, in every Chromium build. It drops line segments that
    # cross the camera plane (the grid shows as a strip above the robot), so not for pictures.
    "swiftshader": ["--disable-gpu", "--enable-unsafe-swiftshader"],
    # Mesa's llvmpipe through ANGLE's EGL backend: conformant, as a GPU draws (docs/ pictures).
    "llvmpipe": ["--use-angle=gl-egl", "--ignore-gpu-blocklist"],
}
GL = os.environ.get("PINRATE_BROWSER_GL", "swiftshader")
if GL not in SOFTWARE_GL:
    raise RuntimeError(f"PINRATE_BROWSER_GL must be one of {sorted(SOFTWARE_GL)}, got {GL!r}")
# Playwright adds --headless itself (headless=True) and the fresh --user-data-dir (persistent context).
FLAGS = [
    "--no-sandbox",
    "--disable-quic",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
    *SOFTWARE_GL[GL],
]


def _browser_missing() -> str:
    if not (Path(CHROMIUM).exists() or shutil.which(CHROMIUM)):
        return f"Chromium not found at {CHROMIUM} (apt install chromium)"
    try:
        import playwright.sync_api  # noqa: F401
    except ImportError:
        return "playwright is not installed (pip install -e '.[test]')"
    return ""


MISSING = _browser_missing()
if MISSING and REQUIRED:
    raise RuntimeError(f"PINRATE_REQUIRE_BROWSER=1 but {MISSING}")
needs_browser = pytest.mark.skipif(bool(MISSING), reason=MISSING or "browser available")


@contextlib.contextmanager
def chromium(width: int = 800, height: int = 600) -> Iterator[object]:
    """A persistent Chromium context with a fresh profile, closed on exit."""
    from playwright.sync_api import sync_playwright

    with sync_playwright() as playwright, tempfile.TemporaryDirectory() as profile:
        context = playwright.chromium.launch_persistent_context(
            profile, executable_path=CHROMIUM, headless=True, args=FLAGS, viewport={"width": width, "height": height}
        )
        try:
            yield context
        finally:
            context.close()
