"""Benchmark: linkages with sliders (prismatic joints), closed-form dyads against Newton.

Measured in one run, on the same machine, per position at 360 and 3,600
positions over one turn:

* an offset slider-crank (r = 40, l = 150, e = 10, an RRP dyad) and the
  crank-shaper quick return (``examples/quick_return.toml``: an RPR and an
  RRP dyad): ``Linkage.motion`` (the closed-form dyads, vectorised numpy)
  against what sliders ran on before the closed forms, ``method="newton"``
  (the compiled Newton loop when numba is installed) and the batched numpy
  Newton (``mechcirc._jit.COMPILED = False``);
* the slider-crank's closed form x = r cos θ + sqrt(l² − (r sin θ + e)²) with
  its two derivatives, vectorised numpy: the floor;
* the FNF six-bar (revolute, a class-III group: compiled Newton) for scale.

Medians of several repeats; the machine is shared, so read the ratios.

Run:  python benchmarks/bench_sliders.py
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from mechcirc import _jit
from mechcirc.kinematics import load_linkage, parse_linkage
from timing import wall

ROOT = Path(__file__).resolve().parents[1]
R, L, E = 40.0, 150.0, 10.0
SLIDER_CRANK = f"""
[points]
A = [0.0, 0.0]
B = [{R!r}, 0.0]
C = [{R + math.sqrt(L * L - E * E)!r}, {-E!r}]
G1 = [0.0, {-E!r}]
G2 = [100.0, {-E!r}]
[ground]
points = ["A", "G1", "G2"]
[links]
crank = ["A", "B"]
rod = ["B", "C"]
block = ["C"]
[[sliders]]
link = "block"
guide = "ground"
line = ["G1", "G2"]
[[cranks]]
link = "crank"
omega = 10.0
"""


def closed_form(th, w=10.0):
    h, h1, h2 = R * np.sin(th) + E, R * np.cos(th), -R * np.sin(th)
    S = np.sqrt(L * L - h * h)
    x1 = -R * np.sin(th) - h * h1 / S
    x2 = -R * np.cos(th) - (h1 * h1 + h * h2) / S - (h * h1) ** 2 / S ** 3
    return R * np.cos(th) + S, w * x1, w * w * x2


def main() -> None:
    cases = {"slider-crank": parse_linkage(SLIDER_CRANK, "slider-crank"),
             "quick return": load_linkage(ROOT / "examples" / "quick_return.toml"),
             "FNF six-bar": load_linkage(ROOT / "examples" / "fnf_sixbar.toml")}
    print("per position [µs]        N      dyads   compiled Newton   numpy Newton   "
          "Newton/dyads   closed form")
    for N in (360, 3600):
        th = np.linspace(0.0, 2 * math.pi, N)
        for name, lk in cases.items():
            def run(lk=lk, th=th, method="auto"):
                return lk.motion(th, method=method).points
            _jit.COMPILED = None
            run(method="newton")                   # compile / load the cache once
            dyads = wall(run, 7)[0] if lk.solver == "dyads" else math.nan
            fast = wall(lambda run=run: run(method="newton"), 7)[0]
            _jit.COMPILED = False
            slow = wall(lambda run=run: run(method="newton"), 3)[0]
            _jit.COMPILED = None
            floor = wall(lambda th=th: closed_form(th), 7)[0] if name == "slider-crank" \
                else None
            extra = f"{floor / N * 1e6:10.2f}" if floor is not None else ""
            print(f"{name:<18} {N:6d} {dyads / N * 1e6:10.1f} {fast / N * 1e6:17.1f} "
                  f"{slow / N * 1e6:14.1f} {fast / dyads:13.1f}x  {extra}")
    lk = cases["slider-crank"]
    m = lk.motion(np.linspace(0.0, 2 * math.pi, 3600))
    k = m.point_names.index("C")
    x, v, a = closed_form(m.theta)
    print(f"agreement with the closed form at 3,600 positions: "
          f"x {np.max(np.abs(m.points[:, k, 0] - x)):.1e}, v {np.max(np.abs(m.velocities[:, k, 0] - v)):.1e}, "
          f"a {np.max(np.abs(m.accelerations[:, k, 0] - a)):.1e} (mm, mm/s, mm/s²)")


if __name__ == "__main__":
    main()
