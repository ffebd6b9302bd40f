"""Benchmark: the scene path on the Mrázek one-side scene against the retired sley kernel.

Issue 13 §1 goal: the scene time domain (one Lagrange II kernel for any scene,
``mechcirc.scene.simulate_scene``, which ``mechcirc.sley.simulate`` now runs) within
1.5× of the dedicated hand-written sley kernel it replaced, at the same step rule
and error.  The hand-written kernel is kept as ``benchmarks/_sley_kernel_baseline.py``
(the retired ``mechcirc/sley/_kernels.py`` and its RK4 driver) for this comparison.

Problem: Table 1 variant 3 (clearance 0.001 rad, beat-up 500 N·m), 5
revolutions, 7200 output points.  Both use classical RK4 at the same step
(50 steps per period of the fastest linearised mode: the same integer number
of steps per revolution, checked).  The scene kernel also cuts a step where a
clearance edge is crossed or the beat-up window opens or closes (about 5 %
more evaluations), so it is the more accurate of the two (the difference of
their extrema is printed: about the retired kernel's error).  Timed, interleaved, median of
N repetitions, both compiled by numba and warm:

* kernel: the RK4 integration of the 5 revolutions;
* total: the scene's whole library call (set-up — kinematic tables, step rule —
  included; the error estimate switched off, since it is a second, optional run)
  against the baseline's kernel (its set-up was not separable from the old module).

Run:  python benchmarks/bench_scene_sley.py [--repeat 7]
"""

from __future__ import annotations

import argparse
import math
import os
import statistics
import sys
import time
import warnings


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=7)
    args = ap.parse_args(argv)
    sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
    import _sley_kernel_baseline as base

    from mechcirc.sley import preset, simulate
    from mechcirc.sley.linear import max_rate

    warnings.simplefilter("ignore")
    params = preset("one-side", 3)
    # the retired step rule: 50 steps per period of the fastest linearised mode (the scene
    # rounds it up to an even number, so that the estimate's run has half as many)
    per_rev = max(int(math.ceil(max_rate(params) * 50 / params.omega)), 16)
    a = simulate("one-side", 3, error_estimate=False)          # compile / cache load
    assert a.n_steps // 5 - per_rev in (0, 1), (a.n_steps, per_rev)
    per_rev = a.n_steps // 5
    base.run(params, 5, 7200, per_rev)
    k_scene, k_base, t_scene = [], [], []
    for _ in range(args.repeat):
        t0 = time.perf_counter()
        a = simulate("one-side", 3, error_estimate=False)
        t_scene.append(time.perf_counter() - t0)
        k_scene.append(a.wall_time)
        ext, wall = base.run(params, 5, 7200, per_rev)
        k_base.append(wall)
    assert a.n_steps == 5 * per_rev, f"different step rules: {a.n_steps} != {5 * per_rev}"
    def gap(x, y):
        return max(abs(x[k][j] - y[k][j]) / max(map(abs, y[k])) for k in ext for j in (0, 1))

    worst = gap(a.extrema, ext)
    # Which of the two is the more accurate: both against DOP853 at rtol 1e-12.
    ref = simulate("one-side", 3, method="DOP853", rtol=1e-12, error_estimate=False).extrema
    med = statistics.median
    print(f"load average {os.getloadavg()[0]:.2f} on {os.cpu_count()} cores; "
          f"{a.n_steps} RK4 steps each; largest relative difference of the extrema {worst:.1e}")
    print(f"against DOP853 at rtol 1e-12: scene {gap(a.extrema, ref):.1e}, "
          f"retired kernel {gap(ext, ref):.1e}")
    print(f"{'':<8} {'scene [ms]':>11} {'sley [ms]':>10} {'ratio':>7}")
    print(f"{'kernel':<8} {1e3 * med(k_scene):>11.2f} {1e3 * med(k_base):>10.2f} "
          f"{med(k_scene) / med(k_base):>7.2f}")
    print(f"{'total':<8} {1e3 * med(t_scene):>11.1f} {1e3 * med(k_base):>10.1f} "
          f"{med(t_scene) / med(k_base):>7.2f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
