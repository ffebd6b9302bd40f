"""Parse and reduce time per element (issue 14 §2): ladders of 10² … 10⁶ statements.

The ladder is the one of ``bench_reduce.py``: a drive, a mass to the frame,
then sections of spring ∥ damper in series and a mass to the frame (values
log-uniform, written as Python's shortest repr, e.g. ``316227.76601683796``;
every tenth value carries a unit, ``N/m``, ``N·s/m`` or ``kg``, so the unit
path is measured too).  For each size N it prints, measured in the same run:

* **floor**: a minimal tokenizer (``str.split`` per line, ``float()``, one
  ``Element`` per line, no checks, no error locations) — what any parser must
  at least spend building the same objects;
* **parse**: :func:`mechcirc.parse` (all checks, located errors, expressions
  kept for formulas);
* **reduce**: the series-parallel reduction (``circuit.tree``; ``reduction.py``);
* **plan**: the tree compiled into the flat arrays a sweep evaluates
  (``reduction.plan``, built once per circuit on its first sweep);

as CPU µs per element, the ratio parse / floor, and the growth of the per-element
time against the previous size (1.0 = linear).  Best of ``--repeat`` runs
(default 3 below 10⁵ elements, 1 above).  It asserts nothing.  Run from the
repository root::

    python benchmarks/bench_parse.py            # 10² … 10⁵
    python benchmarks/bench_parse.py --full     # up to 10⁶ (about a minute, 2-3 GB)
"""

from __future__ import annotations

import argparse
import gc
import os
import platform
import time

import numpy as np

import mechcirc
from mechcirc import reduction
from mechcirc.circuit import Element
from mechcirc.netlist import MAX_STATEMENTS


def ladder_text(n_elements: int, seed: int = 0) -> str:
    """A drive and ``n_elements`` elements (``n_elements + 1`` statements)."""
    rng = np.random.default_rng(seed)
    lines = ["drive V n0 0 velocity=1", "mass m0 n0 0 5.0"]
    i = 0
    while len(lines) - 1 < n_elements:
        i += 1
        unit = i % 10 == 0
        lines.append(f"spring k{i} n{i - 1} n{i} {10 ** rng.uniform(5, 10)!r}"
                     + (" N/m" if unit else ""))
        lines.append(f"damper c{i} n{i - 1} n{i} {10 ** rng.uniform(0, 2)!r}"
                     + (" N·s/m" if unit else ""))
        lines.append(f"mass m{i} n{i} 0 {10 ** rng.uniform(-4, 0)!r}" + (" kg" if unit else ""))
    # A partial last section would leave k, c dangling (unloaded): masses instead.
    extra = len(lines) - 1 - n_elements
    if extra:
        del lines[-3:]
        lines += [f"mass x{j} n{i - 1} 0 {10 ** rng.uniform(-4, 0)!r}" for j in range(3 - extra)]
    return "\n".join(lines) + "\n"


_SI = {"N/m": 1.0, "N·s/m": 1.0, "kg": 1.0}


def floor_parse(text: str) -> list:
    """The floor: split, float, one Element per line; no checks at all."""
    out = []
    for lineno, line in enumerate(text.split("\n"), 1):
        f = line.split()
        if not f or f[0] == "drive":
            continue
        value = float(f[4])
        if len(f) > 5:
            value *= _SI[f[5]]
        out.append(Element(f[0], f[1], f[2], f[3], value, 1.0, lineno, 1))
    return out


def timed(fn, repeat: int) -> tuple[float, object]:
    """Best CPU time [s] of ``fn()`` (process time: the machine is shared) and its result.

    The cyclic garbage collector is off during each call, as :func:`mechcirc.parse`
    turns it off itself: the floor gets the same advantage."""
    best, result = float("inf"), None
    for _ in range(repeat):
        result = None
        gc.collect()
        gc.disable()
        try:
            t0 = time.process_time()
            result = fn()
            best = min(best, time.process_time() - t0)
        finally:
            gc.enable()
    return best, result


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--full", action="store_true", help="include 10⁶ elements")
    ap.add_argument("--repeat", type=int, default=None)
    args = ap.parse_args()
    sizes = [10 ** k for k in range(2, 7 if args.full else 6)]
    print(f"python {platform.python_version()}, {platform.machine()}, {os.cpu_count()} CPUs, "
          f"load average {', '.join(f'{x:.1f}' for x in os.getloadavg())} at the start")
    print("| elements | floor [µs/el] | parse [µs/el] | parse / floor | parse growth "
          "| reduce [µs/el] | reduce growth | parse + reduce [µs/el] | plan [µs/el] "
          "| parse + reduce + plan [µs/el] |")
    print("|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
    prev = None
    for size in sizes:
        # 10^k statements: the drive and 10^k - 1 elements (so 10^6 fits the limit).
        n = size - 1
        if size > MAX_STATEMENTS:
            print(f"| {n:,} | — | refused: the statement limit is {MAX_STATEMENTS:,} |||||")
            continue
        text = ladder_text(n)
        repeat = args.repeat or (3 if n < 100_000 else 1)
        t_floor, elems = timed(lambda: floor_parse(text), repeat)
        assert len(elems) == n
        del elems
        t_parse, circuit = timed(lambda: mechcirc.parse(text, source="ladder.mcir"), repeat)
        assert len(circuit.elements) == n
        # A fresh circuit per run: the reduction is cached on the circuit.
        circuits = [circuit] + [mechcirc.parse(text) for _ in range(repeat - 1)]
        it = iter(circuits)
        t_red, _ = timed(lambda: next(it).tree, repeat)
        trees = iter([c.tree for c in circuits])
        t_plan, _ = timed(lambda: reduction.plan(next(trees)), repeat)
        del circuits, it, circuit, trees
        per = (1e6 * t_floor / n, 1e6 * t_parse / n, 1e6 * t_red / n, 1e6 * t_plan / n)
        g_parse = f"{per[1] / prev[1]:.2f}" if prev else "—"
        g_red = f"{per[2] / prev[2]:.2f}" if prev else "—"
        print(f"| {n:,} | {per[0]:.2f} | {per[1]:.2f} | {per[1] / per[0]:.1f} | {g_parse} "
              f"| {per[2]:.2f} | {g_red} | {per[1] + per[2]:.2f} | {per[3]:.2f} "
              f"| {per[1] + per[2] + per[3]:.2f} |", flush=True)
        prev = per


if __name__ == "__main__":
    main()
