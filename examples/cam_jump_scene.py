"""Follower jump in a scene (examples/cam_jump_scene.toml) against the closed form.

The follower (0.5 kg, spring 5 kN/m with a 50 N preload) rides on the cam through a
stiff contact (1e11 N/m) that pushes only.  The closed form of a rigid follower: the
contact force N = F0 + k s + m Ω² s'' first reaches zero at the shaft speed
Ω* = min over θ of sqrt((F0 + k s)/(−m s'')).  The scene's jump speed is the root of
its least contact force over one simulated turn: bracketed by steps of 5 % from the
scene's 600 rpm, then a secant in Omega^2 through runs where the contact holds, to
1e-8 (without the closed form).  Then one
turn at 800 rpm: the contact opens.

Run from the repository root:  python examples/cam_jump_scene.py
"""

import math
from pathlib import Path

from mechcirc.motion_laws import cam_cycle
from mechcirc.scene import load_scene, simulate_scene
from mechcirc.scene.jump import contact_report, scene_jump_speed
from mechcirc.transient.follower import jump_speed

scene = load_scene(Path(__file__).resolve().with_name("cam_jump_scene.toml"))
rpm, angle = jump_speed(cam_cycle("cycloidal", 100, 80, 80, 0.02), 0.5, 5e3, 50.0)
w = rpm * math.pi / 30
print(f"jump speed, closed form (rigid follower): {rpm:.6f} rpm, contact force 0 at "
      f"{angle:.3f} deg")
got = scene_jump_speed(scene, steps_per_period=100)
print(f"jump speed, scene (secant, rtol {got.rtol:g}, {got.runs} runs of one turn): "
      f"{got.omega * 30 / math.pi:.6f} rpm")
print(f"relative difference: {abs(got.omega / w - 1):.0e} (goal 1e-6)")

rep = contact_report(scene, simulate_scene(scene, omega=800 * math.pi / 30, revolutions=1,
                                           error_estimate=False))
k_c = next(e.stiffness for e in scene.elastic if e.name == "contact")
print(f"at 800 rpm: the follower leaves the cam by up to {-rep.min_contact / k_c * 1e3:.4g} mm "
      f"at {rep.min_contact_angle_deg:.2f} deg (least contact force, k_c x compression: "
      f"{rep.min_contact:.4g} N); the contact opens {len(rep.separations)} times:")
for start, length in rep.separations:
    print(f"  at {start:7.2f} deg for {length:6.2f} deg")
