"""Cycle map of the heald scene (issue 21): every crank angle one design of a batch.

``examples/heald_scene.toml`` over ``--points`` crank angles (default 360), 5
harmonics: ``cycle_map`` as shipped (the circuits of all angles formed at once
by build's ratio formulas on the linkage's motion arrays, one batch) against
the reference path in the
same run (``mechcirc.scene.cycle._BATCHED = False``: one ``scene.build`` per
angle, the angles' circuits then one batch too).  CPU time
(``time.process_time``), median of ``--repeats`` alternated runs after a
warm-up; it prints the time per angle (goal ≤ 1 ms), the ratio, and how far the
two maps differ.  It asserts nothing.  Run from the repository root::

    python benchmarks/bench_cycle.py [--points 360] [--repeats 5]
"""

from __future__ import annotations

import argparse
import os
import time
from pathlib import Path

import numpy as np

import mechcirc.scene.cycle as cycle
from mechcirc.scene import load_scene

SCENE = Path(__file__).resolve().parents[1] / "examples" / "heald_scene.toml"


def run(scene, points, batched):
    cycle._BATCHED = batched
    try:
        t0 = time.process_time()
        cmap = cycle.cycle_map(scene, points=points)
        return time.process_time() - t0, cmap
    finally:
        cycle._BATCHED = True


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--points", type=int, default=360)
    ap.add_argument("--repeats", type=int, default=5)
    args = ap.parse_args()
    scene = load_scene(SCENE)
    print(f"{SCENE.name}, {args.points} angles; load {os.getloadavg()[0]:.1f}")
    run(scene, args.points, True)
    run(scene, args.points, False)                       # warm-up: kernels, caches
    times = {True: [], False: []}
    for _ in range(args.repeats):
        for batched in (True, False):
            t, _ = run(scene, args.points, batched)
            times[batched].append(t)
    _, a = run(scene, args.points, True)
    _, b = run(scene, args.points, False)
    fast, slow = (float(np.median(times[k])) * 1e3 / args.points for k in (True, False))
    wa, wb = a.natural_frequencies(), b.natural_frequencies()
    print(f"batched:           {fast:6.3f} ms per angle (goal ≤ 1 ms)")
    print(f"one build a angle: {slow:6.3f} ms per angle; ratio {slow / fast:.1f}x")
    print(f"agreement: resonances {np.nanmax(np.abs(wa - wb) / wb):.1e}, |Q0| "
          f"{np.nanmax(np.abs(a.Q0 - b.Q0) / np.abs(b.Q0)):.1e} (relative); skipped "
          f"{len(a.skipped)} and {len(b.skipped)}; load after {os.getloadavg()[0]:.1f}")


if __name__ == "__main__":
    main()
