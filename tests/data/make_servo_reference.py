"""Write tests/data/servo_reference.npz: servo runs of the release before the layered layout.

Run once, on release f983e6a (0.1.0, the flat layout), as
``PYTHONPATH=<checkout of f983e6a>/src python tests/data/make_servo_reference.py``.
``tests/control/test_servo_reference.py`` requires today's servo to reproduce every run:
bit for bit where the step is pure Python floats and Pinocchio (the closed-form MCA and
Schur kernels), to 1e-12 where numpy's LAPACK takes part (exact, dls, non-square blocks).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

import pinrate
from pinrate import paper_results
from pinrate.kinematics.targets import nearby_target

RUNS: dict[str, dict] = {}


def demo(robot_name: str, algorithm: str, seed: int) -> None:
    robot = pinrate.load(robot_name)
    partition = pinrate.Partition.auto(robot)
    _, target = nearby_target(robot, partition, seed)
    RUNS[f"demo-{robot_name}-{algorithm}-{seed}"] = {
        "robot": robot_name,
        "q0": robot.home(),
        "target": target,
        "algorithm": algorithm,
        "settings": {},
        "trajectory": pinrate.servo(robot, robot.home(), target, algorithm=algorithm, partition=partition),
    }


def paper(name: str, robot_name: str, q0: np.ndarray, q_target: np.ndarray, dead_beat: bool) -> None:
    robot = pinrate.load(robot_name)
    settings = (
        {"gain": 100.0, "max_linear_speed": math.inf, "max_angular_speed": math.inf, "max_steps": 500}
        if dead_beat
        else {"max_steps": 5000}
    )
    target = robot.pose(q_target)
    RUNS[name] = {
        "robot": robot_name,
        "q0": q0,
        "target": target,
        "algorithm": "mca2",
        "settings": {"dt": 0.01, "tol": 1e-6, **settings},
        "trajectory": pinrate.servo(robot, q0, target, algorithm="mca2", dt=0.01, tol=1e-6, **settings),
    }


def main() -> None:
    for seed in (0, 1, 2):
        demo("ur5", "mca1", seed)
    for algorithm in ("exact", "schur", "mca2", "mca3", "dls"):
        demo("ur5", algorithm, 0)
    demo("panda", "mca1", 0)
    demo("scara", "mca1", 0)
    demo("barker_arm", "mca2", 0)
    pose = paper_results.polar_pose_with_lambda
    paper("fig6a", "planar_polar", pose(0.50, 0, 60), pose(0.45, 20, 40), True)
    paper("fig6b", "planar_polar", pose(-1.5, 0, 150), pose(-0.9, 20, 130), True)
    ik = paper_results.scara_configuration
    paper("fig9a", "scara", ik(1.10, 0.155, -21.3, -1), ik(1.116, 0.124, -21.3, -1), False)
    paper("fig9b", "scara", ik(1.0, -0.037, -50, 1), ik(0.95, -0.06, -50, 1), False)

    arrays: dict[str, np.ndarray] = {}
    for name, run in RUNS.items():
        trajectory = run["trajectory"]
        arrays[f"{name}/robot"] = np.array(run["robot"])
        arrays[f"{name}/algorithm"] = np.array(run["algorithm"])
        arrays[f"{name}/settings"] = np.array(repr(run["settings"]))
        arrays[f"{name}/q0"] = run["q0"]
        arrays[f"{name}/target"] = run["target"]
        for field in ("q", "joint_rates", "position_error", "orientation_error", "spectral_radius"):
            arrays[f"{name}/{field}"] = getattr(trajectory, field)
        arrays[f"{name}/status"] = np.array(trajectory.status)
        arrays[f"{name}/reason"] = np.array(trajectory.reason)
        print(f"{name}: {trajectory.steps} steps, {trajectory.reason}")
    np.savez_compressed(Path(__file__).with_name("servo_reference.npz"), **arrays)


if __name__ == "__main__":
    main()
