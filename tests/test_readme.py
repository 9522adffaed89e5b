"""The README's library examples run as printed, one after the other."""

from __future__ import annotations

import re
from pathlib import Path

README = Path(__file__).resolve().parents[1] / "README.md"


def test_library_example_runs(capsys) -> None:
    text = README.read_text(encoding="utf-8")
    section = text.split("## As a library", 1)[1]
    section = section.split("\n## ", 1)[0]
    blocks = re.findall(r"```python\n(.*?)```", section, re.S)
    assert len(blocks) == 2  # the library, then the MuJoCo plant on the same robot and target
    namespace: dict[str, object] = {}
    for code in blocks:
        exec(compile(code, "README.md", "exec"), namespace)
    out = capsys.readouterr().out.splitlines()
    assert "arm (3 joints" in "\n".join(out) and "True" in "\n".join(out)
    assert 0 < float(out[-1]) < 0.01  # the plant's tracking error, m
