"""Benchmark: the scene path on the Mrázek one-side scene against the dedicated sley kernel.

Issue 13 §1 goal: the scene time domain (one Lagrange II kernel for any scene,
``mechcirc.scene.simulate_scene``) within 1.5× of today's dedicated sley kernel
(``mechcirc.sley._kernels``) at the same step rule and error.

Problem: Table 1 variant 3 (clearance 0.001 rad, beat-up 500 N·m), 5
revolutions, 7200 output points.  Both use classical RK4 at the same step
(50 steps per period of the fastest linearised mode: the same integer number
of steps per revolution, checked) and agree to ~1e-9 relative in every
extremum (printed), so the error is the same.  Timed, interleaved, median of
N repetitions, both compiled by numba and warm:

* kernel: the RK4 integration of the 5 revolutions (``wall_time`` of each result);
* total: the whole library call (set-up — kinematic tables, step rule — included;
  the error estimate of both is switched off, since it is a second, optional run).

Run:  python benchmarks/bench_scene_sley.py [--repeat 7]
"""

from __future__ import annotations

import argparse
import os
import statistics
import time
import warnings


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=7)
    args = ap.parse_args(argv)
    from mechcirc.scene.simulation import simulate_scene
    from mechcirc.sley import simulate
    from mechcirc.sley.scenes import preset_scene

    warnings.simplefilter("ignore")
    scene = preset_scene("one-side", 3)
    from mechcirc.scene.motion import motion_model

    model = motion_model(scene)
    simulate_scene(scene, model=model, error_estimate=False)          # compile / cache load
    simulate("one-side", 3, error_estimate=False)
    k_scene, k_sley, t_scene, t_sley = [], [], [], []
    for _ in range(args.repeat):
        t0 = time.perf_counter()
        a = simulate_scene(scene, error_estimate=False)
        t_scene.append(time.perf_counter() - t0)
        k_scene.append(a.wall_time)
        t0 = time.perf_counter()
        b = simulate("one-side", 3, error_estimate=False)
        t_sley.append(time.perf_counter() - t0)
        k_sley.append(b.wall_time)
    assert a.steps_per_revolution * a.revolution == b.n_steps, "different step rules"
    worst = max(abs(a.extrema[k][j] - b.extrema[k][j]) / max(map(abs, b.extrema[k]))
                for k in b.extrema for j in (0, 1))
    med = statistics.median
    print(f"load average {os.getloadavg()[0]:.2f} on {os.cpu_count()} cores; "
          f"{b.n_steps} RK4 steps each; largest relative difference of the extrema {worst:.1e}")
    print(f"{'':<8} {'scene [ms]':>11} {'sley [ms]':>10} {'ratio':>7}")
    print(f"{'kernel':<8} {1e3 * med(k_scene):>11.2f} {1e3 * med(k_sley):>10.2f} "
          f"{med(k_scene) / med(k_sley):>7.2f}")
    print(f"{'total':<8} {1e3 * med(t_scene):>11.1f} {1e3 * med(t_sley):>10.1f} "
          f"{med(t_scene) / med(t_sley):>7.2f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
