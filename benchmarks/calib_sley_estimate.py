"""How well the RK4 error estimate bounds the true error (sley presets and scenes).

For each case: the RK4 result's ``error_estimate`` (change of the extrema between
the returned run at the step and a run at twice the step) and ``periodicity``,
and the true error of the returned run's extrema against DOP853 at rtol 1e-12
(the reference, an independent integrator on the same equations), measured the
same way as the estimate (every output, relative to its largest magnitude).
The goal: estimate / true >= 1.  ``spp``: the steps per period of the returned run (the
default chooses 25, or 50 when the estimate at 25 exceeds 1e-3).
Run: python benchmarks/calib_sley_estimate.py [--method rk4|rk8] [--sweep]
(``--method rk8``: the 8th-order fixed-step method with its quintic output,
default steps 8 or 16 per period.)
"""

import sys
import warnings
from pathlib import Path

from mechcirc.scene import load_scene, simulate_scene
from mechcirc.scene.simulation import _rel_change
from mechcirc.sley.scenes import preset_scene

EX = Path(__file__).resolve().parent.parent / "examples"
CASES = [
    ("one-side v1", lambda: preset_scene("one-side", 1), {}),
    ("one-side v3", lambda: preset_scene("one-side", 3), {}),
    ("both-sides v3", lambda: preset_scene("both-sides", 3), {}),
    ("one-side v3, 6 steps/period", lambda: preset_scene("one-side", 3),
     dict(steps_per_period=6)),
    ("one-side v3, C2=C4=1e7, R=1", lambda: preset_scene("one-side", 3, C2=1e7, C4=1e7),
     dict(revolutions=1)),
    ("one-side v1, omega=1000", lambda: preset_scene("one-side", 1), dict(omega=1000.0)),
]
for name in ("heald_scene", "slider_crank_scene", "fnf_sixbar_scene", "cam_heald_scene"):
    if (EX / f"{name}.toml").exists():
        CASES.append((name, lambda n=name: load_scene(EX / f"{n}.toml"), {}))


METHOD = sys.argv[sys.argv.index("--method") + 1] if "--method" in sys.argv else "rk4"
if METHOD not in ("rk4", "rk8"):
    raise SystemExit(f"--method must be rk4 or rk8, not {METHOD!r}")
print(f"method {METHOD}")
print(f"{'case':<32} {'spp':>4} {'estimate':>9} {'true err':>9} {'est/true':>9} {'periodic':>9}"
      "  warned")
for label, make, kw in CASES:
    scene = make()
    with warnings.catch_warnings(record=True) as w:
        warnings.simplefilter("always")
        r = simulate_scene(scene, **kw, method=METHOD)
    kw.pop("steps_per_period", None)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        ref = simulate_scene(scene, **kw, method="DOP853", rtol=1e-12, error_estimate=False)
    true = _rel_change(r.extrema, ref.extrema)
    per = "-" if r.periodicity is None else f"{r.periodicity:9.2g}"
    spp = next(n for n in r.notes if n.startswith(("RK4 step", "RK8 step")))
    spp = spp.split(" per period of the fastest")[0].rsplit(", ", 1)[-1]   # the one returned
    print(f"{label:<32} {spp:>4} {r.error_estimate:9.2g} {true:9.2g} "
          f"{r.error_estimate / true:9.3g} "
          f"{per:>9}  {len(w) > 0}", flush=True)

if __name__ == "__main__" and "--sweep" in __import__("sys").argv:
    # Every preset (2 revolutions, 1800 points) at 8, 20, 50, 100 steps per period.
    print("\nsweep: drive variant spp  estimate  true  est/true")
    ratios = []
    for drive in ("one-side", "both-sides"):
        for variant in range(1, 8):
            scene = preset_scene(drive, variant)
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                ref = simulate_scene(scene, revolutions=2, points=1800, method="DOP853",
                                     rtol=1e-12, error_estimate=False)
                for spp in (8, 20, 50, 100):
                    r = simulate_scene(scene, revolutions=2, points=1800, steps_per_period=spp,
                                       method=METHOD)
                    true = _rel_change(r.extrema, ref.extrema)
                    ratios.append(r.error_estimate / true)
                    print(f"{drive:<10} {variant} {spp:3d} {r.error_estimate:9.2g} {true:9.2g} "
                          f"{ratios[-1]:7.3g}", flush=True)
    print(f"{len(ratios)} cases: est/true min {min(ratios):.3g}, "
          f"below 1 in {sum(x < 1 for x in ratios)}")
