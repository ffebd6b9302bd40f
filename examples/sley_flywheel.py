"""Mrázek's sley on a dynamic main shaft: speed fluctuation and sley acceleration against
the flywheel.

The one-side sley (``examples/mrazek_one_side.toml``, Table 1 variant 3) with its
elastic rods rigid is turned by an induction motor (Kloss's formula; our own
choice: a six-pole 50 Hz motor on the crankshaft, ω_s = 104.72 rad/s, rated 1.5 kW
at 100 rad/s, breakdown torque 2.5 × rated) through a flywheel J_f.  For each J_f
the steady cycle gives the coefficient of fluctuation δ = (ω_max − ω_min)/ω_mean
and the sley's angular acceleration ε4P (rigid: φ'' θ̇² + φ' θ̈) beside ε4T, the
theoretical one at constant speed; the start-up from rest is timed.

Run from the repository root: ``python examples/sley_flywheel.py``.
"""

from pathlib import Path

from mechcirc.scene import parse_scene
from mechcirc.scene.shaft import simulate_shaft

SHAFT = """
[shaft]
flywheel = 0.1
motor = "kloss"
sync_speed = 104.72
rated_power = 1500.0
rated_speed = 100.0
breakdown_torque = 37.5
start_deg = 20.33930882625235
"""
FLYWHEELS = (0.02, 0.05, 0.1, 0.2, 0.5, 1.0, 2.0)


def sley_with_shaft():
    """The one-side sley scene with the [shaft] table above."""
    path = Path("examples/mrazek_one_side.toml")
    return parse_scene(path.read_text(encoding="utf-8") + SHAFT, str(path))


def rows(flywheels=FLYWHEELS, startup=True):
    """(J_f, ω_mean, δ, ε4P min, ε4P max, motor torque min, max, start-up time) per flywheel,
    the rods rigid."""
    scene = sley_with_shaft()
    out = []
    for jf in flywheels:
        r = simulate_shaft(scene, flywheel=jf, startup=startup, rigid=True)
        e = r.body_accelerations["sley"]
        out.append((jf, r.omega_mean, r.delta, float(e.min()), float(e.max()),
                    float(r.motor_torque.min()), float(r.motor_torque.max()), r.startup_time))
    return out


def main() -> None:
    m = sley_with_shaft().shaft.motor
    print(f"one-side sley (rigid), Kloss motor ω_s = {m.sync_speed:g} rad/s, "
          f"T_b = {m.breakdown_torque:g} N·m, s_b = {m.breakdown_slip:.4f}")
    print(f"{'J_f [kg·m²]':>11} {'ω_mean':>8} {'δ':>8} {'ε4P min':>9} {'ε4P max':>9} "
          f"{'T_motor min':>11} {'max':>7} {'start-up [s]':>12}")
    for jf, wm, d, e0, e1, t0, t1, tu in rows():
        print(f"{jf:>11g} {wm:>8.2f} {d:>8.4f} {e0:>9.0f} {e1:>9.0f} {t0:>11.1f} {t1:>7.1f} "
              f"{tu:>12.3f}")


def elastic(flywheel=0.5, large=1.0e3, points=720):
    """The elastic sley on the shaft at ``flywheel``: (result, rigid result); and at a
    ``large`` flywheel the largest relative difference of the extrema of ε4P and M2V from
    the constant-speed simulation at its ω_mean (DOP853, rtol 1e-10)."""
    from mechcirc.scene.simulation import simulate_scene

    scene = sley_with_shaft()
    r = simulate_shaft(scene, flywheel=flywheel, startup=False, points=points)
    rig = simulate_shaft(scene, flywheel=flywheel, startup=False, points=points, rigid=True)
    big = simulate_shaft(scene, flywheel=large, startup=False, points=points)
    c = simulate_scene(scene, omega=big.omega_mean, method="DOP853", rtol=1e-10,
                       error_estimate=False, points=points)
    gap = 0.0
    for mine, ref in ((big.body_accelerations["sley"], c.values["sley.acceleration"]),
                      (big.values["C2.force"], c.values["C2.force"])):
        span = max(abs(ref.min()), abs(ref.max()))
        gap = max(gap, abs(mine.min() - ref.min()) / span, abs(mine.max() - ref.max()) / span)
    return r, rig, gap


def main_elastic() -> None:
    r, rig, gap = elastic()
    e, m = r.body_accelerations["sley"], r.values["C2.force"]
    print(f"elastic rods, J_f = {r.flywheel:g} kg·m²: ω_mean = {r.omega_mean:.4f} rad/s, "
          f"δ = {r.delta:.5f} (rods rigid: {rig.delta:.5f}), ε4P {e.min():.0f} … {e.max():.0f} "
          f"rad/s², M2V {m.min():.1f} … {m.max():.1f} N·m")
    print(f"J_f = 1000 kg·m² against the constant-speed simulation at its ω_mean: extrema of "
          f"ε4P and M2V within {gap:.2g} (relative)")


if __name__ == "__main__":
    import sys

    main()
    if "--rigid-only" not in sys.argv:
        main_elastic()
