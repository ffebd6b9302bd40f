"""The cam contact's release located inside the shaft's rk8 steps.

The follower's contact (ElastoBacklash: spring k_c ∥ damper d_c that only pushes) releases
where its would-be force k_c c + d_c ċ reaches 0 and caps its damping part where d_c ċ
reaches k_c c: kinks that depend on the rate ċ, not only on the squeeze c.  ``regions``
decides the contact's piece by those signs and ``locate`` finds the switch on the step's
interpolant, so the 8th-order stepper keeps a high order over the cycle.  The reference is
the hand-written equations of test_shaft_cam.py integrated by DOP853 at rtol 1e-12 over the
revolution from each run's own steady state.
"""

import math

import numpy as np
from mechcirc.scene.shaft import simulate_shaft
from scipy.integrate import solve_ivp

from test_shaft_cam import WS, in_theta, scene


def _speed_error(r) -> float:
    """Largest error of the shaft's speed over the cycle ``r``, relative to ω_s."""
    x0 = [r.speed[0], 0.0, r.states[0, 0], r.states[0, 1]]
    ref = solve_ivp(in_theta, (0.0, 2 * math.pi), x0, method="DOP853", rtol=1e-12,
                    atol=[1e-12, 1e-15, 1e-15, 1e-12], dense_output=True)
    return float(np.max(np.abs(ref.sol(r.theta)[0] - r.speed))) / WS


def test_rk8_converges_through_the_contact_release():
    """rk8 at 4, 8, 16 steps per period: measured 6.0e-9, 7.7e-13, 4.0e-14 (×7800, ×19;
    32 steps: 1.3e-14, the floor of rounding and of the reference).  With the release
    located on the interpolant of the step across it only (not placed again on the cut
    step's own), the same runs gave 5.0e-8, 2.6e-8, 3.8e-10 (32: 4.4e-11);
    before the release was located at all 4.0e-6, 5.1e-8, 2.3e-7 at 8, 16, 32 (against the
    code's own DOP853 path at rtol 1e-12, 360 samples): no convergence.  Asserted: each
    halving of the step divides the error by ≥ 6 and the 16-step error is ≤ 2e-13 (5x
    margin)."""
    sc = scene()
    err = [_speed_error(simulate_shaft(sc, points=90, startup=False, method="rk8",
                                       steps_per_period=s)) for s in (4, 8, 16)]
    assert err[0] / err[1] >= 6.0
    assert err[1] / err[2] >= 6.0
    assert err[2] <= 2e-13
