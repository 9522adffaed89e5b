"""Servo a UR5's tool to a pose with MCA1 and watch the Theorem's spectral radius on the way."""

import numpy as np
import pinocchio as pin

import pinrate

robot = pinrate.load("ur5")  # tip tool0, sensor at the tip
home = robot.home()
offset = pin.SE3(pin.rpy.rpyToMatrix(0.2, -0.1, 0.3), np.array([0.05, -0.1, 0.08]))  # in the tool frame
target = robot.pose(home) @ offset.homogeneous

trajectory = pinrate.servo(robot, home, target, algorithm="mca1")
print(pinrate.Partition.auto(robot))
print(
    f"{trajectory.reason}; final errors {trajectory.position_error[-1]:.2e} m, "
    f"{trajectory.orientation_error[-1]:.2e} rad"
)
print(
    f"spectral radius along the path: {trajectory.spectral_radius.min():.3f} .. "
    f"{trajectory.spectral_radius.max():.3f} (< 1 at every step: the Theorem's test passes pointwise; "
    "it is not a guarantee along a path, see docs/choices.md)"
)
