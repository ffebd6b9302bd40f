"""Nodal sweeps at sparse-solver speed (issue 14 §3): mechcirc against one plain ``splu`` per ω.

For each network, in the same run and interleaved (median of ``--repeat``
runs each), prints the time of

* the baseline: A(ω) = D + C + j(ωM − Kₛ/ω) built with scipy.sparse
  arithmetic and factorised by ``scipy.sparse.linalg.splu`` at every ω,
  one solve, no refinement, no error estimate;
* ``nodal.solve(system, ω, refine=False)``: mechcirc's plain solve (fixed
  pattern, ordering found once, banded LAPACK LU where the band is narrow);
* ``nodal.solve(system, ω)``: the default, refined in extended precision
  with the error estimate (what ``Circuit.sweep(method="nodal")`` does);

and the ratios, and the largest relative difference of K between mechcirc
and the baseline.  Networks: random ladders of 9,999 (and, with ``--big``,
99,999) elements forced through nodal analysis, the 30×30 spring–mass grid
of issue 11 and a 100×100 grid (``--big``).  ngspice is not used here.

Run from the repository root: ``python benchmarks/bench_nodal_speed.py [--big]``.
"""

from __future__ import annotations

import argparse
import statistics
import time

import numpy as np

import mechcirc
import mechcirc.nodal as nodal


def grid(n: int, k: float = 1e4, m: float = 1.0) -> str:
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


def ladder(n_el: int, seed: int = 0) -> str:
    """Springs k in [1e4, 2e4] N/m in series, masses m in [0.2, 1.2] kg to the frame."""
    rng = np.random.default_rng(seed)
    lines = ["drive V n0 0 velocity=1"]
    for i in range(n_el):
        node = i // 2
        if i % 2 == 0:
            lines.append(f"spring k{i} n{node} n{node + 1} {rng.uniform(1e4, 2e4)!r}")
        else:
            lines.append(f"mass m{i} n{node + 1} 0 {rng.uniform(0.2, 1.2)!r}")
    return "\n".join(lines)


def baseline(system, omega):
    from scipy.sparse.linalg import splu

    base = (system.D + system.C).tocsc()
    M, Ks = system.M.tocsc(), system.Ks.tocsc()
    b = system.injection().astype(complex)
    out = np.empty(omega.size, dtype=complex)
    for i, w in enumerate(omega):
        out[i] = system.difference(splu((base + 1j * (w * M - Ks / w)).tocsc()).solve(b))
    return out


def timed(fn):
    t0 = time.process_time()
    out = fn()
    return time.process_time() - t0, out


def run(name, text, omega, repeat):
    system = mechcirc.parse(text).nodal
    runs = {"splu per ω": lambda: baseline(system, omega),
            "mechcirc plain": lambda: nodal.solve(system, omega, refine=False).K,
            "mechcirc refined": lambda: nodal.solve(system, omega).K}
    times = {k: [] for k in runs}
    results = {}
    for _ in range(repeat):                     # interleaved
        for k, fn in runs.items():
            t, results[k] = timed(fn)
            times[k].append(t)
    med = {k: statistics.median(v) for k, v in times.items()}
    ref = results["splu per ω"]
    diff = np.max(np.abs(results["mechcirc refined"] / ref - 1))
    print(f"{name}: {system.size} unknowns, {omega.size} points (CPU s, median of {repeat})")
    for k in runs:
        print(f"    {k:18s} {med[k]:8.3f} s   ratio to splu {med[k] / med['splu per ω']:.2f}")
    print(f"    refined / plain {med['mechcirc refined'] / med['mechcirc plain']:.2f} "
          f"(goal <= 1.5); max |K/K_splu - 1| = {diff:.1e}")


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--big", action="store_true", help="99,999-element ladder, 100×100 grid")
    ap.add_argument("--points", type=int, default=1001)
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args()
    omega = np.geomspace(0.6, 6e3, args.points)
    run("ladder 9,999 elements", ladder(9999), omega, args.repeat)
    run("30×30 grid", grid(30), np.geomspace(10, 1e3, args.points), args.repeat)
    if args.big:
        run("ladder 99,999 elements", ladder(99999), omega, 1)
        run("100×100 grid", grid(100), np.geomspace(10, 1e3, args.points), 1)


if __name__ == "__main__":
    main()
