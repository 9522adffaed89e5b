"""The resolved-rate algorithms against the paper's error identities (eq. 20-54)."""

from __future__ import annotations

import math

import numpy as np
import pytest

import pinrate
from pinrate import Partition
from pinrate.solvers import reference, singular


def reference_G_H(A, B, U, W):
    """G = U A^-1 B W^-1 and H = B W^-1 U A^-1 straight from eq. 32 and 50 (pinv if not square)."""
    A_inv, W_inv = np.linalg.pinv(A), np.linalg.pinv(W)
    return U @ A_inv @ B @ W_inv, B @ W_inv @ U @ A_inv


def cases():
    """(robot, partition) pairs: square 3+3, a wide 4+3 arm, a 2+1 planar arm, a 3+1 SCARA."""
    yield pinrate.load("ur5"), None
    yield pinrate.load("panda"), None
    yield pinrate.robots.planar_polar(), None
    yield pinrate.robots.scara(), None


CASES = list(cases())
IDS = ["ur5", "panda", "planar_polar", "scara"]
SQUARE_CASES = [case for case, name in zip(CASES, IDS, strict=True) if name != "panda"]
SQUARE_IDS = [name for name in IDS if name != "panda"]


def random_state(robot, partition, seed):
    rng = np.random.default_rng(seed)
    partition = partition or Partition.auto(robot)
    q = robot.sample_configurations(1, rng, joints=partition.joints)[0]
    twist = rng.normal(size=partition.m + partition.k)
    return q, partition, twist


def applied_twist(robot, q, partition, rates):
    """The twist the rates actually produce, J q̇, in partition order."""
    return robot.jacobian(q)[partition.rows()] @ rates


@pytest.mark.parametrize(("robot", "given"), CASES, ids=IDS)
@pytest.mark.parametrize("seed", range(8))
def test_mca1_reproduces_v_and_errs_by_minus_U_qa(robot, given, seed) -> None:
    q, partition, twist = random_state(robot, given, seed)
    m = partition.m
    rates = pinrate.joint_rates(robot, q, twist, algorithm="mca1", partition=partition)
    produced = applied_twist(robot, q, partition, rates)
    A, B, U, W = partition.blocks(robot, robot.jacobian(q))
    arm_rates = rates[[robot.velocity_indices(j)[0] for j in partition.arm]]
    np.testing.assert_allclose(produced[:m], twist[:m], atol=1e-9)  # eq. 28, v' = v
    error = twist[m:] - produced[m:]
    np.testing.assert_allclose(error, -U @ arm_rates, atol=1e-9)  # eq. 30
    G, _ = reference_G_H(A, B, U, W)
    if A.shape[0] == A.shape[1]:  # eq. 31 needs A^-1 A = I
        np.testing.assert_allclose(error, -U @ np.linalg.inv(A) @ twist[:m] + G @ twist[m:], atol=1e-8)


@pytest.mark.parametrize(("robot", "given"), CASES, ids=IDS)
@pytest.mark.parametrize("seed", range(8))
def test_mca2_reproduces_omega_and_errs_by_minus_B_qw(robot, given, seed) -> None:
    q, partition, twist = random_state(robot, given, seed)
    m = partition.m
    rates = pinrate.joint_rates(robot, q, twist, algorithm="mca2", partition=partition)
    produced = applied_twist(robot, q, partition, rates)
    A, B, U, W = partition.blocks(robot, robot.jacobian(q))
    wrist_rates = rates[[robot.velocity_indices(j)[0] for j in partition.wrist]]
    np.testing.assert_allclose(produced[m:], twist[m:], atol=1e-9)  # eq. 47
    error = twist[:m] - produced[:m]
    np.testing.assert_allclose(error, -B @ wrist_rates, atol=1e-9)  # eq. 48
    _, H = reference_G_H(A, B, U, W)
    if A.shape[0] == A.shape[1]:  # eq. 49
        np.testing.assert_allclose(error, H @ twist[:m] - B @ np.linalg.inv(W) @ twist[m:], atol=1e-8)


@pytest.mark.parametrize(("robot", "given"), SQUARE_CASES, ids=SQUARE_IDS)
@pytest.mark.parametrize("seed", range(8))
def test_mca3_errs_by_H_v_and_G_omega(robot, given, seed) -> None:
    # Eq. 53-54 use A A^-1 = I and W W^-1 = I: square blocks only.
    q, partition, twist = random_state(robot, given, seed)
    m = partition.m
    rates = pinrate.joint_rates(robot, q, twist, algorithm="mca3", partition=partition)
    produced = applied_twist(robot, q, partition, rates)
    G, H = reference_G_H(*partition.blocks(robot, robot.jacobian(q)))
    np.testing.assert_allclose(twist[:m] - produced[:m], H @ twist[:m], atol=1e-8)  # eq. 53
    np.testing.assert_allclose(twist[m:] - produced[m:], G @ twist[m:], atol=1e-8)  # eq. 54


@pytest.mark.parametrize(("robot", "given"), CASES, ids=IDS)
@pytest.mark.parametrize("algorithm", ["exact", "schur"])
@pytest.mark.parametrize("seed", range(6))
def test_exact_and_schur_reproduce_the_twist(robot, given, algorithm, seed) -> None:
    q, partition, twist = random_state(robot, given, seed)
    rates = pinrate.joint_rates(robot, q, twist, algorithm=algorithm, partition=partition)
    np.testing.assert_allclose(applied_twist(robot, q, partition, rates), twist, atol=1e-8)


def test_exact_is_minimum_norm_for_a_redundant_arm(panda) -> None:
    q, partition, twist = random_state(panda, None, 3)
    rates = pinrate.joint_rates(panda, q, twist, algorithm="exact")
    reduced = panda.jacobian(q)[partition.rows()][:, :7]
    # Minimum norm: the rates lie in the row space of J (orthogonal to its null space).
    null_space = np.linalg.svd(reduced)[2][6:]
    np.testing.assert_allclose(null_space @ rates[:7], 0.0, atol=1e-9)


def well_conditioned_states(robot, count, threshold=0.05):
    seed = 0
    while count:
        q, _partition, twist = random_state(robot, None, seed)
        seed += 1
        if np.linalg.svd(robot.jacobian(q), compute_uv=False).min() >= threshold:
            count -= 1
            yield q, twist


@pytest.mark.parametrize(("q", "twist"), list(well_conditioned_states(pinrate.load("ur5"), 4)))
def test_dls_approaches_exact_away_from_singularities(ur5, q, twist) -> None:
    jacobian = ur5.jacobian(q)
    exact = pinrate.joint_rates(ur5, q, twist, algorithm="exact")
    damped = pinrate.joint_rates(ur5, q, twist, algorithm="dls")
    # J^T (J J^T + λ² I)^-1 = J^-1 (I + λ² (J J^T)^-1)^-1: relative change O(λ² / σ_min²).
    sigma_min = np.linalg.svd(jacobian, compute_uv=False).min()
    bound = 2 * reference.DLS_DAMPING**2 / sigma_min**2
    assert np.linalg.norm(damped - exact) <= bound * np.linalg.norm(exact) + 1e-12


def test_partition_joints_only(panda) -> None:
    q, _partition, twist = random_state(panda, None, 1)
    for algorithm in pinrate.ALGORITHMS:
        rates = pinrate.joint_rates(panda, q, twist, algorithm=algorithm)
        assert rates.shape == (9,)
        np.testing.assert_array_equal(rates[7:], 0.0)


def test_mca2_is_exact_when_wrist_axes_meet_at_the_tcp() -> None:
    # Eq. 22: B = 0 when the three wrist axes meet at the TCP (Barker's wrist centre).
    robot = pinrate.robots.barker_arm()
    for seed in range(5):
        q, partition, twist = random_state(robot, None, seed)
        _A, B, _U, _W = partition.blocks(robot, robot.jacobian(q))
        np.testing.assert_allclose(B, 0.0, atol=1e-12)
        exact = pinrate.joint_rates(robot, q, twist, algorithm="exact")
        np.testing.assert_allclose(pinrate.joint_rates(robot, q, twist, algorithm="mca2"), exact, rtol=1e-8, atol=1e-8)


def test_mca1_is_exact_on_a_cartesian_arm() -> None:
    # §3: U = 0 only for a Cartesian arm; with B = 0 as well J is block diagonal.
    robot = pinrate.robots.cartesian()
    for seed in range(5):
        q, partition, twist = random_state(robot, None, seed)
        _A, _B, U, _W = partition.blocks(robot, robot.jacobian(q))
        np.testing.assert_allclose(U, 0.0, atol=1e-12)
        exact = pinrate.joint_rates(robot, q, twist, algorithm="exact")
        for algorithm in ("mca1", "mca2", "mca3"):
            np.testing.assert_allclose(
                pinrate.joint_rates(robot, q, twist, algorithm=algorithm), exact, rtol=1e-9, atol=1e-9
            )


# ---------------------------------------------------------------------- singular blocks
def test_singular_A_raises_for_mca_and_exact_falls_back() -> None:
    robot = pinrate.robots.two_link_planar()
    position_only = Partition(["theta1", "theta2"], [], linear="xy", angular="")
    q = np.array([0.3, 0.0])  # stretched out: eq. 10's determinant l1 l2 S2 vanishes
    twist = np.array([0.1, 0.2])
    for algorithm in ("mca1", "mca2", "mca3"):
        with pytest.raises(pinrate.SingularBlockError, match="block A") as error:
            pinrate.joint_rates(robot, q, twist, algorithm=algorithm, partition=position_only)
        assert error.value.block == "A" and "two_link_planar" in str(error.value)
    with pytest.raises(pinrate.SingularBlockError, match="A - B W"):
        pinrate.joint_rates(robot, q, twist, algorithm="schur", partition=position_only)
    for algorithm in ("exact", "dls"):
        rates = pinrate.joint_rates(robot, q, twist, algorithm=algorithm, partition=position_only)
        assert np.isfinite(rates).all()
    # The least-squares fallback realises the reachable part of the command: v_y only.
    rates = pinrate.joint_rates(robot, q, twist, algorithm="exact", partition=position_only)
    np.testing.assert_allclose(robot.jacobian(q)[[0, 1]] @ rates, [0.0, 0.2], atol=1e-12)


def test_nearly_singular_A_raises_rather_than_blowing_up() -> None:
    robot = pinrate.robots.two_link_planar()
    position_only = Partition(["theta1", "theta2"], [], linear="xy", angular="")
    q = np.array([0.0, 1e-12])
    with pytest.raises(pinrate.SingularBlockError):
        pinrate.joint_rates(robot, q, [0.1, 0.2], algorithm="mca1", partition=position_only)


def test_singular_W_is_named() -> None:
    robot = pinrate.load("ur5")
    q = robot.home()
    q[4] = 0.0  # wrist_2 = 0: wrist 1 and wrist 3 axes align, W is singular
    with pytest.raises(pinrate.SingularBlockError, match="block W"):
        pinrate.joint_rates(robot, q, np.ones(6) * 0.1, algorithm="mca2")


def test_hadamard_ratio_closed_forms() -> None:
    assert singular.hadamard_ratio(np.diag([3.0, 0.001, 7.0])) == pytest.approx(1.0)
    assert singular.hadamard_ratio(np.array([[1.0, 1.0], [0.0, 0.0]])) == 0.0
    theta = 0.3
    shear = np.array([[1.0, math.cos(theta)], [0.0, math.sin(theta)]])
    assert singular.hadamard_ratio(shear) == pytest.approx(math.sin(theta))


# ---------------------------------------------------------------------- bad input
def test_twist_of_the_wrong_length(ur5) -> None:
    with pytest.raises(pinrate.InputError, match=r"twist.*\(6,\)"):
        pinrate.joint_rates(ur5, ur5.home(), np.zeros(5))
    polar = pinrate.robots.planar_polar()
    with pytest.raises(pinrate.InputError, match=r"\(3,\)"):
        pinrate.joint_rates(polar, polar.home(), np.zeros(6))


def test_twist_with_nan(ur5) -> None:
    twist = np.zeros(6)
    twist[4] = math.nan
    with pytest.raises(pinrate.InputError, match="NaN"):
        pinrate.joint_rates(ur5, ur5.home(), twist)


def test_q_with_inf(ur5) -> None:
    q = ur5.home()
    q[0] = math.inf
    with pytest.raises(pinrate.InputError, match="shoulder_pan_joint"):
        pinrate.joint_rates(ur5, q, np.zeros(6))


def test_unknown_algorithm(ur5) -> None:
    with pytest.raises(pinrate.InputError, match=r"mca4.*mca1"):
        pinrate.joint_rates(ur5, ur5.home(), np.zeros(6), algorithm="mca4")
