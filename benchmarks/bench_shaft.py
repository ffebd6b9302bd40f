"""The dynamic main shaft: the scene's compiled stepper (``method="rk4"`` / ``"rk8"``) against
scipy's DOP853 at rtol 1e-8 on the same equations (the same kernel right-hand side, called
from Python at every step), at equal accuracy, timed in the same run.

Cases (steady cycle only, 360 samples):

* the elastic slider-crank of tests/scene/test_shaft_elastic.py (Kloss motor, flywheel
  0.01 kg·m², a process moment window on the crank);
* the cam follower whose contact opens (tests/scene/test_shaft_cam.py, contact 1e8 N/m);
* the rigid one-side sley on a 0.1 kg·m² flywheel (``rigid=True``; examples/sley_flywheel.py);
* the elastic slider-crank with a 2 µm dead zone in its rod (tests/scene/test_shaft_rk8.py:
  four impacts a cycle).

``--rigid`` runs every case rigid (``rigid=True``).  Each case also times the default
(``method=None``: RK4 at 100 steps per period with elastic parts, rk8 at 16 rigid).

The error of a run is the largest gap of its speed over the cycle from a DOP853 run at
rtol 1e-12, relative to that run's mean speed.  Each time is the median of ``--repeat``
runs' CPU seconds of this process (``time.process_time``; the machine may be shared), the
kernels compiled (or loaded) first.  The ratio at equal accuracy: DOP853 rtol 1e-8 against
the cheapest rk4/rk8 run whose error is at most DOP853's.

Run from the repository root: ``python benchmarks/bench_shaft.py [--repeat N]``.
"""

import argparse
import importlib.util
import os
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(ROOT / "tests" / "scene"), str(ROOT / "tests")]

import mechcirc._jit as jit  # noqa: E402
from mechcirc.scene import parse_scene  # noqa: E402
from mechcirc.scene.shaft import simulate_shaft, warm_up  # noqa: E402
from timing import cpu  # noqa: E402


def sley():
    spec = importlib.util.spec_from_file_location("sley_flywheel",
                                                  ROOT / "examples" / "sley_flywheel.py")
    ex = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(ex)
    path = ROOT / "examples" / "mrazek_one_side.toml"
    return parse_scene(path.read_text(encoding="utf-8") + ex.SHAFT, str(path))


def cases():
    import test_shaft_cam as cam
    import test_shaft_elastic as sc
    import test_shaft_rk8 as gap

    return [("elastic slider-crank", sc.scene, {}, (4, 6, 8, 16), (50, 100, 200)),
            ("cam follower, contact opens", cam.scene, {}, (8, 16, 32, 64), (100, 200, 400)),
            ("rigid one-side sley", sley, dict(flywheel=0.1, rigid=True), (4, 8, 16),
             (8, 16, 32, 100)),
            ("slider-crank, 2 µm dead zone", gap.gap_scene, {}, (8, 12, 16, 24, 32),
             (50, 100, 200))]


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--case", type=int, action="append", help="only these cases (0-3)")
    ap.add_argument("--rigid", action="store_true", help="every case rigid")
    args = ap.parse_args(argv)
    jit.COMPILED = True
    warm_up()
    print(f"load average {os.getloadavg()[0]:.2f} on {os.cpu_count()} cores; CPU medians of "
          f"{args.repeat}; error: speed over the cycle / mean speed, against DOP853 rtol 1e-12")
    for k, (name, make, kw, spp8, spp4) in enumerate(cases()):
        if args.case and k not in args.case:
            continue
        scene = make()
        kw = dict(kw, rigid=True) if args.rigid else kw
        simulate_shaft(scene, points=90, startup=False, method="rk8", **kw)   # compile once
        ref = simulate_shaft(scene, points=360, startup=False, method="DOP853", rtol=1e-12, **kw)
        print(f"\n{name}{' (rigid)' if args.rigid else ''}\n  {'method':8s} {'setting':22s} {'CPU [ms]':>10s} {'error':>9s}")
        rows = []
        runs = [("DOP853", "rtol 1e-8", dict(method="DOP853", rtol=1e-8)),
                ("default", "method=None", {})]
        runs += [("rk8", f"{s} steps/period", dict(method="rk8", steps_per_period=s))
                 for s in spp8]
        runs += [("rk4", f"{s} steps/period", dict(method="rk4", steps_per_period=s))
                 for s in spp4]
        for method, setting, opts in runs:
            t, r = cpu(lambda opts=opts, scene=scene, kw=kw: simulate_shaft(
                scene, points=360, startup=False, **opts, **kw), args.repeat)
            err = float(np.max(np.abs(r.speed - ref.speed))) / ref.omega_mean
            rows.append((method, setting, t, err))
            print(f"  {method:8s} {setting:22s} {t * 1e3:10.2f} {err:9.1e}")
        _, _, tb, eb = rows[0]
        for m in ("rk8", "rk4"):
            ok = [r for r in rows if r[0] == m and r[3] <= eb]
            if not ok:
                print(f"  {m}: no run reached DOP853 rtol 1e-8's error {eb:.1e}")
                continue
            best = min(ok, key=lambda r: r[2])
            print(f"  at equal error: DOP853 rtol 1e-8 ({eb:.1e}, {tb * 1e3:.1f} ms) / {m} "
                  f"{best[1]} ({best[3]:.1e}, {best[2] * 1e3:.2f} ms) = {tb / best[2]:.1f}x")


if __name__ == "__main__":
    main()
