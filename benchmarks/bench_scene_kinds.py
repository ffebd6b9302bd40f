"""Benchmark: scene simulations against scipy DOP853 on the same equations, at equal error.

Goal (scenes in the time domain): simulations >= 20x faster than scipy's DOP853 at
rtol 1e-8 on the same equations, at equal accuracy.  Three kinds of scene:

* the slider-crank scene (``examples/slider_crank_scene.toml``: one elastic rod,
  a block on a guide);
* the geared FNF six-bar scene (``examples/fnf_sixbar_scene.toml``: two cranks
  geared, a cycle of two turns);
* the dynamic main shaft (``mechcirc.scene.shaft.simulate_shaft`` on the one-side
  sley with the flywheel and Kloss motor of ``examples/sley_flywheel.py``).

For the two scenes, mechcirc's own integrators (``method="rk4"`` and ``"rk8"``, numba,
at several ``steps_per_period``) and scipy's ``solve_ivp(DOP853)`` (``method="DOP853"``: the
same compiled right-hand side, called from solve_ivp, at several rtol) integrate
the same equations; the error of each run is the largest difference of any
element force over the tabulated last cycle, relative to that force's peak,
against a reference run of DOP853 at rtol 1e-13 (a different integrator from
the rk4 runs; for DOP853's own runs it is the same method at 10^5 x tighter
tolerance).  CPU time (``time.process_time``, median of --repeat, warm: numba
compiled before timing) of the whole library call, error estimate off.  The
ratio at equal error is DOP853 at rtol 1e-8 against the cheapest rk4 run whose
error is at most DOP853's.

The dynamic shaft is integrated by scipy DOP853 itself (shooting in θ for the
steady cycle), so there the comparison is mechcirc at its default rtol against
DOP853 at 1e-8, i.e. the same integrator: its error (speed over the cycle,
relative to the mean speed, against rtol 1e-13) and time are printed for the
record; the ratio at equal accuracy is 1 by construction.

Run:  python benchmarks/bench_scene_kinds.py [--repeat 3] [--points 720]
"""

from __future__ import annotations

import argparse
import os
import warnings
from pathlib import Path

import numpy as np
from timing import cpu

ROOT = Path(__file__).resolve().parents[1]
SPP = {"rk4": (6.25, 12.5, 25.0, 50.0, 100.0, 200.0, 400.0, 800.0),
       "rk8": (4.0, 6.0, 8.0, 12.0, 16.0, 25.0, 50.0, 100.0)}
RTOLS = (1e-6, 1e-8, 1e-10, 1e-12)


def force_error(run, ref) -> float:
    """Largest |F - F_ref| over the cycle relative to max |F_ref|, over every element force."""
    worst = 0.0
    for key, f_ref in ref.values.items():
        if key.endswith(".force"):
            peak = float(np.max(np.abs(f_ref)))
            if peak > 0:
                worst = max(worst, float(np.max(np.abs(run.values[key] - f_ref))) / peak)
    return worst


def scene_rows(path, repeat, points):
    from mechcirc.scene import load_scene, motion_model, simulate_scene

    scene = load_scene(str(path))
    model = motion_model(scene)

    def sim(**kw):
        return simulate_scene(scene, model=model, points=points, error_estimate=False, **kw)

    sim(method="rk4")                                   # numba compile / cache load
    ref = sim(method="DOP853", rtol=1e-13)
    rows = []
    for meth, spps in SPP.items():
        for spp in spps:
            t, r = cpu(lambda spp=spp, meth=meth: sim(method=meth, steps_per_period=spp), repeat)
            rows.append((meth, f"{spp:g} steps/period", t, force_error(r, ref), r.nfev))
    for rtol in RTOLS:
        t, r = cpu(lambda rtol=rtol: sim(method="DOP853", rtol=rtol), repeat)
        rows.append(("DOP853", f"rtol {rtol:g}", t, force_error(r, ref), r.nfev))
    return rows


def shaft_rows(repeat):
    from mechcirc.scene import parse_scene
    from mechcirc.scene.shaft import simulate_shaft

    import importlib.util
    spec = importlib.util.spec_from_file_location("sley_flywheel",
                                                  ROOT / "examples" / "sley_flywheel.py")
    ex = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(ex)
    text = (ROOT / "examples" / "mrazek_one_side.toml").read_text(encoding="utf-8")
    scene = parse_scene(text + ex.SHAFT, str(ROOT / "examples" / "mrazek_one_side.toml"))

    def sim(rtol):
        # the rigid mechanism, as measured in docs/performance.md (the elastic shaft,
        # now the default, calls the kernel from Python at every step)
        return simulate_shaft(scene, flywheel=0.1, startup=False, rtol=rtol, rigid=True,
                              method="DOP853")

    ref = sim(1e-13)
    rows = []
    for rtol in (1e-6, 1e-8, 1e-10, 1e-12):
        t, r = cpu(lambda rtol=rtol: sim(rtol), repeat)
        err = float(np.max(np.abs(np.interp(ref.theta, r.theta, r.speed) - ref.speed))
                    / ref.omega_mean)
        who = "mechcirc (default)" if rtol == 1e-10 else "DOP853 (same)"
        rows.append((who, f"rtol {rtol:g}", t, err, 0))
    return rows


def report(name, rows):
    print(f"\n{name}")
    print(f"  {'method':<20} {'setting':<20} {'CPU [ms]':>10} {'error':>9} {'f-evals':>9}")
    for who, setting, t, err, nfev in rows:
        print(f"  {who:<20} {setting:<20} {1e3 * t:>10.2f} {err:>9.1e} {nfev:>9d}")
    dop = next((r for r in rows if r[0] == "DOP853" and r[1] == "rtol 1e-08"), None)
    if dop is None:
        return
    for meth in SPP:
        ok = [r for r in rows if r[0] == meth and r[3] <= dop[3]]
        if not ok:
            print(f"  no {meth} run reaches DOP853 rtol 1e-8's error {dop[3]:.1e}")
            continue
        best = min(ok, key=lambda r: r[2])
        print(f"  at equal error: DOP853 rtol 1e-8 ({dop[3]:.1e}, {1e3 * dop[2]:.1f} ms) / "
              f"{meth} {best[1]} ({best[3]:.1e}, {1e3 * best[2]:.2f} ms) = "
              f"{dop[2] / best[2]:.1f}x")
        # the cost at exactly DOP853's error: log-log between the two runs around it
        rk = sorted((r for r in rows if r[0] == meth), key=lambda r: -r[3])
        for a, b in zip(rk, rk[1:]):
            if b[3] <= dop[3] <= a[3] and a[3] > b[3] > 0:
                f = np.log(a[3] / dop[3]) / np.log(a[3] / b[3])
                t = float(np.exp(np.log(a[2]) + f * np.log(b[2] / a[2])))
                print(f"  interpolated: {meth} at error {dop[3]:.1e} costs {1e3 * t:.2f} ms: "
                      f"{dop[2] / t:.1f}x")
                break


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--points", type=int, default=720, help="tabulated points per cycle")
    args = ap.parse_args(argv)
    warnings.simplefilter("ignore")
    print(f"load average {os.getloadavg()[0]:.2f} on {os.cpu_count()} cores; CPU medians of "
          f"{args.repeat}; error: element forces over the last cycle, against DOP853 rtol 1e-13")
    for name, path in (("slider-crank scene", ROOT / "examples" / "slider_crank_scene.toml"),
                       ("geared FNF six-bar scene", ROOT / "examples" / "fnf_sixbar_scene.toml")):
        report(name, scene_rows(path, args.repeat, args.points))
    print("\ndynamic shaft (one-side sley, J_f = 0.1 kg·m², steady cycle only; error: speed "
          "over the cycle / mean speed)")
    rows = shaft_rows(args.repeat)
    for who, setting, t, err, _ in rows:
        print(f"  {who:<20} {setting:<20} {1e3 * t:>10.1f} ms {err:>9.1e}")
    print("  the shaft is integrated by DOP853 itself: equal error is equal cost (ratio 1)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
