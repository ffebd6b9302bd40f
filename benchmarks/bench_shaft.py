"""The elastic dynamic main shaft: the compiled RK4 loop (``method="rk4"``) against scipy's
DOP853 on the same equations (the scene kernel's right-hand side called from Python at every
step), timed in the same run.

Scenes: the elastic slider-crank of tests/scene/test_shaft_elastic.py (Kloss motor, flywheel
0.01 kg·m², process moment) and the cam follower that jumps of tests/scene/test_shaft_cam.py
(contact 1e8 N/m).  Each: the steady cycle and the start-up (slider-crank) or the steady
cycle (cam); the accuracy of each run is its speed's largest gap over the cycle from a
DOP853 run at rtol 1e-12 (relative to ω_s).  The kernels are compiled (or loaded) first;
the times are this process's CPU seconds.

Run from the repository root: ``python benchmarks/bench_shaft.py``.
"""

import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(ROOT / "tests" / "scene"), str(ROOT / "tests")]

import mechcirc._jit as jit  # noqa: E402
from mechcirc.scene.shaft import simulate_shaft, warm_up  # noqa: E402


def timed(fn):
    """(result, CPU seconds of this process: the machine may be shared, wall time varies)."""
    t = time.process_time()
    out = fn()
    return out, time.process_time() - t


def main():
    import test_shaft_cam as cam
    import test_shaft_elastic as sc

    jit.COMPILED = True
    warm_up()
    cases = [("elastic slider-crank", sc.scene, sc.WS, True),
             ("cam follower jump", cam.scene, cam.WS, False)]
    for name, make, ws, startup in cases:
        simulate_shaft(make(), points=90, startup=False)            # compile / load once
        ref = simulate_shaft(make(), points=360, startup=False, method="DOP853", rtol=1e-12)
        print(f"{name}:")
        times = {}
        for label, kw in (("rk4 (compiled)", {}),
                          ("DOP853 rtol 1e-8", dict(method="DOP853", rtol=1e-8)),
                          ("DOP853 rtol 1e-10", dict(method="DOP853", rtol=1e-10))):
            r, t = timed(lambda kw=kw, make=make, up=startup: simulate_shaft(
                make(), points=360, startup=up, **kw))
            times[label] = t
            gap = float(np.max(np.abs(r.speed - ref.speed))) / ws
            print(f"  {label:18s} {t:8.2f} s CPU   speed gap {gap:.2e} of ω_s   start-up "
                  f"{r.startup_time}")
        base = times["rk4 (compiled)"]
        print(f"  speed-up: {times['DOP853 rtol 1e-8'] / base:.1f}× over DOP853 rtol 1e-8, "
              f"{times['DOP853 rtol 1e-10'] / base:.1f}× over rtol 1e-10")


if __name__ == "__main__":
    main()
