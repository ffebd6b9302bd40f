"""A cam whose follower can jump (``[cam] contact``) on the dynamic main shaft, against the
hand-written equations of the shaft, the contact and the follower.

The shipped follower-jump scene (``examples/cam_jump_scene.toml``: a massless tappet lifted
by the cycloidal law, a 0.5 kg follower riding on it through a contact that only pushes, a
5 kN/m follower spring with 50 N preload) with a contact of 1e8 N/m (damping ratio 0.5), a
flywheel J_f and a Kloss motor whose speed lies above the follower's jump speed.  With y the
follower's travel, s(θ) the lift (written out here) and the squeeze c = s + F₀/k_c − y:

    m ÿ = N − F₀ − k y,        J_f θ̈ = T(θ̇) − N s′(θ),

N = k_c c + d_c ċ for c > 0 with its damping part at most its spring part and never pulling
(the ElastoBacklash law), else 0; T Kloss's formula.  The contact's push on the tappet is
the cam shaft's load torque N s′ (virtual work).  From the state the code finds at the
cycle's start, scipy's DOP853 (rtol 1e-12) integrates these equations in θ over the cycle.
"""

import math
from pathlib import Path

import numpy as np
import pytest
from mechcirc.scene import parse_scene
from mechcirc.scene.shaft import simulate_shaft
from scipy.integrate import solve_ivp

from reference.cam_lift import cycloidal_cycle

ROOT = Path(__file__).resolve().parents[2]
TEXT = (ROOT / "examples" / "cam_jump_scene.toml").read_text(encoding="utf-8")
M, K, F0, H = 0.5, 5e3, 50.0, 0.020
RISE, DWELL, RET = (math.radians(d) for d in (100.0, 80.0, 80.0))
KC = 1e8
DC = 2 * 0.5 * math.sqrt(KC * M)
JF, WS, TB, SB = 0.05, 95.0, 30.0, 0.2
SHAFT = f"""
[shaft]
flywheel = {JF!r}
motor = "kloss"
sync_speed = {WS!r}
breakdown_torque = {TB!r}
breakdown_slip = {SB!r}
"""


def scene():
    text = TEXT.replace("stiffness = 1.0e11", f"stiffness = {KC!r}").replace(
        "damping = 2.236e5", f"damping = {DC!r}")
    return parse_scene(text + SHAFT, "cam_jump_shaft.toml")


def lift(th):
    """s, s′ of the cycloidal rise 100°, dwell 80°, return 80°, dwell (by hand)."""
    return cycloidal_cycle(th, H, RISE, DWELL, RET)


def push(th, w, y, yd):
    s, s1 = lift(th)
    c, cdot = s + F0 / KC - y, s1 * w - yd
    if c <= 0:
        return 0.0, s1
    fc, fd = KC * c, DC * cdot
    return (0.0 if fc + fd <= 0 else fc + min(fc, fd)), s1


def in_theta(th, Y):
    """d/dθ of [θ̇, t, y, ẏ]."""
    w, _, y, yd = Y
    n, s1 = push(th, w, y, yd)
    slip = (WS - w) / WS
    torque = 2 * TB * slip * SB / (slip * slip + SB * SB)
    return [(torque - n * s1) / JF / w, 1 / w, yd / w, (n - F0 - K * y) / M / w]


@pytest.mark.slow
def test_cam_follower_jump_on_the_shaft_matches_the_hand_equations():
    """The steady cycle at the default step.  The contact's opening and landing are kinks
    the stepper locates (the release where the would-be push k_c c + d_c ċ reaches 0), so
    the default rk8 (16 steps per period of the fastest mode, 2,382 a cycle) keeps its order
    through them; measured (27 Nov, eighth session) against DOP853 at rtol 1e-12 on the hand
    equations: the shaft's speed 9.0e-13 of ω_s, the time 8.5e-14 of the period, the
    follower's travel 1.3e-9 of its largest (≤ 5e-7 m), the state after the cycle in the
    reference 1.0e-12 of ω_s and 6.2e-12 of the travel, the load torque N s′ 3.8e-9 of its
    peak, the contact's push 3.7e-7 of its peak (the landing's 14 kN impact, where the travel
    error is multiplied by k_c = 1e8 N/m).  With the default RK4 at 100 steps per period
    before, 8.3e-11, 1.5e-11, 8.4e-8, …, 2.5e-5 (push); before the release was located
    1.8e-8 … 5.7e-8 (speed), 9.1e-6 … 2.5e-5 (travel), 1.5e-3 … 7.3e-3 (push).  The limits
    below were set for RK4 (a margin of 10 or more over its errors; 100–1000 over rk8's):
    tighter ones would need a reference with the kinks located (test_cam_kink.py)."""
    r = simulate_shaft(scene(), points=720, startup=False)
    x0 = [r.speed[0], 0.0, r.states[0, 0], r.states[0, 1]]
    ref = solve_ivp(in_theta, (0.0, 2 * math.pi), x0, method="DOP853", rtol=1e-12,
                    atol=[1e-12, 1e-15, 1e-15, 1e-12], dense_output=True)
    Y = ref.sol(r.theta)
    travel = np.max(np.abs(Y[2]))
    assert np.max(np.abs(Y[0] - r.speed)) <= 1e-9 * WS
    assert np.max(np.abs(Y[1] - r.time)) <= 2e-10 * r.period
    assert np.max(np.abs(Y[2] - r.states[:, 0])) <= 1e-6 * travel
    assert abs(ref.y[0, -1] - x0[0]) <= 1e-9 * WS and abs(ref.y[2, -1] - x0[2]) <= 2e-9 * travel
    assert abs(ref.y[1, -1] - r.period) <= 1e-8 * r.period
    n, s1 = np.array([push(t, w, y, yd) for t, w, y, yd in zip(r.theta, Y[0], Y[2], Y[3])]).T
    # the follower leaves the cam (no push over part of the turn) and lands on it again
    assert np.count_nonzero(n == 0) > 100 and n[-1] > 0
    assert np.max(np.abs(n + r.values["contact.force"])) <= 3e-4 * np.max(n)
    assert np.max(np.abs(n * s1 - r.load_torque)) <= 2e-6 * np.max(np.abs(n * s1))
