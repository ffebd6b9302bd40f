"""The two-crank six-bar of the FNF warp-knitting machine, by "conditional stop".

Seed: Koshel & Koshel (2014).  The mechanism has six moving links
and eight revolute pairs, so W = 3·6 − 2·8 = 2, with a class-III Assur group
on the ternary link 4.  The paper finds each point's velocity by stopping one
crank at a time and adding the two velocity plans (eq. 6–8):
V_K = V_K(ω1 = 0) + V_K(ω2 = 0).  The OCR keeps no link lengths, so the
geometry in ``examples/fnf_sixbar.toml`` is our own.

This script shows the superposition holding over a full turn, and how close
the velocities are to finite differences of the positions.

Run from the repository root: ``python examples/fnf_sixbar.py``.
"""

import math

import numpy as np

from mechcirc.kinematics import load_linkage


def main() -> None:
    lk = load_linkage("examples/fnf_sixbar.toml")
    print(f"{lk.source}: {len(lk.link_names)} moving links, {lk.revolute_pairs} revolute "
          f"pairs, mobility W = {lk.mobility}, cranks "
          f"{', '.join(f'{c.link} ({c.omega:g} rad/s)' for c in lk.cranks)}")
    for g in lk.assur_groups():
        print(f"  Assur group of class {g.group_class}, order {g.order}: links "
              f"{', '.join(g.links)}" + (f" on base link {g.base}" if g.base else ""))
    thetas = np.radians(np.arange(0.0, 361.0, 5.0))
    states = lk.solve(thetas)
    worst_sum, worst_fd, scale = 0.0, 0.0, 0.0
    h = 1e-5
    for st in states:
        for point, v in st.velocities.items():
            parts = sum(st.contributions[c][point] for c in st.contributions)
            worst_sum = max(worst_sum, float(np.max(np.abs(parts - v))))
            scale = max(scale, float(np.max(np.abs(v))))
    # Finite differences of positions along the motion (central, step h in θ of crank 1).
    w1 = lk.cranks[0].omega
    for th in thetas[::6]:
        a, b, c = lk.solve([th - h, th, th + h])
        for point in b.velocities:
            fd = (c.points[point] - a.points[point]) / (2 * h / w1)
            worst_fd = max(worst_fd, float(np.max(np.abs(fd - b.velocities[point]))))
    print(f"  over {len(thetas)} positions of a full turn of crank 1, largest point velocity "
          f"{scale:.4g} length/s")
    print(f"  |V − (V(ω1 = 0) + V(ω2 = 0))| ≤ {worst_sum:.2e} (superposition, relative "
          f"{worst_sum / scale:.1e})")
    print(f"  |V − finite difference of positions| ≤ {worst_fd:.2e} (relative "
          f"{worst_fd / scale:.1e}, step {h:g} rad: truncation ~h²)")
    st = states[len(states) // 4]
    point = max(st.velocities, key=lambda p: np.hypot(*st.velocities[p]))
    print(f"  at θ = {math.degrees(thetas[len(states) // 4]):.0f}°, point {point}: V = "
          f"{np.round(st.velocities[point], 4)}, contributions "
          + ", ".join(f"{c}: {np.round(st.contributions[c][point], 4)}" for c in st.contributions))


if __name__ == "__main__":
    main()
