"""Every worked result of the two papers, recomputed by pinrate on the papers' robots.

:func:`results` returns one :class:`Result` per equation or figure: the paper's statement,
pinrate's value computed now, and the test that checks it against an independent closed
form. :func:`markdown` renders them as ``docs/paper-results.md`` (a test keeps that file
equal to a fresh computation, so it cannot go stale; ``pinrate paper`` prints it).

Misprints found in the OCR'd text (each derived again and tested):

* S&K eq. 20 prints "U = -A^-1 B N" for the block L.
* S&K eq. 70, second column (theta2): printed (0, d3 - l C5, -l C4 - S5); the derivation
  (theta2 turns about the sensor's x axis at the joint centre, the TCP lies at
  d3 z + l (S4 S5, -C4 S5, C5)) gives (0, -(d3 + l C5), -l C4 S5). The printed det(A) and
  eq. 71 follow the misprinted column; with the corrected one G has the eigenvalues
  0, l C5 / (d3 + l C5) and l K / (d3 C2 + l K) with K = C2 C5 - S2 C4 S5, so eq. 72
  (K > 0) is sufficient (the exact condition is K > -d3 C2 / (2 l)) and eq. 73 becomes
  C5 > -d3 / (2 l); both hold throughout when d3 > 2 l and -90° < theta5 < 90°.
* S&K eq. 71, entry (3, 3): printed l (d3 S2 C4 S5 + l S2 C4 S5 C5) / det(A); the printed
  eq. 70 gives l (-d3 S2 C4 S5 + l S2 C4 S5 C5) / det(A). Derivation: with the printed
  column 2 (0, d3 - l C5, -l C4 S5) A is lower triangular, det(A) = a11 (d3 - l C5) (the
  printed det(A)), a11 = d3 C2 + l C2 C5 - l S2 C4 S5; U's third row is (-S2, 0, 0), so row
  3 of G = U A^-1 B W^-1 is -S2 / a11 times row 1 of B W^-1, which is (0, l C5, l C4 S5)
  (solve x W = (l C4 S5, l S4 C5, 0)). Hence G(3, 3) = -l S2 C4 S5 / a11
  = l (-d3 S2 C4 S5 + l S2 C4 S5 C5) / det(A), while G(3, 2) = -l S2 C5 / a11 is printed
  right. Every other entry of eq. 71 is U A^-1 B W^-1 of the printed eq. 70
  (:func:`printed_eq71_errors`); the OCR's "-l C4 - S5" at (3, 2) of eq. 70 does not
  enter G (U's third column is 0 and A is lower triangular: U A^-1 uses A's leading 2x2).
* Fig. 6: the printed polar poses cannot give the printed λ under any reading tried
  (TCP or wrist point, absolute or relative orientation); the simulation is rerun from
  poses built to have the printed λ values.
* Fig. 9(b): at the printed target (0.95, -0.06, -50°) G is next to its pole
  (l2 S2 + l3 S23 = 0) and very sensitive; the printed start λ 1.62 is reached at -49.75°.

What two of the paper's statements measure (read from the text, computed as read):

* S&K §5.3's "at least within 50 percent of the work volume convergence always exists"
  is about the (theta2, theta5) square (-90°, 90°)² with theta4 free ("always": for every
  theta4): K = C2 C5 - S2 C4 S5 is affine in C4, so eq. 72 holds for every theta4 iff
  C2 C5 > |S2 S5|, i.e. cos(|theta2| + |theta5|) > 0, |theta2| + |theta5| < 90°: exactly
  half the square. At one theta4 with C4 = ±1 it is |theta2 ± theta5| < 90°, 3/4 of it
  (the paper's "much larger" effective work volume when C4 does not take both values).
* Fig. 6(b), "the convergence condition is not fulfilled and the trajectory diverges":
  |λ| = 1.5 > 1 at the start (the target's -0.9 is inside). The dead-beat MCA2 iteration
  (the Theorem's setting) first moves away (the servo's divergence stop fires at step 4),
  then, without joint limits, crosses G's pole d2 + l C3 = 0, takes d2 through 0 and
  converges on the mirror branch d2 < 0 (theta1 - 180°, theta3 + 180°: the same pose),
  which the robot's stroke (d2 >= 0.05 m) and the paper's d2 > 0 exclude; with the limits
  held it stops at d2 = 0.05 m, theta3 = 180° short of the target (:func:`fig6b_continued`).
  So the figure's outcome holds on the robot, while |λ| > 1 at the start alone does not
  make the iteration diverge: the Theorem's condition is sufficient, not necessary.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from .. import robots
from ..analysis import design
from ..control.commands import PoseGoal
from ..control.controller import Controller, error_norms
from ..control.servo_loop import servo
from ..errors import InputError, SingularBlockError
from ..kinematics.manipulator import Robot
from ..kinematics.partition import Partition
from ..solvers.rates import joint_rates
from ..theorem import convergence, convergence_from_blocks, sample_convergence, spectral_radius_at
from . import barker
from .barker import barker_singular_configurations


@dataclass(frozen=True)
class Result:
    """One row of docs/paper-results.md."""

    reference: str
    paper: str
    pinrate: str
    test: str


def _max_over_configurations(robot: Robot, count: int, function: Callable[[np.ndarray], float], seed: int = 0) -> float:
    return max(function(q) for q in robot.sample_configurations(count, seed))


# ---------------------------------------------------------------------- §2 sensor-frame Jacobians
def two_link_deviation(count: int = 200) -> float:
    """max |J_linear - eq. 10| over random configurations (l1 = 0.7, l2 = 0.45)."""
    l1, l2 = 0.7, 0.45
    robot = robots.two_link_planar(l1=l1, l2=l2)

    def deviation(q: np.ndarray) -> float:
        s2, c2 = math.sin(q[1]), math.cos(q[1])
        return float(np.abs(robot.jacobian(q)[:2] - [[l1 * s2, 0.0], [l2 + l1 * c2, l2]]).max())

    return _max_over_configurations(robot, count, deviation)


def cylindrical_deviation(count: int = 200) -> float:
    """max |J_linear - diag(d3, 1, 1)| (eq. 13)."""
    robot = robots.cylindrical()
    return _max_over_configurations(
        robot, count, lambda q: float(np.abs(robot.jacobian(q)[:3] - np.diag([q[2], 1, 1])).max())
    )


def spherical_deviation(count: int = 200) -> float:
    """max |J_linear - diag(d3 C2, d3, 1)| (eq. 16)."""
    robot = robots.spherical()
    return _max_over_configurations(
        robot,
        count,
        lambda q: float(np.abs(robot.jacobian(q)[:3] - np.diag([q[2] * math.cos(q[1]), q[2], 1])).max()),
    )


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


def arm_jacobian_is_monomial(robot: Robot, joints: list[str], count: int = 50) -> bool:
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
        "cartesian": arm_jacobian_is_monomial(cartesian, ["d1", "d2", "d3"]),
        "cylindrical": arm_jacobian_is_monomial(robots.cylindrical(), ["theta1", "d2", "d3"]),
        "spherical": arm_jacobian_is_monomial(robots.spherical(), ["theta1", "theta2", "d3"]),
        "scara": arm_jacobian_is_monomial(scara, ["theta1", "theta2", "d"]),
        "articulated (ur5)": arm_jacobian_is_monomial(
            ur5, ["shoulder_pan_joint", "shoulder_lift_joint", "elbow_joint"]
        ),
    }


def _ur5_wrist_centre() -> Robot:
    return robots.load("ur5", tip="wrist_1_link", sensor="wrist_1_link")


# ---------------------------------------------------------------------- eq. 22
def max_abs_B(robot: Robot, count: int = 100) -> float:
    partition = Partition.auto(robot)
    return _max_over_configurations(
        robot, count, lambda q: float(np.abs(partition.blocks(robot, robot.jacobian(q))[1]).max())
    )


def mca2_minus_exact(robot: Robot, count: int = 50) -> float:
    """max |mca2 - exact| over random configurations and twists."""
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


# ---------------------------------------------------------------------- §5.1 polar
def polar_G_deviation(count: int = 500) -> float:
    """max |G - l C3 / (d2 + l C3)| (eq. 56), l = 0.2."""
    robot = robots.planar_polar()

    def deviation(q: np.ndarray) -> float:
        closed_form = 0.2 * math.cos(q[2]) / (q[1] + 0.2 * math.cos(q[2]))
        return abs(float(convergence(robot, q).G[0, 0]) - closed_form)

    return _max_over_configurations(robot, count, deviation)


def polar_boundary_agreement(count: int = 5000) -> float:
    """Share of samples where ρ < 1 agrees with eq. 58, C3 > -d2 / (2 l)."""
    sample = sample_convergence(robots.planar_polar(), count, rng=4)
    analytic = np.cos(sample.q[:, 2]) > -sample.q[:, 1] / (2 * 0.2)
    return float(np.mean((sample.spectral_radius < 1) == analytic))


def polar_rule(points: int = 61) -> float:
    """The smallest lower stroke d2_min whose worst ρ < 1 (the rule says 2 l = 0.4)."""
    return design.smallest_parameter(
        lambda d2_min: robots.planar_polar(l=0.2, d2_min=d2_min), 0.1, 0.9, points=points, tolerance=1e-5
    )


# ---------------------------------------------------------------------- §5.2 SCARA
def scara_G_deviation(count: int = 500) -> float:
    """max |G - l3 S23 / (l2 S2 + l3 S23)| (eq. 60), relative, l1 = l2 = l3 = 0.4."""
    robot = robots.scara()

    def deviation(q: np.ndarray) -> float:
        s2, s23 = math.sin(q[1]), math.sin(q[1] + q[3])
        closed_form = 0.4 * s23 / (0.4 * s2 + 0.4 * s23)
        return abs(float(convergence(robot, q).G[0, 0]) - closed_form) / max(1.0, abs(closed_form))

    return _max_over_configurations(robot, count, deviation)


def scara_boundary_agreement(count: int = 5000) -> float:
    """Share of samples where ρ < 1 agrees with eq. 63, S23 / S2 > -l2 / (2 l3)."""
    sample = sample_convergence(robots.scara(), count, rng=5)
    s2, s23 = np.sin(sample.q[:, 1]), np.sin(sample.q[:, 1] + sample.q[:, 3])
    return float(np.mean((sample.spectral_radius < 1) == (s23 / s2 > -0.5)))


def hirata_rule(points: int = 121) -> float:
    """The largest tool length l3 (m) with worst ρ < 1 on the Hirata ARH-300."""
    return design.largest_parameter(lambda l3: robots.hirata_arh300(l3=l3), 0.01, 0.3, points=points, tolerance=1e-6)


HIRATA_CLOSED_FORM = 0.275 * math.sin(math.radians(25)) / 2
"""l2 sin(25°) / 2: the worst case S2 = sin 25°, S23 = -1 of eq. 63."""


# ---------------------------------------------------------------------- §5.3 six-DOF spherical
def spherical_6dof_jacobian(q: np.ndarray, l: float) -> np.ndarray:  # noqa: E741
    """Eq. 70 with its second column corrected (see the module docstring)."""
    _, t2, d3, t4, t5, _ = q
    C2, S2, C4, S4, C5, S5 = (
        math.cos(t2),
        math.sin(t2),
        math.cos(t4),
        math.sin(t4),
        math.cos(t5),
        math.sin(t5),
    )
    return np.array(
        [
            [d3 * C2 + l * C2 * C5 - l * S2 * C4 * S5, 0, 0, l * C4 * S5, l * S4 * C5, 0],
            [-l * S2 * S4 * S5, -(d3 + l * C5), 0, l * S4 * S5, -l * C4 * C5, 0],
            [-l * C2 * S4 * S5, -l * C4 * S5, 1, 0, -l * S5, 0],
            [0, 1, 0, 0, C4, S4 * S5],
            [C2, 0, 0, 0, S4, -C4 * S5],
            [-S2, 0, 0, 1, 0, C5],
        ]
    )


def spherical_6dof_eigenvalues(q: np.ndarray, l: float) -> np.ndarray:  # noqa: E741
    """0, l C5 / (d3 + l C5), l K / (d3 C2 + l K), K = C2 C5 - S2 C4 S5 (from the corrected eq. 70)."""
    _, t2, d3, t4, t5, _ = q
    K = math.cos(t2) * math.cos(t5) - math.sin(t2) * math.cos(t4) * math.sin(t5)
    return np.array([0.0, l * math.cos(t5) / (d3 + l * math.cos(t5)), l * K / (d3 * math.cos(t2) + l * K)])


def spherical_6dof_deviations(count: int = 300) -> tuple[float, float]:
    """(max |J - corrected eq. 70|, max eigenvalue mismatch of G)."""
    robot = robots.spherical_6dof()
    l = 0.1  # noqa: E741
    worst_jacobian = worst_eigen = 0.0
    for q in robot.sample_configurations(count, 6):
        worst_jacobian = max(worst_jacobian, float(np.abs(robot.jacobian(q) - spherical_6dof_jacobian(q, l)).max()))
        try:
            found = np.sort(np.abs(convergence(robot, q).eigenvalues))
        except SingularBlockError:
            continue
        worst_eigen = max(worst_eigen, float(np.abs(found - np.sort(np.abs(spherical_6dof_eigenvalues(q, l)))).max()))
    return worst_jacobian, worst_eigen


def spherical_6dof_printed_jacobian(q: np.ndarray, l: float) -> np.ndarray:  # noqa: E741
    """Eq. 70 as printed (sensor axes; m, rad): column 2 (0, d3 - l C5, -l C4 S5), the OCR's
    "-l C4 - S5" read as -l C4 S5 (it does not enter G, module docstring)."""
    d3, t4, t5 = (float(value) for value in q[2:5])
    printed = spherical_6dof_jacobian(q, l)
    printed[:3, 1] = [0.0, d3 - l * math.cos(t5), -l * math.cos(t4) * math.sin(t5)]
    return printed


def spherical_6dof_printed_G(q: np.ndarray, l: float, *, d3_sign_33: float = 1.0) -> np.ndarray:  # noqa: E741
    """Eq. 71 as printed: G = (l / det A) [...] with the printed det(A) = d3² C2 - d3 l S2 C4 S5
    - l² C2 C5² + l² S2 C4 S5 C5 (dimensionless). ``d3_sign_33 = -1`` changes the sign of the d3
    term of entry (3, 3), the correction (module docstring)."""
    _, t2, d3, t4, t5, _ = q
    C2, S2, C4, S4, C5, S5 = (math.cos(t2), math.sin(t2), math.cos(t4), math.sin(t4), math.cos(t5), math.sin(t5))
    det = d3 * d3 * C2 - d3 * l * S2 * C4 * S5 - l * l * C2 * C5 * C5 + l * l * S2 * C4 * S5 * C5
    entries = np.array(
        [
            [
                -d3 * C2 * C5 - l * C2 * C5 * C5 + l * S2 * C4 * S5 * C5,
                l * S2 * S4 * S5 * C5,
                d3 * C2 * S4 * S5 + l * C2 * S4 * S5 * C5,
            ],
            [0.0, d3 * C2 * C5 - l * C2 * C5 * C5, d3 * C2 * C4 * S5 - l * C2 * C4 * S5 * C5],
            [0.0, -d3 * S2 * C5 + l * S2 * C5 * C5, d3_sign_33 * d3 * S2 * C4 * S5 + l * S2 * C4 * S5 * C5],
        ]
    )
    return l / det * entries


def printed_eq71_errors(count: int = 300) -> tuple[float, float, float]:
    """Eq. 71 against G = U A^-1 B W^-1 of the printed eq. 70 (pinrate's
    :func:`convergence_from_blocks` on its blocks), over random q of the six-DOF robot, each
    error relative to max(1, |G|): (max over the entries other than (3, 3), max at (3, 3) as
    printed, max at (3, 3) with its d3 term's sign changed)."""
    robot = robots.spherical_6dof()
    l = 0.1  # noqa: E741
    others = printed = corrected = 0.0
    mask = np.ones((3, 3), dtype=bool)
    mask[2, 2] = False
    for q in robot.sample_configurations(count, 24):
        J = spherical_6dof_printed_jacobian(q, l)
        G = convergence_from_blocks(J[:3, :3], J[:3, 3:], J[3:, :3], J[3:, 3:]).G
        scale = max(1.0, float(np.abs(G).max()))
        as_printed = spherical_6dof_printed_G(q, l)
        others = max(others, float(np.abs(G - as_printed)[mask].max()) / scale)
        printed = max(printed, abs(float(G[2, 2] - as_printed[2, 2])) / scale)
        corrected = max(corrected, abs(float(G[2, 2] - spherical_6dof_printed_G(q, l, d3_sign_33=-1.0)[2, 2])) / scale)
    return others, printed, corrected


@dataclass(frozen=True)
class WorkVolume:
    """Shares of the six-DOF robot's (theta2, theta5) square where eq. 72 holds (§5.3)."""

    samples: int
    every_theta4: float  # eq. 72 holds for every theta4 (the paper's "always"); exactly 1/2
    theta4_zero: float  # eq. 72 holds at theta4 = 0 (C4 = 1); exactly 3/4
    sufficient: bool  # pinrate's ρ < 1 wherever eq. 72 holds for every theta4 (three theta4 each)


def eq72_K(theta2: np.ndarray, theta4: np.ndarray, theta5: np.ndarray) -> np.ndarray:
    """K = C2 C5 - S2 C4 S5 of eq. 72 (rad in, dimensionless out)."""
    return np.cos(theta2) * np.cos(theta5) - np.sin(theta2) * np.cos(theta4) * np.sin(theta5)


def spherical_6dof_work_volume(count: int = 20000, seed: int = 12) -> WorkVolume:
    """§5.3's "at least within 50 percent of the work volume convergence always exists".

    ``count`` configurations drawn uniformly in the robot's joint limits (theta2, theta5 in
    (-90°, 90°), the paper's assumptions C2 > 0 and -90° < theta5 < 90°; d3 in [0.3, 0.8] m
    > 2 l). Eq. 72 holds for every theta4 where K > 0 at C4 = +1 and at C4 = -1 (K is affine in
    C4): the share of those samples estimates the area of |theta2| + |theta5| < 90° over the
    square, 1/2. ``sufficient``: at each such sample pinrate's ρ (:func:`spectral_radius_at`,
    the corrected eq. 70) is below 1 at the sample's theta4 and at theta4 = 0 and 180°.
    """
    robot = robots.spherical_6dof()
    q = robot.sample_configurations(count, seed)
    theta2, theta5 = q[:, 1], q[:, 4]
    every = (eq72_K(theta2, np.zeros(count), theta5) > 0) & (eq72_K(theta2, np.full(count, math.pi), theta5) > 0)
    region = q[every]
    variants = [region]
    for theta4 in (0.0, math.pi):
        turned = region.copy()
        robot.set_joint_values(turned, "theta4", np.full(len(turned), theta4))
        variants.append(turned)
    radii = spectral_radius_at(robot, np.concatenate(variants))
    return WorkVolume(
        samples=count,
        every_theta4=float(np.mean(every)),
        theta4_zero=float(np.mean(eq72_K(theta2, np.zeros(count), theta5) > 0)),
        sufficient=bool((radii < 1).all()),
    )


# ---------------------------------------------------------------------- Barker


def barker_det_deviation(count: int = 300, **lengths: float) -> float:
    """max |det A - eq. D9| / (1 + |eq. D9|), with (S2 ES + F5)(SAL3 WE S3 + A3 C3) ES."""
    robot = robots.barker_arm(**lengths)  # type: ignore[arg-type]  # lengths holds no tip or sensor
    parameters = robots.parameters("barker_arm") | lengths
    es, we, a3 = parameters["es"], parameters["we"], parameters["a3"]
    sal3 = math.sin(parameters["alpha3"])
    partition = Partition.auto(robot)

    def deviation(q: np.ndarray) -> float:
        s2, s3, s23, c23, c3 = (
            math.sin(q[1]),
            math.sin(q[2]),
            math.sin(q[1] + q[2]),
            math.cos(q[1] + q[2]),
            math.cos(q[2]),
        )
        f5 = s23 * sal3 * we + c23 * a3
        closed_form = (s2 * es + f5) * (sal3 * we * s3 + a3 * c3) * es
        A = partition.blocks(robot, robot.jacobian(q))[0]
        return abs(float(np.linalg.det(A)) - closed_form) / (1 + abs(closed_form))

    return _max_over_configurations(robot, count, deviation)


def barker_singular(q: np.ndarray) -> bool:
    """Whether MCA2 reports block A singular at q on the nominal Barker arm."""
    robot = robots.barker_arm()
    try:
        joint_rates(robot, q, np.ones(6), algorithm="mca2")
    except SingularBlockError as error:
        return error.block == "A"
    return False


RateSolver = Callable[[Robot, np.ndarray, np.ndarray], np.ndarray]
"""(robot, q, sensor-frame twist) -> joint rates (nv,): the solver a check is run on."""


def _mca2_rates(robot: Robot, q: np.ndarray, twist: np.ndarray) -> np.ndarray:
    return joint_rates(robot, q, twist, algorithm="mca2")


def barker_wrist_deviation(count: int = 200, *, solver: RateSolver | None = None, **lengths: float) -> float:
    """max relative residual of Barker's eq. 49-51 for the wrist rates a solver produces.

    At random q and random hand-axes twists (TVEL, RVEL) (m/s, rad/s) the solver (default
    pinrate's MCA2, :func:`joint_rates`) gives the six rates. The residual is computed from the
    paper alone: RVEL^ = L RVEL (eq. B1, L of eq. B16-B24 with P2 = -S23), RVEL~ = RVEL^ -
    z0 theta1 - z1 theta2 - z2 theta3 with the solver's arm rates (eq. 48; z of eq. C7-C10),
    D1..D5 (eq. 52-56), then

        theta5 + C4 D5 + S4 D4 (eq. 49),   S5 theta6 + S4 D5 - C4 D4 (eq. 50),
        theta4 + C5 theta6 - SAL3 D3 + CAL3 D2 (eq. 51),

    each over max(1, max |rate|) (rad/s). It is rounding for rates that realise the commanded
    RVEL; wrong wrist (or arm) rates leave it at their error.
    """
    robot = robots.barker_arm(**lengths)  # type: ignore[arg-type]  # lengths holds no tip or sensor
    solve = _mca2_rates if solver is None else solver
    alpha3 = (robots.parameters("barker_arm") | lengths)["alpha3"]
    sal3, cal3 = math.sin(alpha3), math.cos(alpha3)
    generator = np.random.default_rng(9)
    worst = 0.0
    for q in robot.sample_configurations(count, 8):
        twist = generator.normal(size=6)
        rates = np.asarray(solve(robot, q, twist), dtype=float)
        rvel_hat = barker.hand_to_base(q, lengths) @ twist[3:]  # eq. B1
        rvel_tilde = barker.wrist_residual_rotation(q, rvel_hat, rates[:3])  # eq. 48
        _, D2, D3, D4, D5 = barker.wrist_terms(q, rvel_tilde, lengths)  # eq. 52-56
        C4, S4, C5, S5 = math.cos(q[3]), math.sin(q[3]), math.cos(q[4]), math.sin(q[4])
        residual = max(
            abs(rates[4] - (-C4 * D5 - S4 * D4)),  # eq. 49
            abs(S5 * rates[5] - (-S4 * D5 + C4 * D4)),  # eq. 50
            abs(rates[3] + C5 * rates[5] - (sal3 * D3 - cal3 * D2)),  # eq. 51
        )
        worst = max(worst, residual / max(1.0, float(np.abs(rates).max())))
    return worst


# ---------------------------------------------------------------------- Fig. 6 and Fig. 9 simulations
@dataclass(frozen=True)
class Simulation:
    """An MCA2 servo run like the paper's Fig. 6 and 9."""

    start_lambda: float
    target_lambda: float
    final_lambda: float
    converged: bool
    reason: str
    error_growth: float  # the largest total error over the initial one
    final_q: np.ndarray
    q: np.ndarray  # (steps + 1, nq): the servo's configurations, q0 first
    total_error: np.ndarray  # (steps + 1,): position + orientation error norms (m + rad) at each q


def simulate_mca2(robot: Robot, q0: np.ndarray, q_target: np.ndarray, *, dead_beat: bool) -> Simulation:
    """MCA2 from q0 to the pose at q_target.

    ``dead_beat``: the sensor commands the whole error each sample (gain dt = 1, no speed
    limits: the setting of the Theorem, eq. 40 with beta = 1); otherwise the default servo
    (gain 1, dt 0.01, speed limits).
    """
    settings = (
        {"gain": 100.0, "max_linear_speed": math.inf, "max_angular_speed": math.inf, "max_steps": 500}
        if dead_beat
        else {"max_steps": 5000}
    )
    trajectory = servo(robot, q0, robot.pose(q_target), algorithm="mca2", dt=0.01, tol=1e-6, **settings)
    total = trajectory.position_error + trajectory.orientation_error
    return Simulation(
        start_lambda=float(convergence(robot, q0).G[0, 0]),
        target_lambda=float(convergence(robot, q_target).G[0, 0]),
        final_lambda=float(convergence(robot, trajectory.q[-1]).G[0, 0]),
        converged=trajectory.converged,
        reason=trajectory.reason,
        error_growth=float(total.max() / total[0]),
        final_q=trajectory.q[-1],
        q=trajectory.q,
        total_error=total,
    )


DEAD_BEAT_GAIN = 100.0
"""1/s: with dt = 0.01 s, gain dt = 1, the sensor commands the whole error each sample."""


@dataclass(frozen=True)
class Continuation:
    """The servo's dead-beat MCA2 step iterated with no stop rule (Fig. 6(b))."""

    q: np.ndarray  # (steps + 1, nq), q0 first
    position_error: np.ndarray  # (steps + 1,) m, sensor axes
    orientation_error: np.ndarray  # (steps + 1,) rad
    converged: bool  # both norms below tol at the last q
    statuses: tuple[str, ...]  # each step's Status name

    @property
    def steps(self) -> int:
        """Steps taken."""
        return len(self.q) - 1

    @property
    def total_error(self) -> np.ndarray:
        """Position + orientation error norms (m + rad) at each q: the servo's stop-rule measure."""
        return self.position_error + self.orientation_error


def continue_dead_beat_mca2(
    robot: Robot,
    q0: np.ndarray,
    q_target: np.ndarray,
    *,
    position_limits: bool,
    max_steps: int = 2000,
    tol: float = 1e-6,
) -> Continuation:
    """:func:`simulate_mca2`'s dead-beat step (MCA2, gain 100 1/s, dt 0.01 s, no speed or
    velocity limits) taken again and again from q0 towards the pose at q_target until both
    error norms are under ``tol`` (m, rad) or ``max_steps`` ran out: the servo without its
    stop rules (it has no switch for them). ``singularity="generalized_inverse"`` keeps a
    near-singular A from halting the run (it changes a step only where a singular value of A
    falls under the controller's threshold); ``position_limits`` holds the URDF's limits."""
    controller = Controller(
        robot,
        algorithm="mca2",
        dt=0.01,
        singularity="generalized_inverse",
        velocity_limits=math.inf,
        position_limits=position_limits,
        max_linear_speed=math.inf,
        max_angular_speed=math.inf,
    )
    goal = PoseGoal.of(robot.pose(q_target), DEAD_BEAT_GAIN)
    q = robot.check_q(q0)
    configurations: list[np.ndarray] = [q]
    positions: list[float] = []
    orientations: list[float] = []
    statuses: list[str] = []
    while True:
        position, orientation = error_norms(controller.observe(q, goal), controller.index.m)
        positions.append(position)
        orientations.append(orientation)
        converged = position < tol and orientation < tol
        if converged or len(statuses) == max_steps:
            break
        step = controller.step(q, goal)
        q = step.q
        configurations.append(q)
        statuses.append(step.status.name)
    errors = np.array(positions), np.array(orientations)
    return Continuation(np.array(configurations), *errors, converged, tuple(statuses))


FIG6_POSES = {
    "a": ((0.50, 0.0, 60.0), (0.45, 20.0, 40.0)),
    "b": ((-1.5, 0.0, 150.0), (-0.9, 20.0, 130.0)),
}
"""Fig. 6's (start, target) as (λ, theta1 in deg, theta3 in deg) of :func:`polar_pose_with_lambda`."""


def polar_pose_with_lambda(lam: float, theta1_deg: float, theta3_deg: float, l: float = 0.2) -> np.ndarray:  # noqa: E741
    """The polar configuration with G = lam at the given angles: d2 = l C3 (1 / lam - 1)."""
    c3 = math.cos(math.radians(theta3_deg))
    return np.array([math.radians(theta1_deg), l * c3 * (1 / lam - 1), math.radians(theta3_deg)])


def fig6_poses(which: str) -> tuple[np.ndarray, np.ndarray]:
    """(q0, q_target) of Fig. 6(``which``), ``which`` "a" or "b" (:data:`FIG6_POSES`)."""
    start, target = FIG6_POSES[which]
    return polar_pose_with_lambda(*start), polar_pose_with_lambda(*target)


def fig6() -> tuple[Simulation, Simulation]:
    """Fig. 6 rerun from poses with the printed λ: (a) 0.50 -> 0.45, (b) -1.5 -> -0.9."""
    robot = robots.planar_polar()
    converging = simulate_mca2(robot, *fig6_poses("a"), dead_beat=True)
    diverging = simulate_mca2(robot, *fig6_poses("b"), dead_beat=True)
    return converging, diverging


def fig6b_continued(max_steps: int = 2000) -> tuple[Continuation, Continuation]:
    """Fig. 6(b)'s dead-beat MCA2 past the servo's divergence stop: (without joint limits,
    with the URDF's limits held: 0.05 <= d2 <= 1 m, |theta1|, |theta3| <= 180°)."""
    robot = robots.planar_polar()
    q0, q_target = fig6_poses("b")
    return (
        continue_dead_beat_mca2(robot, q0, q_target, position_limits=False, max_steps=max_steps),
        continue_dead_beat_mca2(robot, q0, q_target, position_limits=True, max_steps=max_steps),
    )


def polar_pole_crossings(q: np.ndarray, l: float = 0.2) -> int:  # noqa: E741
    """How often d2 + l C3, the denominator of G (eq. 56), changes sign along q (steps, nq)."""
    denominator = q[:, 1] + l * np.cos(q[:, 2])
    return int(np.count_nonzero(np.diff(np.sign(denominator)) != 0))


def scara_configuration(
    x: float,
    y: float,
    orientation_deg: float,
    elbow: int,
    *,
    l1: float = 0.4,
    l2: float = 0.4,
    l3: float = 0.4,
    d: float = -0.1,
) -> np.ndarray:
    """SCARA inverse kinematics: TCP at (x, y) with the tool at ``orientation_deg``; elbow ±1."""
    phi = math.radians(orientation_deg)
    wx, wy = x - l3 * math.cos(phi), y - l3 * math.sin(phi)
    c2 = (wx * wx + wy * wy - l1 * l1 - l2 * l2) / (2 * l1 * l2)
    theta2 = elbow * math.acos(max(-1.0, min(1.0, c2)))
    theta1 = math.atan2(wy, wx) - math.atan2(l2 * math.sin(theta2), l1 + l2 * math.cos(theta2))
    return np.array([theta1, theta2, d, phi - theta1 - theta2])


def fig9() -> tuple[Simulation, Simulation]:
    """Fig. 9 from the printed poses, default servo: (a) elbow-down branch, (b) elbow-up branch.

    With λ > 0 real, Re λ > 1 makes the error grow for any gain, so no dead-beat sensor is
    needed to see (b) fail.
    """
    robot = robots.scara()
    converging = simulate_mca2(
        robot,
        scara_configuration(1.10, 0.155, -21.3, -1),
        scara_configuration(1.116, 0.124, -21.3, -1),
        dead_beat=False,
    )
    diverging = simulate_mca2(
        robot,
        scara_configuration(1.0, -0.037, -50, 1),
        scara_configuration(0.95, -0.06, -50, 1),
        dead_beat=False,
    )
    return converging, diverging


# ---------------------------------------------------------------------- the table
ROUNDING = 1e-12
"""A deviation under this is rounding: its digits depend on the machine's BLAS and libm, so
the tables print it as "< 1e-12" (the tests hold the claims to their own tolerances)."""


def _deviation(value: float) -> str:
    return f"< {ROUNDING:g}" if abs(value) < ROUNDING else f"{value:.1e}"


def _yes(flag: bool) -> str:
    return "yes" if flag else "no"


def _outcome(simulation: Simulation) -> str:
    if simulation.converged:
        return "converges"
    return f"diverges ({simulation.reason.split(':')[0]}, error ×{simulation.error_growth:.1f})"


def _fig6b_row(servo_run: Simulation) -> Result:
    """S&K Fig. 6(b): the servo's run and its step continued past the stop rules."""
    free, held = fig6b_continued()
    total, total_free = servo_run.total_error, free.total_error
    stop = len(total) - 1
    below_zero = int(np.argmax(free.q[:, 1] < 0)) if (free.q[:, 1] < 0).any() else -1
    turn1, turn3 = (
        abs(math.degrees(math.remainder(float(offset), 2 * math.pi)))
        for offset in free.q[-1, [0, 2]] - fig6_poses("b")[1][[0, 2]]
    )
    return Result(
        "S&K Fig. 6(b)",
        "polar, MCA2: λ -1.5 (start) -> -0.9 (target), |λ| > 1 at the start: "
        '"the convergence condition is not fulfilled and the trajectory diverges"',
        f"dead-beat sensor, λ {servo_run.start_lambda:.2f} -> {servo_run.target_lambda:.2f}: the servo stops at "
        f"step {stop} (diverging: error ×{total[-1] / total[0]:.1f} its start, ×{total[-1] / total.min():.1f} its "
        f"best). Its step iterated on, no stop rule: without joint limits the error grows to "
        f"×{total_free.max() / total_free[0]:.1f} at step {int(np.argmax(total_free))}, G's pole d2 + l C3 = 0 is "
        f"crossed {polar_pole_crossings(free.q)} times, d2 < 0 from step {below_zero}, and it "
        f"{'converges' if free.converged else 'does not converge'} in {free.steps} steps on the mirror branch "
        f"d2 = {free.q[-1, 1]:.3f} m (theta1 {turn1:.0f}°, theta3 {turn3:.0f}° from the target's: the target pose, "
        f"outside the stroke 0.05-1 m); with the URDF's limits held it ends at d2 = {held.q[-1, 1]:.2f} m, theta3 = "
        f"{math.degrees(held.q[-1, 2]):.0f}°, {held.position_error[-1]:.3f} m and {held.orientation_error[-1]:.2f} "
        f"rad from the target after {held.steps} steps. On the robot the paper's outcome holds; |λ| > 1 at the "
        "start alone does not make the iteration diverge (the Theorem's condition is sufficient only)",
        "papers/test_worked_examples.py::test_fig_6b_continued",
    )


def _barker_arm_rows() -> list[Result]:
    """Barker eq. 25-44 against pinrate's step (:mod:`pinrate.papers.barker`)."""
    test = "papers/test_barker.py::"
    extended, extended_along = barker.singular_case(0), barker.singular_case(0, barker.ALONG_THE_ARM)
    least_radius = barker.singular_case(1)
    condition, _, reduction_error = barker.reduction_at_theta1_zero()
    reference_tvel = ", ".join(f"{value:g}" for value in barker.REFERENCE_TVEL)
    return [
        Result(
            "Barker eq. 25-31",
            "TVEL^ = M [theta1 theta2 theta3]', M from F1..F5; F2 = SN~ + CAL3 WE with SN~ = SN + R3 "
            "(the OCR drops the tilde, eq. C19)",
            f"R_hand A (the robot's arm block in base axes) vs M: max deviation {_deviation(barker.m_deviation())} m "
            f"(nominal), {_deviation(barker.m_deviation(alpha3=1.4, a3=0.05, r3=0.03))} "
            f"(alpha3 = 1.4, a3 = 0.05, r3 = 0.03)",
            test + "test_m_eq_25_31",
        ),
        Result(
            "Barker eq. 34-37",
            "closed-form arm rates for det M != 0 (as printed, eq. 35 has the wrong overall sign and "
            "eq. 36 the wrong sign of TVEL(2) F6; eq. 34 is (C1 TVEL(2) - S1 TVEL(1)) / F1)",
            f"MCA1 and MCA2 steps vs eq. 34-37 with the signs derived: max relative deviation "
            f"{_deviation(max(barker.arm_rates_deviation(), barker.arm_rates_deviation(alpha3=1.4, a3=0.05, r3=0.03)))}"
            f" (nominal and alpha3 = 1.4, a3 = 0.05, r3 = 0.03); the printed eq. 35-36 are off by up to "
            f"{barker.printed_arm_rates_error():.1f}× the largest rate",
            test + "test_arm_rates_eq_34_37",
        ),
        Result(
            "Barker eq. 38",
            "near det M = 0: the generalized inverse, M* TVEL^",
            f"singularity=generalized_inverse at theta3 = 0 and at S2 ES + F5 = 0, commands with and without "
            f"a component along the arm, MCA1 and MCA2: step vs M* TVEL^ (M* cut at singular_threshold), max "
            f"deviation {_deviation(barker.generalized_inverse_deviation())} rad/s",
            test + "test_generalized_inverse_eq_38",
        ),
        Result(
            "Barker eq. 39-44",
            "theta1 by eq. 39 (F2 != 0), (theta2, theta3) = M1* g1: only a 2x2 inverse",
            f"off the singular region, MCA2 step vs reduction: max relative deviation "
            f"{_deviation(barker.reduction_deviation())}; but det M1 = S1 det M: "
            f"at theta1 = 0 (c = {condition:.2f}) M1 is "
            f"singular, M1* drops TVEL(2) and misses TVEL^ = ({reference_tvel}) m/s by {reduction_error:.2f} m/s",
            test + "test_reduction_eq_39_44",
        ),
        Result(
            "Barker eq. 38 vs 39-44, theta3 = 0",
            "M* (eq. 38) and M1* (eq. 44) are both the generalized-inverse solution",
            f"M's null vector (0, F4, -F3) leaves theta1 alone: for TVEL^ in M's range the step and the "
            f"reduction agree within {_deviation(np.abs(extended.step_rates - extended.reduction).max())} rad/s, both "
            f"exact; with {barker.ALONG_THE_ARM} m/s along the arm added they differ: theta1 "
            f"{extended_along.step_rates[0]:.3f} (step) vs {extended_along.reduction[0]:.3f} rad/s, TVEL^ missed "
            f"by {extended_along.step_error:.3f} (the unreachable part, least) vs "
            f"{extended_along.reduction_error:.3f} m/s",
            test + "test_eq_38_and_39_44_at_full_extension",
        ),
        Result(
            "Barker eq. 38 vs 39-44, S2 ES + F5 = 0",
            "M* (eq. 38) and M1* (eq. 44) are both the generalized-inverse solution",
            f"M's null vector (F3, F2, 0) moves theta1: for a feasible TVEL^ both are exact (miss "
            f"{_deviation(least_radius.step_error)}, {_deviation(least_radius.reduction_error)} m/s) "
            "yet differ: the step (M*) "
            f"gives theta1, theta2 = {least_radius.step_rates[0]:.4f}, {least_radius.step_rates[1]:.4f} rad/s, "
            f"the reduction {least_radius.reduction[0]:.4f}, {abs(least_radius.reduction[1]):.4f} "
            "(M1 = [[0, 0], [0, -F5]]); pinrate's generalized_inverse is M*",
            test + "test_eq_38_and_39_44_at_least_radius",
        ),
    ]


def _barker_elbow_row() -> Result:
    """Barker eq. 45-46 against pinrate's auxiliary elbow control (:mod:`pinrate.control.elbow`)."""
    elbow, shoulder = barker.auxiliary_elbow_deviation()
    bends = ", ".join(f"{bend:+.2f}" for bend in barker.elbow_bends())
    return Result(
        "Barker eq. 45-46",
        "near theta3 = 0: theta3 = K3 (TVEL)_X2, 0 for an outward command at theta3 = 0; "
        "theta2 = -WE/(WE+ES) theta3 + K2 (TVEL)_Y2/(WE+ES); the sign of K3 changed at each entry "
        "(X2, Y2 are rows of R_2^1 R_1^0; the OCR's B28-B29 misplace a bracket and flip a sign, next row)",
        f"singularity=auxiliary_elbow at theta3 = 0, 18 commands along X2 and Y2 on 3 arm poses, K2 = 1: "
        f"max relative deviation {_deviation(elbow)} (theta3, eq. 45) and {_deviation(shoulder)} (theta2, eq. 46); "
        f"theta3 after three retractions from full extension: {bends} rad",
        "papers/test_barker.py::test_auxiliary_elbow_eq_45_46",
    )


def _barker_appendix_b_rows() -> tuple[Result, Result]:
    """Barker eq. B1-B24 and B27-B29 against the robot (:mod:`pinrate.papers.barker`)."""
    test = "papers/test_barker.py::"
    derived, printed, b4 = barker.hand_to_base_errors()
    derived_off, printed_off, b4_off = barker.hand_to_base_errors(alpha3=1.4, a3=0.05, r3=0.03)
    components, as_printed, bracket_only = barker.upper_arm_component_errors()
    hand = Result(
        "Barker eq. B1-B24",
        "TVEL^ = L TVEL, RVEL^ = L RVEL, L = R_0^6 from P1, P2, Q1..Q4, T1..T4 (B6-B24); B11 prints "
        "P2 = -S23 CAL3: it is -S23 (R_1^2 R_2^3 of eq. A2-A3 has first column (-C23, -S23, 0))",
        f"L with P2 = -S23 vs the robot's hand rotation: max deviation {_deviation(derived)} (nominal), "
        f"{_deviation(derived_off)} (alpha3 = 1.4, a3 = 0.05, r3 = 0.03); with the printed P2, L is off by up to "
        f"{printed:.2f} (nominal) and {printed_off:.2f} (alpha3 = 1.4), B4 by up to {b4:.2f} and {b4_off:.2f} per "
        "entry (max |S23| (1 - CAL3))",
        test + "test_hand_to_base_b1_b24",
    )
    upper_arm = Result(
        "Barker eq. B27-B29",
        "(TVEL)_X2, (TVEL)_Y2 = rows 1-2 of R_2^1 R_1^0 TVEL^ (B27); B28-B29 print S2[C1 TVEL(1) - S1 TVEL(2) "
        "+ C2 TVEL(3)] and C2[C1 TVEL(1) - S1 TVEL(2) - S2 TVEL(3)]: the bracket closes after TVEL(2) and "
        "S1 TVEL(2) has sign + (rows (S2 C1, S2 S1, C2), (C2 C1, C2 S1, -S2))",
        f"derived B28-B29 vs TVEL^ along the robot's X2 (shoulder to elbow) and Y2 = z1 x X2, unit TVEL^: max "
        f"deviation {_deviation(components)} m/s; as printed off by up to {as_printed:.2f} m/s, with only the "
        f"bracket mended {bracket_only:.2f} m/s",
        test + "test_upper_arm_components_b27_b29",
    )
    return hand, upper_arm


def _barker_wrist_rows() -> list[Result]:
    """Barker eq. 57-63 against pinrate's step (:mod:`pinrate.papers.barker`)."""
    test = "papers/test_barker.py::"
    off, at_zero = barker.wrist_generalized_inverse_deviation()
    region_step, region_closed_form = barker.wrist_region_rates()
    rules = barker.wrist_rule_deviations()
    return [
        Result(
            "Barker eq. 57-60",
            "(theta4, theta6) = M2* g2, M2 = [[0, S5], [1, C5]]; at theta5 = 0 M2* splits theta4 + theta6 equally",
            f"MCA2 wrist rates vs eq. 49, 60: max relative deviation {_deviation(off)} off theta5 = 0; at theta5 = 0 "
            f"(wrist=split) {_deviation(at_zero)} rad/s; inside the wrist region off 0 split keeps theta4 = theta6 "
            f"(theta5 = 0.02: {region_step[0]:.2f}, {region_step[2]:.2f} rad/s) where M2^-1 gives "
            f"{region_closed_form[0]:.1f}, {region_closed_form[2]:.1f} rad/s",
            test + "test_wrist_eq_57_60",
        ),
        Result(
            "Barker eq. 61-63",
            "theta5 = 0: theta4 + theta6 = SAL3 D3 - CAL3 D2 shared equally (61), theta4 = 0 (62), "
            "theta6 at its limit and theta4 takes it (63)",
            f"MCA2 step vs the rule, max deviation: split {_deviation(rules['split'])}, "
            f"hold_first {_deviation(rules['hold_first'])}, "
            f"last_then_first {_deviation(rules['last_then_first'])} rad/s",
            test + "test_wrist_rules_eq_61_63",
        ),
    ]


def results() -> list[Result]:
    """Recompute every row (a few seconds)."""
    rows = [
        Result(
            "S&K eq. 10 (Fig. 1)",
            "J = [[l1 S2, 0], [l2 + l1 C2, l2]] in the sensor frame",
            f"max deviation {_deviation(two_link_deviation())} over 200 random q",
            "papers/test_worked_examples.py::test_two_link_eq_10",
        ),
        Result(
            "S&K eq. 13",
            "cylindrical: J = diag(d3, 1, 1)",
            f"max deviation {_deviation(cylindrical_deviation())}",
            "papers/test_worked_examples.py::test_cylindrical_eq_13",
        ),
        Result(
            "S&K eq. 16 (Fig. 2)",
            "spherical: J = diag(d3 C2, d3, 1)",
            f"max deviation {_deviation(spherical_deviation())}",
            "papers/test_worked_examples.py::test_spherical_eq_16",
        ),
    ]
    independence = first_joint_independent()
    rows.append(
        Result(
            "S&K §2",
            "J in the sensor frame does not depend on theta1 (its encoder can go)",
            "independent: " + ", ".join(f"{k} {_yes(v)}" for k, v in independence.items()),
            "papers/test_worked_examples.py::test_first_joint_independent",
        )
    )
    diagonal = diagonal_arms()
    rows.append(
        Result(
            "S&K §2",
            "J diagonal iff the joints move the end orthogonally: Cartesian, cylindrical, "
            "spherical yes; SCARA, articulated no",
            "one entry per row and column: " + ", ".join(f"{k} {_yes(v)}" for k, v in diagonal.items()),
            "papers/test_worked_examples.py::test_diagonal_arms",
        )
    )
    barker_centre = robots.barker_arm()
    rows.append(
        Result(
            "S&K eq. 22",
            "B = 0 iff the wrist axes meet at the TCP; then MCA2 is exact",
            f"max |B|: Barker wrist centre {_deviation(max_abs_B(barker_centre))}, Cartesian "
            f"{_deviation(max_abs_B(robots.cartesian()))}, "
            f"Barker hand {max_abs_B(robots.barker_arm(tip='hand')):.2f}; "
            f"max |mca2 - exact| at the wrist centre {_deviation(mca2_minus_exact(barker_centre))}",
            "papers/test_worked_examples.py::test_eq_22_B_zero_iff_wrist_meets_tcp",
        )
    )
    rows.append(
        Result(
            "S&K eq. 56",
            "polar: G = l C3 / (d2 + l C3)",
            f"max deviation {_deviation(polar_G_deviation())}",
            "theorem/test_convergence.py::test_planar_polar_G_is_eq_56",
        )
    )
    rows.append(
        Result(
            "S&K eq. 58, Fig. 5",
            "polar converges iff C3 > -d2 / (2 l)",
            f"ρ < 1 agrees with eq. 58 on {100 * polar_boundary_agreement():.2f} % of 5000 samples",
            "papers/test_worked_examples.py::test_polar_boundary",
        )
    )
    rows.append(
        Result(
            "S&K §5.1 rule",
            "d2 / l > 2 ⇒ converges in the whole work volume",
            f"smallest d2_min with worst ρ < 1: {polar_rule():.4f} m = {polar_rule() / 0.2:.3f} l",
            "papers/test_worked_examples.py::test_polar_rule",
        )
    )
    rows.append(
        Result(
            "S&K eq. 60",
            "SCARA: G = l3 S23 / (l2 S2 + l3 S23)",
            f"max relative deviation {_deviation(scara_G_deviation())}",
            "theorem/test_convergence.py::test_scara_G_is_eq_60",
        )
    )
    rows.append(
        Result(
            "S&K eq. 63, Fig. 8",
            "SCARA converges iff S23 / S2 > -l2 / (2 l3)",
            f"ρ < 1 agrees with eq. 63 on {100 * scara_boundary_agreement():.2f} % of 5000 samples",
            "papers/test_worked_examples.py::test_scara_boundary",
        )
    )
    rows.append(
        Result(
            "S&K §5.2, Fig. 10",
            "Hirata ARH-300 (l2 = 275 mm, 25° < theta2 < 145°): l3 < 60 mm "
            f"(exactly l2 sin 25° / 2 = {1000 * HIRATA_CLOSED_FORM:.2f} mm)",
            f"largest l3 with worst ρ < 1 (bisection, 121² grid): {1000 * hirata_rule():.2f} mm",
            "papers/test_worked_examples.py::test_hirata_rule",
        )
    )
    jacobian_deviation, eigen_deviation = spherical_6dof_deviations()
    rows.append(
        Result(
            "S&K eq. 70-71",
            "six-DOF spherical J and G (eq. 70 column 2 misprinted)",
            f"J vs corrected eq. 70: {_deviation(jacobian_deviation)}; eigenvalues of G vs "
            f"0, l C5/(d3 + l C5), l K/(d3 C2 + l K): {_deviation(eigen_deviation)}",
            "papers/test_worked_examples.py::test_spherical_6dof_jacobian_and_eigenvalues",
        )
    )
    printed_others, printed_33, corrected_33 = printed_eq71_errors()
    rows.append(
        Result(
            "S&K eq. 71",
            "G = (l / det A)[...] from the printed eq. 70; entry (3, 3) printed d3 S2 C4 S5 + l S2 C4 S5 C5",
            f"U A^-1 B W^-1 of the printed eq. 70 (column 2 (0, d3 - l C5, -l C4 S5)) vs eq. 71, 300 random q, "
            f"relative: entries other than (3, 3) {_deviation(printed_others)}; (3, 3) as printed "
            f"off by up to {printed_33:.2f}, with the d3 term's sign changed (-d3 S2 C4 S5 + l S2 C4 S5 C5) "
            f"{_deviation(corrected_33)}",
            "papers/test_worked_examples.py::test_printed_eq_71",
        )
    )
    volume = spherical_6dof_work_volume()
    rows.append(
        Result(
            "S&K eq. 72-73, Fig. 12",
            "-90° < theta5 < 90°, d3 > 2 l: eq. 72 (C2 C5 - S2 C4 S5 > 0) gives convergence always (any theta4) "
            "within at least 50 % of the work volume; much more when C4 does not take both ±1",
            f"{volume.samples} samples uniform in the joint limits ((theta2, theta5) in (-90°, 90°)²): eq. 72 holds "
            f"for every theta4 (at C4 = ±1) on {100 * volume.every_theta4:.2f} % (exactly 1/2: "
            f"|theta2| + |theta5| < 90°; binomial SE {100 * math.sqrt(0.25 / volume.samples):.2f} %), at theta4 = 0 "
            f"on {100 * volume.theta4_zero:.2f} % (exactly 3/4); pinrate's ρ < 1 wherever it holds for every "
            f"theta4 (at theta4 = 0°, 180° and the sample's): {_yes(volume.sufficient)}",
            "papers/test_worked_examples.py::test_spherical_6dof_work_volume",
        )
    )
    rows.append(
        Result(
            "Barker eq. D9",
            "det M = (S2 ES + F5)(SAL3 WE S3 + A3 C3) ES, F5 = S23 SAL3 WE + C23 A3",
            f"max relative deviation {_deviation(barker_det_deviation())} (nominal), "
            f"{_deviation(barker_det_deviation(alpha3=1.4, a3=0.05, r3=0.03))} (alpha3 = 1.4, a3 = 0.05, r3 = 0.03)",
            "papers/test_worked_examples.py::test_barker_determinant",
        )
    )
    extended, folded = barker_singular_configurations()
    rows.append(
        Result(
            "Barker eq. 32-33",
            "singular when S2 ES + F5 = 0 or SAL3 WE S3 + A3 C3 = 0",
            f"MCA2 reports A singular at theta3 = 0: {_yes(barker_singular(extended))}; "
            f"at S2 ES + S23 WE = 0: {_yes(barker_singular(folded))}",
            "papers/test_worked_examples.py::test_barker_singularities",
        )
    )
    rows.extend(_barker_arm_rows())
    hand_row, upper_arm_row = _barker_appendix_b_rows()
    rows.append(_barker_elbow_row())
    rows.append(upper_arm_row)
    rows.append(hand_row)
    rows.append(
        Result(
            "Barker eq. 49-51",
            "theta5 = -C4 D5 - S4 D4, S5 theta6 = -S4 D5 + C4 D4, theta4 + C5 theta6 = SAL3 D3 - CAL3 D2, "
            "D1..D5 of eq. 52-56 from RVEL~ (eq. 48)",
            "pinrate's MCA2 rates for 200 random q and hand-axes twists, put into eq. 49-51 with RVEL^ = L RVEL "
            "(eq. B1) and RVEL~ from their arm rates: max residual / max(1, |rates|) "
            f"{_deviation(barker_wrist_deviation())} rad/s (nominal), "
            f"{_deviation(barker_wrist_deviation(alpha3=1.4, a3=0.05, r3=0.03))} (alpha3 = 1.4, a3 = 0.05, r3 = 0.03)",
            "papers/test_worked_examples.py::test_barker_wrist_rates",
        )
    )
    rows.extend(_barker_wrist_rows())
    polar_a, polar_b = fig6()
    rows.append(
        Result(
            "S&K Fig. 6(a)",
            "polar, MCA2: λ 0.50 -> 0.45, converges",
            f"dead-beat sensor, λ {polar_a.start_lambda:.2f} -> {polar_a.target_lambda:.2f}: "
            f"{_outcome(polar_a)} (poses built for the printed λ: the printed poses give other λ)",
            "papers/test_worked_examples.py::test_fig_6",
        )
    )
    rows.append(_fig6b_row(polar_b))
    scara_a, scara_b = fig9()
    rows.append(
        Result(
            "S&K Fig. 9(a)",
            "SCARA, MCA2: λ 0.695 -> 0.718, converges",
            f"printed poses, λ {scara_a.start_lambda:.3f} -> {scara_a.target_lambda:.3f}: {_outcome(scara_a)}",
            "papers/test_worked_examples.py::test_fig_9",
        )
    )
    rows.append(
        Result(
            "S&K Fig. 9(b)",
            "SCARA, MCA2: λ 1.62 -> 1.70, diverges",
            f"printed poses, λ {scara_b.start_lambda:.3f} -> {scara_b.target_lambda:.4g} (the target "
            f"sits next to G's pole; 1.62 is reached at -49.75°): "
            f"the error grows ×{scara_b.error_growth:.2f} "
            f"while λ > 1, until the servo crosses the elbow singularity theta2 = 0 and "
            f"{'converges' if scara_b.converged else 'stops'} on the other elbow branch "
            f"(λ {scara_b.final_lambda:.2f})",
            "papers/test_worked_examples.py::test_fig_9",
        )
    )
    return rows


def markdown(rows: list[Result]) -> str:
    """docs/paper-results.md: the intro and one table row per result."""
    if not isinstance(rows, list | tuple) or not all(isinstance(row, Result) for row in rows):
        raise InputError("markdown takes the list of Result rows that results() returns")
    lines = [
        "# The papers' results, reproduced by pinrate",
        "",
        "Generated by `pinrate paper` (`pinrate.papers`); `tests/papers/test_worked_examples.py` recomputes",
        "this file and fails when it differs. Every value is computed on the papers' robots of",
        "`pinrate.robots` (URDFs in `urdf/`); every test compares against a closed form derived by hand.",
        "Misprints of the OCR'd papers, and how each was settled, are listed in the docstrings of",
        "`pinrate/papers/worked_examples.py` and, for Barker's controller, `pinrate/papers/barker.py`.",
        "",
        "| result | the paper | pinrate | test |",
        "|---|---|---|---|",
    ]
    for row in rows:
        cells = (cell.replace("|", "\\|") for cell in (row.reference, row.paper, row.pinrate))
        lines.append("| {} | {} | {} | `{}` |".format(*cells, row.test))
    return "\n".join(lines) + "\n"
