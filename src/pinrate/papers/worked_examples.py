"""Every worked result of the two papers, recomputed by pinrate on the papers' robots.

:func:`results` runs the registry of :mod:`.table`: one :class:`~.table.Result` per equation or
figure (the paper's statement, pinrate's value computed now, and the test that checks it
against an independent closed form), each computed by a ``@row`` function next to its
computation, section by section (:data:`SECTIONS`). :func:`~.table.markdown` renders them as
``docs/paper-results.md`` (a test keeps that file equal to a fresh computation, so it cannot
go stale; ``pinrate paper`` prints it).

Misprints found in the OCR'd text, each derived again, tested, and documented in the module
of the row it concerns:

* S&K eq. 20 prints "U = -A^-1 B N" for the block L (:mod:`.sensor_jacobians`).
* S&K eq. 70, second column (theta2), and what follows from it: the printed det(A), eq. 71,
  and eq. 72-73 as conditions (:mod:`.spherical_6dof`).
* S&K eq. 71, entry (3, 3): the sign of its d3 term (:mod:`.spherical_6dof`).
* Fig. 6: the printed polar poses cannot give the printed λ (:mod:`.polar_simulation`).
* Fig. 9(b): at the printed target G is next to its pole; the printed start λ 1.62 is reached
  at -49.75° (:mod:`.scara_simulation`).
* Barker 1983: eq. 28, 35-36, 47, 59-63, B11 and B28-B29 (:mod:`.barker` lists them).

What two of the paper's statements measure (read from the text, computed as read): S&K §5.3's
"at least within 50 percent of the work volume convergence always exists"
(:mod:`.spherical_6dof`), and Fig. 6(b)'s "the convergence condition is not fulfilled and the
trajectory diverges" (:mod:`.polar_simulation`).
"""

from __future__ import annotations

from types import ModuleType

from . import (
    barker_arm_rates,
    barker_elbow,
    barker_hand_rotation,
    barker_jacobian,
    barker_wrist,
    convergence_boundaries,
    polar_simulation,
    scara_simulation,
    sensor_jacobians,
    spherical_6dof,
)
from .table import Result, rows_of

SECTIONS: tuple[ModuleType, ...] = (
    sensor_jacobians,  # S&K §2-3: eq. 10, 13, 16, 22
    convergence_boundaries,  # S&K §5.1-5.2: eq. 56-63, Fig. 5, 8, 10
    spherical_6dof,  # S&K §5.3: eq. 70-73, Fig. 12
    barker_jacobian,  # Barker eq. D9, 32-33, 25-31
    barker_arm_rates,  # Barker eq. 34-44
    barker_elbow,  # Barker eq. 45-46, B27-B29
    barker_hand_rotation,  # Barker eq. B1-B24
    barker_wrist,  # Barker eq. 49-63
    polar_simulation,  # S&K Fig. 6
    scara_simulation,  # S&K Fig. 9
)
"""The modules whose ``@row`` functions make the table, in the table's order."""


def results() -> list[Result]:
    """Recompute every row (a few seconds): each section's rows, in order."""
    return [compute() for section in SECTIONS for compute in rows_of(section)]
