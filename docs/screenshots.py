"""Retake the pictures in docs/ in headless Chromium with Mesa's llvmpipe (a conformant
software GL: SwiftShader, the tests' default, drops grid lines that cross the camera plane).

Run: ``make screenshots`` (or ``.venv/bin/python docs/screenshots.py``). It writes
``docs/ur5-demo.png`` from ``pinrate demo ur5 --record``'s replay, then runs the console's
browser tests with ``PINRATE_DOCS_SCREENSHOTS=1`` (each writes its ``docs/teleop-*.png``).
Look at every picture before committing it.
"""

from __future__ import annotations

import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
os.environ["PINRATE_BROWSER_GL"] = "llvmpipe"
sys.path.insert(0, str(ROOT / "tests"))

from browser import chromium  # noqa: E402  (tests/browser.py: the tests' Chromium set-up)

REPLAY_FPS = 30.0
"""Frames per second of the demo's replay (:meth:`pinrate.viewer.Viewer.save_html`'s default)."""

SHOT_AT = 0.85
"""Share of the replay played before the picture: the hand on its way to the last target."""


def demo_picture(out: Path) -> None:
    with tempfile.TemporaryDirectory() as folder:
        replay = Path(folder) / "demo.html"
        run = subprocess.run(
            [sys.executable, "-m", "pinrate.cli", "demo", "ur5", "--targets", "3", "--record", str(replay)],
            check=True,
            stdin=subprocess.DEVNULL,
            capture_output=True,
            text=True,
            timeout=600,
        )
        frames = int(run.stdout.rsplit("(", 1)[1].split()[0])  # "recorded   PATH (N frames)"
        with chromium(900, 700) as context:
            page = context.new_page()
            page.goto(replay.as_uri())
            page.wait_for_function("() => window.viewer !== undefined", timeout=60_000)
            time.sleep(SHOT_AT * frames / REPLAY_FPS)
            page.screenshot(path=str(out))
    print(f"wrote {out}")


def console_pictures() -> None:
    environment = {**os.environ, "PINRATE_DOCS_SCREENSHOTS": "1", "PINRATE_BROWSER_GL": "llvmpipe"}
    subprocess.run(
        [sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", "tests/teleop/test_browser.py"],
        check=True,
        cwd=ROOT,
        env=environment,
        timeout=1800,
    )


if __name__ == "__main__":
    demo_picture(ROOT / "docs" / "ur5-demo.png")
    if "--demo-only" not in sys.argv:
        console_pictures()
