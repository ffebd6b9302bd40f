"""The cam contact's release located inside the shaft's rk8 steps.

The follower's contact (ElastoBacklash: spring k_c ∥ damper d_c that only pushes) releases
where its would-be force k_c c + d_c ċ reaches 0 and caps its damping part where d_c ċ
reaches k_c c: kinks that depend on the rate ċ, not only on the squeeze c.  ``regions``
decides the contact's piece by those signs and ``locate`` finds the switch on the step's
interpolant, so the 8th-order stepper keeps a high order over the cycle.  The reference is
the hand-written equations of test_shaft_cam.py integrated by DOP853 at rtol 3e-12 over the
revolution from each run's own steady state, with the contact's switches located
(test_shaft_cam.located_reference): unlocated, its error moved with the last bits of the
state it starts from by more than the 16-step error asserted.
"""

import numpy as np
from mechcirc.scene.shaft import simulate_shaft

from test_shaft_cam import WS, located_reference, scene


def _speed_error(r) -> float:
    """Largest error of the shaft's speed over the cycle ``r``, relative to ω_s, against
    :func:`test_shaft_cam.located_reference` (the hand equations from the run's own state at
    θ = 0, DOP853 at rtol 3e-12, the contact's switches located)."""
    return float(np.max(np.abs(located_reference(r)[0][0] - r.speed))) / WS


def test_rk8_converges_through_the_contact_release():
    """rk8 at 4, 8, 16 steps per period: measured 6.0e-9, 8.0e-13, 3.3e-14 (×7500, ×24;
    the last the floor of rounding; the reference at rtol 3e-12 is within 5.5e-15 of one
    at 3e-14).  Over 12 draws of the motion tables' coefficients moved by ±1 ulp at most
    3.3e-14 at 16 steps, the ratios at least ×7500, ×24; against the unlocated DOP853 at rtol
    1e-12 used before, the 16-step error reached 5.1e-12 and the second ratio fell to 0.16
    (three draws in 12 failed).  With the release located on the interpolant of the step
    across it only (not placed again on the cut step's own), the same runs gave 5.0e-8,
    2.6e-8, 3.8e-10 (32: 4.4e-11); before the release was located at all 4.0e-6, 5.1e-8,
    2.3e-7 at 8, 16, 32 (against the code's own DOP853 path at rtol 1e-12, 360 samples):
    no convergence.  On the kernels' Python copy, the located release moved late by 1e-5
    (1e-4) of the step gives 6.3e-9, 7.0e-12, 1.3e-11 (8.8e-9, 3.8e-10, 1.9e-10), and no
    location no steady cycle at 4 steps, 1.6e-5 and 2.6e-6 at 8 and 16: all rejected.
    Asserted: each halving of the step divides the error by ≥ 6 (4x margin) and the 16-step
    error is ≤ 2e-13 (6x margin)."""
    sc = scene()
    err = [_speed_error(simulate_shaft(sc, points=90, startup=False, method="rk8",
                                       steps_per_period=s)) for s in (4, 8, 16)]
    assert err[0] / err[1] >= 6.0
    assert err[1] / err[2] >= 6.0
    assert err[2] <= 2e-13
