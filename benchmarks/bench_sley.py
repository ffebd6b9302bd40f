"""Benchmark: the sley time-domain model, speed against error (issue 5 §4).

Problem: one-side drive, Table 1 variant 3 (clearance 0.001 rad, beat-up moment
500 N·m), 5 revolutions, 7200 output points per revolution.

* Reference: ``solve_ivp`` DOP853 at rtol 1e-10 (the compiled scene right-hand side).
* Baseline of the goal: ``solve_ivp`` DOP853 at rtol 1e-8, measured in the same
  run.  Goal: the default method ≥ 50× faster at a peak error ≤ 0.1 %.
* Baseline and every method and tolerance offered: CPU time per simulated revolution
  (the whole ``simulate`` call, median of several; the scipy runs without their own
  error estimate, i.e. one run each; every rk4 run with its estimate; the default's
  step chosen for the accuracy goal: 25 steps per period, else 50) and the relative error of the
  extrema of ε4P and M2V (and ε2P) against the reference.
* Cold time of the numba method in a fresh process: with numba's on-disk cache
  present, and with an empty cache directory (full compilation).
* Batch: the 14 presets with ``simulate_batch`` on every core against one by one.

Run:  python benchmarks/bench_sley.py [--plot benchmarks/bench_sley.png]
"""

from __future__ import annotations

import argparse
import os
import platform
import subprocess
import sys
import tempfile
import warnings

import numpy as np
from timing import cpu, wall

VARIANT = ("one-side", 3)
REVS = 5


def errors(res, ref):
    out = {}
    for key in ("eps4P", "M2V", "eps2P"):
        scale = max(abs(v) for v in ref.extrema[key])
        out[key] = max(abs(a - b) for a, b in zip(res.extrema[key], ref.extrema[key])) / scale
    return out


def cold_call(env_extra: dict) -> float:
    code = ("import time; t = time.perf_counter(); c = time.process_time(); "
            "from mechcirc.sley import simulate; "
            "r = simulate('one-side', 3, 5); "
            "print(time.perf_counter() - t, time.process_time() - c, r.backend)")
    env = dict(os.environ, **env_extra)
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True, env=env)
    secs, cpu, backend = out.stdout.split()
    return float(secs), float(cpu), backend


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--plot", default="benchmarks/bench_sley.png", help="speed-vs-error plot")
    ap.add_argument("--no-cold", action="store_true", help="skip the fresh-process timings")
    ap.add_argument("--no-batch", action="store_true", help="skip the batch timings")
    args = ap.parse_args()

    import numba  # noqa: F401  (the benchmark is about the compiled method)
    import scipy

    from mechcirc.sley import simulate, simulate_batch

    print(f"python {platform.python_version()}, numpy {np.__version__}, scipy "
          f"{scipy.__version__}, numba {numba.__version__}, {platform.machine()}, "
          f"{os.cpu_count()} cores")
    warnings.simplefilter("ignore")
    print(f"load average {os.getloadavg()[0]:.1f}")
    if not args.no_cold:
        cold_report()

    drive, variant = VARIANT
    # both kernels compiled here if numba's cache lacks them: by default an uncached kernel
    # runs its Python copy, and a baseline on the Python right-hand side inflates the ratio
    import mechcirc._jit as jit
    jit.COMPILED = True
    simulate(drive, variant, 1)                      # warm: compile / load cache once
    simulate(drive, variant, 1, method="DOP853", rtol=1e-3, error_estimate=False)
    # the goal's baseline: one DOP853 run at rtol 1e-8 (no error estimate of its own)
    t_ref, ref = cpu(lambda: simulate(drive, variant, REVS, method="DOP853", rtol=1e-10,
                                        error_estimate=False), 1)
    t_base, base = cpu(lambda: simulate(drive, variant, REVS, method="DOP853", rtol=1e-8,
                                          error_estimate=False), 3)
    t_def, res = cpu(lambda: simulate(drive, variant, REVS), 20)
    return rest(args, drive, variant, t_ref, ref, t_base, base, t_def, res, simulate,
                simulate_batch)


def cold_report():
    cached, cached_cpu, backend = cold_call({})
    with tempfile.TemporaryDirectory() as empty:
        compiled, compiled_cpu, _ = cold_call({"NUMBA_CACHE_DIR": empty})
    print(f"load average {os.getloadavg()[0]:.1f}; cold first call in a fresh process "
          f"({backend}), 5 revolutions incl. imports: {cached:.2f} s ({cached_cpu:.2f} s CPU) "
          f"with numba's cache, {compiled:.2f} s ({compiled_cpu:.2f} s CPU) compiling from "
          "scratch")


def rest(args, drive, variant, t_ref, ref, t_base, base, t_def, res, simulate, simulate_batch):
    from mechcirc.sley.simulation import table_error

    e_def = errors(res, ref)
    print(f"\nreference DOP853 rtol 1e-10: {t_ref:.3f} s, nfev {ref.nfev}")
    print(f"baseline  DOP853 rtol 1e-8 : {t_base * 1e3:.1f} ms (median of 3), nfev {base.nfev}")
    spp = next(n for n in res.notes if n.startswith("RK4 step"))
    spp = spp.split(" per period of the fastest")[0].rsplit(", ", 1)[-1]
    print(f"default   rk4 ({res.backend}, {spp} steps/period chosen, with its error estimate "
          f"{res.error_estimate:.1e}): {t_def * 1e3:.2f} ms (median of 20), {res.n_steps} steps "
          "(both runs)")
    ok = t_base / t_def >= 50 and max(e_def["eps4P"], e_def["M2V"]) <= 1e-3
    print(f"speed-up default / baseline: {t_base / t_def:.0f}x; peak error eps4P "
          f"{e_def['eps4P']:.1e}, M2V {e_def['M2V']:.1e} (eps2P {e_def['eps2P']:.1e}); "
          f"goal >= 50x at <= 0.1 %: {'met' if ok else 'NOT met'}")
    print(f"transfer-function table vs FourBar closed form: {table_error()}")

    rows = []
    for spp in (20, 30, 40, 50, 80, 120, 200):
        t, r = cpu(lambda spp=spp: simulate(drive, variant, REVS, steps_per_period=spp), 10)
        rows.append(("rk4 numba", f"{spp} steps/period", t, r.nfev, errors(r, ref)))
    rows.append(("rk4 numba", "default", t_def, res.nfev, e_def))
    # rk8 (DOP853's 8th-order formula at a fixed step, quintic output), with its estimate
    for spp in (4, 6, 8, 12, 16, None):
        t, r = cpu(lambda spp=spp: simulate(drive, variant, REVS, method="rk8",
                                              steps_per_period=spp), 10)
        e = errors(r, ref)
        rows.append(("rk8 numba", "default" if spp is None else f"{spp} steps/period", t,
                     r.nfev, e))
        print(f"rk8 {rows[-1][1]}: {t_base / t:.0f}x the baseline, peak error "
              f"{max(e['eps4P'], e['M2V']):.1e}, its estimate {r.error_estimate:.1e}"
              f" ({'bounds' if r.error_estimate >= max(e.values()) else 'BELOW'} the error)")
    t, r = cpu(lambda: simulate(drive, variant, REVS, method="rk4-python"), 1)
    rows.append(("rk4 python", "default", t, r.nfev, errors(r, ref)))
    for method, tols in (("DOP853", (1e-6, 1e-8, 1e-10)), ("RK45", (1e-6, 1e-8)),
                         ("LSODA", (1e-6, 1e-8))):
        for tol in tols:
            if method == "DOP853" and tol == 1e-10:
                t, r = t_ref, ref
            elif method == "DOP853" and tol == 1e-8:
                t, r = t_base, base
            else:
                t, r = cpu(lambda m=method, tol=tol: simulate(drive, variant, REVS, method=m,
                                                                rtol=tol, error_estimate=False),
                             1)
            rows.append((method, f"rtol {tol:g}", t, r.nfev, errors(r, ref)))
    print(f"\n{'method':<11} {'setting':<17} {'ms/rev':>9} {'vs base':>8} {'nfev':>8} "
          f"{'err eps4P':>10} {'err M2V':>10} {'err eps2P':>10}")
    for name, setting, t, nfev, e in rows:
        print(f"{name:<11} {setting:<17} {t / REVS * 1e3:>9.3f} {t_base / t:>7.1f}x {nfev:>8d} "
              f"{e['eps4P']:>10.1e} {e['M2V']:>10.1e} {e['eps2P']:>10.1e}")

    for revs in () if args.no_batch else (REVS, 100):
        t_seq, _ = wall(lambda revs=revs: simulate_batch(revolutions=revs, processes=1))
        t_par, _ = wall(lambda revs=revs: simulate_batch(revolutions=revs))
        print(f"batch, 14 presets x {revs} revolutions: one by one {t_seq:.2f} s, "
              f"simulate_batch on {os.cpu_count()} cores {t_par:.2f} s "
              f"(process start-up and numba cache loads included)")

    if args.plot:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        fig, ax = plt.subplots(figsize=(7, 5))
        for name in dict.fromkeys(r[0] for r in rows):
            sel = [r for r in rows if r[0] == name]
            err = [max(r[4]["eps4P"], r[4]["M2V"]) for r in sel]
            ax.plot([r[2] / REVS * 1e3 for r in sel], np.maximum(err, 1e-12), "o-", label=name)
            for r, e in zip(sel, err):
                ax.annotate(r[1], (r[2] / REVS * 1e3, max(e, 1e-12)), fontsize=6)
        ax.axhline(1e-3, color="k", lw=0.6, ls="--", label="0.1 % goal")
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("CPU time per simulated revolution [ms]")
        ax.set_ylabel("relative error of extrema of ε4P, M2V")
        ax.set_title("sley one-side variant 3, 5 revolutions: speed vs error\n"
                     "(reference solve_ivp DOP853 rtol 1e-10)")
        ax.grid(alpha=0.3, which="both")
        ax.legend(fontsize=8)
        fig.savefig(args.plot, dpi=120, bbox_inches="tight")
        print(f"plot: {args.plot}")


if __name__ == "__main__":
    main()
