"""The API reference builds from the docstrings without one warning (docs/api, ``make api``).

Sphinx with ``-W --keep-going -n``: every cross-reference in a docstring resolves, every
docstring is well-formed reStructuredText, each object is described once, and every module of
pinrate is on a page (docs/api/conf.py). The dummy builder reads and resolves as the HTML one
does, without writing pages (half the time).
"""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

from support import ROOT

SOURCE = ROOT / "docs" / "api"


def test_the_api_reference_builds_without_a_warning(tmp_path: Path) -> None:
    warnings = tmp_path / "warnings.txt"
    command = [sys.executable, "-m", "sphinx", "-b", "dummy", "-E", "-W", "--keep-going", "-n", "-q"]
    run = subprocess.run(
        [*command, "-w", str(warnings), "-d", str(tmp_path / "doctrees"), str(SOURCE), str(tmp_path / "out")],
        capture_output=True,
        text=True,
        timeout=300,
        check=False,
    )
    written = warnings.read_text(encoding="utf-8") if warnings.exists() else ""
    assert run.returncode == 0 and not written.strip(), written or run.stderr[-4000:]


def test_the_index_links_every_guide() -> None:
    """Every Markdown page of docs/ is linked from the reference's index, and every link
    names a page that exists."""
    index = (SOURCE / "index.rst").read_text(encoding="utf-8")
    linked = set(re.findall(r"/blob/main/docs/([\w.-]+\.md)>", index))
    pages = {path.name for path in (ROOT / "docs").glob("*.md")}
    assert linked == pages


def test_every_package_has_its_page() -> None:
    """One page per package of pinrate, each in the index's table of contents."""
    packages = {path.parent for path in (ROOT / "src" / "pinrate").rglob("__init__.py")}
    names = {".".join(path.relative_to(ROOT / "src").parts) for path in packages}
    pages = {path.stem for path in SOURCE.glob("*.rst")} - {"index"}
    assert pages == names
    index = (SOURCE / "index.rst").read_text(encoding="utf-8")
    assert all(re.search(rf"^   {re.escape(name)}$", index, re.MULTILINE) for name in names)
