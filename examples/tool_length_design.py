"""Designer's question: up to which tool length do the cheap algorithms converge everywhere?

The Hirata ARH-300 SCARA (Shoham & Koren §5.2): l2 = 0.275 m, 25° <= theta2 <= 145°. The
paper's rule: l3 < l2 sin(25°) / 2 = 58.1 mm ("l3 < 60 mm"). Here the work-volume fraction
where rho(G) < 1 is sampled for a few tool lengths.
"""

import math

import pinrate

for tool_mm in (40, 55, 60, 80, 120, 200):
    robot = pinrate.robots.hirata_arh300(l3=tool_mm / 1000)
    sample = pinrate.sample_convergence(robot, 20000, rng=0)
    low, high = sample.interval
    print(
        f"l3 = {tool_mm:3d} mm: rho < 1 on {100 * sample.fraction:6.2f} % of the work volume "
        f"(95 % CI {100 * low:.2f} .. {100 * high:.2f} %), worst rho {sample.spectral_radius.max():.3f}"
    )
print(f"paper's rule: l3 < l2 sin 25° / 2 = {1000 * 0.275 * math.sin(math.radians(25)) / 2:.1f} mm")
