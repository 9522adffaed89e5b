"""The same servo run on both paths: the compiled core and pure Python, side by side.

pinrate picks the compiled core (``pinrate_core``, built by ``make core``) where it is
installed; ``pinrate.compiled.use`` chooses a path for this process. Both give the same
trajectory (bit for bit here: the UR5's sensor is at its tip and MCA1 is a closed form).
"""

import time

import numpy as np

import pinrate
from pinrate.compiled import use

robot = pinrate.load("ur5")
home = robot.home()
target = robot.pose(home)
target[:3, 3] += [0.1, -0.05, 0.05]  # 4x4 pose of the tip in the world
print(f"backend: {pinrate.backend()}")

runs = {}
for path in ("python", "compiled") if pinrate.backend().name == "compiled" else ("python",):
    use(path)
    start = time.perf_counter()
    runs[path] = pinrate.servo(robot, home, target, algorithm="mca1", tol=1e-9, max_steps=4000)
    seconds = time.perf_counter() - start
    trajectory = runs[path]
    per_step = seconds / trajectory.steps * 1e6
    print(f"{path:>8}: {trajectory.reason}, {seconds * 1e3:.1f} ms ({per_step:.2f} µs per step)")
use(None)

if len(runs) == 2:
    python, compiled = runs["python"], runs["compiled"]
    same = np.array_equal(python.q, compiled.q) and python.status == compiled.status
    print(f"the same trajectory on both paths, bit for bit: {same}")
else:
    print(f"only the Python path ran: {pinrate.backend().reason}")
