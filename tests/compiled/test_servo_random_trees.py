"""The two paths on random URDF trees (tests/support.py's ``random_urdf``: odd axes, prismatic
and continuous joints, branches, pseudo-inverse blocks), every algorithm and strategy, from
home and from random starts.

The paths make different operations here (the core's pseudo-inverses are Eigen's, Python's
numpy's), so q differs by rounding from the first step (~1e-17). Where the loop contracts
that difference stays at rounding; it grows where the loop amplifies it: a non-contracting
error map (ρ >= 1) or a discrete decision (a joint held at a limit, a direction cut by the
generalized inverse, a frozen joint), whose side a rounding difference can choose. The claim
tested: the paths agree (every word and detail; q within 1e-9) up to the first step where
the Python run met such a condition, on every run; and many runs never part at all.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

import pinrate
from compiled_core import needs_core, path
from pinrate.kinematics.targets import nearby_target
from support import fuzz_count, random_urdf

pytestmark = needs_core

ALGORITHMS = ("exact", "mca1", "mca2", "mca3", "dls")
STRATEGIES = ("decelerate", "generalized_inverse", "freeze", "adaptive_dls")
CONTRACTING_WORDS = {pinrate.Status.OK.word, pinrate.Status.TWIST_SATURATED.word, pinrate.Status.RATE_LIMITED.word}
"""Steps without a discrete decision: the saturation and the rate limit scale continuously."""

Q_AGREEMENT = 1e-9
"""q of the two paths before they part: rounding (1e-17 per step) grown by a contracting
loop stays far below this; a step past it is where the paths part."""


def parting_step(python: pinrate.Trajectory, compiled: pinrate.Trajectory) -> int | None:
    """The first configuration index where the runs' words, details or q differ (None: never)."""
    count = min(len(python.status), len(compiled.status))
    for index in range(count):
        if python.status[index] != compiled.status[index] or python.detail[index] != compiled.detail[index]:
            return index
        if float(np.max(np.abs(python.q[index] - compiled.q[index]))) > Q_AGREEMENT:
            return index
    return None if len(python.status) == len(compiled.status) else count


def first_sensitive_step(run: pinrate.Trajectory) -> float:
    """The first configuration index from which the loop could amplify rounding (inf: none)."""
    for index, word in enumerate(run.status[:-1]):
        if word not in CONTRACTING_WORDS or not run.spectral_radius[index] < 1.0:
            return index
    return math.inf


@pytest.mark.parametrize("seed", range(fuzz_count(10)))
def test_the_paths_part_only_where_the_loop_amplifies_rounding(tmp_path: Path, seed: int) -> None:
    rng = np.random.default_rng(1000 + seed)
    urdf = tmp_path / "random.urdf"
    urdf.write_text(random_urdf(rng), encoding="utf-8")
    try:
        robot = pinrate.load(urdf)
        partition = pinrate.Partition.auto(robot)
    except pinrate.PinrateError:
        pytest.skip("this tree has no arm to servo")
    for trial in range(3):
        algorithm, singularity = str(rng.choice(ALGORITHMS)), str(rng.choice(STRATEGIES))
        _, target = nearby_target(robot, partition, int(rng.integers(1 << 30)), spread=float(rng.choice([0.5, 2.5])))
        start = robot.home() if trial == 0 else robot.random_configuration(rng)
        settings = {"algorithm": algorithm, "singularity": singularity, "max_steps": 1500}
        runs = []
        for choice in ("python", "compiled"):
            with path(choice):
                runs.append(pinrate.servo(robot, start, target, **settings))
        python, compiled = runs
        parted = parting_step(python, compiled)
        if parted is not None:
            sensitive = first_sensitive_step(python)
            assert sensitive <= parted, (
                f"{settings}, trial {trial}: the paths part at step {parted} "
                f"({python.status[parted]!r} {python.detail[parted]!r} vs {compiled.status[parted]!r} "
                f"{compiled.detail[parted]!r}) with the loop contracting and no decision before it"
            )
