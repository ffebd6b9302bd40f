"""The translating cam follower scene (examples/cam_follower_scene.toml) against its
closed form.

1. Kinematics over a turn: the follower's lift against the cycloidal law
   s = h (u − sin 2πu / 2π) written out here, the lever angle ψ against the
   intersection of the circles |A − O| = OA and |A − F| = FA, and ψ̇ from
   differentiating |A − F|² = FA² (the push rod keeps its length).
2. The circuit at θ: the drive ratio r0 = s'(θ) (the follower's speed per unit
   cam speed; 2h/β at mid-rise) and the resonance of the frame on the rod and
   the warp with the follower held, ω² = (k ℓ_y² + k_w) / m.
3. One revolution in the time domain: the follower's acceleration against
   s''(θ) Ω², and the rod's force.

Run from the repository root:  python examples/cam_follower_scene.py
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from mechcirc.scene import build, load_scene, simulate_scene

SCENE = Path(__file__).resolve().parent / "cam_follower_scene.toml"


def cycloidal(theta, h, rise, dwell, ret):
    """s, s', s'' of a cycloidal rise, dwell, return, dwell (angles in rad)."""
    theta = np.mod(theta, 2 * math.pi)
    s, s1, s2 = (np.zeros_like(theta) for _ in range(3))
    for lo, beta, sign in ((0.0, rise, 1.0), (rise + dwell, ret, -1.0)):
        on = (theta >= lo) & (theta < lo + beta)
        u = (theta[on] - lo) / beta
        s[on] = h * (u - np.sin(2 * np.pi * u) / (2 * np.pi)) if sign > 0 else \
            h * (1 - u + np.sin(2 * np.pi * u) / (2 * np.pi))
        s1[on] = sign * h / beta * (1 - np.cos(2 * np.pi * u))
        s2[on] = sign * 2 * np.pi * h / beta ** 2 * np.sin(2 * np.pi * u)
    s[(theta >= rise) & (theta < rise + dwell)] = h
    return s, s1, s2


def lever(s, sd, O, F0, oa, fa):
    """ψ (from the pose's A − O direction) and ψ̇ of the lever with the follower at F0 + (0, s)."""
    dx, dy = F0[0] - O[0], F0[1] + s - O[1]
    d = np.hypot(dx, dy)
    a = (oa * oa - fa * fa + d * d) / (2 * d)
    h = np.sqrt(oa * oa - a * a)
    ax, ay = O[0] + (a * dx - h * dy) / d, O[1] + (a * dy + h * dx) / d
    psi = np.arctan2(ay - O[1], ax - O[0])
    rx, ry = ax - F0[0], ay - F0[1] - s
    return psi, ry * sd / (oa * (-rx * np.sin(psi) + ry * np.cos(psi)))


def main() -> None:
    scene = load_scene(SCENE)
    lk, L, w = scene.linkage, scene.length_scale, scene.omega_shaft
    P = {k: v * L for k, v in lk.pose.items()}
    oa, ob = (float(np.hypot(*(P[k] - P["O"]))) for k in ("A", "B"))
    fa = float(np.hypot(*(P["A"] - P["F"])))
    h, ang = 0.020, [math.radians(v) for v in (120.0, 60.0, 120.0)]
    th = np.linspace(0.0, 2 * math.pi, 721)
    mo = lk.motion(th)
    s, s1, s2 = cycloidal(th, h, *ang)
    f = mo.point_names.index("F")
    psi, psid = lever(s, s1 * w, P["O"], P["F"], oa, fa)
    j = lk.link_index()["lever"]
    print(f"follower lifted {h * 1e3:g} mm (cycloidal 120/60/120/60°), lever OA = {oa * 1e3:g} "
          f"mm, push rod {fa * 1e3:g} mm, Ω = {w:g} rad/s")
    print("1. against the closed form over 721 cam angles (max |difference|)")
    print(f"   follower s {np.max(np.abs(mo.points[:, f, 1] * L - s)):.1e} m, "
          f"v {np.max(np.abs(mo.velocities[:, f, 1] * L - w * s1)):.1e} m/s, "
          f"a {np.max(np.abs(mo.accelerations[:, f, 1] * L - w * w * s2)):.1e} m/s² "
          f"(|a| up to {np.max(np.abs(w * w * s2)):.4g})")
    print(f"   lever ψ {np.max(np.abs(mo.q[:, 3 * j + 2] - psi)):.1e} rad, "
          f"ψ̇ {np.max(np.abs(mo.qdot[:, 3 * j + 2] - psid)):.1e} rad/s "
          f"(swing {np.degrees(np.ptp(psi)):.4f}°)")
    m = next(x.value for x in scene.masses if x.name == "m_heald")
    k = next(x.stiffness for x in scene.elastic if x.name == "k_rod")
    kw = next(x.stiffness for x in scene.loads if x.name == "k_warp")
    print("2. circuit at θ: drive ratio r0 [m/rad], resonance with the follower held [rad/s]")
    for deg in (60.0, 250.0):
        t = math.radians(deg)
        sc = build(scene, t)
        st, st1, _ = (float(v[0]) for v in cycloidal(np.array([t]), h, *ang))
        p = float(lever(np.array([st]), np.zeros(1), P["O"], P["F"], oa, fa)[0][0])
        bx = P["O"][0] + ob * math.cos(p)
        l0 = float(np.hypot(*(P["H"] - P["B"])))
        ly = -math.sqrt(l0 * l0 - (P["H"][0] - bx) ** 2) / l0      # ∂ℓ/∂y, H below B
        (res,) = [r.omega for r in sc.circuit.resonances() if r.kind == "resonance"]
        print(f"   θ = {deg:5.1f}°: r0 {sc.drive_ratio:.12g} (closed form {abs(st1):.12g}), "
              f"resonance {res:.10g} (closed form {math.sqrt((k * ly * ly + kw) / m):.10g})")
    sm = simulate_scene(scene, error_estimate=False)
    a_ref = cycloidal(sm.crank_angle, h, *ang)[2] * w * w
    fr = sm.values["k_rod.force"]
    print(f"3. revolution {sm.revolution}: follower acceleration off the law's by "
          f"{np.max(np.abs(sm.values['F.acceleration_y'] - a_ref)):.1e} m/s² (peak "
          f"{np.max(np.abs(a_ref)):.4g}); rod force {fr.min():.1f} … {fr.max():.1f} N")


if __name__ == "__main__":
    main()
