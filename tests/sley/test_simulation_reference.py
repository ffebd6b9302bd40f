"""`mechcirc.sley.simulate` (the presets of Tables 1 and 2) against eqs. (4) and (9) written
out independently in ``_sley_reference`` and integrated by DOP853 at rtol 1e-12.

Written before the hand-written sley equations were retired (the presets now run as
their scenes): it records that the preset results agree with the paper's equations
to 1e-6 relative whichever model computes them.  Measured with the hand-written
model (rel. difference of the extrema eps2P, eps4P, M2V (, eps5P, M5V)):

=====================  =========  ===============  ===============
case                   DOP853     rk4, 200 steps   rk4, 800 steps
=====================  =========  ===============  ===============
one-side 1 (no gap)    1.4e-8     1.3e-8           —
one-side 3 (gap)       2.9e-9     2.7e-5           7.5e-7
both-sides 1 (no gap)  1.4e-8     1.1e-8           —
both-sides 3 (gap)     1.0e-8     1.6e-5           6.0e-7
=====================  =========  ===============  ===============

(the 1.4e-8 floor is the kinematic table against the closed form).  Tolerances:
1e-7 for DOP853 and the smooth rk4 runs (margin ≥ 7×), 1.5e-6 for rk4 across the
clearance (800 steps per period; margin 2×; at a dead-zone kink RK4 loses its order).
"""

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import _sley_reference as ref
from mechcirc.sley import preset, simulate


def reference(drive, variant, revolutions, npts):
    """Extrema of the last of ``revolutions`` from the independent equations."""
    p = preset(drive, variant)
    keys = ("I2P", "I4", "I4P", "C2", "C4", "k2", "k4", "omega", "clearance", "M0")
    if drive == "both-sides":
        keys += ("I5P", "I7", "C5", "C7", "k5", "k7")
    d = {k: getattr(p, k) for k in keys}
    d["theta0"] = th0 = ref.first_nu_zero()
    phi4, mu, _ = ref.rocker(th0)
    if drive == "one-side":
        f = ref.eq4_rhs(d, ref.front_dead_centre(), p.alpha)
        y0 = [th0, p.omega, phi4, mu * p.omega]
        atol = [1e-13, 1e-9, 1e-13, 1e-10]
    else:
        f = ref.eq9_rhs(d, ref.front_dead_centre(), p.alpha)
        y0 = [th0, p.omega, th0, p.omega, phi4, mu * p.omega]
        atol = [1e-13, 1e-9, 1e-13, 1e-9, 1e-13, 1e-10]
    T = 2 * math.pi / p.omega
    t_eval = (revolutions - 1) * T + np.arange(npts) * T / npts
    sol = solve_ivp(f, (0, revolutions * T), y0, method="DOP853", rtol=1e-12, atol=atol,
                    t_eval=t_eval)
    assert sol.status == 0
    acc = np.array([f(t, y) for t, y in zip(sol.t, sol.y.T)])
    out = {"eps2P": acc[:, 1], "eps4P": acc[:, -1],
           "M2V": np.array([ref.driving_moment(d, t, y) for t, y in zip(sol.t, sol.y.T)])}
    if drive == "both-sides":
        out["eps5P"] = acc[:, 3]
        out["M5V"] = np.array([-d["C5"] * ref.dead_zone(y[2] - th0 - d["omega"] * t,
                                                         d["clearance"])
                               - d["k5"] * (y[3] - d["omega"]) for t, y in zip(sol.t, sol.y.T)])
    return {k: (float(v.min()), float(v.max())) for k, v in out.items()}


def rel(got, want):
    return max(abs(got[k][i] - want[k][i]) / max(map(abs, want[k]))
               for k in want for i in (0, 1))


@pytest.mark.parametrize("drive, variant, spp, tol", [("one-side", 3, 800, 1.5e-6),
                                                      ("both-sides", 1, 200, 1e-7)])
def test_presets_agree_with_independent_equations(drive, variant, spp, tol):
    want = reference(drive, variant, 2, 1440)
    got = simulate(drive, variant, revolutions=2, points_per_revolution=1440,
                   steps_per_period=spp, error_estimate=False)
    assert set(want) <= set(got.extrema)
    assert rel(got.extrema, want) < tol
    got = simulate(drive, variant, revolutions=2, points_per_revolution=1440,
                   method="DOP853", rtol=1e-11)
    assert rel(got.extrema, want) < 1e-7
