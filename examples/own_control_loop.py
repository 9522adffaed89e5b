"""Call pinrate from your own control loop: a sensor hands you a twist, you send joint rates.

Here a fake "sensor" asks the panda's hand to move along its own x axis while turning
about its z axis; MCA1 turns that into rates of the 4 + 3 arm/wrist partition.
"""

import numpy as np

import pinrate

robot = pinrate.load("panda")
partition = pinrate.Partition.auto(robot)  # 4 arm joints, 3 wrist joints, fingers left out
q = robot.home()
dt = 0.01
twist = np.array([0.05, 0.0, 0.0, 0.0, 0.0, 0.2])  # m/s and rad/s in the hand's axes

start = robot.pose(q)
for _ in range(100):
    rates = pinrate.joint_rates(robot, q, twist, algorithm="mca1", partition=partition)
    q = robot.integrate(q, rates, dt)
end = robot.pose(q)

moved = start[:3, :3].T @ (end[:3, 3] - start[:3, 3])  # displacement in the start hand frame
print(
    f"after 1 s the hand moved {np.array2string(moved, precision=4)} m in its own axes "
    "(asked: 0.05 along x, plus the small drift of a turning frame)"
)
print(f"spectral radius here: {pinrate.convergence(robot, q, partition=partition).spectral_radius:.3f}")
