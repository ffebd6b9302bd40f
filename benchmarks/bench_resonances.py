"""Resonances by eigen-solvers (issue 14 §4): ``find_resonances`` against two ``scipy.linalg.eigh`` calls.

Measured in the same run (CPU seconds, median of ``--repeat``):

* the 30×30 spring–mass grid of issue 11 (springs 1e4 N/m between
  neighbours and to the frame, 1 kg per node, corner drive): mechcirc's
  ``resonances()`` (parse included) against the floor of two dense symmetric
  eigenvalue problems of the same size (drive released: n unknowns; held:
  n − 1), ``scipy.linalg.eigh(K, M, eigvals_only=True)``, and against
  itself with the banded eigen-solver switched off (the dense
  ``numpy.linalg.eigvalsh`` path it took before);
* lightly damped ladders of 3,000 and 30,000 elements (1,000 and 10,000
  unknowns, above the dense limit of 500 for damped networks) in a band
  ω ≤ omega_max by shift-invert Arnoldi, which used to be refused.

Run from the repository root: ``python benchmarks/bench_resonances.py``
(``--grid-only`` skips the ladders, which take about half a minute).
"""

from __future__ import annotations

import argparse
import statistics
import sys
from pathlib import Path

import scipy.linalg as la

sys.path.insert(0, str(Path(__file__).resolve().parent))

import mechcirc  # noqa: E402
from mechcirc import resonances  # noqa: E402
from bench_nodal_speed import grid  # noqa: E402
from reference.networks import damped_ladder_lines  # noqa: E402
from timing import cpu


def damped_ladder(n_el: int, seed: int = 0, r: float = 1e-3) -> str:
    return "\n".join(damped_ladder_lines(n_el, seed, r))


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--grid-only", action="store_true")
    args = ap.parse_args()
    text = grid(30)
    system = mechcirc.parse(text).nodal
    K, M = system.Ks.toarray(), system.M.toarray()
    t_res, t_eig, t_dense = [], [], []
    banded_from = resonances.BANDED_FROM
    for _ in range(args.repeat):
        t, found = cpu(lambda: mechcirc.parse(text).resonances())
        t_res.append(t)
        t, _ = cpu(lambda: (la.eigh(K, M, eigvals_only=True),
                            la.eigh(K[1:, 1:], M[1:, 1:], eigvals_only=True)))
        t_eig.append(t)
        resonances.BANDED_FROM = 10 ** 9          # the dense path, as before the banded solver
        try:
            t, dense = cpu(lambda: mechcirc.parse(text).resonances())
        finally:
            resonances.BANDED_FROM = banded_from
        t_dense.append(t)
    worst = max(abs(r.omega - d.omega) / d.omega for r, d in zip(found, dense))
    a, b, c = (statistics.median(x) for x in (t_res, t_eig, t_dense))
    print(f"30×30 grid: {len(found)} roots; resonances() {a:.2f} s CPU (parse included), "
          f"two eigh {b:.2f} s, the dense path {c:.2f} s; ratios {a / b:.2f} and {a / c:.2f} "
          f"(issue 14: 303 s before; goal ≤ 1 s); roots of the two paths agree to {worst:.1e}")
    if args.grid_only:
        return
    for n_el, band in ((3000, 10.0), (30000, 2.0)):
        text = damped_ladder(n_el)
        t, found = cpu(lambda text=text, band=band: mechcirc.parse(text).resonances(omega_max=band))
        worst = max((r.error for r in found), default=float("nan"))
        print(f"damped ladder, {n_el:,} elements ({mechcirc.parse(text).nodal.size} unknowns), "
              f"band ω ≤ {band:g} rad/s: {len(found)} roots in {t:.2f} s CPU (refused "
              f"before); largest error estimate {worst:.1e}")

if __name__ == "__main__":
    main()
