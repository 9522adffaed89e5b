"""ρ < 1 along a path is not sufficient (issue 10): MCA1's angular error carries the term
−U A⁻¹ v (Shoham & Koren eq. 30), which grows without bound as A nears singularity; pinrate
reports that coupling beside ρ (pinrate.theorem.coupling_along, the demo's summary)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

import pinrate
from pinrate.cli.demo import verdict_lines
from pinrate.theorem import coupling_along

IRB140 = Path(__file__).parent.parent / "data" / "third_party" / "rtb_irb140.urdf"
# Found by a random search (servo from a random start to a nearby target, MCA1, defaults).
START = [-0.0941, -0.4275, -0.8235, 2.7141, -1.462, 3.198]
GOAL = [0.0519, -0.67, -0.9381, 2.6639, -1.798, 2.9833]


def test_mca1_diverges_with_rho_below_one_and_the_coupling_says_why() -> None:
    robot = pinrate.load(IRB140)
    trajectory = pinrate.servo(robot, START, robot.pose(np.array(GOAL)))
    assert trajectory.reason.startswith("diverging"), trajectory.reason
    assert np.all(trajectory.spectral_radius < 0.5)  # the Theorem's test passes at every step

    # ‖U A⁻¹‖₂ from the Jacobian (arm: joints 1-3 drive xyz; wrist: 4-6 drive the rotation).
    jacobians = [robot.jacobian(q) for q in trajectory.q]
    expected = [np.linalg.norm(J[3:, :3] @ np.linalg.inv(J[:3, :3]), 2) for J in jacobians]
    np.testing.assert_allclose(coupling_along(robot, trajectory.q), expected, rtol=1e-9)
    assert max(expected) > 5 * expected[0]  # A nears singularity on the way
    assert max(np.linalg.cond(J[:3, :3]) for J in jacobians) > 5 * np.linalg.cond(jacobians[0][:3, :3])

    lines = verdict_lines(robot, trajectory)
    assert any(line.startswith("coupling   |U A^-1|") for line in lines)
    assert any(line.startswith("why        diverged although rho < 1") for line in lines), lines
