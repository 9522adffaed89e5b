"""Random URDF trees: every one that loads has Jacobians that match finite differences of its
own poses; every mutation of one loads or is refused with a PinrateError, never another
exception, a NaN or a crash. Seeded and bounded; PINRATE_FUZZ_SCALE runs more."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

import pinrate
from support import finite_difference_jacobian, fuzz_count, random_urdf


@pytest.mark.parametrize("seed", range(fuzz_count(150)))
def test_random_trees_match_finite_differences(tmp_path: Path, seed: int) -> None:
    rng = np.random.default_rng(seed)
    path = tmp_path / f"random{seed}.urdf"
    path.write_text(random_urdf(rng), encoding="utf-8")
    bodies = [frame.name for frame in pinrate.load(path).model.frames if frame.name.startswith("link")]
    robot = pinrate.load(path, sensor=str(rng.choice(bodies)))  # any sensor frame, the base's too
    for _ in range(3):
        q = robot.random_configuration(rng)
        jacobian = robot.jacobian(q)
        assert np.isfinite(jacobian).all()
        np.testing.assert_allclose(jacobian, finite_difference_jacobian(robot, q), atol=2e-6)
        np.testing.assert_allclose(robot.kinematics(q)[0], jacobian, atol=1e-12)


MUTATIONS = ("drop attribute", "bad number", "duplicate element", "drop element", "joint type", "truncate", "junk")


def mutate(text: str, rng: np.random.Generator) -> str:
    """One random corruption of a URDF's text."""
    mutation = MUTATIONS[int(rng.integers(len(MUTATIONS)))]
    if mutation == "drop attribute":
        attributes = list(re.finditer(r' [a-z_]+="[^"]*"', text))
        hit = attributes[int(rng.integers(len(attributes)))]
        return text[: hit.start()] + text[hit.end() :]
    if mutation == "bad number":
        numbers = list(re.finditer(r"-?\d+(\.\d+)?(e-?\d+)?", text))
        hit = numbers[int(rng.integers(len(numbers)))]
        junk = str(rng.choice(["nan", "inf", "-inf", "abc", "1e400", "", "1,5", "0x10"]))
        return text[: hit.start()] + junk + text[hit.end() :]
    if mutation in ("duplicate element", "drop element"):
        elements = list(re.finditer(r"<(link|joint) .*?(/>|</joint>)", text))
        hit = elements[int(rng.integers(len(elements)))]
        middle = hit.group(0) * 2 if mutation == "duplicate element" else ""
        return text[: hit.start()] + middle + text[hit.end() :]
    if mutation == "joint type":
        kinds = list(re.finditer(r'type="[a-z]+"', text))
        hit = kinds[int(rng.integers(len(kinds)))]
        kind = str(rng.choice(["floating", "planar", "hinge", "", "REVOLUTE", "fixed", "continuous"]))
        return text[: hit.start()] + f'type="{kind}"' + text[hit.end() :]
    if mutation == "truncate":
        return text[: int(rng.integers(1, len(text)))]
    position = int(rng.integers(len(text)))
    return text[:position] + str(rng.choice(["<", ">", "&", '"', "\x00", "é", "<link/>"])) + text[position:]


@pytest.mark.parametrize("seed", range(fuzz_count(25)))
def test_mutated_urdfs_load_or_are_refused_cleanly(tmp_path: Path, seed: int) -> None:
    rng = np.random.default_rng(1000 + seed)
    outcomes = {"loaded": 0, "refused": 0}
    for case in range(20):
        path = tmp_path / f"mutant{case}.urdf"
        path.write_text(mutate(random_urdf(rng), rng), encoding="utf-8", errors="surrogateescape")
        try:
            robot = pinrate.load(path)
        except pinrate.PinrateError as error:
            assert str(error), "an error without a message"
            outcomes["refused"] += 1
            continue
        outcomes["loaded"] += 1
        q = robot.random_configuration(rng)
        assert np.isfinite(robot.jacobian(q)).all() and np.isfinite(robot.pose(q)).all()
    assert outcomes["refused"] > 0  # the mutations do break files
