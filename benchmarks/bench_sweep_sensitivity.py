"""Sensitivities on a sweep (``mechcirc.modes.sweep_sensitivity``) against the nodal sweep alone.

On ``netlists/stb_heald.mcir`` at 1000 log points 10 … 10⁴ rad/s, in one run,
interleaved, CPU time (median of ``--repeat``):

* the nodal sweep (``Circuit.sweep(omega, method="nodal")``: one refined solve
  per ω), the baseline;
* ``sweep_sensitivity`` with every name (elements, levers, ``.param`` values)
  and with one name (``k4``);
* the series–parallel sweep by the tree (the default method), for scale.

Prints each time and its ratio to the nodal sweep, with the load before and
after.  Run from the repository root: ``python benchmarks/bench_sweep_sensitivity.py``.
"""

from __future__ import annotations

import argparse
import os
import statistics
import time
from pathlib import Path

import numpy as np

import mechcirc
from mechcirc.modes import sweep_sensitivity

NETLIST = Path(__file__).resolve().parents[1] / "netlists" / "stb_heald.mcir"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=40)
    ap.add_argument("--points", type=int, default=1000)
    args = ap.parse_args()
    c = mechcirc.load(NETLIST)
    w = np.geomspace(10.0, 1e4, args.points)
    calls = {
        "nodal sweep": lambda: c.sweep(w, method="nodal").K,
        "every name": lambda: sweep_sensitivity(c, w),
        "one name (k4)": lambda: sweep_sensitivity(c, w, ["k4"]),
        "tree sweep": lambda: c.sweep(w).K,
    }
    for f in calls.values():                # warm-up: imports, caches, plans
        f()
    print(f"{NETLIST.name}, {args.points} ω, median CPU of {args.repeat} interleaved; "
          f"load {os.getloadavg()[0]:.2f}")
    times: dict[str, list[float]] = {k: [] for k in calls}
    for _ in range(args.repeat):
        for k, f in calls.items():
            t0 = time.process_time()
            f()
            times[k].append(time.process_time() - t0)
    base = statistics.median(times["nodal sweep"])
    for k, ts in times.items():
        m = statistics.median(ts)
        print(f"  {k:<14} {m * 1e3:9.3f} ms   {m / base:6.2f}× the nodal sweep")
    print(f"load after {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()
