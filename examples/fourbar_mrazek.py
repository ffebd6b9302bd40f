"""Mrázek's beat-up four-bar and the patent's synthesis rules, reproduced.

Sources: Mrázek, *Theoretical analysis of dynamics of four-bar beat-up
mechanism* — crank 29, coupler 37, rocker 188, frame 189 mm;
the theoretical rocker acceleration ε4T = ν·ω² of Table 1 is printed as
−2319 … 2915 s⁻² at ω = 100 s⁻¹ and −371 … 466 s⁻² at ω = 40 s⁻¹, and the
beat-up angle is φP = arccos(((l2P + l3)² + d² − l4²) / (2 d (l2P + l3))).
Patent CN104178888: a medium loom has a 35–36 mm crank, a front
transmission angle > 70°, a minimum one > 45°, |Φ2''|/|Φ1''| < 0.3, d < 180 mm
and a swing of 23–26°.

Run from the repository root: ``python examples/fourbar_mrazek.py``.
"""

import math

from mechcirc.kinematics import FourBar, synthesize

PAPER = {100.0: (-2319.0, 2915.0), 40.0: (-371.0, 466.0)}


def main() -> None:
    fb = FourBar(crank=29.0, coupler=37.0, rocker=188.0, frame=189.0)
    print("Mrázek's four-bar 29/37/188/189 mm")
    for omega, (lo_p, hi_p) in PAPER.items():
        lo, hi = fb.rocker_acceleration_range(omega)
        print(f"  ε4T at ω = {omega:5.0f} 1/s: ours {lo:9.2f} .. {hi:8.2f} s⁻², paper "
              f"{lo_p:6.0f} .. {hi_p:5.0f}; difference {lo - lo_p:+.2f} / {hi - hi_p:+.2f} "
              f"(paper rounds to integers)")
    l2, l3, l4, d = 29.0, 37.0, 188.0, 189.0
    phi_p = math.degrees(math.acos(((l2 + l3) ** 2 + d ** 2 - l4 ** 2) / (2 * d * (l2 + l3))))
    front, back = fb.dead_centres()
    print(f"  beat-up (front dead centre): θ = {math.degrees(front.theta):.4f}°, "
          f"eq. (7)'s φP = {phi_p:.4f}°, difference {math.degrees(front.theta) - phi_p:+.1e}°")
    print(f"  swing {math.degrees(fb.swing()):.2f}°; transmission angle "
          f"{math.degrees(fb.transmission_range().gamma_min):.1f}° .. "
          f"{math.degrees(fb.transmission_range().gamma_max):.1f}°")

    result = synthesize(load="medium", swing=24.0, limit=3)
    print("\nPatent CN104178888, medium loom, swing 24°: best designs")
    print(f"  {'a':>5} {'b':>6} {'c':>6} {'d':>6}  {'front γ':>7} {'min γ':>6} "
          f"{'Φ2/Φ1':>6} {'swing':>6}  binding")
    for des in result.designs:
        cr = des.criteria
        print(f"  {des.a:5.1f} {des.b:6.1f} {des.c:6.1f} {des.d:6.1f}  "
              f"{cr['front_transmission'].value:7.1f} {cr['min_transmission'].value:6.1f} "
              f"{cr['acceleration_ratio'].value:6.3f} {des.swing_deg:6.2f}  "
              f"{', '.join(des.binding)}")
    ok = all(d.feasible for d in result.designs)
    print(f"  every listed design meets every criterion (checked on the linkage itself): {ok}")


if __name__ == "__main__":
    main()
