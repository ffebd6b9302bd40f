"""Netlist text of the test networks used by several test files and benchmarks.

Written once here so that a test and the benchmark measuring the same network
read the same circuit.
"""

from __future__ import annotations

import numpy as np


def grid_text(n: int, k: float = 1e4, m: float = 1.0) -> str:
    """Uniform n×n spring–mass grid: masses ``m`` and springs ``k`` to the frame at
    every node, springs ``k`` between neighbours, driven at the corner g0_0."""
    lines = ["drive V g0_0 0 velocity=1"]
    for i in range(n):
        for j in range(n):
            g = f"g{i}_{j}"
            lines += [f"mass m{i}_{j} {g} 0 {m}", f"spring f{i}_{j} {g} 0 {k}"]
            if i + 1 < n:
                lines.append(f"spring h{i}_{j} {g} g{i + 1}_{j} {k}")
            if j + 1 < n:
                lines.append(f"spring v{i}_{j} {g} g{i}_{j + 1} {k}")
    return "\n".join(lines)


def damped_ladder_lines(n_el: int, seed: int = 0, r: float = 1e-3) -> list[str]:
    """The lightly damped ladder of ``n_el`` elements: k in [1e4, 2e4] N/m in series,
    m in [0.2, 1.2] kg and a damper r to the frame at each inner node (random, seeded)."""
    rng = np.random.default_rng(seed)
    lines = ["drive V n0 0 velocity=1"]
    i = node = 0
    while i < n_el:
        lines.append(f"spring k{i} n{node} n{node + 1} {rng.uniform(1e4, 2e4)!r}")
        i += 1
        if i < n_el:
            lines.append(f"mass m{i} n{node + 1} 0 {rng.uniform(0.2, 1.2)!r}")
            i += 1
        if i < n_el:
            lines.append(f"damper c{i} n{node + 1} 0 {r!r}")
            i += 1
        node += 1
    return lines
