"""The command line parses before it imports anything heavy (issue 20): ``--help`` of the CLI
and of every subcommand, and a refused argument, load neither numpy, Pinocchio, matplotlib,
meshcat, tornado nor any of pinrate's layers below the CLI; each subcommand loads what it
needs when it runs. What this costs in seconds is ``benchmarks/startup.py``'s to measure;
these tests check which modules load (pinrate.cli.parser, pinrate.cli.entry)."""

from __future__ import annotations

import json
import subprocess
import sys

import pytest

from pinrate.cli import parser

HEAVY = ("numpy", "pinocchio", "matplotlib", "meshcat", "tornado", "pinrate_core")
"""Third-party modules parsing must not load (numpy alone costs about 0.1-0.2 s here)."""

LIGHT = {"pinrate", "pinrate.cli", "pinrate.cli.entry", "pinrate.cli.parser", "pinrate.cli.arguments"}
"""The only pinrate modules parsing may load."""

SUBCOMMANDS = ("list", "paper", "analyze", "demo", "teleop")

PARSE = """
import contextlib, io, json, sys
from pinrate.cli import main

codes = {}
for argv in json.loads(sys.argv[1]):
    with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
        codes[" ".join(argv)] = main(argv)
loaded = sorted(name for name in sys.modules if name.split(".")[0] in ("pinrate", *json.loads(sys.argv[2])))
print(json.dumps({"codes": codes, "loaded": loaded}))
"""


def named(modules: set[str]) -> list[str]:
    """pinrate's modules by name, the others by their top-level package (numpy, not its 90 modules)."""
    return sorted({name if name.startswith("pinrate.") else name.split(".")[0] for name in modules})


def loaded_after(argvs: list[list[str]]) -> tuple[dict[str, int], set[str]]:
    """Exit codes of ``main(argv)`` for each argv, run one after the other in a fresh
    interpreter, and the pinrate and :data:`HEAVY` modules loaded by then."""
    result = subprocess.run(
        [sys.executable, "-c", PARSE, json.dumps(argvs), json.dumps(HEAVY)],
        capture_output=True,
        text=True,
        timeout=120,
        check=False,
    )
    assert result.returncode == 0, result.stderr
    answer = json.loads(result.stdout)
    return answer["codes"], set(answer["loaded"])


def test_help_of_the_cli_and_of_every_subcommand_loads_nothing_heavy() -> None:
    argvs = [["--help"], *([name, "--help"] for name in SUBCOMMANDS)]
    codes, loaded = loaded_after(argvs)
    assert codes == {" ".join(argv): 0 for argv in argvs}
    assert loaded <= LIGHT, f"parsing --help loaded {named(loaded - LIGHT)}"


def test_a_refused_argument_is_answered_before_anything_heavy_loads() -> None:
    argvs = [["demo", "ur5", "--algorithm", "bogus"], ["teleop", "ur5", "--frame", "world"], ["bogus"], []]
    codes, loaded = loaded_after(argvs)
    assert set(codes.values()) == {2}
    assert loaded <= LIGHT, f"a usage error loaded {named(loaded - LIGHT)}"


def test_a_subcommand_loads_what_it_needs_only() -> None:
    # `list` needs the robots (and so numpy and Pinocchio), not the analysis, the papers,
    # matplotlib, the viewer or the teleop console.
    codes, loaded = loaded_after([["list"]])
    assert codes == {"list": 0}
    assert {"numpy", "pinocchio", "pinrate.robots", "pinrate.cli.robot_list"} <= loaded
    unneeded = {"matplotlib", "meshcat", "tornado", "pinrate.analysis", "pinrate.papers", "pinrate.viewer"}
    assert not loaded & unneeded, named(loaded & unneeded)
    others = ("pinrate.cli.demo", "pinrate.cli.analyze", "pinrate.cli.paper_results", "pinrate.cli.teleop")
    assert not {name for name in loaded if name.startswith(others)}


def test_each_choice_copied_into_the_parser_matches_its_source() -> None:
    # The parser keeps copies (importing the sources would load numpy and Pinocchio).
    from pinrate.control.servo_loop import MAX_STEPS
    from pinrate.control.singularity import STRATEGIES, WRIST_STRATEGIES
    from pinrate.kinematics.urdf_structure import MAX_JOINTS
    from pinrate.plants.mujoco_plant import ACTUATORS
    from pinrate.solvers.registry import ALGORITHMS
    from pinrate.teleop.session import FRAMES

    assert parser.ALGORITHMS == ALGORITHMS
    assert parser.STRATEGIES == STRATEGIES
    assert parser.WRIST_STRATEGIES == WRIST_STRATEGIES
    assert parser.FRAMES == FRAMES
    assert parser.MAX_JOINTS == MAX_JOINTS
    assert parser.MAX_STEPS == MAX_STEPS
    assert parser.ACTUATORS == ACTUATORS


@pytest.mark.parametrize("name", SUBCOMMANDS)
def test_every_subcommand_has_a_runner(name: str) -> None:
    from pinrate.cli import entry

    assert callable(entry._command(name))
