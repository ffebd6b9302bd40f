"""rk8 (the DOP853 formula at fixed steps) across the kinks of a clearance gap: its error
falls with the step instead of jumping where a kink sits on a step boundary."""

import numpy as np

from mechcirc.scene.shaft import simulate_shaft
from test_shaft_rk8 import gap_scene


def test_rk8_converges_across_a_dead_zone_on_the_shaft():
    """The elastic slider-crank with a 2 µm dead zone on the shaft (four gap edges and the
    moment window's two a cycle), rk8 at 8 and 16 steps per period of the rod's mode, output
    at 360 points (so 360 and 720 steps a cycle: the window opens on a step's end at 720),
    against DOP853 at rtol 1e-12 (no kink location; the same equations).  Measured 3.2e-11
    and 8.2e-12 of the mean speed (the second the reference's own floor); before the fix
    8.6e-10 and 4.0e-8: a kink on a step's end sent the bisection to the step's start, and
    the located cut, from the interpolant of the step across the kink, came late.
    Asserted 1e-10 (3x margin on the first) and no growth with the finer step."""
    scene = gap_scene()
    ref = simulate_shaft(scene, points=360, startup=False, method="DOP853", rtol=1e-12)
    err = [float(np.max(np.abs(simulate_shaft(scene, points=360, startup=False, method="rk8",
                                              steps_per_period=s).speed - ref.speed)))
           / ref.omega_mean for s in (8, 16)]
    assert err[0] <= 1e-10
    assert err[1] <= 1e-10
    assert err[1] <= 1.5 * err[0]
