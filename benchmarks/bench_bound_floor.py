"""The least numpy can spend on the series–parallel error bound, against K (issue 26).

For each tree (the 45- and 999-element ladders of ``bench_bound_cost.py`` at 401 ω,
``netlists/stb_heald.mcir`` at 400 ω) this times, alternated in one process, medians
of CPU time:

* K alone on the numpy path (``mechcirc._jit.COMPILED`` False), and K with its error
  bound (what ``Sweep.error`` and ``Sweep.flags`` compute);
* two floors: bare numpy calls over the tree's nodes (from :func:`mechcirc.reduction.plan`)
  at the same points, with no Python around them but one loop, every buffer allocated
  beforehand, and everything that does not depend on a child's bound (the leaves'
  shares, the constants, the sums' reciprocals) taken as free:

  - *exact rule*: the reciprocal rule ρ/(1 − ρ) of the bound in the fewest calls
    a node can take in numpy: |S| of its sum (a complex absolute value where the sum
    is complex) and, per internal child, E += E_c/((|S_c| − E_c)·|S_c|) as 4 calls
    (subtract, multiply, divide, add; the clamp at 0 left out);
  - *affine rule*: any bound carried node by node that is linear in the children's
    bounds (E += β_c·E_c): |S| and 2 calls per internal child.

It prints 1 + floor / K beside issue 26's goal for K with its bound (≤ 1.5× K); a
floor above the goal means no numpy pass node by node meets it.  It asserts nothing.
Run from the repository root::

    python benchmarks/bench_bound_floor.py [--repeat 41]
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "benchmarks"))

import mechcirc  # noqa: E402
from mechcirc import _jit, reduction  # noqa: E402

from bench_work_precision import ladder, ladder_netlist  # noqa: E402

GOAL = 1.5


def cases() -> dict:
    out = {}
    for n in (45, 999):
        ks, ms, r = ladder(n)
        out[f"ladder of {n}"] = (mechcirc.parse(ladder_netlist(ks, ms, r)).tree,
                                 np.geomspace(2 * np.pi * 0.1, 2 * np.pi * 1e3, 401))
    out["stb_heald.mcir"] = (mechcirc.load(str(ROOT / "netlists" / "stb_heald.mcir")).tree,
                             np.linspace(10.0, 1000.0, 400))
    return out


def floors(tree, omega) -> tuple:
    """The two floors' loops over ``tree``'s plan, buffers made here (one per stack slot)."""
    p = reduction.plan(tree)
    W = omega.size
    rng = np.random.default_rng(1)
    E = rng.uniform(1e-15, 1e-14, (p.n_slots, W))
    A = rng.uniform(1.0, 2.0, (p.n_slots, W))
    scratch = np.empty(W)
    # A node's sum, its own share of the bound (taken as given) and a weight β < 1 (the
    # values stay bounded): three sets used in turn, hot in cache as K's fresh sums are.
    sums = [rng.uniform(1.0, 2.0, W) + 1j * rng.uniform(1.0, 2.0, W) for _ in range(3)]
    alphas = [rng.uniform(1e-15, 1e-14, W) for _ in range(3)]
    betas = [rng.uniform(0.1, 0.5, W) for _ in range(3)]
    steps = []
    for i, kind in enumerate(p.kind.tolist()):
        if kind == 2:                      # a lever: two calls, left out
            continue
        s = int(p.slot[i])
        total = sums[i % 3] if p.cplx[i] else sums[i % 3].real.copy()
        # A child's |S|, its bound, β and what the term is added to: the node's own
        # share for the first, the sum after.
        kids = [(A[int(p.slot[c])], E[int(p.slot[c])], betas[j % 3],
                 alphas[i % 3] if j == 0 else E[s]) for j, c in
                enumerate(p.kids[p.kstart[i]:p.kstart[i + 1]].tolist())]
        steps.append((total, A[s], E[s], kids))
    abs_, sub, mul, div, add = np.abs, np.subtract, np.multiply, np.divide, np.add

    def exact():
        for total, a, e, kids in steps:
            for ac, ec, _, base in kids:
                sub(ac, ec, scratch)
                mul(scratch, ac, scratch)
                div(ec, scratch, scratch)
                add(base, scratch, e)
            abs_(total, a)

    def affine():
        for total, a, e, kids in steps:
            for _, ec, beta, base in kids:
                mul(beta, ec, scratch)
                add(base, scratch, e)
            abs_(total, a)

    return exact, affine


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=41)
    args = ap.parse_args()
    print(f"load average {os.getloadavg()[0]:.1f}; medians of {args.repeat} calls, CPU ms, "
          "numpy path, alternated in one process")
    saved = _jit.COMPILED
    _jit.COMPILED = False
    try:
        for name, (tree, omega) in cases().items():
            exact, affine = floors(tree, omega)
            fns = {"K": lambda t=tree, w=omega: reduction.evaluate(t, w),
                   "K+bound": lambda t=tree, w=omega: reduction.evaluate(t, w, error=True),
                   "exact": exact, "affine": affine}
            for f in fns.values():
                f()
            times: dict = {k: [] for k in fns}
            repeat = args.repeat if "999" not in name else max(5, args.repeat // 3)
            for _ in range(repeat):
                for k, f in fns.items():
                    t = time.process_time()
                    f()
                    times[k].append(time.process_time() - t)
            m = {k: float(np.median(v)) * 1e3 for k, v in times.items()}
            K = m["K"]
            print(f"{name:<16} K {K:.3f}, K+bound {m['K+bound']:.3f} ({m['K+bound'] / K:.2f}x K); "
                  f"floors: exact rule {m['exact']:.3f} ({1 + m['exact'] / K:.2f}x K), "
                  f"affine rule {m['affine']:.3f} ({1 + m['affine'] / K:.2f}x K); "
                  f"goal <= {GOAL}x")
    finally:
        _jit.COMPILED = saved
    print(f"load average after: {os.getloadavg()[0]:.1f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
