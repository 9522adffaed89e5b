"""The control step under anything (issue 23): random robots (the catalogue, the papers'
arms, a third-party arm, random URDF trees), random controllers (algorithm, strategy, wrist
rule, dt, velocity and acceleration limits, posture, position limits off), random starts
(home, inside the limits, outside them) and random commands (twists from 1e-300 to 1e6, sign
flips, NaN and past the physical bound, jogs, uncoupled commands, pose goals near and unreachable). The invariants, per
step:

- a start outside the kept position limits, or a NaN or out-of-bound command, is an
  InputError naming it;
  nothing else raises;
- q and the rates are finite; q stays within the kept limits;
- every 1-DOF joint moves by its reported rate × dt (the rates said are the rates applied);
- no rate exceeds its velocity limit;
- a step said OK or TWIST_SATURATED with the exact algorithm makes its twist (to 1e-6 of it,
  and 1e-12 m/s or rad/s).

Seeded and bounded; PINRATE_FUZZ_SCALE runs more.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

import pinrate
from pinrate import Controller, InputError, JointJog, PoseGoal, Status, Uncoupled
from pinrate.checks import PHYSICAL_BOUND
from support import fuzz_count, random_urdf

AL5D = Path(__file__).parent.parent / "data" / "third_party" / "rtb_al5d_robot.urdf"
CATALOGUE = ("ur5", "panda", "kinova", "scara", "spherical_6dof", "barker_arm", "two_link_planar", "al5d")
EPS = np.finfo(float).eps


def robot_for(seed: int, tmp_path: Path) -> pinrate.Robot | None:
    rng = np.random.default_rng(seed)
    if seed % 3 != 2:
        name = CATALOGUE[seed % len(CATALOGUE)]
        if name == "al5d":
            return pinrate.load(AL5D)
        if hasattr(pinrate.robots, name) and name not in ("ur5", "panda", "kinova"):
            return getattr(pinrate.robots, name)()
        return pinrate.load(name)
    path = tmp_path / f"tree{seed}.urdf"
    path.write_text(random_urdf(rng), encoding="utf-8")
    try:
        return pinrate.load(path)
    except pinrate.PinrateError:
        return None


def controller_for(robot: pinrate.Robot, rng: np.random.Generator) -> Controller:
    options: dict[str, object] = {
        "algorithm": str(rng.choice(pinrate.ALGORITHMS)),
        "singularity": str(rng.choice(["decelerate", "generalized_inverse", "freeze", "adaptive_dls"])),
        "wrist": str(rng.choice(["split", "hold_first", "last_then_first"])),
        "dt": float(rng.choice([0.001, 0.01, 0.05])),
        "velocity_limits": [None, 0.5, math.inf][int(rng.integers(3))],
    }
    if rng.random() < 0.3:
        options["acceleration_limits"] = float(rng.choice([1.0, 20.0]))
    if rng.random() < 0.2:
        options["position_limits"] = False
    if rng.random() < 0.2 and robot.nv > 6:
        options["posture"] = "home"
    return Controller(robot, **options)


def command_for(robot: pinrate.Robot, controller: Controller, q: np.ndarray, rng: np.random.Generator) -> object:
    size = controller.index.rows.size
    kind = rng.random()
    if kind < 0.55:
        magnitude = 10.0 ** rng.uniform(-300, 6) if rng.random() < 0.2 else rng.uniform(0.01, 2.0)
        return rng.normal(size=size) * magnitude
    if kind < 0.7:
        joint = str(rng.choice(controller.partition.joints))
        return JointJog({joint: float(rng.normal()) * float(rng.choice([0.1, 1.0, 100.0]))})
    if kind < 0.8 and controller.partition.wrist and controller.index.m:
        return Uncoupled(rng.normal(size=controller.index.m) * 0.2, {controller.partition.wrist[0]: 0.3})
    if kind < 0.9:
        far = robot.pose(robot.random_configuration(rng))
        far[:3, 3] *= float(rng.choice([1.0, 10.0]))  # sometimes out of reach
        return PoseGoal.of(far, gain=float(rng.choice([1.0, 50.0])))
    command = rng.normal(size=size)
    command[int(rng.integers(size))] = math.nan
    return command


def limited(robot: pinrate.Robot) -> list[tuple[str, int, float, float]]:
    rows = []
    for joint in robot.joint_names:
        limits = robot.joint_limits(joint)
        if limits is not None:
            rows.append((joint, robot.model.joints[robot.joint_id(joint)].idx_q, *limits))
    return rows


@pytest.mark.parametrize("seed", range(fuzz_count(24)))
def test_the_step_keeps_its_invariants_under_anything(tmp_path: Path, seed: int) -> None:
    robot = robot_for(seed, tmp_path)
    if robot is None:
        return  # a tree with no arm: the loading fuzz covers it
    rng = np.random.default_rng(seed)
    bounds = limited(robot)
    one_dof = [(joint.idx_q, joint.idx_v) for joint in robot.model.joints[1:] if joint.nq == 1]
    for _ in range(3):
        controller = controller_for(robot, rng)
        start = rng.random()
        q = robot.home() if start < 0.4 else robot.neutral() if start < 0.6 else robot.random_configuration(rng)
        outside = [joint for joint, index, lower, upper in bounds if not lower <= q[index] <= upper]
        for _ in range(60):
            command = command_for(robot, controller, q, rng)
            # NaN, or a component past the physical bound (1e6): refused by name
            nan = isinstance(command, np.ndarray) and not (np.abs(command) <= PHYSICAL_BOUND).all()
            try:
                step = controller.step(q, command)
            except InputError as error:
                assert (outside and controller.position_limits) or nan, f"{error} (seed {seed})"
                assert nan or outside[0] in str(error)
                if outside and controller.position_limits:
                    break
                continue
            assert not (outside and controller.position_limits) and not nan
            assert np.isfinite(step.q).all() and np.isfinite(step.joint_rates).all()
            if controller.position_limits:
                for joint, index, lower, upper in bounds:
                    assert lower <= step.q[index] <= upper, (joint, seed, step.detail)
            for index_q, index_v in one_dof:
                # q + v dt rounds to an ulp of the larger of |q| and |q_next|; so does their difference
                rounding = 4 * EPS * max(1.0, abs(q[index_q]), abs(step.q[index_q])) / controller.dt
                assert abs((step.q[index_q] - q[index_q]) / controller.dt - step.joint_rates[index_v]) <= rounding
            assert np.all(np.abs(step.joint_rates) <= controller.velocity_limits * (1 + 1e-12))
            if controller.algorithm == "exact" and step.status in (Status.OK, Status.TWIST_SATURATED):
                made = robot.jacobian(q)[controller.index.rows] @ step.joint_rates
                # relative 1e-6 (the reach tolerance), plus 1e-12 absolute: a posture task's
                # null-space motion leaves J q̇ off by rounding (~1e-16), whatever the twist
                assert np.linalg.norm(made - step.twist) <= 1e-6 * np.linalg.norm(step.twist) + 1e-12, seed
            q = step.q
