"""Shoham & Koren §2-3: the Jacobian in the sensor frame, and its blocks.

Rows: eq. 10 (two-link planar arm, Fig. 1), eq. 13 (cylindrical), eq. 16 (spherical, Fig. 2),
§2's two structural claims (J does not depend on theta1; J is diagonal iff the joints move the
arm end in orthogonal directions), and eq. 22 (B = 0 iff the wrist axes meet at the TCP, and
then MCA2 is exact). Every deviation is the largest over random configurations of pinrate's
robot (m, rad; dimensionless for J's angular rows).

Misprint (derived again and tested): S&K eq. 20 prints "U = -A^-1 B N" for the block L.
"""

from __future__ import annotations

import math

import numpy as np

from .. import robots
from ..analysis import design
from ..kinematics.manipulator import Robot
from ..kinematics.partition import Partition
from ..solvers.rates import joint_rates
from .table import Result, deviation_text, row, yes_no


# ---------------------------------------------------------------------- eq. 10, 13, 16
def two_link_deviation(count: int = 200) -> float:
    """max ``|J_linear - eq. 10|`` over random configurations (l1 = 0.7, l2 = 0.45)."""
    l1, l2 = 0.7, 0.45
    robot = robots.two_link_planar(l1=l1, l2=l2)

    def deviation(q: np.ndarray) -> float:
        s2, c2 = math.sin(q[1]), math.cos(q[1])
        return float(np.abs(robot.jacobian(q)[:2] - [[l1 * s2, 0.0], [l2 + l1 * c2, l2]]).max())

    return max(deviation(q) for q in robot.sample_configurations(count, 0))


@row
def _two_link_row() -> Result:
    """S&K eq. 10 (Fig. 1): the two-link planar arm's J in the sensor frame."""
    return Result(
        "S&K eq. 10 (Fig. 1)",
        "J = [[l1 S2, 0], [l2 + l1 C2, l2]] in the sensor frame",
        f"max deviation {deviation_text(two_link_deviation())} over 200 random q",
        "papers/test_worked_examples.py::test_two_link_eq_10",
    )


def cylindrical_deviation(count: int = 200) -> float:
    """max ``|J_linear - diag(d3, 1, 1)|`` (eq. 13)."""
    robot = robots.cylindrical()
    return max(
        float(np.abs(robot.jacobian(q)[:3] - np.diag([q[2], 1, 1])).max())
        for q in robot.sample_configurations(count, 0)
    )


@row
def _cylindrical_row() -> Result:
    """S&K eq. 13: the cylindrical robot's J."""
    return Result(
        "S&K eq. 13",
        "cylindrical: J = diag(d3, 1, 1)",
        f"max deviation {deviation_text(cylindrical_deviation())}",
        "papers/test_worked_examples.py::test_cylindrical_eq_13",
    )


def spherical_deviation(count: int = 200) -> float:
    """max ``|J_linear - diag(d3 C2, d3, 1)|`` (eq. 16)."""
    robot = robots.spherical()
    return max(
        float(np.abs(robot.jacobian(q)[:3] - np.diag([q[2] * math.cos(q[1]), q[2], 1])).max())
        for q in robot.sample_configurations(count, 0)
    )


@row
def _spherical_row() -> Result:
    """S&K eq. 16 (Fig. 2): the spherical robot's J."""
    return Result(
        "S&K eq. 16 (Fig. 2)",
        "spherical: J = diag(d3 C2, d3, 1)",
        f"max deviation {deviation_text(spherical_deviation())}",
        "papers/test_worked_examples.py::test_spherical_eq_16",
    )


# ---------------------------------------------------------------------- §2, the structure of J
def first_joint_independent() -> dict[str, bool]:
    """Whether the sensor-frame Jacobian is independent of the first joint (§2)."""
    checks = {
        "two_link_planar": robots.two_link_planar(),
        "cylindrical": robots.cylindrical(),
        "spherical": robots.spherical(),
        "planar_polar": robots.planar_polar(),
        "scara": robots.scara(),
    }
    return {name: robot.joint_names[0] in design.independent_joints(robot) for name, robot in checks.items()}


@row
def _first_joint_row() -> Result:
    """S&K §2: J in the sensor frame does not depend on theta1."""
    independence = first_joint_independent()
    return Result(
        "S&K §2",
        "J in the sensor frame does not depend on theta1 (its encoder can go)",
        "independent: " + ", ".join(f"{k} {yes_no(v)}" for k, v in independence.items()),
        "papers/test_worked_examples.py::test_first_joint_independent",
    )


def _arm_jacobian_is_monomial(robot: Robot, joints: list[str], count: int = 50) -> bool:
    """Whether J[linear, joints] has one non-zero per row and column at every sampled q."""
    columns = [robot.velocity_indices(j)[0] for j in joints]
    for q in robot.sample_configurations(count, 3):
        block = np.abs(robot.jacobian(q)[:3, columns]) > 1e-9
        if not (block.sum(axis=0) == 1).all() or not (block.sum(axis=1) == 1).all():
            return False
    return True


def diagonal_arms() -> dict[str, bool]:
    """§2: "J is diagonal iff the joints move the arm end in orthogonal directions"."""
    cartesian = robots.cartesian(tip="slide_z", sensor="slide_z")
    scara = robots.scara(tip="quill", sensor="sensor")
    ur5 = _ur5_wrist_centre()
    return {
        "cartesian": _arm_jacobian_is_monomial(cartesian, ["d1", "d2", "d3"]),
        "cylindrical": _arm_jacobian_is_monomial(robots.cylindrical(), ["theta1", "d2", "d3"]),
        "spherical": _arm_jacobian_is_monomial(robots.spherical(), ["theta1", "theta2", "d3"]),
        "scara": _arm_jacobian_is_monomial(scara, ["theta1", "theta2", "d"]),
        "articulated (ur5)": _arm_jacobian_is_monomial(
            ur5, ["shoulder_pan_joint", "shoulder_lift_joint", "elbow_joint"]
        ),
    }


def _ur5_wrist_centre() -> Robot:
    return robots.load("ur5", tip="wrist_1_link", sensor="wrist_1_link")


@row
def _diagonal_row() -> Result:
    """S&K §2: J is diagonal iff the joints move the arm end in orthogonal directions."""
    diagonal = diagonal_arms()
    return Result(
        "S&K §2",
        "J diagonal iff the joints move the end orthogonally: Cartesian, cylindrical, "
        "spherical yes; SCARA, articulated no",
        "one entry per row and column: " + ", ".join(f"{k} {yes_no(v)}" for k, v in diagonal.items()),
        "papers/test_worked_examples.py::test_diagonal_arms",
    )


# ---------------------------------------------------------------------- eq. 22, B = 0
def max_abs_B(robot: Robot, count: int = 100) -> float:
    partition = Partition.auto(robot)
    return max(
        float(np.abs(partition.blocks(robot, robot.jacobian(q))[1]).max())
        for q in robot.sample_configurations(count, 0)
    )


def mca2_minus_exact(robot: Robot, count: int = 50) -> float:
    """max ``|mca2 - exact|`` over random configurations and twists."""
    generator = np.random.default_rng(1)
    worst = 0.0
    for q in robot.sample_configurations(count, 2):
        twist = generator.normal(size=6)
        worst = max(
            worst,
            float(
                np.abs(
                    joint_rates(robot, q, twist, algorithm="mca2") - joint_rates(robot, q, twist, algorithm="exact")
                ).max()
            ),
        )
    return worst


@row
def _b_zero_row() -> Result:
    """S&K eq. 22: B = 0 iff the wrist axes meet at the TCP; then MCA2 is exact."""
    barker_centre = robots.barker_arm()
    return Result(
        "S&K eq. 22",
        "B = 0 iff the wrist axes meet at the TCP; then MCA2 is exact",
        f"max |B|: Barker wrist centre {deviation_text(max_abs_B(barker_centre))}, Cartesian "
        f"{deviation_text(max_abs_B(robots.cartesian()))}, "
        f"Barker hand {max_abs_B(robots.barker_arm(tip='hand')):.2f}; "
        f"max |mca2 - exact| at the wrist centre {deviation_text(mca2_minus_exact(barker_centre))}",
        "papers/test_worked_examples.py::test_eq_22_B_zero_iff_wrist_meets_tcp",
    )
