"""Every worked result of the two papers, recomputed on the papers' robots
(``docs/paper-results.md``, ``pinrate paper``)."""

from .table import Result, markdown
from .worked_examples import results

__all__ = ["Result", "markdown", "results"]
