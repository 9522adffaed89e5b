"""Print pip constraints pinning every [project] dependency of pyproject.toml to its floor.

CI installs the package under these (``pip install -c``) in a second venv and runs the suite
there, so a floor in pyproject is one that has been tested: ``"numpy>=2.2"`` becomes
``numpy==2.2``. A dependency without a floor fails here: every one must state what it needs.
"""

from __future__ import annotations

import re
import sys
from pathlib import Path

import tomllib


def floors(pyproject: Path) -> list[str]:
    dependencies = tomllib.loads(pyproject.read_text(encoding="utf-8"))["project"]["dependencies"]
    constraints = []
    for requirement in dependencies:
        match = re.fullmatch(r"\s*([A-Za-z0-9_.\-]+)(\[[^\]]*\])?\s*>=\s*([0-9][^,;\s]*)\s*(,.*)?", requirement)
        if match is None:
            raise SystemExit(f"floors.py: {requirement!r} states no floor (name>=version)")
        constraints.append(f"{match.group(1)}=={match.group(3)}")
    return constraints


if __name__ == "__main__":
    print("\n".join(floors(Path(sys.argv[1] if len(sys.argv) > 1 else "pyproject.toml"))))
