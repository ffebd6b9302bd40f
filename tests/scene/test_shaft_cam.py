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
cycle's start, scipy's DOP853 (rtol 3e-12) integrates these equations in θ over the cycle,
the contact's switches located (:func:`located_reference`).
"""

import math
from pathlib import Path

import numpy as np
import pytest
from mechcirc.scene import parse_scene
from mechcirc.scene.shaft import simulate_shaft

from reference.located import at, located
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


def side(th, Y):
    """The contact's piece of :func:`push` at [θ̇, t, y, ẏ]: 0 no push, 1 k_c c + d_c ċ, 2 its
    damping part capped (2 k_c c)."""
    s, s1 = lift(th)
    c, cdot = s + F0 / KC - Y[2], s1 * Y[0] - Y[3]
    if c <= 0 or KC * c + DC * cdot <= 0:
        return 0
    return 1 if DC * cdot < KC * c else 2


def in_theta(th, Y):
    """d/dθ of [θ̇, t, y, ẏ]."""
    w, _, y, yd = Y
    n, s1 = push(th, w, y, yd)
    slip = (WS - w) / WS
    torque = 2 * TB * slip * SB / (slip * slip + SB * SB)
    return [(torque - n * s1) / JF / w, 1 / w, yd / w, (n - F0 - K * y) / M / w]


def located_reference(r, rtol=3e-12):
    """The hand equations over the cycle from the run ``r``'s own state at θ = 0, by
    DOP853 at ``rtol`` with every kink at a step's end (:func:`reference.located.located`):
    the contact's switches (:func:`side`) bisected, the law's joints (rise, dwell, return)
    stops.  Returns ([θ̇, t, y, ẏ] at ``r.theta`` (rows), the state after the cycle)."""
    x0 = np.array([r.speed[0], 0.0, r.states[0, 0], r.states[0, 1]])
    atol = 1e-3 * rtol * np.array([WS, 2 * math.pi / WS, H, H * WS])
    ends = [RISE, RISE + DWELL, RISE + DWELL + RET, 2 * math.pi]
    end, pieces = located(lambda th, Y: np.array(in_theta(th, Y)), 0.0, x0, ends, side,
                          rtol, atol)
    return at(pieces, r.theta), end


@pytest.mark.slow
def test_cam_follower_jump_on_the_shaft_matches_the_hand_equations():
    """The steady cycle at the default step.  The contact's opening and landing are kinks
    the stepper locates (the release where the would-be push k_c c + d_c ċ reaches 0), so
    the default rk8 (16 steps per period of the fastest mode, 2,382 a cycle) keeps its order
    through them.  Against :func:`located_reference` (its own error at rtol 3e-12: 2.4e-14
    of ω_s, 6.8e-12 of the travel, against rtol 3e-14) measured: the shaft's speed 9.4e-13
    of ω_s, the time 1.2e-13 of the period, the follower's travel 1.26e-9 of its largest
    (≤ 5e-7 m), the state after the cycle in the reference 1.02e-12 of ω_s and 6.2e-12 of
    the travel, the period 1.2e-13, the load torque N s′ 3.4e-9 of its peak, the contact's
    push 3.7e-7 of its peak (the landing's 14 kN impact, where the travel error is
    multiplied by k_c = 1e8 N/m).  Over 12 draws of the motion tables' coefficients moved
    by ±1 ulp at most 9.45e-13, 1.21e-13, 1.26e-9, 1.02e-12, 6.19e-12, 1.21e-13, 3.45e-9,
    3.70e-7; against the unlocated DOP853 at rtol 1e-12 used before, the speed's error
    reached 8.3e-12 and the load torque's 1.8e-8 on the same draws.  Asserted 3e-12,
    4e-13, 4e-9, 4e-12, 2e-11, 4e-13, 1.2e-8, 1.2e-6 (≥ 3.1x margins; the limits before
    were RK4's, 100–1000 times looser).  They reject RK4 at its default 100 steps per
    period (8.3e-11 speed, 2.5e-5 push: ×28 and ×20 over), and, on the kernels' Python
    copy, the located release cut late by 1e-4 of the step (1.0e-10, 4.0e-5) or by 1e-5
    (8.9e-12, 3.5e-6): all three passed the old limits."""
    r = simulate_shaft(scene(), points=720, startup=False)
    Y, end = located_reference(r)
    travel = np.max(np.abs(Y[2]))
    assert np.max(np.abs(Y[0] - r.speed)) <= 3e-12 * WS
    assert np.max(np.abs(Y[1] - r.time)) <= 4e-13 * r.period
    assert np.max(np.abs(Y[2] - r.states[:, 0])) <= 4e-9 * travel
    assert abs(end[0] - r.speed[0]) <= 4e-12 * WS
    assert abs(end[2] - r.states[0, 0]) <= 2e-11 * travel
    assert abs(end[1] - r.period) <= 4e-13 * r.period
    n, s1 = np.array([push(t, w, y, yd) for t, w, y, yd in zip(r.theta, Y[0], Y[2], Y[3])]).T
    # the follower leaves the cam (no push over part of the turn) and lands on it again
    assert np.count_nonzero(n == 0) > 100 and n[-1] > 0
    assert np.max(np.abs(n + r.values["contact.force"])) <= 1.2e-6 * np.max(n)
    assert np.max(np.abs(n * s1 - r.load_torque)) <= 1.2e-8 * np.max(np.abs(n * s1))
