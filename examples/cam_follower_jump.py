"""Follower jump: the shaft speed at which a spring-loaded follower leaves its cam.

The follower of ``examples/cam_follower.mcir`` (m = 0.5 kg, spring 5 kN/m with a
50 N preload, damper 5 N·s/m) on a cycloidal cam (rise 100°, dwell 80°, return
80°, stroke 20 mm).  The closed form of a rigid follower — the speed at which the
contact force N = F0 + k s + cΩ s' + mΩ² s'' first reaches zero — is compared
with the simulated onset of separation: the follower on a stiff contact
(k_c = 1e11 N/m, damping ratio 0.5, the clearance law of ``mechcirc transient``),
bisected on the shaft speed (brentq on the least contact force over the first
turn, in a bracket of ±0.01 % about the closed form: 9 runs, against 29 from ±0.1 %
for the same answer within 1e-7).  Then the netlist runs at 800 rpm and its separations are listed.

Run:  python examples/cam_follower_jump.py
"""

import math
from pathlib import Path

from mechcirc.motion_laws import cam_cycle
from mechcirc.netlist import load
from mechcirc.transient import transient
from mechcirc.transient.follower import jump_speed, separation_speed

MASS, SPRING, PRELOAD, DAMPING = 0.5, 5e3, 50.0, 5.0
CONTACT = 1e11
motion = cam_cycle("cycloidal", 100, 80, 80, 0.02)

rpm, angle = jump_speed(motion, MASS, SPRING, PRELOAD, DAMPING)
print(f"jump speed, closed form (rigid follower): {rpm:.6f} rpm, contact force 0 at "
      f"{angle:.3f} deg")
sim = separation_speed(motion, MASS, SPRING, PRELOAD, DAMPING, contact=CONTACT,
                       contact_damping=2 * 0.5 * math.sqrt(CONTACT * MASS),
                       bracket=(0.9999 * rpm, 1.0001 * rpm))
print(f"jump speed, simulated onset of separation: {sim:.6f} rpm")
print(f"relative difference: {abs(sim / rpm - 1):.1e} (goal 1e-6)")

circuit = load(Path(__file__).with_name("cam_follower.mcir"))
r = transient(circuit, 60 / 800, 60 / 800 / 7200, rpm=800)
print(f"at 800 rpm the contact opens {len(r.separations)} time(s) in the first turn:")
for s in r.separations:
    print(f"  at {s.angle_deg:8.3f} deg for {s.duration_deg:7.3f} deg, impact velocity "
          f"{s.impact_velocity:.4f} m/s")
