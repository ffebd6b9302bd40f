"""Calibrate the nodal error estimates and resonance errors against mpmath (issue 11).

A corpus of random networks (``tests/reference/mp_nodal.py``: random
spanning tree to the frame plus extra elements, so bridges and meshes that
are in general not series–parallel; masses and springs with values over 12
decades; undamped and lightly damped; some with levers of ratio 1e-3…1e3)
is evaluated

* by ``mechcirc.nodal.solve`` on the dense path (≤ 60 unknowns) and on the
  sparse path (the same networks with the dense limit set to 0), at random
  ω over four decades around each network's characteristic frequency;
* by ``find_resonances`` (every root polished, one per network kind);

and against mpmath (``lu_solve`` at 30 digits, ``findroot`` for the
roots), which uses the netlist's binary values exactly.  Printed per path:
points, false alarms (flag ≠ 0 where the true error < 1e-8), misses (true
error > 1e-6 without a flag), the share of points where the estimate is at
least the true error, and percentiles of estimate / true error (true error
floored at 1e-17, the reference's own resolution in a float64 result).

Run from the repository root: ``python benchmarks/calibrate_nodal.py
[--networks 200] [--seed 0]`` (about a minute per 50 networks).
"""

from __future__ import annotations

import argparse
import sys
import time
import warnings
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))

import mechcirc  # noqa: E402
import mechcirc._nodal_solvers as solvers  # noqa: E402
import mechcirc.nodal as nodal  # noqa: E402
from reference import mp_nodal as mp  # noqa: E402

FLOOR = 1e-17


def flags(K, err):
    bad = ~np.isfinite(K) | (K == 0)
    return np.where(bad, 1, np.where(err > 1e-6, 2, 0))


def summarize(name, true, est, flag):
    true, est, flag = map(np.asarray, (true, est, flag))
    t = np.maximum(true, FLOOR)
    ratio = est / t
    fa = np.sum((flag != 0) & (true < 1e-8))
    miss = np.sum((true > 1e-6) & (flag == 0))
    covered = np.mean(est >= true)
    finite = ratio[np.isfinite(ratio)]
    n_inf = int(np.sum(~np.isfinite(true)))
    p50, p99 = (np.percentile(finite, q) if finite.size else np.nan for q in (50, 99))
    print(f"| {name} | {true.size} | {fa} ({100 * fa / max(true.size, 1):.2f} %) | {miss} | "
          f"{100 * covered:.2f} % | {p50:.1e} | {p99:.1e} | {(np.max(finite) if finite.size else np.nan):.1e} | "
          f"{np.max(true[np.isfinite(true)], initial=0):.1e} |" +
          (f" ({n_inf} points where mechcirc or mpmath is not finite)" if n_inf else ""))
    return fa, miss, covered


def corpus(rng, count):
    for i in range(count):
        n_nodes = int(rng.integers(4, 40))
        yield mp.random_network(rng, n_nodes=n_nodes, damped=bool(i % 2),
                                levers=int(rng.integers(0, 3)) if i % 3 == 0 else 0)


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--networks", type=int, default=100)
    ap.add_argument("--points", type=int, default=4, help="ω per network")
    ap.add_argument("--roots", type=int, default=3, help="roots checked per network")
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args()
    rng = np.random.default_rng(args.seed)
    warnings.simplefilter("ignore")
    rows = {"nodal dense": ([], [], []), "nodal sparse": ([], [], []),
            "resonances": ([], [], [])}
    t0 = time.time()
    limit = solvers.DENSE_LIMIT
    n_used = 0
    skipped = 0
    for text, spec, w_char in corpus(rng, args.networks):
        try:
            c = mechcirc.parse(text)
            system = c.nodal
        except mechcirc.MechcircError:
            continue                     # e.g. a lever that leaves a node undetermined
        n_used += 1
        omega = w_char * 10 ** rng.uniform(-2, 2, args.points)
        ref = np.array([complex(mp.K(spec, 1j * w, 30)) for w in omega])
        for path, lim in (("nodal dense", limit), ("nodal sparse", 0)):
            if path == "nodal dense" and system.size > limit:
                continue
            solvers.DENSE_LIMIT = lim
            try:
                s = nodal.solve(system, omega)
            finally:
                solvers.DENSE_LIMIT = limit
            with np.errstate(all="ignore"):
                true = np.abs(s.K - ref) / np.abs(ref)
            true = np.where(np.isfinite(true), true, np.inf)
            t, e, f = rows[path]
            t.extend(true)
            e.extend(s.error)
            f.extend(flags(s.K, s.error))
        if system.size <= 20:
            try:
                found = c.resonances()
            except mechcirc.MechcircError:
                found = []
            pick = rng.permutation(len(found))[:args.roots]
            for j in pick:
                r = found[j]
                s0 = complex(-r.zeta * r.omega, r.omega_d)
                try:
                    sr = mp.root(spec, s0, r.kind == "antiresonance", 30)
                except (ValueError, ZeroDivisionError, TypeError):
                    skipped += 1         # reference did not converge: not counted
                    continue
                if abs(sr - s0) > 1e-3 * abs(s0):
                    skipped += 1         # findroot went to another root: not this one's reference
                    continue
                true = abs(abs(sr) - r.omega) / abs(sr)
                t, e, f = rows["resonances"]
                t.append(true)
                e.append(r.error)
                f.append(2 if r.error > 1e-6 else 0)
    print(f"{n_used} networks, seed {args.seed}, {time.time() - t0:.0f} s; {skipped} roots "
          "where mpmath.findroot did not converge or went to another root (not counted)\n")
    print("| path | points | false alarms | misses | estimate ≥ true | "
          "est/true median | est/true 99 % | est/true max | true error max |")
    print("|---|---|---|---|---|---|---|---|---|")
    for name, (t, e, f) in rows.items():
        if t:
            summarize(name, t, e, f)


if __name__ == "__main__":
    main()
