"""Model reduction (issue 7 §4): elements kept, sweep time and measured error against the tolerance.

Three circuits, each with the band a designer would ask for:

* ``netlists/stb_heald.mcir`` (15 elements, undamped), band 10 … 1000 rad/s
  (its four resonances and anti-resonances lie in it);
* the illustrative heald scene ``examples/heald_scene.toml`` linearised at
  θ = 40° (20 elements, damped), band 0.5·Ω … 8·Ω = 30 … 480 rad/s;
* a 1,000-element ladder (333 sections of spring ∥ damper and a mass to the
  frame; values log-uniform over 10⁵…10¹⁰ N/m, 1…100 N·s/m, 10⁻⁴…1 kg; seed 0),
  band 1 … 100 rad/s (about ten lightly damped resonances).

For each tolerance T: elements kept, time to reduce, time of a 10⁵-point
sweep of the full and the reduced circuit (best of 3, called alternately), the measured worst
relative error of K over the check grid (2,000 log-spaced points plus two
beside each resonance) and the largest relative shift of a resonance in the
band.  Prints a Markdown table; writes ``benchmarks/bench_reduce.png``.
It asserts nothing.  Run from the repository root::

    python benchmarks/bench_reduce.py [--quick]
"""

from __future__ import annotations

import argparse
import math
import platform
import time
from pathlib import Path

import numpy as np

import mechcirc
from mechcirc.scene import build, load_scene
from mechcirc import simplify

ROOT = Path(__file__).resolve().parents[1]


def ladder(n_sections: int, seed: int = 0):
    rng = np.random.default_rng(seed)
    lines = ["drive V n0 0 velocity=1", "mass m0 n0 0 5.0"]
    for i in range(1, n_sections + 1):
        lines.append(f"spring k{i} n{i - 1} n{i} {10 ** rng.uniform(5, 10)!r}")
        lines.append(f"damper c{i} n{i - 1} n{i} {10 ** rng.uniform(0, 2)!r}")
        lines.append(f"mass m{i} n{i} 0 {10 ** rng.uniform(-4, 0)!r}")
    return mechcirc.parse("\n".join(lines), source="ladder1000.mcir")


def interleaved(fa, fb, repeats=3):
    """Best wall times [s] of ``fa`` and ``fb``, called alternately (load slows both alike)."""
    ta = tb = math.inf
    for _ in range(repeats):
        t0 = time.perf_counter()
        fa()
        t1 = time.perf_counter()
        fb()
        t2 = time.perf_counter()
        ta, tb = min(ta, t1 - t0), min(tb, t2 - t1)
    return ta, tb


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--quick", action="store_true", help="three tolerances only")
    args = ap.parse_args()
    tols = (1e-9, 1e-3, 1e-1) if args.quick else (1e-9, 1e-6, 1e-3, 1e-2, 1e-1)
    scene = load_scene(ROOT / "examples" / "heald_scene.toml")
    cases = [
        ("stb_heald.mcir", mechcirc.load(ROOT / "netlists" / "stb_heald.mcir"), (10.0, 1000.0)),
        ("heald scene @40°", build(scene, math.radians(40.0)).circuit,
         (0.5 * scene.omega_shaft, 8 * scene.omega_shaft)),
        ("ladder, 1,000 elements", ladder(333), (1.0, 100.0)),
    ]
    import os

    print(f"python {platform.python_version()}, numpy {np.__version__}, "
          f"{platform.machine()}, {os.cpu_count()} CPUs, load average "
          f"{', '.join(f'{x:.1f}' for x in os.getloadavg())} at the start")
    print("| circuit | band [rad/s] | T | elements kept | reduce [s] | sweep 10⁵ pts full → "
          "reduced [ms] | measured worst error | largest resonance shift |")
    print("|---|---|---|---|---|---|---|---|")
    rows = []
    for label, circuit, band in cases:
        omega_sweep = np.geomspace(band[0], band[1], 100_000)
        for tol in tols:
            t0 = time.perf_counter()
            r = simplify(circuit, band, tol)
            t_red = time.perf_counter() - t0
            t_full, t_sw = interleaved(lambda: circuit.sweep(omega_sweep),
                                       lambda: r.circuit.sweep(omega_sweep))
            shifts = [abs(s["relative_shift"]) for s in r.shifts if s["relative_shift"] is not None]
            gone = sum(1 for s in r.shifts if s["reduced"] is None)
            shift = (f"{max(shifts):.1e}" if shifts else "none in band") + \
                (f" ({gone} gone)" if gone else "")
            print(f"| {label} | {band[0]:g} … {band[1]:g} | {tol:g} | {r.elements_after} / "
                  f"{r.elements_before} | {t_red:.2f} | {1e3 * t_full:.1f} → {1e3 * t_sw:.1f} | "
                  f"{r.error:.2e} | {shift} |")
            rows.append((label, tol, r.elements_after, r.elements_before, t_full, t_sw, r.error))
    _plot(rows, ROOT / "benchmarks" / "bench_reduce.png")
    print("wrote benchmarks/bench_reduce.png")


def _plot(rows, path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (a1, a2) = plt.subplots(1, 2, figsize=(10, 4))
    for label in dict.fromkeys(r[0] for r in rows):
        sel = [r for r in rows if r[0] == label]
        tol = [r[1] for r in sel]
        a1.semilogx(tol, [r[2] / r[3] for r in sel], "o-", label=label)
        err = [max(r[6], 1e-17) for r in sel]
        a2.loglog(err, [r[5] / r[4] for r in sel], "o-", label=label)
    a1.set_xlabel("tolerance T")
    a1.set_ylabel("elements kept / elements")
    a1.set_ylim(0, 1.05)
    a2.set_xlabel("measured worst relative error of K in the band (0 drawn at 1e-17)")
    a2.set_ylabel("sweep time reduced / full")
    for a in (a1, a2):
        a.grid(True, which="both", alpha=0.3)
        a.legend(fontsize=7)
    fig.suptitle("mechcirc reduce: size and speed against measured error")
    fig.tight_layout()
    fig.savefig(path, dpi=110)


if __name__ == "__main__":
    main()
