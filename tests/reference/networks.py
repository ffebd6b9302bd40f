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


#: Random network 76 of mp_nodal.random_network (seed 3): masses between nodes, values
#: over 12 decades; one mode not seen from the drive comes out of the held and released
#: eigen-solves 1.3e-7 apart (tests/test_resonances.py, tests/test_batch.py).
UNSEEN_MODE_12_DECADES = """drive V n1 0 velocity=1
mass e0 n1 0 4.399311767373876
mass e1 n2 n1 0.053308565423130075
mass e2 n3 n1 481.0732353383091
mass e3 n4 0 888090.2492139423
spring e4 n5 n4 0.2645184891415655
mass e5 n6 n1 417.00468112838615
mass e6 n7 n1 0.00014618761155269516
spring e7 n8 n5 101745.71930182866
mass e8 n1 n8 0.019623490587541627
spring e9 n7 n1 8144.954288761449
spring e10 n5 n3 9.170231161902271e-06
spring e11 0 n7 1.1175355790310573e-05
"""
