"""The smallest shedding cam: base radius for a pressure angle ≤ 45° and no undercut.

A heald-frame lever (oscillating roller follower) swings 15° with a modified
sine rise of 100°, a dwell of 80° and a return of 100° (the shed held open, then
closed, then a bottom dwell of 80°).  The smallest admissible base radius is
found from the two checks of ``cam_profile`` (a scan, then bisection); the
profile can then be written as SVG.

Run:  python examples/shedding_cam.py [profile.svg]
"""

import math
import sys

from mechcirc.kinematics.cam import cam_profile, save_profile
from mechcirc.motion_laws import cam_cycle

ARM, PIVOT, ROLLER = 150.0, 200.0, 20.0          # mm
motion = cam_cycle("modified_sine", 100, 80, 100, math.radians(15.0))


def cam(rb):
    return cam_profile(motion, rb, "oscillating", roller_radius=ROLLER, arm=ARM, pivot=PIVOT)


def passes(rb):
    return all(c.ok for c in cam(rb).checks)


# r_b + r_f must lie in (|D − L|, D + L) for the arm to reach the base circle.  With the
# pivot fixed the pressure angle is not monotonic in r_b (it is least near where the arm
# stands square to the line to the cam's centre), so a scan in 5 mm steps finds the first
# admissible radius and bisection then pins it down.
radii = [PIVOT - ARM - ROLLER + 1e-6 + 5.0 * k for k in range(60)]
first = next(k for k, rb in enumerate(radii) if passes(rb))
lo, hi = radii[first - 1], radii[first]
while hi - lo > 1e-3:                             # bisection to 1 µm
    mid = 0.5 * (lo + hi)
    lo, hi = (lo, mid) if passes(mid) else (mid, hi)
best = cam(hi)
phi, cut = best.check("pressure_angle"), best.check("undercut")
print(f"modified sine 100/80/100°, 15° swing; arm {ARM:g} mm pivoted {PIVOT:g} mm from the "
      f"cam, roller {ROLLER:g} mm")
print(f"smallest base radius: {hi:.3f} mm")
print(f"  max pressure angle {math.degrees(phi.value):.3f}° at θ = "
      f"{math.degrees(phi.theta):.2f}° (limit {math.degrees(phi.limit):g}°)")
print(f"  smallest convex radius of curvature {cut.value:.3f} mm at θ = "
      f"{math.degrees(cut.theta):.2f}°")
below = cam(hi - 0.01)
print(f"at {hi - 0.01:.3f} mm: " + ", ".join(f"{c.name} {'ok' if c.ok else 'fails'}"
                                             for c in below.checks))
if len(sys.argv) > 1:
    save_profile(best, svg=sys.argv[1])
    print(f"wrote {sys.argv[1]}")
