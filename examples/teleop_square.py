"""Barker's operator without a browser: a scripted hand drives a UR5's tool around a square
in its own axes with pinrate.Teleop, then reverses the whole motion back to the start.

Run: python examples/teleop_square.py
"""

from __future__ import annotations

import numpy as np

import pinrate

DT = 0.002  # 500 Hz, the console's default
SIDE_SECONDS = 1.0  # each side: full deflection for one second at 0.1 m/s -> 10 cm

robot = pinrate.load("ur5")
teleop = pinrate.Teleop(robot, max_linear_speed=0.1, dt=DT)
start = teleop.q.copy()
hand_axes = robot.frame_pose(start, robot.sensor)[:3, :3]  # the sensor's axes in the world
corner = robot.pose(start)[:3, 3]
now = 0.0
print("side  deflection (hand axes)  travel in hand axes (m)")
for side, deflection in enumerate(([1, 0, 0], [0, 1, 0], [-1, 0, 0], [0, -1, 0]), start=1):
    for _ in range(round(SIDE_SECONDS / DT)):
        teleop.command(deflection, [0, 0, 0], now=now)  # a stick held: the heartbeat refreshes it
        now += DT
        step = teleop.tick(now)
    teleop.command([0, 0, 0], [0, 0, 0], now=now)  # stick released
    reached = robot.pose(teleop.q)[:3, 3]
    travel = np.array2string(hand_axes.T @ (reached - corner), precision=4, suppress_small=True)
    print(f"{side}     {deflection!s:22}  {travel}  {step.status.value}")
    corner = reached
print(f"square closed to {np.linalg.norm(robot.pose(teleop.q)[:3, 3] - robot.pose(start)[:3, 3]) * 1e3:.2f} mm")

teleop.reverse(now)
ticks = 0
while teleop.reversing:
    now += DT
    teleop.tick(now)
    ticks += 1
print(f"reversed in {ticks * DT:.2f} s of motion; back at the start to {np.abs(teleop.q - start).max():.1e} rad")
