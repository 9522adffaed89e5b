"""Close the loop on physics: the controller drives a MuJoCo simulation of the UR5.

Each step the controller reads the configuration the simulation measured (Shoham & Koren's
Fig. 3), never its own integration; the trajectory's plant record says what the simulated
drives did beside the commands. Needs ``pip install "pinrate[mujoco]"``.
"""

import numpy as np

import pinrate
from pinrate.plants import MujocoPlant

robot = pinrate.load("ur5")
q = robot.home()
target = robot.pose(q)
target[:3, 3] += [0.10, -0.05, 0.05]  # 122 mm away, in the world frame

kinematic = pinrate.servo(robot, q, target, algorithm="exact", gain=2.0, velocity_limits=None)
for actuator in ("velocity", "position"):
    plant = MujocoPlant(robot, actuator=actuator)
    simulated = pinrate.servo(robot, q, target, algorithm="exact", gain=2.0, velocity_limits=None, plant=plant)
    record = simulated.plant
    steps = min(len(kinematic.q), len(simulated.q))
    pairs = zip(kinematic.q[:steps], simulated.q[:steps], strict=True)
    apart = max(np.linalg.norm(robot.pose(a)[:3, 3] - robot.pose(b)[:3, 3]) for a, b in pairs)
    print(f"{plant.name}: {simulated.reason}")
    print(
        f"  tip tracking error {record.tracking_error.max() * 1e3:.3f} mm at most; the tip's path within "
        f"{apart * 1e3:.3f} mm of the kinematic run's ({kinematic.reason})"
    )
