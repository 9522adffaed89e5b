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
* Fig. 6: the printed polar poses cannot give the printed λ under any reading tried
  (TCP or wrist point, absolute or relative orientation); the simulation is rerun from
  poses built to have the printed λ values.
* Fig. 9(b): at the printed target (0.95, -0.06, -50°) G is next to its pole
  (l2 S2 + l3 S23 = 0) and very sensitive; the printed start λ 1.62 is reached at -49.75°.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from .. import robots
from ..analysis import design
from ..control.servo_loop import servo
from ..errors import InputError, SingularBlockError
from ..kinematics.manipulator import Robot
from ..kinematics.partition import Partition
from ..solvers.rates import joint_rates
from ..theorem import convergence, sample_convergence
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


def spherical_6dof_fractions(count: int = 20000) -> tuple[float, float, bool]:
    """(share with ρ < 1, share with K > 0 (eq. 72), whether every K > 0 sample has ρ < 1)."""
    sample = sample_convergence(robots.spherical_6dof(), count, rng=12)
    q = sample.q
    K = np.cos(q[:, 1]) * np.cos(q[:, 4]) - np.sin(q[:, 1]) * np.cos(q[:, 3]) * np.sin(q[:, 4])
    return sample.fraction, float(np.mean(K > 0)), bool((sample.spectral_radius[K > 0] < 1).all())


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


def barker_wrist_deviation(count: int = 200, **lengths: float) -> float:
    """max residual of eq. 49-51 for pinrate's wrist rates (D1..D5 of eq. 52-56)."""
    robot = robots.barker_arm(**lengths)  # type: ignore[arg-type]  # lengths holds no tip or sensor
    alpha3 = (robots.parameters("barker_arm") | lengths)["alpha3"]
    sal3, cal3 = math.sin(alpha3), math.cos(alpha3)
    generator = np.random.default_rng(9)
    worst = 0.0
    for q in robot.sample_configurations(count, 8):
        rates = joint_rates(robot, q, generator.normal(size=6), algorithm="mca2")
        hand = robot.frame_pose(q, "hand")[:3, :3]
        residual = hand @ (robot.jacobian(q)[3:, 3:] @ rates[3:])  # RVEL~ of eq. 48, base axes
        t1, t2, t3, t4, t5, _ = q
        C1, S1, S23, C23 = math.cos(t1), math.sin(t1), math.sin(t2 + t3), math.cos(t2 + t3)
        C4, S4, C5, S5 = math.cos(t4), math.sin(t4), math.cos(t5), math.sin(t5)
        D1 = C1 * residual[0] + S1 * residual[1]
        D2 = S1 * residual[0] - C1 * residual[1]
        D3 = S23 * D1 + C23 * residual[2]
        D4 = C23 * D1 - S23 * residual[2]
        D5 = cal3 * D3 + sal3 * D2
        worst = max(
            worst,
            abs(rates[4] - (-C4 * D5 - S4 * D4)),
            abs(S5 * rates[5] - (-S4 * D5 + C4 * D4)),
            abs(rates[3] + C5 * rates[5] - (sal3 * D3 - cal3 * D2)),
        )
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
    )


def polar_pose_with_lambda(lam: float, theta1_deg: float, theta3_deg: float, l: float = 0.2) -> np.ndarray:  # noqa: E741
    """The polar configuration with G = lam at the given angles: d2 = l C3 (1 / lam - 1)."""
    c3 = math.cos(math.radians(theta3_deg))
    return np.array([math.radians(theta1_deg), l * c3 * (1 / lam - 1), math.radians(theta3_deg)])


def fig6() -> tuple[Simulation, Simulation]:
    """Fig. 6 rerun from poses with the printed λ: (a) 0.50 -> 0.45, (b) -1.5 -> -0.9."""
    robot = robots.planar_polar()
    converging = simulate_mca2(
        robot, polar_pose_with_lambda(0.50, 0, 60), polar_pose_with_lambda(0.45, 20, 40), dead_beat=True
    )
    diverging = simulate_mca2(
        robot, polar_pose_with_lambda(-1.5, 0, 150), polar_pose_with_lambda(-0.9, 20, 130), dead_beat=True
    )
    return converging, diverging


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
        "(the OCR's B28-B29 misplace a bracket: X2, Y2 are rows of R_2^1 R_1^0)",
        f"singularity=auxiliary_elbow at theta3 = 0, 18 commands along X2 and Y2 on 3 arm poses, K2 = 1: "
        f"max relative deviation {_deviation(elbow)} (theta3, eq. 45) and {_deviation(shoulder)} (theta2, eq. 46); "
        f"theta3 after three retractions from full extension: {bends} rad",
        "papers/test_barker.py::test_auxiliary_elbow_eq_45_46",
    )


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
    fraction, k_fraction, sufficient = spherical_6dof_fractions()
    rows.append(
        Result(
            "S&K eq. 72-73, Fig. 12",
            "converges where C2 C5 - S2 C4 S5 > 0: at least 50 % of the work volume",
            f"ρ < 1 on {100 * fraction:.1f} %; eq. 72 holds on {100 * k_fraction:.1f} %; "
            f"eq. 72 ⇒ ρ < 1 on every sample: {_yes(sufficient)}",
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
    rows.append(_barker_elbow_row())
    rows.append(
        Result(
            "Barker eq. 49-51",
            "wrist rates from D1..D5",
            f"max residual {_deviation(barker_wrist_deviation())}",
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
    rows.append(
        Result(
            "S&K Fig. 6(b)",
            "polar, MCA2: λ -1.5 -> -0.9, diverges",
            f"dead-beat sensor, λ {polar_b.start_lambda:.2f} -> {polar_b.target_lambda:.2f}: {_outcome(polar_b)}",
            "papers/test_worked_examples.py::test_fig_6",
        )
    )
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
