"""Speed of the netlist core (issue 2 §10).

(a) Sweep of ``netlists/stb_heald.mcir`` at 10⁶ ω points in-process against a
    hand-written vectorised numpy evaluation of the seed's eq. (7), measured in
    the same run.  Goal: mechcirc ≤ 2× eq. (7).
(b) Parse + reduce (``circuit.tree``) of generated ladder netlists of 100 …
    100,000 elements.  Goal: 10,000 elements ≤ 1 s, growth close to linear.

Times are the best of several repeats (``time.perf_counter``).  The script
prints; it asserts nothing.  Run from the repository root::

    python benchmarks/bench_sweep.py            # full run
    python benchmarks/bench_sweep.py --quick    # fewer repeats, up to 10,000 elements
    python benchmarks/bench_sweep.py --gc-off   # (b) without the cyclic garbage collector
    python benchmarks/bench_sweep.py --refine   # (c) only

(c) Nodal refinement on and off (``sweep(method="nodal", refine=...)``, the
    CLI's ``--refine/--no-refine``) on the ladders of (b) and a stiff chain,
    401 points: the time of each (best of, wall) in the same run, the ratio, how far the
    plain solve lands from the refined one (the refined K is checked against
    mpmath in tests/test_sweep_refine.py) beside the plain solve's own estimate.
"""

from __future__ import annotations

import argparse
import gc
import os
import platform
import time
from pathlib import Path

import numpy as np

import mechcirc
from timing import wall

NETLIST = Path(__file__).resolve().parents[1] / "netlists" / "stb_heald.mcir"


# --------------------------------------------------------------------------
# (a) eq. (7) by hand, as one would write it in numpy
# --------------------------------------------------------------------------

def eq7_evaluator(p):
    """Return ``K(omega)`` by eq. (7) with every ω-independent factor precomputed."""
    m1, m2, m3, m4, m5 = (p[f"m{i}"] for i in range(1, 6))
    m6, m7, m8, m9, m10, m11, m12 = (p[f"m{i}"] for i in range(6, 13))
    k0, k4, k5 = p["k0"], p["k4"], p["k5"]
    eta1, eta2, eta3, eta4 = p["eta1"], p["eta2"], p["eta3"], p["eta4"]
    eta_c = eta1**2 * eta2 * eta3**2
    eta_B, eta_C = eta1**2 * eta2, eta_c
    M_I = m10 * m11 * m12 / (m10 * m12 + m11 * m12 + m10 * m11)
    M_II = m6 * m7 * m8 * m9 / (m7 * m8 * m9 + m6 * m8 * m9 + m6 * m7 * m9 + m6 * m7 * m8)
    M_III = (m1 * m2 * m3 * m4 * eta1**2 * eta_B * eta_C
             / (m2 * m3 * m4 * eta1**2 * eta_B * eta_C + m1 * m3 * m4 * eta_B * eta_C
                + m1 * m2 * m4 * eta1**2 * eta_C + m1 * m2 * m3 * eta1**2 * eta_B))
    MM = M_I * M_II
    b0 = k0 * (M_I * eta4 + M_II)
    c1, c0 = m5 * (k4 * eta_c + k5), k4 * k5 * eta_c
    g = MM * k0 * eta4

    def K(w):
        w2 = w * w
        A = m5 * w2 - k5
        B = MM * w2 - b0
        BC = B * (c1 * w2 - c0)
        num = w2 * A * (M_III * B - g) - BC
        den = w * M_III * (A * w2 * g + BC)
        out = np.empty(w.shape, dtype=complex)
        out.real = 0.0
        out.imag = num / den
        return out

    return K


def params_of(circuit):
    p = {name: circuit.element(name).value
         for name in [f"m{i}" for i in range(1, 13)] + ["k0", "k4", "k5"]}
    p.update({k: circuit.params[k] for k in ("eta1", "eta2", "eta3", "eta4")})
    return p


def bench_sweep(n_points, repeats):
    circuit = mechcirc.load(NETLIST)
    circuit.tree                                    # reduce once, outside the timing
    omega = np.geomspace(1.0, 1e5, n_points)
    K_eq7 = eq7_evaluator(params_of(circuit))
    V0 = circuit.drive.amplitude

    def lib_with_Q0():
        r = circuit.sweep(omega)
        return r.Q0                                 # Q0 is computed on first access

    def ref_with_Q0():
        return V0 / K_eq7(omega)

    # Interleave the four measurements so that load from other processes on
    # the machine hits them alike; each call's result is dropped before the
    # next call, so every call allocates its arrays afresh.
    fns = {"lib": lambda: circuit.sweep(omega), "ref": lambda: K_eq7(omega),
           "lib_q": lib_with_Q0, "ref_q": ref_with_Q0}
    times = {key: [] for key in fns}
    for _ in range(repeats):
        for key, fn in fns.items():
            t0 = time.perf_counter()
            fn()
            times[key].append(time.perf_counter() - t0)
    best = {key: min(ts) for key, ts in times.items()}
    median = {key: float(np.median(ts)) for key, ts in times.items()}
    s, ref = circuit.sweep(omega), K_eq7(omega)
    err = np.max(np.abs(s.K - ref) / np.abs(ref))
    print(f"(a) sweep of {NETLIST.name}, {n_points:,} ω points, best (median) of {repeats}")
    for label, a, b in (("K only  ", "lib", "ref"), ("K and Q0", "lib_q", "ref_q")):
        print(f"    {label}  mechcirc {best[a] * 1e3:6.1f} ({median[a] * 1e3:6.1f}) ms   "
              f"eq. (7) numpy {best[b] * 1e3:6.1f} ({median[b] * 1e3:6.1f}) ms   "
              f"ratio {best[a] / best[b]:.2f} ({median[a] / median[b]:.2f})")
    print(f"    (max relative difference of K over all points: {err:.1e})")
    return best, median


# --------------------------------------------------------------------------
# (b) ladders
# --------------------------------------------------------------------------

def ladder(n_elements):
    """Series mass, shunt spring to the frame, repeated; the last element a damper."""
    lines = ["drive V n0 0 velocity=0.1"]
    node = 0
    for i in range(n_elements - 1):
        if i % 2 == 0:
            lines.append(f"mass m{node} n{node} n{node + 1} {1 + (i % 7) * 0.1}")
            node += 1
        else:
            lines.append(f"spring k{node} n{node} 0 {1e5 * (1 + (i % 5) * 0.1)}")
    lines.append(f"damper c n{node} 0 50")
    return "\n".join(lines) + "\n"


def bench_ladders(sizes, repeats, gc_off=False):
    print(f"(b) parse + reduce ladder netlists (mass, spring to frame, …, damper), best of "
          f"{repeats}" + (", cyclic garbage collector off" if gc_off else ""))
    print(f"    {'elements':>9} {'parse':>10} {'reduce':>10} {'total':>10} {'per element':>13}")
    rows = []
    for n in sizes:
        text = ladder(n)

        def parse_and_reduce():
            gc.collect()
            if gc_off:
                gc.disable()
            try:
                t0 = time.perf_counter()
                c = mechcirc.parse(text, source=f"ladder{n}.mcir")
                t1 = time.perf_counter()
                c.tree
                t2 = time.perf_counter()
            finally:
                gc.enable()
            return t1 - t0, t2 - t1, c

        best = None
        for _ in range(repeats if n <= 10_000 else max(1, repeats // 2)):
            tp, tr, c = parse_and_reduce()
            if best is None or tp + tr < sum(best):
                best = (tp, tr)
        tp, tr = best
        total = tp + tr
        rows.append((n, tp, tr, total))
        print(f"    {len(c.elements):>9,} {tp * 1e3:>8.1f}ms {tr * 1e3:>8.1f}ms {total * 1e3:>8.1f}ms "
              f"{total / n * 1e6:>10.1f} µs")
    return rows


STIFF = """drive V a 0 velocity=1
mass m1 a 0 1e-3
spring k1 a b 1e9
mass m2 b 0 1e3
spring k2 b c 1e2
mass m3 c 0 1e-2
damper d1 c 0 0.5
"""


def bench_refine(repeats):
    print(f"(c) nodal sweep, 401 points, refined (default) against --no-refine, best of {repeats}")
    print(f"    {'network':>16} {'refined':>10} {'plain':>10} {'ratio':>6} "
          f"{'|plain-refined|':>16} {'plain estimate':>15}")
    omega = np.geomspace(1.0, 1e5, 401)
    for name, text in (("stiff chain (6)", STIFF), ("ladder 45", ladder(45)),
                       ("ladder 999", ladder(999)), ("ladder 9,999", ladder(9_999))):
        c = mechcirc.parse(text)
        c.sweep(omega[:2], method="nodal")          # pattern, solver and kernels built once
        times = {}
        for refine in (True, False):
            times[refine], times[refine, "s"] = wall(
                lambda r=refine: c.sweep(omega, method="nodal", refine=r), repeats, best=True)
        a, b = times[True, "s"], times[False, "s"]
        with np.errstate(all="ignore"):
            diff = np.nanmax(np.abs(b.K - a.K) / np.abs(a.K))
        print(f"    {name:>16} {times[True] * 1e3:>8.1f}ms {times[False] * 1e3:>8.1f}ms "
              f"{times[True] / times[False]:>5.2f}x {diff:>16.2g} {np.nanmax(b.error):>15.2g}")


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true", help="fewer repeats and sizes")
    parser.add_argument("--gc-off", action="store_true",
                        help="(b) with Python's cyclic garbage collector disabled while timing")
    parser.add_argument("--refine", action="store_true", help="only (c), refinement on/off")
    args = parser.parse_args()
    print(f"mechcirc {mechcirc.__version__}, Python {platform.python_version()}, "
          f"numpy {np.__version__}, {platform.machine()}, {os.cpu_count()} CPUs, "
          f"{platform.processor() or platform.platform()}")
    if args.refine:
        bench_refine(2 if args.quick else 5)
        return
    if args.quick:
        bench_sweep(1_000_000, 2)
        bench_ladders([100, 1_000, 10_000], 2, args.gc_off)
        bench_refine(2)
    else:
        bench_sweep(1_000_000, 15)
        bench_ladders([100, 1_000, 10_000, 100_000], 5, args.gc_off)
        bench_refine(5)


if __name__ == "__main__":
    main()
