"""Independent references for the sley tests (eqs. 4 and 9 of Mrázek); never imports mechcirc.

* Four-bar by Freudenstein's form of loop closure, g(θ, φ) = 0 with
  g = a² + d² + c² − b² − 2ad cos θ + 2dc cos φ − 2ac cos(θ − φ), solved for φ in
  closed form (P cos φ + Q sin φ = R) on the assembly whose rocker tip lies above
  the frame line; μ and ν by implicit differentiation of g.
* Eq. (4) of Mrázek written out again from the paper with its own clearance law.
"""

import functools
import math

import numpy as np
from scipy.integrate import solve_ivp

A, B, C, D = 0.029, 0.037, 0.188, 0.189


def rocker(theta, a=A, b=B, c=C, d=D):
    """(φ, μ, ν) of the rocker, tip above the frame line."""
    ct, st = math.cos(theta), math.sin(theta)
    P = 2 * d * c - 2 * a * c * ct
    Q = -2 * a * c * st
    R = -(a * a + d * d + c * c - b * b - 2 * a * d * ct)
    base = math.atan2(Q, P)
    spread = math.acos(R / math.hypot(P, Q))
    cands = [base + spread, base - spread]
    phi = next(p for p in cands if math.sin(p) > 0)
    s, cdiff = math.sin(theta - phi), math.cos(theta - phi)
    g_t = 2 * a * d * st + 2 * a * c * s
    g_p = -2 * d * c * math.sin(phi) - 2 * a * c * s
    mu = -g_t / g_p
    g_tt = 2 * a * d * ct + 2 * a * c * cdiff
    g_tp = -2 * a * c * cdiff
    g_pp = -2 * d * c * math.cos(phi) + 2 * a * c * cdiff
    nu = -(g_tt + 2 * g_tp * mu + g_pp * mu * mu) / g_p
    return phi % (2 * math.pi), mu, nu


def nu_range(n=20000):
    """(min ν, max ν) over a revolution: dense grid, then golden-section refinement."""
    th = np.linspace(0, 2 * math.pi, n, endpoint=False)
    nu = np.array([rocker(t)[2] for t in th])
    out = []
    for sign, i in ((1, int(np.argmin(nu))), (-1, int(np.argmax(nu)))):
        lo, hi = th[i] - 2 * math.pi / n, th[i] + 2 * math.pi / n
        gr = (math.sqrt(5) - 1) / 2
        for _ in range(80):
            x1, x2 = hi - gr * (hi - lo), lo + gr * (hi - lo)
            if sign * rocker(x1)[2] < sign * rocker(x2)[2]:
                hi = x2
            else:
                lo = x1
        out.append(rocker(0.5 * (lo + hi))[2])
    return out[0], out[1]


def front_dead_centre(a=A, b=B, c=C, d=D):
    """Crank angle where crank and coupler are extended (|AC| = a + b), tip above the line."""
    alpha = math.acos(((a + b) ** 2 + d * d - c * c) / (2 * d * (a + b)))
    for th in (alpha, -alpha % (2 * math.pi)):
        phi = rocker(th)[0]
        if abs(math.hypot(d + c * math.cos(phi), c * math.sin(phi)) - (a + b)) < 1e-9:
            return th
    raise AssertionError("no front dead centre")


@functools.lru_cache(maxsize=None)
def first_nu_zero():
    """The crank angle of the first zero of ν (a constant: 3,800 closed-form solves, computed
    once per process rather than by each caller)."""
    th = np.linspace(0, 2 * math.pi, 3601)
    nu = np.array([rocker(t)[2] for t in th])
    i = int(np.flatnonzero(np.sign(nu[:-1]) != np.sign(nu[1:]))[0])
    lo, hi = th[i], th[i + 1]
    for _ in range(100):
        mid = 0.5 * (lo + hi)
        if np.sign(rocker(mid)[2]) == np.sign(rocker(lo)[2]):
            lo = mid
        else:
            hi = mid
    return 0.5 * (lo + hi)


def dead_zone(e, cl):
    if abs(e) <= cl:
        return 0.0
    return e - math.copysign(cl, e)


def eq4_rhs(p, phi_p, alpha, beat_sign=-1.0):
    """f(t, y) of eq. (4) in absolute angles y = [φ2P, ω2P, φ4P, ω4P]; p a dict."""
    def f(t, y):
        phi2 = p["theta0"] + p["omega"] * t
        phi4, mu, nu = rocker(y[0])
        w4 = mu * y[1]
        d2 = dead_zone(y[0] - phi2, p["clearance"])
        d4 = dead_zone(y[2] - phi4, p["clearance"])
        x = (y[0] - phi_p + alpha / 2) % (2 * math.pi)
        m4 = p["M0"] * math.sin(math.pi * x / alpha) if x < alpha else 0.0
        J = p["I2P"] + p["I4"] * mu * mu
        e2 = (-p["I4"] * mu * nu * y[1] ** 2 - p["C2"] * d2 + p["C4"] * mu * d4
              - p["k2"] * (y[1] - p["omega"]) + p["k4"] * mu * (y[3] - w4)) / J
        e4 = (-p["C4"] * d4 - p["k4"] * (y[3] - w4) + beat_sign * m4) / p["I4P"]
        return np.array([y[1], e2, y[3], e4])
    return f


def driving_moment(p, t, y):
    phi2 = p["theta0"] + p["omega"] * t
    return -p["C2"] * dead_zone(y[0] - phi2, p["clearance"]) - p["k2"] * (y[1] - p["omega"])


def eq9_rhs(p, phi_p, alpha, beat_sign=-1.0):
    """f(t, y) of eq. (9), y = [φ2P, ω2P, φ5P, ω5P, φ4P, ω4P] (absolute angles)."""
    def f(t, y):
        phi2 = p["theta0"] + p["omega"] * t
        phi4, mu, nu = rocker(y[0])
        phi7, mu7, nu7 = rocker(y[2])
        w4, w7 = mu * y[1], mu7 * y[3]
        cl = p["clearance"]
        d2, d5 = dead_zone(y[0] - phi2, cl), dead_zone(y[2] - phi2, cl)
        d4, d7 = dead_zone(y[4] - phi4, cl), dead_zone(y[4] - phi7, cl)
        x = (y[0] - phi_p + alpha / 2) % (2 * math.pi)
        m4 = p["M0"] * math.sin(math.pi * x / alpha) if x < alpha else 0.0
        e2 = (-p["I4"] * mu * nu * y[1] ** 2 - p["C2"] * d2 + p["C4"] * mu * d4
              - p["k2"] * (y[1] - p["omega"]) + p["k4"] * mu * (y[5] - w4)) \
            / (p["I2P"] + p["I4"] * mu * mu)
        e5 = (-p["I7"] * mu7 * nu7 * y[3] ** 2 - p["C5"] * d5 + p["C7"] * mu7 * d7
              - p["k5"] * (y[3] - p["omega"]) + p["k7"] * mu7 * (y[5] - w7)) \
            / (p["I5P"] + p["I7"] * mu7 * mu7)
        e4 = (-p["C4"] * d4 - p["C7"] * d7 + beat_sign * m4 - p["k4"] * (y[5] - w4)
              - p["k7"] * (y[5] - w7)) / p["I4P"]
        return np.array([y[1], e2, y[3], e5, y[5], e4])
    return f


def extrema(p, revolutions, npts):
    """Extrema of eps2P, eps4P, M2V (and eps5P, M5V) over the last of ``revolutions``.

    ``p`` has the attributes of a preset (``drive``, ``I2P`` … ``M0``, ``alpha``); the
    equations are integrated by DOP853 at rtol 1e-12 from the first zero of ν, and
    sampled at ``npts`` instants of the last revolution.
    """
    keys = ("I2P", "I4", "I4P", "C2", "C4", "k2", "k4", "omega", "clearance", "M0")
    if p.drive == "both-sides":
        keys += ("I5P", "I7", "C5", "C7", "k5", "k7")
    d = {k: getattr(p, k) for k in keys}
    d["theta0"] = th0 = first_nu_zero()
    phi4, mu, _ = rocker(th0)
    if p.drive == "one-side":
        f = eq4_rhs(d, front_dead_centre(), p.alpha)
        y0 = [th0, p.omega, phi4, mu * p.omega]
        atol = [1e-13, 1e-9, 1e-13, 1e-10]
    else:
        f = eq9_rhs(d, front_dead_centre(), p.alpha)
        y0 = [th0, p.omega, th0, p.omega, phi4, mu * p.omega]
        atol = [1e-13, 1e-9, 1e-13, 1e-9, 1e-13, 1e-10]
    T = 2 * math.pi / p.omega
    t_eval = (revolutions - 1) * T + np.arange(npts) * T / npts
    sol = solve_ivp(f, (0, revolutions * T), y0, method="DOP853", rtol=1e-12, atol=atol,
                    t_eval=t_eval)
    assert sol.status == 0
    acc = np.array([f(t, y) for t, y in zip(sol.t, sol.y.T)])
    out = {"eps2P": acc[:, 1], "eps4P": acc[:, -1],
           "M2V": np.array([driving_moment(d, t, y) for t, y in zip(sol.t, sol.y.T)])}
    if p.drive == "both-sides":
        out["eps5P"] = acc[:, 3]
        out["M5V"] = np.array([-d["C5"] * dead_zone(y[2] - th0 - d["omega"] * t,
                                                    d["clearance"])
                               - d["k5"] * (y[3] - d["omega"]) for t, y in zip(sol.t, sol.y.T)])
    return {k: (float(v.min()), float(v.max())) for k, v in out.items()}


def worst_relative_difference(got, want):
    """max over the keys of ``want`` of |got − want| / max |want| at the minimum and maximum."""
    return max(abs(got[k][i] - want[k][i]) / max(map(abs, want[k]))
               for k in want for i in (0, 1))
