"""``pinrate paper``: every result of the two papers recomputed, as the Markdown table of
``docs/paper-results.md`` (:mod:`pinrate.papers`). Importing this module loads the papers'
computations, and with them the analysis and matplotlib."""

from __future__ import annotations

import argparse

from ..papers import markdown, results


def paper(_: argparse.Namespace) -> int:
    """``pinrate paper``: the papers' results recomputed, as a Markdown table."""
    print(markdown(results()), end="")
    return 0
