"""Every worked result of the two papers, recomputed on the papers' robots
(``docs/paper-results.md``, ``pinrate paper``)."""

from .worked_examples import Result, markdown, results

__all__ = ["Result", "markdown", "results"]
