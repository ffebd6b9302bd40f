"""A cam on the dynamic main shaft (``[shaft]`` with ``[cam]``, a rigid mechanism) against
the hand-written equation of a flywheel, a Kloss motor and a cam-lifted mass.

The follower (mass m) is lifted by the cycloidal law s(θ) written out here; its
kinetic energy ½ m s′(θ)² θ̇² gives, by Lagrange II,

    (J_f + m s′²) θ̈ + m s′ s″ θ̇² = T(θ̇),   T = 2 T_b / (σ/σ_b + σ_b/σ),  σ = (ω_s − θ̇)/ω_s,

integrated in θ (dθ̇/dθ = θ̈/θ̇) by scipy's DOP853 at rtol 1e-13, piece by piece of the law,
its steady cycle found by brentq on θ̇(2π) − θ̇(0): the shaft's speed over the cycle to
1e-6 relative (measured 1.2e-7).  A cam with elastic parts and a follower that
can jump on the shaft: tests/scene/test_shaft_cam.py.
"""

import math

import numpy as np
from scipy.integrate import solve_ivp
from scipy.optimize import brentq

from mechcirc.scene import parse_scene
from mechcirc.scene.shaft import simulate_shaft

M, JF, WS, TB, SB = 5.0, 0.02, 62.83, 20.0, 0.2
H, RISE, DWELL, RET = 0.02, *(math.radians(d) for d in (100.0, 80.0, 80.0))
TEXT = f"""
name = "cam on a dynamic shaft"
units = "mm"
[points]
F = [0.0, 0.0]
A = [0.0, 150.0]
O = [-200.0, 150.0]
G1 = [0.0, -200.0]
G2 = [0.0, -100.0]
[ground]
points = ["O", "G1", "G2"]
[links]
follower = ["F"]
push = ["F", "A"]
lever = ["O", "A"]
[[sliders]]
link = "follower"
guide = "ground"
line = ["G1", "G2"]
[[cranks]]
link = "lever"
omega = 60.0
[cam]
follower = "follower"
follower_type = "roller"
law = "cycloidal"
rise = 100.0
dwell = 80.0
return = 80.0
stroke = 20.0
[[masses]]
name = "m_follower"
point = "F"
mass = {M!r}
[drive]
point = "F"
velocity = 1.0
[shaft]
flywheel = {JF!r}
motor = "kloss"
sync_speed = {WS!r}
breakdown_torque = {TB!r}
breakdown_slip = {SB!r}
"""


def lift(th):
    """s′, s″ of the cycloidal rise 100°, dwell 80°, return 80°, dwell, by hand."""
    th = th % (2 * math.pi)
    for lo, beta, sign in ((0.0, RISE, 1.0), (RISE + DWELL, RET, -1.0)):
        if lo <= th < lo + beta:
            u = (th - lo) / beta
            return (sign * H / beta * (1 - math.cos(2 * math.pi * u)),
                    sign * 2 * math.pi * H / beta ** 2 * math.sin(2 * math.pi * u))
    return 0.0, 0.0


def torque(w):
    slip = (WS - w) / WS
    return 2 * TB / (slip / SB + SB / slip)


def rhs(th, y):
    s1, s2 = lift(th)
    w = y[0]
    return [(torque(w) - M * s1 * s2 * w * w) / (JF + M * s1 * s1) / w]


KNOTS = (0.0, RISE, RISE + DWELL, RISE + DWELL + RET, 2 * math.pi)


def cycle(w0):
    y, sols = [w0], []
    for a, b in zip(KNOTS[:-1], KNOTS[1:]):
        r = solve_ivp(rhs, (a, b), y, method="DOP853", rtol=1e-13, atol=1e-12,
                      dense_output=True)
        sols.append((a, b, r.sol))
        y = r.y[:, -1]
    return y[0] - w0, sols


def test_steady_speed_against_the_hand_equation():
    r = simulate_shaft(parse_scene(TEXT, "cam_shaft.toml"), startup=False)
    w0 = brentq(lambda w: cycle(w)[0], 50.0, 70.0, xtol=1e-13)
    sols = cycle(w0)[1]
    th = np.mod(r.theta, 2 * math.pi)
    ref = np.array([next(s(t)[0] for a, b, s in sols if a <= t <= b) for t in th])
    assert np.max(np.abs(r.speed - ref)) <= 1e-6 * np.max(ref)       # measured 1.2e-7
