"""The illustrative heald motion (examples/heald_scene.toml) as a designer would read it.

1. At one crank angle: the rigid parts, each element's velocity ratio to the
   drive, and the resonances of the circuit mechcirc derives.
2. A cross-check of that circuit by energy: the reflected inertia of the first
   rigid part, Σ m_i (v_i/ω)² + Σ J_j (ω_j/ω)², from central differences of
   the linkage's *positions* (not its velocities).
3. Over the cycle: the range of each resonance, where one meets a harmonic of
   the shaft speed, and the largest |Q0| at each harmonic.
4. Model only what the scene needs: 'reduce' on the circuit at that angle.

Run from the repository root:  python examples/heald_scene.py
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from mechcirc.scene import build, load_scene
from mechcirc.scene.cycle import cycle_map
from mechcirc import simplify

SCENE = Path(__file__).resolve().parent / "heald_scene.toml"
THETA_DEG = 40.0


def main() -> None:
    scene = load_scene(SCENE)
    theta = math.radians(THETA_DEG)
    model = build(scene, theta)
    print(f"scene {scene.name!r}: {len(scene.masses)} masses, {len(scene.elastic)} elastic "
          f"links, {len(scene.loads)} load; shaft Ω = {scene.omega_shaft:g} rad/s")
    print(f"\n1. at θ = {THETA_DEG:g}° from the pose")
    for node, part in model.parts.items():
        print(f"   node {node:<7} {', '.join(part)}")
    for name, r in model.ratios.items():
        print(f"   ratio {name:<7} {r: .6f}")
    found = model.circuit.resonances()
    for r in found:
        print(f"   {r.kind:<14} {r.omega:9.2f} rad/s ({r.f_hz:7.2f} Hz), zeta {r.zeta:.4f}")

    # 2. reflected inertia of the drive's rigid part by central differences of positions
    first = model.circuit.drive.n1
    h = 1e-5
    lo, hi = scene.linkage.solve(np.array([theta - h, theta + h]))
    L = scene.length_scale
    fd = 0.0
    for m in scene.masses:
        if m.kind == "mass" and scene.part_of_point(m.point) == 0:
            v = (hi.points[m.point] - lo.points[m.point]) * L / (2 * h)
            fd += m.value * float(v @ v)
        elif m.kind == "inertia" and m.link in model.parts[first]:
            a, b = scene.linkage.links[m.link][:2]

            def ang(s):
                d = s.points[b] - s.points[a]
                return math.atan2(d[1], d[0])

            fd += m.value * ((ang(hi) - ang(lo)) / (2 * h)) ** 2
    circ = sum(e.value * e.eta for e in model.circuit.elements
               if e.kind == "mass" and e.n1 == first)
    print(f"\n2. reflected inertia of part {first!r}: circuit {circ:.9g} kg·m², "
          f"finite differences {fd:.9g} kg·m² (relative difference {abs(circ - fd) / fd:.1e})")

    # 3. the cycle
    cmap = cycle_map(scene, points=72, harmonics=8)
    W = cmap.natural_frequencies()
    print(f"\n3. over one revolution ({len(cmap.theta)} crank angles, {len(cmap.skipped)} "
          f"skipped)")
    for k in range(W.shape[1]):
        print(f"   resonance {k + 1}: {np.nanmin(W[:, k]):8.2f} … {np.nanmax(W[:, k]):8.2f} rad/s")
    for c in cmap.crossings():
        print(f"   resonance {c['mode'] + 1} meets {c['harmonic']}·Ω = {c['omega']:g} rad/s "
              f"at θ ≈ {c['theta_deg']:.1f}°")
    for j, hh in enumerate(cmap.harmonics):
        i = int(np.nanargmax(np.abs(cmap.Q0[:, j])))
        print(f"   max |Q0| at {hh}·Ω: {abs(cmap.Q0[i, j]):8.3f} N·m at θ = "
              f"{math.degrees(cmap.theta[i]):5.1f}°")

    # 4. reduce the circuit at θ for K at the drive up to the 8th harmonic
    band = (0.5 * cmap.omega_shaft, 8 * cmap.omega_shaft)
    for tol in (1e-9, 1e-2):
        red = simplify(model.circuit, band, tol)
        print(f"\n4. reduce over [{band[0]:g}, {band[1]:g}] rad/s, tol {tol:g}: "
              f"{red.elements_before} -> {red.elements_after} elements, measured worst "
              f"relative error {red.error:.3g}")
        for s in red.shifts:
            print(f"   {s['kind']:<14} {s['full']:.6g} -> {s['reduced']:.6g} rad/s "
                  f"({s['relative_shift']:+.2e})")


if __name__ == "__main__":
    main()
