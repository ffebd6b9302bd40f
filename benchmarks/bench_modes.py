"""Modes and sensitivities (issue 22 §1–2) against ``resonances()`` alone, in the same run.

CPU seconds, median of ``--repeat``, each from a fresh parse (nothing cached):

* the STB heald netlist (13 nodes, 5 roots, 6 ``.param``): the goal is modes +
  sensitivities ≤ 2× the cost of ``resonances`` alone;
* the 30×30 spring–mass grid of bench_resonances (900 unknowns, 817 roots),
  where the eigenvectors (one dense ``eigh`` of the released problem; the held
  roots and vectors follow from it by the secular equation, where
  ``resonances`` solves the held problem's eigenvalues by a banded solver) and
  the per-root work show.

The three calls alternate within each repetition; besides the ratio of the
medians, the spread of the per-repetition ratios is printed, and the share of
``modes`` that is the eigen-solve with vectors
(``resonance_pairs(vectors=True)``, the floor of any ``modes``).

``--before PATH`` also times, in the same repetitions and in turn before and
after this one, the ``modes`` of another copy of ``mechcirc/modes.py`` (e.g.
``git show main:mechcirc/modes.py > /tmp/m.py``), loaded beside this one with the
same ``resonances``: on a loaded machine the medians of separate runs move by
more than a change of a few per cent (an A/A run, the same file twice, gives
the size of that noise).

Run from the repository root: ``python benchmarks/bench_modes.py`` (on a loaded
machine with ``OPENBLAS_NUM_THREADS=1``: idle BLAS threads spinning count as CPU time).
"""

from __future__ import annotations

import argparse
import statistics
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

import mechcirc  # noqa: E402
from bench_nodal_speed import grid  # noqa: E402
from mechcirc.modes import modes  # noqa: E402
from mechcirc.resonances import resonance_pairs  # noqa: E402
from timing import cpu


def compare(label: str, text: str, repeat: int, before=None) -> None:
    t_res, t_modes, t_vec, t_before = [], [], [], []
    for k in range(repeat):
        t, found = cpu(lambda: mechcirc.parse(text).resonances())
        t_res.append(t)
        # With --before, the two modes() in turn first (what runs first pays more faults).
        for f, out in [(modes, t_modes), (before, t_before)][::1 if k % 2 else -1]:
            if f is not None:
                out.append(cpu(lambda f=f: f(mechcirc.parse(text)))[0])
        t, _ = cpu(lambda: resonance_pairs(mechcirc.parse(text), vectors=True))
        t_vec.append(t)
    a, b, c = (statistics.median(x) for x in (t_res, t_modes, t_vec))
    each = sorted(m / r for m, r in zip(t_modes, t_res))
    print(f"{label}: {len(found)} roots; resonances() {a * 1e3:.1f} ms CPU, modes() with "
          f"sensitivities {b * 1e3:.1f} ms; ratio {b / a:.2f} (per repetition "
          f"{each[0]:.2f}–{each[-1]:.2f}; goal ≤ 2); of which the roots with vectors "
          f"{c * 1e3:.1f} ms ({c / a:.2f}× resonances())")
    if before is not None:
        d = statistics.median(t_before)
        paired = statistics.median(m / o for m, o in zip(t_modes, t_before))
        print(f"  the modes() before: {d * 1e3:.1f} ms, ratio {d / a:.2f}; now / before "
              f"{b / d:.3f} (median of the per-repetition ratios {paired:.3f})")


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--before", type=Path, help="another mechcirc/modes.py to time alongside")
    args = ap.parse_args()
    before = None
    if args.before:
        import importlib.util

        spec = importlib.util.spec_from_file_location("mechcirc._modes_before", args.before)
        module = importlib.util.module_from_spec(spec)
        sys.modules[spec.name] = module         # its dataclasses look their module up
        spec.loader.exec_module(module)
        before = module.modes
    root = Path(__file__).resolve().parents[1]
    compare("stb_heald", (root / "netlists" / "stb_heald.mcir").read_text(), args.repeat, before)
    compare("30×30 grid", grid(30), args.repeat, before)


if __name__ == "__main__":
    main()
