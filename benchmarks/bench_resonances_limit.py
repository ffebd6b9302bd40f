"""Resonances at the dense limit (docs/reliability.md, "Bounded work"): CPU time at 1,999 unknowns.

A seeded chain drive → spring → mass → spring → … (masses 0.5–2 kg to the frame,
springs 1e3–1e4 N/m): 1,999 undamped unknowns, one below ``MAX_UNKNOWNS``.
Prints the CPU time of ``resonances()`` (all threads of this process) and the
share spent polishing the roots on K.  Set ``OPENBLAS_NUM_THREADS=1`` to see
the single-thread figure (threads that spin on a loaded machine add CPU time).

    OPENBLAS_NUM_THREADS=1 python benchmarks/bench_resonances_limit.py
"""

from __future__ import annotations

import argparse
import random
import time

import mechcirc
from mechcirc import resonances


def chain(n: int, seed: int = 1) -> str:
    r = random.Random(seed)
    lines = ["drive V n0 0 velocity=1"]
    for i in range(n):
        lines.append(f"mass m{i} n{i + 1} 0 {r.uniform(0.5, 2)}")
        lines.append(f"spring k{i} n{i} n{i + 1} {r.uniform(1e3, 1e4)}")
    return "\n".join(lines) + "\n"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--unknowns", type=int, default=resonances.MAX_UNKNOWNS - 1)
    n = ap.parse_args().unknowns
    c = mechcirc.parse(chain(n))
    _ = c.nodal                                   # assembled outside the timing
    polish = resonances._polish
    spent = [0.0]

    def timed(*a, **k):
        t = time.process_time()
        try:
            return polish(*a, **k)
        finally:
            spent[0] += time.process_time() - t

    resonances._polish = timed
    t0 = time.process_time()
    res = c.resonances()
    total = time.process_time() - t0
    print(f"{n} unknowns: {len(res)} roots, {total:.1f} s CPU, of which polishing "
          f"{spent[0]:.1f} s ({100 * spent[0] / total:.0f} %)")


if __name__ == "__main__":
    main()
