"""Calibrate the series–parallel error bound (``Sweep.error``) against mpmath (issue 11 §1).

Corpus (``tests/reference/sp_corpus.py``, evaluated independently of mechcirc's
reduction at 40 digits):

* random SP trees of 2 … 60 elements with levers (ratios 1e±3) and values over
  12 decades, undamped / lightly damped (2 % dampers) / damped (30 %), on a
  log grid 1e-3 … 1e3 rad/s and, for undamped trees, at relative distances
  1e-6, −1e-9, 1e-12, −1e-14 and 0 from their exact poles and zeros;
* issue 11's lightly damped ladders (k ∈ [1e4, 2e4], m ∈ [0.2, 1.2],
  r = 1e-3) of 45 and 999 elements at 401 points, and 1e2 … 1e5 elements at
  fewer points (mpmath is the slow part);
* the same ladders undamped.

Prints per corpus part: points, false alarms (flag 2 where the true error is
below 1e-8), misses (true error above 1e-6 without flag 2), points where the
bound is below the true error, and percentiles of bound / max(true, u) over the points with a finite bound, and the share
of points where the bound exceeds 1e4 × max(true, u), an infinite bound
included (u = 1.1e-16: a float64 result cannot be closer than one rounding).
Goals: misses 0, false alarms ≤ 1 %, bound ≥ true everywhere, ≤ 1e4 × true at
99 %.  Run from the repository root::

    python benchmarks/calibrate_sp.py [--quick] [--path compiled|numpy]
"""

from __future__ import annotations

import argparse
import sys
import time
import warnings
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))

from mechcirc import FLAG_NEAR_SINGULAR, FLAG_SINGULAR  # noqa: E402
from reference import sp_corpus as corpus  # noqa: E402

U = np.finfo(float).eps / 2


def run(expr, omega):
    c = corpus.to_circuit(expr)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        s = c.sweep(omega, method="sp")
    true = corpus.true_error(s.K, corpus.reference(expr, omega))
    return s.error, true, s.flags


def summarise(name, parts):
    est = np.concatenate([p[0] for p in parts])
    true = np.concatenate([p[1] for p in parts])
    flags = np.concatenate([p[2] for p in parts])
    reg = flags != FLAG_SINGULAR
    est, true, flags = est[reg], true[reg], flags[reg]
    accurate = true < 1e-8
    fa = np.count_nonzero(accurate & (flags == FLAG_NEAR_SINGULAR))
    miss = np.count_nonzero((true > 1e-6) & (flags != FLAG_NEAR_SINGULAR))
    under = np.count_nonzero(est < true)
    fin = np.isfinite(est)
    ratio = est[fin] / np.maximum(true[fin], U)
    loose = np.count_nonzero(~(est <= 1e4 * np.maximum(true, U)))     # inf counts as loose
    p50, p99 = np.percentile(ratio, [50, 99]) if ratio.size else (np.nan, np.nan)
    print(f"| {name} | {est.size} | {np.count_nonzero(~reg)} | {np.count_nonzero(true > 1e-6)} | "
          f"{fa} ({100 * fa / max(accurate.sum(), 1):.2f} %) | {miss} | {under} | "
          f"{p50:.3g} | {p99:.3g} | {ratio.max() if ratio.size else np.nan:.3g} | "
          f"{np.count_nonzero(~fin)} | {100 * loose / max(est.size, 1):.2f} % |")
    return est, true, flags


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="a tenth of the corpus")
    ap.add_argument("--path", choices=("compiled", "numpy"), default="compiled",
                    help="evaluate by the compiled plan (numba) or the numpy path")
    args = ap.parse_args()
    from mechcirc import _jit

    _jit.COMPILED = args.path == "compiled"
    print(f"# evaluation path: {args.path}")
    q = 10 if args.quick else 1
    rng = np.random.default_rng(11)
    t0 = time.perf_counter()
    print("| corpus | points | flag 1 | true > 1e-6 | false alarms | misses | bound < true | "
          "median bound/true | 99 % | max | bound = inf | bound > 1e4·true (inf incl.) |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|")
    allparts = []
    for label, damped in (("random SP + levers, undamped", 0.0),
                          ("random SP + levers, lightly damped", 0.02),
                          ("random SP + levers, damped", 0.3)):
        parts = []
        for _ in range(max(2, 150 // q)):
            expr = corpus.random_tree(rng, int(rng.integers(2, 60)), damped=damped)
            omega = np.geomspace(1e-3, 1e3, 41)
            if corpus.lossless(expr):
                crit = corpus.critical_points(expr, 1e-3, 1e3, 100)[:6]
                near = [w * (1 + d) for w in crit for d in (1e-6, -1e-9, 1e-12, -1e-14, 0.0)]
                omega = np.concatenate([omega, near])
            parts.append(run(expr, omega))
        summarise(label, parts)
        allparts += parts
    for r, label in ((1e-3, "ladders r = 1e-3"), (None, "ladders undamped")):
        parts = []
        for n, pts in ((45, 401), (999, 401), (100, 1001 // q), (1000, 201 // q),
                       (10_000, 41 // q), (100_000, 5)):
            if args.quick and n > 10_000:
                continue
            expr = corpus.ladder(rng, n, r=r)
            omega = np.geomspace(2 * np.pi * 0.1, 2 * np.pi * 1e3, max(pts, 3))
            parts.append(run(expr, omega))
        summarise(label, parts)
        allparts += parts
    summarise("**all**", allparts)
    print(f"\n({time.perf_counter() - t0:.0f} s)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
