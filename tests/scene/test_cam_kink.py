"""The cam contact's release located inside the shaft's rk8 steps.

The follower's contact (ElastoBacklash: spring k_c ∥ damper d_c that only pushes) releases
where its would-be force k_c c + d_c ċ reaches 0 and caps its damping part where d_c ċ
reaches k_c c: kinks that depend on the rate ċ, not only on the squeeze c.  ``regions``
decides the contact's piece by those signs and ``locate`` finds the switch on the step's
interpolant, so the 8th-order stepper keeps a high order over the cycle.  The reference is
DOP853 at rtol 1e-12 on the same equations (the hand-written equations of
test_shaft_cam.py check those equations themselves).
"""

import numpy as np
import pytest
from mechcirc.scene.shaft import simulate_shaft

from test_shaft_cam import WS, scene


@pytest.mark.slow
def test_rk8_converges_through_the_contact_release():
    """rk8 at 8, 16, 32 steps per period against DOP853 rtol 1e-12 (the cost is that
    reference: ~25 s CPU): the largest error of the shaft's speed over the cycle, relative
    to ω_s, measured 2.6e-8, 3.9e-10, 4.4e-11 (×66, ×8.9).  Before the release was located
    the same rk8 runs gave 4.0e-6, 5.1e-8, 2.3e-7 (360 samples): no convergence, the error
    rising from 16 to 32.  Asserted: each halving of the step divides the error by ≥ 6 and
    the 32-step error is ≤ 2e-10 (4.5x margin)."""
    sc = scene()
    ref = simulate_shaft(sc, points=90, startup=False, method="DOP853", rtol=1e-12)
    err = [np.max(np.abs(simulate_shaft(sc, points=90, startup=False, method="rk8",
                                        steps_per_period=s).speed - ref.speed)) / WS
           for s in (8, 16, 32)]
    assert err[0] / err[1] >= 6.0
    assert err[1] / err[2] >= 6.0
    assert err[2] <= 2e-10
