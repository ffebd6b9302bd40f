"""SP sweep against a hand-written numpy continued fraction (issue 14 §1).

For issue 11's ladders (springs k ∈ [1e4, 2e4] N/m in series, masses m ∈
[0.2, 1.2] kg to the frame, a damper r = 1e-3 N·s/m at the end) of 15 … 1e5
elements, at 1000 log points 0.1 Hz – 1 kHz, the script times in the same run:

* ``floor``: the ladder's continued fraction written by hand in numpy, from the
  end of the ladder: Y = jωm + 1/K (c at the end), K = jω/k + 1/Y;
* ``sp``: ``mechcirc.reduction.evaluate`` on the circuit's tree (K only);
* ``sp+err``: the same with the error bound (``error=True``), which is what
  ``Sweep.flags`` needs.

Goals: sp ≤ 1.2 × floor, sp+err ≤ 1.5 × sp.

With ``--reduce`` it also times the reduction (``circuit.tree``) of n springs in
parallel between two nodes and of a series chain of n springs, n = 4,000 …
64,000 (issue 14 §2: 16,000 in parallel took 264 s before the flattening was
made linear; goal < 0.1 s), and prints the time per element.  Times are the median of
``--repeats`` runs (``time.perf_counter``); the tree is built once (reduction is
timed elsewhere).  It prints; it asserts nothing.  Run from the repository root::

    python benchmarks/bench_sp_sweep.py [--quick]
"""

from __future__ import annotations

import argparse
import os
import platform
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))

from mechcirc.reduction import evaluate  # noqa: E402
from reference import sp_corpus  # noqa: E402


def floor_ladder(ks, ms, r, omega):
    """The continued fraction by hand (numpy, complex arrays)."""
    jw = 1j * omega
    inv_k = 1.0 / ks
    K = None
    for k_inv, m in zip(inv_k[::-1], ms[::-1]):
        Y = jw * m + (r if K is None else 1.0 / K)
        K = jw * k_inv + 1.0 / Y
    return K


def median_time(fn, repeats):
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return float(np.median(times))


def bench_reduce() -> int:
    import mechcirc

    print(f"# load {os.getloadavg()[0]:.1f}; reduction (circuit.tree) of runs of n springs")
    print(f"{'run':>9} {'n':>7} {'reduce s':>9} {'µs/elem':>8}")
    for kind in ("parallel", "series"):
        for n in (4000, 16_000, 64_000):
            if kind == "parallel":
                lines = [f"spring k{i} a 0 {1e3 + i}" for i in range(n)]
            else:
                nodes = ["a"] + [f"n{i}" for i in range(1, n)] + ["0"]
                lines = [f"spring k{i} {nodes[i]} {nodes[i + 1]} {1e3 + i}" for i in range(n)]
            c = mechcirc.parse("drive V a 0 velocity=1\n" + "\n".join(lines))
            t0 = time.perf_counter()
            c.tree
            t = time.perf_counter() - t0
            print(f"{kind:>9} {n:>7} {t:>9.3f} {t / n * 1e6:>8.1f}")
    return 0


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="up to 1e4 elements, 3 repeats")
    ap.add_argument("--points", type=int, default=1000)
    ap.add_argument("--reduce", action="store_true", help="only time parallel/series runs")
    args = ap.parse_args()
    if args.reduce:
        return bench_reduce()
    sizes = [15, 45, 999, 10_000] + ([] if args.quick else [100_000])
    omega = np.geomspace(2 * np.pi * 0.1, 2 * np.pi * 1e3, args.points)
    print(f"# {platform.processor() or platform.machine()}, {os.cpu_count()} cores, "
          f"load {os.getloadavg()[0]:.1f}; {args.points} points; median times")
    print(f"{'elements':>9} {'floor ms':>9} {'sp ms':>9} {'sp+err ms':>10} "
          f"{'sp/floor':>9} {'err/sp':>7} {'max|dK|/|K|':>12}")
    for n in sizes:
        rng = np.random.default_rng(n)
        n_sec = n // 2
        ks, ms = rng.uniform(1e4, 2e4, n_sec), rng.uniform(0.2, 1.2, n_sec)
        # The same ladder for mechcirc: rebuild it from the same numbers.
        expr = None
        node = ("leaf", "damper", 1e-3)
        for k, m in zip(ks[::-1], ms[::-1]):
            node = ("s", [("leaf", "spring", float(k)), ("p", [("leaf", "mass", float(m)), node])])
        expr = node
        tree = sp_corpus.to_circuit(expr).tree
        repeats = 3 if (args.quick or n >= 100_000) else 7
        K_floor = floor_ladder(ks, ms, 1e-3, omega)
        K_sp = evaluate(tree, omega)
        diff = float(np.max(np.abs(K_sp - K_floor) / np.abs(K_floor)))
        t_floor = median_time(lambda: floor_ladder(ks, ms, 1e-3, omega), repeats)
        t_sp = median_time(lambda: evaluate(tree, omega), repeats)
        t_err = median_time(lambda: evaluate(tree, omega, error=True), repeats)
        print(f"{n:>9} {t_floor * 1e3:>9.2f} {t_sp * 1e3:>9.2f} {t_err * 1e3:>10.2f} "
              f"{t_sp / t_floor:>9.2f} {t_err / t_sp:>7.2f} {diff:>12.1e}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
