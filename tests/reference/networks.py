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


#: Tree 17 of tests/test_startup.py's corpus (damped, 11 nodes): a resonance and an
#: anti-resonance 6.2e-7 apart at 69.38 rad/s.  Its secant on K from float64 factors
#: (A(s) nearly singular there) put the anti-resonance 3.1e-13 off, said to be good to
#: 2.1e-15 (tests/test_resonances.py).
CLOSE_PAIR_TREE = """drive V a 0 velocity=1.0
spring s0 n0 0 0.002049236268152773
damper d1 a n0 32.23456148153904
mass m2 n2 0 681.1882619453548
spring s3 n1 n2 5972.409326077765
spring s4 n4 0 0.061611419738159624
spring s5 n5 n4 39.56780892793871
mass m6 n3 n5 1.7149822710551363
spring s7 n1 n3 2.6384263703769584
spring s8 n1 n3 21886.358196371555
damper d9 a 0 3.3557154710477994
mass m10 n8 0 0.0006419982523069722
damper d11 n7 n8 0.006728740641891391
mass m12 n6 n7 15337.148738591985
mass m13 a n6 0.00011423836215521655
spring s14 a 0 0.00027910278210491294
spring s15 a 0 2.1273922785822597e-06
mass m16 a 0 77.42376333917122
damper d17 a 0 1.5611483480621373e-06
lever L0 a 0 n1 0 ratio=8.004075118720241
"""

#: Random network 202 of mp_nodal.random_network (seed 2 of a fuzz drawing 3-8 nodes,
#: damped or not, 0-2 levers, 2-12 decades): an overdamped resonance and anti-resonance
#: 8.5e-10 apart at s = -7617.768 rad/s.  K off the jω axis from float64 factors had no
#: digit there; the pair's check could not tell, and the anti-resonance's secant went to
#: 7617.7663, 2.6e-7 off, said to be good to 2.4e-7 (tests/test_resonances.py).
OVERDAMPED_CLOSE_PAIR = """drive V n1 0 velocity=1
mass e0 n1 0 1.1479310005166707
spring e1 n2 n1 6.008425097732464
spring e2 n3 n1 12.79192050685122
mass e3 n4 n1 0.03187044638958083
spring e4 n5 n1 0.01280741933409984
mass e5 n6 n5 0.19250983185397952
mass e6 n7 n4 15.49230645607229
mass e7 n8 n4 20.871924783917283
mass e8 n2 0 0.029892688492283794
spring e9 n6 0 0.03278689461540639
spring e10 n1 n5 0.361308320640519
spring e11 n6 n5 5.429828834801604
damper e12 n3 n1 0.02984009193232547
damper e13 n4 n1 0.00044192728570230963
damper e14 n5 n1 2.8558239887174066e-05
damper e15 n7 n4 0.12703067512025729
damper e16 n6 0 2.4856699487485763e-05
damper e17 n6 n5 0.018075957478127992
lever L0 n1 0 n2 0 ratio=1.509552956783841
"""
