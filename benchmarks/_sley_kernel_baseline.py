"""BASELINE for benchmarks/bench_scene_sley.py: the retired hand-written sley kernel.

Until the presets became scenes, ``mechcirc/sley/_kernels.py`` held eqs. (4) and (9)
written out by hand; this is that file as it was (plus a small driver at the end),
kept only so that the benchmark can measure the generic scene kernel against it in
the same run.  Nothing in ``mechcirc`` imports it.

Right-hand sides of eqs. (4) and (9) and a fixed-step RK4 loop, on plain floats.

One source, two backends: when numba is importable the functions are compiled
with ``@njit(cache=True)``; otherwise (or when loaded through
:func:`load_python`) they run as ordinary Python.  This module is imported only
when a simulation runs, so ``import mechcirc`` never imports numba.

State vectors (angles relative to the driven shaft keep the twist accurate):

* one-side:   y = [δ2, ω2P, φ4P, ω4P],            δ2 = φ2P − φ2
* both-sides: y = [δ2, ω2P, δ5, ω5P, φ4P, ω4P],  δ5 = φ5P − φ2

with φ2 = θ0 + ω t.  Parameter vector ``p`` (indices ``P_*`` below) and the
transfer-function table ``tab`` (quintic Hermite pieces of φ4(θ) on a uniform
periodic grid; μ and ν are its exact first and second derivatives) are arrays.

``aux`` receives [ε2P, ε4P, M2V, ε5P, M5V, M4] at the evaluated state.
"""

from __future__ import annotations

import math

import numpy as np

from mechcirc._jit import decorators
from mechcirc._ode import record_hermite

HAVE_NUMBA, _jit, _ = decorators(bool(globals().get("_FORCE_PYTHON")))

(P_OMEGA, P_THETA0, P_I2P, P_I4, P_I4P, P_C2, P_C4, P_K2, P_K4, P_CL, P_M0, P_PHIP,
 P_ALPHA, P_SIGMA, P_I5P, P_I7, P_C5, P_C7, P_K5, P_K7) = range(20)
N_PARAMS = 20
TWO_PI = 2.0 * math.pi


@_jit
def dead_zone(e, cl):
    """Deformation after the clearance law, eqs. (8)/(11): 0 inside ±cl, e ∓ cl beyond."""
    if e > cl:
        return e - cl
    if e < -cl:
        return e + cl
    return 0.0


@_jit
def transfer(theta, tab):
    """(φ4, μ, ν) at crank angle θ from the quintic Hermite table."""
    n = tab.shape[0]
    h = TWO_PI / n
    u = theta - TWO_PI * math.floor(theta / TWO_PI)
    i = int(u / h)
    if i >= n:
        i = n - 1
    s = u - i * h
    c0 = tab[i, 0]
    c1 = tab[i, 1]
    c2 = tab[i, 2]
    c3 = tab[i, 3]
    c4 = tab[i, 4]
    c5 = tab[i, 5]
    phi = c0 + s * (c1 + s * (c2 + s * (c3 + s * (c4 + s * c5))))
    mu = c1 + s * (2.0 * c2 + s * (3.0 * c3 + s * (4.0 * c4 + s * 5.0 * c5)))
    nu = 2.0 * c2 + s * (6.0 * c3 + s * (12.0 * c4 + s * 20.0 * c5))
    return phi, mu, nu


@_jit
def beat_moment(phi2p, p):
    """M4 of eqs. (5)-(7): half sine of amplitude M0 over φP ± α/2 (σ = α by default)."""
    m0 = p[P_M0]
    if m0 == 0.0:
        return 0.0
    alpha = p[P_ALPHA]
    x = phi2p - p[P_PHIP] + 0.5 * alpha
    x = x - TWO_PI * math.floor(x / TWO_PI)
    if x < alpha:
        return m0 * math.sin(math.pi * x / p[P_SIGMA])
    return 0.0


@_jit
def rhs_one(t, y, p, tab, dy, aux):
    """Eq. (4): derivatives of y = [δ2, ω2P, φ4P, ω4P] into ``dy``; outputs into ``aux``."""
    omega = p[P_OMEGA]
    cl = p[P_CL]
    phi2p = p[P_THETA0] + omega * t + y[0]
    w2p = y[1]
    phi4, mu, nu = transfer(phi2p, tab)
    w4 = mu * w2p
    m2 = -p[P_C2] * dead_zone(y[0], cl) - p[P_K2] * (w2p - omega)        # rod 2 on crank 2P
    m4 = -p[P_C4] * dead_zone(y[2] - phi4, cl) - p[P_K4] * (y[3] - w4)   # rod 4 on sley 4P
    mb = beat_moment(phi2p, p)
    i4 = p[P_I4]
    e2 = (-i4 * mu * nu * w2p * w2p + m2 - mu * m4) / (p[P_I2P] + i4 * mu * mu)
    e4 = (m4 - mb) / p[P_I4P]
    dy[0] = w2p - omega
    dy[1] = e2
    dy[2] = y[3]
    dy[3] = e4
    aux[0] = e2
    aux[1] = e4
    aux[2] = m2
    aux[3] = 0.0
    aux[4] = 0.0
    aux[5] = mb


@_jit
def rhs_both(t, y, p, tab, dy, aux):
    """Eq. (9): derivatives of y = [δ2, ω2P, δ5, ω5P, φ4P, ω4P] into ``dy``."""
    omega = p[P_OMEGA]
    cl = p[P_CL]
    phi2 = p[P_THETA0] + omega * t
    phi2p = phi2 + y[0]
    phi5p = phi2 + y[2]
    w2p = y[1]
    w5p = y[3]
    phi4, mu, nu = transfer(phi2p, tab)
    phi7, mu7, nu7 = transfer(phi5p, tab)
    w4 = mu * w2p
    w7 = mu7 * w5p
    m2 = -p[P_C2] * dead_zone(y[0], cl) - p[P_K2] * (w2p - omega)
    m5 = -p[P_C5] * dead_zone(y[2], cl) - p[P_K5] * (w5p - omega)
    m4 = -p[P_C4] * dead_zone(y[4] - phi4, cl) - p[P_K4] * (y[5] - w4)
    m7 = -p[P_C7] * dead_zone(y[4] - phi7, cl) - p[P_K7] * (y[5] - w7)
    mb = beat_moment(phi2p, p)
    i4 = p[P_I4]
    i7 = p[P_I7]
    e2 = (-i4 * mu * nu * w2p * w2p + m2 - mu * m4) / (p[P_I2P] + i4 * mu * mu)
    e5 = (-i7 * mu7 * nu7 * w5p * w5p + m5 - mu7 * m7) / (p[P_I5P] + i7 * mu7 * mu7)
    e4 = (m4 + m7 - mb) / p[P_I4P]
    dy[0] = w2p - omega
    dy[1] = e2
    dy[2] = w5p - omega
    dy[3] = e5
    dy[4] = y[5]
    dy[5] = e4
    aux[0] = e2
    aux[1] = e4
    aux[2] = m2
    aux[3] = e5
    aux[4] = m5
    aux[5] = mb


@_jit
def rhs(both, t, y, p, tab, dy, aux):
    """Dispatch to eq. (4) (``both`` false) or eq. (9)."""
    if both:
        rhs_both(t, y, p, tab, dy, aux)
    else:
        rhs_one(t, y, p, tab, dy, aux)


@_jit
def rk4_run(both, p, tab, y, t0, h, nsteps, t_out0, dt_out, rec_y, rec_t):
    """Advance ``y`` (in place) by ``nsteps`` classical RK4 steps of size ``h`` [s] from ``t0``.

    The state at the output times t_out0 + j·dt_out (j < len(rec_t)) that fall
    within the steps is stored in ``rec_y[j]`` by cubic Hermite interpolation
    between the step ends (values and derivatives; the derivative at a step's
    end is the next step's first stage, so a step costs four evaluations).
    Returns (time reached, outputs written, no blow-up).
    """
    n = y.shape[0]
    k1 = np.empty(n)
    k2 = np.empty(n)
    k3 = np.empty(n)
    k4 = np.empty(n)
    tmp = np.empty(n)
    ynew = np.empty(n)
    aux = np.empty(6)
    j = 0
    half = 0.5 * h
    sixth = h / 6.0
    rhs(both, t0, y, p, tab, k1, aux)
    for step in range(nsteps):
        t = t0 + step * h
        for i in range(n):
            tmp[i] = y[i] + half * k1[i]
        rhs(both, t + half, tmp, p, tab, k2, aux)
        for i in range(n):
            tmp[i] = y[i] + half * k2[i]
        rhs(both, t + half, tmp, p, tab, k3, aux)
        for i in range(n):
            tmp[i] = y[i] + h * k3[i]
        rhs(both, t + h, tmp, p, tab, k4, aux)
        for i in range(n):
            ynew[i] = y[i] + sixth * (k1[i] + 2.0 * (k2[i] + k3[i]) + k4[i])
        rhs(both, t + h, ynew, p, tab, k4, aux)       # derivative at the step's end
        j = record_hermite(rec_t, rec_y, j, t_out0, dt_out, t, h, step == nsteps - 1,
                           y, k1, ynew, k4, n, 0, tmp)
        for i in range(n):
            y[i] = ynew[i]
            k1[i] = k4[i]
        # a crank speed a thousand times off (or NaN) can only be numerical blow-up
        if not abs(y[1] - p[P_OMEGA]) <= 1e3 * p[P_OMEGA]:
            return t0 + (step + 1) * h, j, False
    return t0 + nsteps * h, j, True


@_jit
def outputs(both, p, tab, ts, ys, out):
    """Evaluate ``aux`` (ε2P, ε4P, M2V, ε5P, M5V, M4) at each stored state into ``out``."""
    n = ys.shape[1]
    dy = np.empty(n)
    aux = np.empty(6)
    for i in range(ts.shape[0]):
        rhs(both, ts[i], ys[i], p, tab, dy, aux)
        for j in range(6):
            out[i, j] = aux[j]


def load_python():
    """A fresh copy of this module that never uses numba (the pure-Python backend)."""
    import importlib.util

    spec = importlib.util.find_spec(__name__)
    mod = importlib.util.module_from_spec(spec)
    mod.__dict__["_FORCE_PYTHON"] = True
    spec.loader.exec_module(mod)
    return mod


# ------------------------------------------------------------- driver (benchmark only)
def run(params, revolutions, npts, per_rev, table_points=1024):
    """The retired ``simulate_params`` RK4 path: (extrema of eps2P, eps4P, M2V, wall time)."""
    import time

    from mechcirc.scene.motion import hermite_table
    from mechcirc.sley.simulation import start_angle

    fb = params.fourbar()
    th = np.linspace(0.0, TWO_PI, table_points + 1)
    st = fb.evaluate(th)
    ref = 0.5 * (st.phi4.max() + st.phi4.min())
    tab = hermite_table(TWO_PI / table_points, st.phi4 - ref, st.mu, st.nu)
    theta0 = start_angle(params)
    p = params
    v = np.zeros(N_PARAMS)
    v[P_OMEGA], v[P_THETA0] = p.omega, theta0
    v[P_I2P], v[P_I4], v[P_I4P] = p.I2P, p.I4, p.I4P
    v[P_C2], v[P_C4], v[P_K2], v[P_K4] = p.C2, p.C4, p.k2, p.k4
    v[P_CL], v[P_M0], v[P_PHIP] = p.clearance, -p.beat_sign * p.M0, fb.dead_centres()[0].theta
    v[P_ALPHA], v[P_SIGMA] = p.alpha, p.sigma
    phi4, mu, _ = fb.transfer(theta0)
    y = np.array([0.0, p.omega, phi4 - ref, mu * p.omega])
    period = TWO_PI / p.omega
    h = period / per_rev
    rec_y, rec_t = np.empty((npts, 4)), np.empty(npts)
    dummy_y, dummy_t = np.empty((0, 4)), np.empty(0)
    t0 = time.perf_counter()
    for r in range(revolutions):
        ry, rt = (rec_y, rec_t) if r == revolutions - 1 else (dummy_y, dummy_t)
        rk4_run(False, v, tab, y, r * period, h, per_rev, r * period, period / npts, ry, rt)
    wall = time.perf_counter() - t0
    out = np.empty((npts, 6))
    outputs(False, v, tab, rec_t, rec_y, out)
    mm = lambda a: (float(a.min()), float(a.max()))
    return {"eps2P": mm(out[:, 0]), "eps4P": mm(out[:, 1]), "M2V": mm(out[:, 2])}, wall
