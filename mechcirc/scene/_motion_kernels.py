"""Right-hand side of a scene's equations of motion (Lagrange II) and its fixed-step
explicit Runge-Kutta stepper (RK4 or RK8), which also runs the dynamic main shaft.

Written once for any scene, on plain arrays built by :mod:`mechcirc.scene.motion`;
compiled with numba when it is importable (the ``fast`` extra), else plain
Python (:func:`load_python` forces that), through :mod:`mechcirc._jit`.

Each rigid part i has one coordinate q_i (the rotation of one of its bodies
from the pose); part 0 (the drive's) is prescribed: q_0 = ψ_0(θ), θ = θs + Ω t.
Every geometric quantity the energies need (a body's rotation, a point's x or
y) is a *function* of its part's coordinate, evaluated with its first and
second derivatives: a quintic Hermite table (value, slope and curvature
matched at every node, so the derivatives are exact derivatives of the
interpolant), a line a + b q, or a circle a + b cos(q + c).

    T = ½ Σ_i m_i(q_i) q̇_i²,   m_i = Σ w f'²  (w: a mass for x and y, an inertia for a rotation)
    m_i q̈_i + ½ m_i' q̇_i² = Q_i = −Σ_e f_e ∂δ_e/∂q_i + Σ moments M ∂φ/∂q_i

Function kinds: 0 periodic table of f(q) − w q over [lo, lo + c) (c: 2π, or the
cycle of geared cranks); 1 table on
[lo, lo + N h] (outside: flagged); 2 line a + b q; 3 circle a + b cos(q + c).
A function of part −1 is evaluated at the crank angle θ (the rigid motion).

Element types: 0 twist δ = f_b − f_a; 1 length δ = |P_b − P_a| − ℓ0 (a side
without functions is a fixed point); 2 load along u: δ = u·(P − P_rig(θ));
3 load toward anchor A: δ = |A − P_rig(θ)| − |A − P|.  Laws: 0 linear
(no clearance), 1 ElastoBacklash (no force in the gap, damping part limited to
|f_d| ≤ |f_c|), 2 Mrázek's dead zone (damping throughout).
"""

from __future__ import annotations

import functools
import math

import numpy as np

from .._jit import decorators, load
from .._ode import hermite_point, record_hermite
from ..transient._kernels import branch_changes, law_branch

HAVE_NUMBA, _jit, _jit_inline = decorators(bool(globals().get("_FORCE_PYTHON")))
# the kernels that allocate nothing, called per step or per evaluation: no reference counting
_leaf = decorators(bool(globals().get("_FORCE_PYTHON")), nrt=False)[1]

TWO_PI = 2.0 * math.pi
# function columns: FI = [kind, part, table]; FF = [a, b, c, lo, h, w, 1/c, 1/h] (the
# reciprocals of a table's period and node spacing, 0 where unused: motion.function_rows)
# element columns: EI = [type, law, fa, fa2, fb, fb2, part_a, part_b]
#                  EF = [k, d, clearance, l0, xa, ya, xb, yb, ux, uy]
# moment columns:  MI = [window fn, body fn]; MF = [amplitude, alpha, sigma, centre]
# PV = [Omega, theta_s, speed limit, functions to evaluate (the dynamics' first), outputs?,
#       speed ripple amplitude A [rad/s], its angular frequency ν [rad/s],
#       loads referred to the mean motion (1) or to the crank angle (0)]


@_jit_inline
def feval(kind, tabs, ti, a, b, c, lo, h, w, ic, ih, q):
    """(value, first, second derivative) of one function at coordinate q; flag out of range.
    ``ic``, ``ih``: 1/c and 1/h (a table's interval by a product, not a division)."""
    if kind == 2:
        return a + b * q, b, 0.0, 0
    if kind == 3:
        cs = math.cos(q + c)
        sn = math.sin(q + c)
        return a + b * cs, -b * sn, -b * cs, 0
    n = tabs.shape[1]
    u = q - lo
    if kind == 0:
        u = u - c * math.floor(u * ic)
        i = int(u * ih)
        bad = 0
    else:
        i = int(math.floor(u * ih))
        # (no branches: each costs blocks in every inlined copy of this function)
        bad = int((i < 0) | ((i >= n) & (u > n * h)))
        i = max(i, 0)
    i = min(i, n - 1)
    s = u - i * h
    c0 = tabs[ti, i, 0]
    c1 = tabs[ti, i, 1]
    c2 = tabs[ti, i, 2]
    c3 = tabs[ti, i, 3]
    c4 = tabs[ti, i, 4]
    c5 = tabs[ti, i, 5]
    f = c0 + s * (c1 + s * (c2 + s * (c3 + s * (c4 + s * c5))))
    f1 = c1 + s * (2.0 * c2 + s * (3.0 * c3 + s * (4.0 * c4 + s * 5.0 * c5)))
    f2 = 2.0 * c2 + s * (6.0 * c3 + s * (12.0 * c4 + s * 20.0 * c5))
    return f + w * q, f1 + w, f2, bad


@_jit_inline
def wrap_phase(x):
    """x mod 2π in [0, 2π), by the product with 1/(2π) (a constant the compiler folds), not a
    division: a division on the right-hand side's critical path costs several products."""
    return x - TWO_PI * math.floor(x * (1.0 / TWO_PI))


@_jit_inline
def window_moment(amp, alpha, sigma, centre, phi):
    """A crank-angle moment (the beat-up): amp · sin(π x/σ) for x = φ − centre + α/2
    (mod 2π) in [0, α), else 0; φ the crank's rotation from the pose [rad]."""
    x = phi - centre + 0.5 * alpha
    x = wrap_phase(x)
    if x < alpha:
        return amp * math.sin(math.pi * x / sigma)
    return 0.0


@_jit_inline
def force_law(law, k, d, cl, e, edot):
    """Force of a spring k ∥ damper d with deformation e, rate edot and clearance cl."""
    if law == 0:
        return k * e + d * edot
    if law == 1:
        # ElastoBacklash, written once (mechcirc.transient._kernels); cl is half the gap
        return law_branch(e, edot, k, d, 2.0 * cl)[0]
    # Mrázek's dead zone: the damper acts inside the gap too
    if e > cl:
        return k * (e - cl) + d * edot
    if e < -cl:
        return k * (e + cl) + d * edot
    return d * edot


@_jit_inline
def fn_at(f, FI, FF, tabs, q):
    """:func:`feval` of function f (its row of FI and FF) at coordinate q."""
    return feval(FI[f, 0], tabs, FI[f, 2], FF[f, 0], FF[f, 1], FF[f, 2], FF[f, 3], FF[f, 4],
                 FF[f, 5], FF[f, 6], FF[f, 7], q)


@_jit_inline
def crank_motion(PV, t):
    """The crank's (angle, speed, acceleration) at time t and the (angle, speed) the loads'
    rigid reference follows.

    θ = θs + Ω t + (A/ν) sin(ν t) (a speed ripple A cos(ν t); A = 0: constant).  A load's
    reference is the rigid motion at the crank angle (PV[7] = 0), or at the mean motion
    θs + Ω t (PV[7] = 1: a load to the frame under a small ripple, as the circuit).
    """
    amp = PV[5]
    theta = PV[1] + PV[0] * t
    omega = PV[0]
    th_load = theta
    w_load = omega
    accel = 0.0
    if amp != 0.0:
        nu = PV[6]
        sn = math.sin(nu * t)
        theta += amp / nu * sn
        omega += amp * math.cos(nu * t)
        accel = -amp * nu * sn
        if PV[7] == 0.0:
            th_load = theta
            w_load = omega
    return theta, omega, accel, th_load, w_load


@_jit_inline
def part_kinematics(y, theta, omega, accel, nf, FI, FF, tabs, MI_, MW, PRIG, work):
    """Every part's coordinate, rate (work rows 0, 1; the drive's part 0 also its
    acceleration, row 2, from its prescribed ψ_0(θ)), every function of them with its
    derivatives (rows 6–8), each part's mass m and dm/dq (rows 3, 4) and a zero generalised
    force (row 5).  Returns the out-of-range flag of the functions."""
    npart = PRIG.shape[0]
    n = npart - 1
    v0, d0, dd0, b0 = fn_at(PRIG[0], FI, FF, tabs, theta)
    work[0, 0] = v0
    work[1, 0] = d0 * omega
    work[2, 0] = dd0 * omega * omega + d0 * accel
    for i in range(n):
        work[0, i + 1] = y[i]
        work[1, i + 1] = y[n + i]
    for j in range(npart):
        work[3, j] = 0.0
        work[4, j] = 0.0
        work[5, j] = 0.0
    bad = 0
    for f in range(nf):
        p = FI[f, 1]
        if p < 0:           # a rigid-motion function of θ: evaluated where needed
            continue
        arg = work[0, p]
        if FI[f, 0] == 2:           # a line a + b q: most functions (a crank, a pinned body)
            b1 = FF[f, 1]
            work[6, f] = FF[f, 0] + b1 * arg
            work[7, f] = b1
            work[8, f] = 0.0
            continue
        a, b1, b2, bb = fn_at(f, FI, FF, tabs, arg)
        work[6, f] = a
        work[7, f] = b1
        work[8, f] = b2
        bad = bad | bb
    for k in range(MI_.shape[0]):
        f = MI_[k]
        p = FI[f, 1]
        work[3, p] += MW[k] * work[7, f] * work[7, f]
        work[4, p] += 2.0 * MW[k] * work[7, f] * work[8, f]
    return bad


@_jit_inline
def end_point(e, side, EI, EF, work):
    """(x, y) of end ``side`` (0: P_a, 1: P_b) of length element e: its functions' values
    (EI[e, 2 + 2 side], EI[e, 3 + 2 side]), or without functions the fixed point in EF."""
    c = 2 + 2 * side
    if EI[e, c] >= 0:
        return work[6, EI[e, c]], work[6, EI[e, c + 1]]
    return EF[e, c + 2], EF[e, c + 3]


@_jit_inline
def length_element(e, EI, EF, work):
    """(δ, ∂δ/∂q_a, ∂δ/∂q_b) of a length element e: δ = |P_b − P_a| − ℓ0, a side without
    functions a fixed point."""
    ga = 0.0
    gb = 0.0
    xa, ya = end_point(e, 0, EI, EF, work)
    xb, yb = end_point(e, 1, EI, EF, work)
    dx = xb - xa
    dyy = yb - ya
    ln = math.sqrt(dx * dx + dyy * dyy)
    ux = dx / ln
    uy = dyy / ln
    de = ln - EF[e, 3]
    if EI[e, 2] >= 0:
        ga = -(ux * work[7, EI[e, 2]] + uy * work[7, EI[e, 3]])
    if EI[e, 4] >= 0:
        gb = ux * work[7, EI[e, 4]] + uy * work[7, EI[e, 5]]
    return de, ga, gb


@_jit_inline
def load_element(e, EI, EF, FI, FF, tabs, th_load, w_load, work):
    """(δ, ∂δ/∂q_b, rigid part of δ̇) of a load e on point P of part b (functions fb, fb2):
    along u, δ = u·(P − P_rig), or toward anchor A, δ = |A − P_rig| − |A − P|; P_rig the same
    functions at the part's rigid coordinate (function fa of θ) at the loads' reference."""
    fx = EI[e, 4]
    fy = EI[e, 5]
    # the part's rigid coordinate (function fa of θ), then x and y of P_rig there, from one
    # fn_at site: numba's inline="always" copies the callee at every site (2.4 s of compile)
    qr = th_load
    qr1 = 0.0
    xr = 0.0
    xr1 = 0.0
    for r in range(3):              # the last pass leaves y's value and rate in yr, yr1
        yr, yr1, v2, bb = fn_at(EI[e, r + 3 if r else 2], FI, FF, tabs, qr)
        if r == 0:
            qr = yr
            qr1 = yr1
        elif r == 1:
            xr = yr
            xr1 = yr1
    vxr = xr1 * qr1 * w_load
    vyr = yr1 * qr1 * w_load
    if EI[e, 0] == 2:
        ux = EF[e, 8]
        uy = EF[e, 9]
        de = ux * (work[6, fx] - xr) + uy * (work[6, fy] - yr)
        gb = ux * work[7, fx] + uy * work[7, fy]
        return de, gb, -(ux * vxr + uy * vyr)
    ax = EF[e, 4]
    ay = EF[e, 5]
    dxr = ax - xr
    dyr = ay - yr
    lr = math.sqrt(dxr * dxr + dyr * dyr)
    dx = ax - work[6, fx]
    dyy = ay - work[6, fy]
    ln = math.sqrt(dx * dx + dyy * dyy)
    gb = (dx * work[7, fx] + dyy * work[7, fy]) / ln
    return lr - ln, gb, -(dxr * vxr + dyr * vyr) / lr


@_jit_inline
def element_forces(want, nb, EI, EF, FI, FF, tabs, th_load, w_load, aux, work, xo):
    """Each element's deformation δ (into aux) and force f (into aux if ``want``), and its
    generalised forces −f ∂δ/∂q on its two parts (work row 5); its rate δ̇ into aux[xo + e]
    when aux is that long (:func:`rk_run`'s, for :func:`regions`)."""
    ne = EI.shape[0]
    for e in range(ne):
        typ = EI[e, 0]
        pa = EI[e, 6]
        pb = EI[e, 7]
        ga = 0.0
        rate_rig = 0.0
        if typ == 0:                # a twist δ = f_b − f_a
            fa = EI[e, 2]
            fb = EI[e, 4]
            de = work[6, fb] - work[6, fa]
            ga = -work[7, fa]
            gb = work[7, fb]
        elif typ == 1:
            de, ga, gb = length_element(e, EI, EF, work)
        else:
            de, gb, rate_rig = load_element(e, EI, EF, FI, FF, tabs, th_load, w_load, work)
        edot = ga * work[1, pa] + gb * work[1, pb] + rate_rig
        fe = force_law(EI[e, 1], EF[e, 0], EF[e, 1], EF[e, 2], de, edot)
        work[5, pa] -= fe * ga
        work[5, pb] -= fe * gb
        aux[nb + ne + e] = de          # always: the clearance events of rk_run read it
        if aux.shape[0] > xo + e:      # rk_run's longer aux: the rates, for regions' release
            aux[xo + e] = edot
        if want:
            aux[nb + e] = fe


@_jit_inline
def window_moments(off, FI, MOI, MOF, aux, work):
    """Each crank-angle moment (:func:`window_moment`) into aux[off + k] and its generalised
    force M ∂φ/∂q on its body's part (work row 5)."""
    for k in range(MOI.shape[0]):
        fw = MOI[k, 0]
        fbd = MOI[k, 1]
        mval = window_moment(MOF[k, 0], MOF[k, 1], MOF[k, 2], MOF[k, 3], work[6, fw])
        work[5, FI[fbd, 1]] += mval * work[7, fbd]
        aux[off + k] = mval


@_jit_inline
def body_outputs(nf, ne, FI, BI, aux, work):
    """Each body's angular acceleration f' q̈ + f'' q̇² into aux[0 .. B) (0 for a body of the
    rigid motion, function ≥ nf) and the drive's moment m q̈ + ½ m' q̇² − Q of part 0 after
    them."""
    nb = BI.shape[0]
    aux[nb + 2 * ne] = work[3, 0] * work[2, 0] + 0.5 * work[4, 0] * work[1, 0] * work[1, 0] - work[5, 0]
    for k in range(nb):
        f = BI[k]
        p = FI[f, 1]
        aux[k] = work[7, f] * work[2, p] + work[8, f] * work[1, p] * work[1, p] if f < nf else 0.0


@_jit_inline
def accelerations(nf, want, bad, FI, BI, EI, MOI, PRIG, dy, aux, work):
    """Each free part's q̈ = (Q − ½ m' q̇²)/m (work row 2) and the derivatives [q̇, q̈] of
    y into dy; with ``want`` the bodies' outputs (:func:`body_outputs`); the out-of-range
    flag ``bad`` last in aux."""
    npart = PRIG.shape[0]
    n = npart - 1
    ne = EI.shape[0]
    for i in range(1, npart):
        work[2, i] = (work[5, i] - 0.5 * work[4, i] * work[1, i] * work[1, i]) / work[3, i]
        dy[i - 1] = work[1, i]
        dy[n + i - 1] = work[2, i]
    if want:
        body_outputs(nf, ne, FI, BI, aux, work)
    aux[BI.shape[0] + 2 * ne + 1 + MOI.shape[0]] = bad


@_leaf
def rhs(t, y, PV, FI, FF, tabs, MI_, MW, EI, EF, MOI, MOF, PRIG, BI, dy, aux, work):
    """Derivatives of y = [q_1..q_n, q̇_1..q̇_n] into dy; outputs into aux.

    aux = [body accelerations (B) | element forces (E) | deformations (E) |
    drive moment | moments (Mo) | out-of-range flag].  work rows: 0 q, 1 q̇, 2 q̈, 3 m,
    4 m', 5 Q, then 6–8 each function's value and first and second derivatives.
    """
    # (:func:`rk_step` makes the same five calls: see there)
    nf, want, nb, ne, nmo = int(PV[3]), PV[4] != 0.0, BI.shape[0], EI.shape[0], MOI.shape[0]
    theta, omega, accel, th_load, w_load = crank_motion(PV, t)
    bad = part_kinematics(y, theta, omega, accel, nf, FI, FF, tabs, MI_, MW, PRIG, work)
    element_forces(want, nb, EI, EF, FI, FF, tabs, th_load, w_load, aux, work,
                   nb + 2 * ne + 2 + nmo)
    window_moments(nb + 2 * ne + 1, FI, MOI, MOF, aux, work)
    accelerations(nf, want, bad, FI, BI, EI, MOI, PRIG, dy, aux, work)


@_leaf
def regions(FI, EI, EF, MOI, MOF, aux, work, off, reg, sw, first):
    """The smooth piece each force law is on, from the last right-hand side evaluated
    (``aux``, ``work``): reg[e] = −1, 0 (inside the gap), +1 for an element with a clearance
    gap (0 for the others; ±2 released, ±3 damping capped for ElastoBacklash in contact:
    :func:`contact_piece`), reg[ne + k] = 1 inside the window of moment k, else 0 (always 0
    for a moment on a part below ``first``: 1 for a scene, whose drive's part 0 moves nothing
    that is integrated; 0 for the shaft, which integrates it); and the
    value each edge test starts from into ``sw`` (a deformation, a window's phase), then
    each element's rate δ̇ (``sw`` of length switches + E; ``aux`` :func:`rk_run`'s).
    Returns how many switches there are (gaps and windows)."""
    ne = EI.shape[0]
    nsw = ne + MOI.shape[0]
    xo = off + ne + 2 + MOI.shape[0]
    count = 0
    for e in range(ne):
        cl = EF[e, 2]
        de = aux[off + e]
        sw[e] = de
        reg[e] = 0
        sw[nsw + e] = aux[xo + e]
        if EI[e, 1] == 0 or not cl > 0.0:
            continue
        count += 1
        if de > cl:
            reg[e] = 1
        elif de < -cl:
            reg[e] = -1
        if EI[e, 1] == 1 and reg[e] != 0:    # ElastoBacklash: released, or damping capped
            reg[e] *= contact_piece(reg[e], de, aux[xo + e], EF[e, 0], EF[e, 1], cl)
    for k in range(MOI.shape[0]):
        x = work[6, MOI[k, 0]] - MOF[k, 3] + 0.5 * MOF[k, 1]
        sw[ne + k] = x
        reg[ne + k] = 0
        if FI[MOI[k, 1], 1] < first:
            continue
        reg[ne + k] = 1 if wrap_phase(x) < MOF[k, 1] else 0
        count += 1
    return count


@_jit_inline
def contact_piece(side, e, edot, k, d, cl):
    """Piece of ElastoBacklash (:func:`force_law`, law 1) in contact on ``side`` (±1) at
    deformation e, rate edot: 1 pushing k(e ∓ cl) + d ė, 2 released (that would-be force
    pulls), 3 the damping part capped at the spring part (force 2k(e ∓ cl))."""
    fc = k * (e - side * cl)
    fd = d * edot
    if side * (fc + fd) <= 0.0:
        return 2
    if side * (fd - fc) >= 0.0:
        return 3
    return 1


@_jit_inline
def edge_gap(i, ne, r0, r1, v, vd, EF, MOF):
    """Signed distance of switch i (value v, rate vd, see :func:`regions`) from the edge it
    crossed going from piece r0 to r1: a gap's edge ±cl, a window's start (phase 0) or end
    (α); within one side of a contact (:func:`contact_piece`) the would-be force k(e ∓ cl)
    + d ė (released) or d ė − k(e ∓ cl) (capped)."""
    if i < ne:
        cl = EF[i, 2]
        if r0 * r1 > 0:               # same side, another piece of the contact's law
            side = 1.0 if r0 > 0 else -1.0
            fc = EF[i, 0] * (v - side * cl)
            fd = EF[i, 1] * vd
            return fc + fd if abs(r0) == 2 or abs(r1) == 2 else fd - fc
        return v - (cl if (r0 > 0 or (r0 == 0 and r1 > 0)) else -cl)
    if r0 == 0:                  # entering the window: the phase wrapped to [−π, π)
        return v - TWO_PI * math.floor((v + math.pi) * (1.0 / TWO_PI))
    return wrap_phase(v) - MOF[i - ne, 1]


@_jit_inline
def gap_root(g0, g1, d0, d1, s):
    """The root in (0, 1) of the cubic Hermite of a gap's values g0, g1 and slopes d0, d1 at
    the step's ends (Newton from s); s when it leaves the interval."""
    c2 = 3.0 * (g1 - g0) - 2.0 * d0 - d1
    c3 = 2.0 * (g0 - g1) + d0 + d1
    for _ in range(4):
        a = g0 + s * (d0 + s * (c2 + s * c3))
        b = d0 + s * (2.0 * c2 + 3.0 * s * c3)
        if not (b != 0.0 and 0.0 < s - a / b < 1.0):
            break
        s -= a / b
    return s


@_leaf
def rk_step(t, hh, y, K, tmp, ynew, TA, TB, TC, PV, FI, FF, tabs, MI_, MW, EI, EF, MOI, MOF,
            PRIG, BI, aux, work, zy, zd):
    """One explicit Runge-Kutta step of size hh from (t, y, K[0] = f(y)) into ynew, with the
    Butcher tableau (TA, TB, TC) of s stages (RK4, or the 8th-order one of DOP853 run at a
    fixed step); K[1 .. s-1] the stages, K[s] = f(ynew) and aux are left at ynew.  f is
    :func:`deriv` (the scene's :func:`rhs`, or the shaft's; ``zy``, ``zd`` its scratch)."""
    n = y.shape[0]
    s = TB.shape[0]
    nf, want, nb, ne, nmo = int(PV[3]), PV[4] != 0.0, BI.shape[0], EI.shape[0], MOI.shape[0]
    for i in range(1, s + 1):           # the stages, then (i = s) the step's end
        for m in range(n):
            acc = 0.0
            for j in range(i):
                c = TA[i, j] if i < s else TB[j]
                if c != 0.0:
                    acc += c * K[j, m]
            tmp[m] = y[m] + hh * acc
        ti = t + TC[i] * hh if i < s else t + hh
        if shaft_mode(PV) == 0:
            # :func:`rhs`'s five calls, its equations compiled in place (the steps run about
            # 10 % faster than calling it): written here, not rhs inlined whole, since numba's
            # inlining copies the callee block by block, each copy with all its variables
            # (rhs: 107 blocks x 2,566 variables, 3 s of a cold compile).
            theta, omega, accel, th_load, w_load = crank_motion(PV, ti)
            bad = part_kinematics(tmp, theta, omega, accel, nf, FI, FF, tabs, MI_, MW, PRIG,
                                  work)
            element_forces(want, nb, EI, EF, FI, FF, tabs, th_load, w_load, aux, work,
                           nb + 2 * ne + 2 + nmo)
            window_moments(nb + 2 * ne + 1, FI, MOI, MOF, aux, work)
            accelerations(nf, want, bad, FI, BI, EI, MOI, PRIG, K[i], aux, work)
        else:
            shaft_rhs(ti, tmp, PV, FI, FF, tabs, MI_, MW, EI, EF, MOI, MOF, PRIG, BI, K[i], aux,
                      work, zy, zd)
    for m in range(n):
        ynew[m] = tmp[m]


@_jit_inline
def locate(t, hh, y, K, ynew, tmp, sw0, sw1, reg, regn, PV, FI, FF, tabs, MI_, MW, EI, EF,
           MOI, MOF, PRIG, BI, aux, work, off, m, zy, zd, probe):
    """Earliest fraction s ∈ (0, 1] of the step at which a force law changes piece (reg →
    regn: a clearance gap's edge or a moment's window crossed), on the step's Hermite
    interpolant (:func:`mechcirc._ode.hermite_point`, quintic in q for m > 0; Illinois, to
    1e-9 of the step): the bracket's upper end; 1 for a switch on its edge at the step's end,
    or (``probe`` > 0) one not yet changed at 1 − ``probe`` (tried first).  ``sw0``/``sw1``:
    the switches at the ends; K the step's stages (K[1] overwritten).  Returns (s, evaluations).
    Inlined at its one site in :func:`cut_at_kink` (≤ 30 arguments: numba inlines no *args)."""
    n, ne, nsw = y.shape[0], EI.shape[0], reg.shape[0]
    k1, k4, dy = K[0], K[K.shape[0] - 1], K[1]
    xo, best, count = off + ne + 2 + MOI.shape[0], 1.0, 0
    for e in range(nsw):
        if reg[e] == regn[e]:
            continue
        lo, hi, v, vd, s, side = 0.0, 1.0, 0.0, 0.0, 0.0, 0
        r0, r1, glo, ghi, g0, g1 = reg[e], regn[e], 0.0, 0.0, 0.0, 0.0
        # it = -2, -1: the step's ends (sw0, sw1), at the one edge_gap site (inlined per site)
        for it in range(-2, 60):
            probing = False
            if it < 0:
                sw = sw0 if it == -2 else sw1
                v, vd = sw[e], (sw[nsw + e] if e < ne else 0.0)
            else:
                if hi - lo <= 1e-9 or hi <= 0.0:
                    break
                s = hi - ghi * (hi - lo) / (ghi - glo) if ghi != glo else 0.5 * (lo + hi)
                probing = it == 0 and 0.0 < probe < 1.0
                if probing:
                    s = 1.0 - probe
                elif it == (probe > 0.0) and e < ne and r0 * r1 <= 0:
                    s = gap_root(g0, g1, hh * sw0[nsw + e], hh * sw1[nsw + e], s)
                if not lo < s < hi:
                    s = 0.5 * (lo + hi)
                hermite_point(tmp, s, hh, y, k1, ynew, k4, n, m)
                deriv(t + s * hh, tmp, PV, FI, FF, tabs, MI_, MW, EI, EF, MOI, MOF, PRIG, BI,
                      dy, aux, work, zy, zd)
                count += 1
                if e < ne:
                    v, vd = aux[off + e], aux[xo + e]
                else:
                    v = work[6, MOI[e - ne, 0]] - MOF[e - ne, 3] + 0.5 * MOF[e - ne, 1]
            g = edge_gap(e, ne, r0, r1, v, vd, EF, MOF)
            if it < 0:
                glo, ghi = (g, ghi) if it == -2 else (glo, g)
                g0, g1 = glo, ghi
                if it == -1 and ghi == 0.0:     # on the edge at the step's end: the change
                    break                       # is there, no cut (hi 1: best unchanged)
                continue
            if (g > 0.0) == (ghi > 0.0) and g != 0.0:
                glo = 0.5 * glo if side == 1 else glo      # Illinois: halve the stale end
                hi, ghi, side = s, g, 1
            else:
                ghi = 0.5 * ghi if side == -1 else ghi
                lo, glo, side = s, g, -1
                if probing:     # not changed by 1 − probe: close enough
                    hi = 1.0
                    break
        best = min(best, hi)
    return best, count


#: The classical RK4 tableau (A, b, c), for :func:`rk_run`.
RK4_A = np.array([[0.0, 0.0, 0.0, 0.0], [0.5, 0.0, 0.0, 0.0], [0.0, 0.5, 0.0, 0.0],
                  [0.0, 0.0, 1.0, 0.0]])
RK4_B = np.array([1.0 / 6.0, 1.0 / 3.0, 1.0 / 3.0, 1.0 / 6.0])
RK4_C = np.array([0.0, 0.5, 0.5, 1.0])


def tableau(method):
    """The Butcher tableau (A, b, c) of an explicit method for :func:`rk_run` and whether its
    output between the steps is quintic in the positions.

    Parameters
    ----------
    method : {"rk4", "rk8"}
        The classical RK4 (cubic output, its order 4), or the 8th-order formula of Dormand
        and Prince's DOP853 (scipy's coefficients) run at a fixed step (12 stages), with
        quintic output (error O(h⁶) in the positions, O(h⁵) in their rates).

    Returns
    -------
    tuple
        (A, b, c, quintic).
    """
    if method != "rk8":
        return RK4_A, RK4_B, RK4_C, False
    from scipy.integrate import DOP853

    s = DOP853.n_stages
    return (np.ascontiguousarray(DOP853.A[:s, :s]), np.ascontiguousarray(DOP853.B),
            np.ascontiguousarray(DOP853.C[:s]), True)


@_leaf
def cut_at_kink(tc, hh, h, y, K, tmp, ynew, sw0, sw1, reg, regn, TA, TB, TC, PV, FI, FF, tabs,
                MI_, MW, EI, EF, MOI, MOF, PRIG, BI, aux, auxl, work, off, m, zy, zd, first):
    """:func:`rk_run`'s step from ``tc`` of ``hh`` (of the run's ``h``), in which a force law
    changed piece, cut at the kink: located on the step's interpolant (:func:`locate`), then,
    that interpolant being of low order across the kink, again on the cut step's own (smooth
    up to the kink), at most 4 times, until the kink is at the cut step's end (to the first
    cut's tolerance) or that step ends before it (the next piece finds it).  ``ynew``, ``K``
    and ``regn``/``sw1`` hold the cut step, ``aux`` its end's outputs (the locations
    evaluate into ``auxl``).

    Returns (the cut step's length, whether it is the whole step, right-hand-side evaluations
    used).
    """
    s = TB.shape[0]
    used, cut, probe = 0, 1.0, 0.0
    # k = 0 the first location, then at most 4 cut steps; locate's one site (it is inlined)
    for k in range(5):
        if k > 0:
            hh = cut * hh
            rk_step(tc, hh, y, K, tmp, ynew, TA, TB, TC, PV, FI, FF, tabs, MI_, MW, EI, EF, MOI,
                    MOF, PRIG, BI, aux, work, zy, zd)
            used += s          # s - 1 stages and f at the end (rk_step)
            regions(FI, EI, EF, MOI, MOF, aux, work, off, regn, sw1, first)
            if not branch_changes(reg, regn):   # cut before the kink: the next piece finds it
                break
            # only whether the kink is within the break's tolerance of the end: tried first
            probe = 0.99e-7 * (1.0 + h / hh)
        more, extra = locate(tc, hh, y, K, ynew, tmp, sw0, sw1, reg, regn, PV, FI, FF, tabs,
                             MI_, MW, EI, EF, MOI, MOF, PRIG, BI, auxl, work, off, m, zy, zd,
                             probe)
        used += extra
        cut = more + 1e-7
        if k == 0 and not (cut * hh > 1e-9 * h and cut < 1.0 - 1e-7):
            return hh, True, used
        if k > 0 and not ((1.0 - cut) * hh > 1e-7 * h and cut * hh > 1e-9 * h):
            break       # as close as the first cut's own tolerance
    return hh, False, used


@_jit
def rk_run(y, t0, h, nsteps, t_out0, dt_out, rec_y, rec_t, PV, FI, FF, tabs, MI_, MW, EI,
           EF, MOI, MOF, PRIG, BI, naux, TA, TB, TC, quintic):
    """``nsteps`` explicit Runge-Kutta steps of h from t0 (y in place) with the tableau (TA, TB,
    TC) (:func:`rk_step`); output between the steps by Hermite interpolation, cubic, or with
    ``quintic`` quintic in the positions q (y = [q, q̇]; :func:`mechcirc._ode.hermite_point`),
    for a method of higher order than the cubic's 4.  A step in which a force law
    changes piece (an element crosses an edge of its clearance gap, a moment's window opens
    or closes: a kink of the force) is cut where it happens (:func:`locate`, then again on
    the cut step's own interpolant, the first being of low order across the kink) and
    finished from there, at most 8 pieces per step, so that the method keeps its order
    through impacts and the beat-up.

    The same loop runs the dynamic main shaft's equations (:func:`shaft_rhs`, PV[8] ≠ 0): its
    state [positions, their rates] as the scene's, and it stops at a step's end where the
    shaft's speed is not ≥ PV[11] (a stall) instead of the scene's speed limit PV[2].

    Returns (time reached, outputs written, no blow-up (no stall), out-of-range seen,
    right-hand-side evaluations).
    """
    n = y.shape[0]
    m = n // 2 if quintic else 0
    s = TB.shape[0]
    K = np.zeros((s + 1, n))
    tmp, ynew = np.empty(n), np.empty(n)
    aux = np.empty(naux + EI.shape[0])     # + the elements' rates, for regions
    auxl = np.empty(aux.shape[0])          # the cuts' locations' (aux stays at ynew)
    work = np.zeros((9, max(FI.shape[0], PRIG.shape[0])))
    zy = np.empty(2 * PRIG.shape[0] - 2)
    zd = np.empty(zy.shape[0])
    shaft = shaft_mode(PV)
    nfev = 1
    ne = EI.shape[0]
    nsw = ne + MOI.shape[0]
    off = BI.shape[0] + ne
    reg, regn = np.zeros(nsw, np.int64), np.zeros(nsw, np.int64)
    sw0, sw1 = np.empty(nsw + ne), np.empty(nsw + ne)
    # int(0), not 0: a literal 0 would have numba compile record_hermite twice (for
    # Literal[int](0), then for int64)
    j, bad = int(0), 0.0
    npart = PRIG.shape[0]
    limit = PV[2]
    deriv(t0, y, PV, FI, FF, tabs, MI_, MW, EI, EF, MOI, MOF, PRIG, BI, K[0], aux, work, zy, zd)
    first = 0 if shaft else 1
    k0, ks = K[0], K[s]     # the views made once (each made in the loop: two atomic counts)
    gaps = regions(FI, EI, EF, MOI, MOF, aux, work, off, reg, sw0, first)
    for step in range(nsteps):
        tc = t0 + step * h
        t_end = tc + h
        for sub in range(8):
            hh = t_end - tc
            rk_step(tc, hh, y, K, tmp, ynew, TA, TB, TC, PV, FI, FF, tabs, MI_, MW, EI, EF,
                    MOI, MOF, PRIG, BI, aux, work, zy, zd)
            nfev += s
            full = True
            if gaps > 0:
                regions(FI, EI, EF, MOI, MOF, aux, work, off, regn, sw1, first)
                if branch_changes(reg, regn) and sub < 7:
                    hh, full, used = cut_at_kink(
                        tc, hh, h, y, K, tmp, ynew, sw0, sw1, reg, regn, TA, TB, TC, PV, FI,
                        FF, tabs, MI_, MW, EI, EF, MOI, MOF, PRIG, BI, aux, auxl, work, off, m,
                        zy, zd, first)
                    nfev += used
                for e in range(nsw + ne):       # the pieces, the switches' values, the rates
                    sw0[e] = sw1[e]
                    if e < nsw:
                        reg[e] = regn[e]
            if aux[naux - 1] > bad:
                bad = aux[naux - 1]
            j = record_hermite(rec_t, rec_y, j, t_out0, dt_out, tc, hh,
                               full and step == nsteps - 1, y, k0, ynew, ks, n, m, tmp)
            for i in range(n):
                y[i], K[0, i] = ynew[i], K[s, i]
            if shaft:
                if not shaft_speed(y, PV, npart) >= PV[11]:
                    return tc + hh, j, False, bad, nfev
            else:
                for i in range(npart - 1, n):
                    if not abs(y[i]) <= limit:
                        return tc + hh, j, False, bad, nfev
            if full:
                break
            tc += hh
    return t0 + nsteps * h, j, True, bad, nfev


@_jit
def output_pass(ts, ys, out, mode, PV, FI, FF, tabs, MI_, MW, EI, EF, MOI, MOF, PRIG, BI):
    """The equations at each stored state ys[i]: one kernel for :func:`outputs` (``mode`` 0:
    aux into ``out``, its column i the state i's aux, so that each output is a contiguous
    row), :func:`output_extrema` (1: the least (row 0) and largest (row 1) of each aux column,
    as the rows would give them; a NaN stays NaN) and :func:`shaft_eval` (2: the shaft's, ts
    unused); each compiled kernel emits the equations' code again."""
    n = ys.shape[1]
    naux = out.shape[0] if mode == 0 else out.shape[1] - (5 if mode == 2 else 0)
    dy, y = np.empty(n), np.empty(n)
    aux = np.empty(naux)
    work = np.zeros((9, max(FI.shape[0], PRIG.shape[0])))
    zy = np.empty(2 * PRIG.shape[0] - 2)
    zd = np.empty(zy.shape[0])
    if mode == 1:
        for j in range(naux):
            out[0, j] = np.inf
            out[1, j] = -np.inf
    for i in range(ys.shape[0]):
        for j in range(n):      # a copy, not the view ys[i] (two atomic reference counts)
            y[j] = ys[i, j]
        if mode == 2:
            acc = shaft_rhs(0.0, y, PV, FI, FF, tabs, MI_, MW, EI, EF, MOI, MOF, PRIG, BI, dy,
                            aux, work, zy, zd)
            for j in range(naux):
                out[i, j] = aux[j]
            out[i, naux] = acc
            out[i, naux + 1] = motor_torque(PV, PV[0], 12)
            out[i, naux + 2] = work[3, 0]
            out[i, naux + 3] = work[4, 0]
            out[i, naux + 4] = work[5, 0]
            continue
        rhs(ts[i], y, PV, FI, FF, tabs, MI_, MW, EI, EF, MOI, MOF, PRIG, BI, dy, aux, work)
        if mode == 1:
            for j in range(naux):
                v = aux[j]
                if v < out[0, j] or math.isnan(v):
                    out[0, j] = v
                if v > out[1, j] or math.isnan(v):
                    out[1, j] = v
        else:
            for j in range(naux):
                out[j, i] = aux[j]


def outputs(ts, ys, out, PV, FI, FF, tabs, MI_, MW, EI, EF, MOI, MOF, PRIG, BI):
    """Evaluate aux at each stored state into ``out`` (its column i the state i's aux, so that
    each output is a contiguous row): :func:`output_pass`."""
    output_pass(ts, ys, out, 0, PV, FI, FF, tabs, MI_, MW, EI, EF, MOI, MOF, PRIG, BI)


def output_extrema(ts, ys, ext, PV, FI, FF, tabs, MI_, MW, EI, EF, MOI, MOF, PRIG, BI):
    """The least (row 0) and largest (row 1) of each aux column over the stored states,
    as :func:`outputs` would give them row by row (a NaN stays NaN): :func:`output_pass`."""
    output_pass(ts, ys, ext, 1, PV, FI, FF, tabs, MI_, MW, EI, EF, MOI, MOF, PRIG, BI)


@_jit
def eval_many(kind, tabs, ti, a, b, c, lo, h, w, ic, ih, qs, out):
    """One function at many coordinates: out[i] = (value, first, second derivative)."""
    for i in range(qs.shape[0]):
        v, d1, d2, bad = feval(kind, tabs, ti, a, b, c, lo, h, w, ic, ih, qs[i])
        out[i, 0] = v
        out[i, 1] = d1
        out[i, 2] = d2


@_jit
def point_samples(kind, tabs, ti, a, b, c, lo, h, w, ic, ih, qs, qd, qdd, pos, acc):
    """One coordinate of a point at many samples of its part's motion (q, q̇, q̈): its value
    f(q) into pos[i] and its acceleration f''(q) q̇² + f'(q) q̈ into acc[i]."""
    for i in range(qs.shape[0]):
        v, d1, d2, bad = feval(kind, tabs, ti, a, b, c, lo, h, w, ic, ih, qs[i])
        pos[i] = v
        acc[i] = d2 * qd[i] * qd[i] + d1 * qdd[i]


_NONE = np.empty(0)      # the times shaft_eval does not pass to output_pass


@functools.cache
def load_python():
    """A copy of this module that never uses numba (:func:`mechcirc._jit.load`), loaded once
    per process: the rigid states, the motor law and every run without the compiled kernels
    share it."""
    return load(__name__, _FORCE_PYTHON=True)


# ---------------------------------------------------------------------------------------------
# The dynamic main shaft (mechcirc.scene.shaft): the drive's part turned by the shaft's θ, a
# state beside the free parts', the scene's right-hand side above supplying the forces on it;
# integrated by rk_run like a scene.  PV (shaft_args in mechcirc.scene.shaft) = the scene's
# PV, then [8] 1 (in θ) or 2 (in time), [9] J_f, [10] c, [11] the speed floor, [12:] MP:
# [0, ω_s, T_b, s_b] (Kloss) or [1, 0, 0, 0, n, speeds (n), torques (n)] (a table).


@_jit_inline
def motor_torque(MP, w, o=0):
    """The motor's torque T(ω) [N·m] (its parameters at MP[o:]): Kloss's
    2 T_b s s_b/(s² + s_b²), s = (ω_s − ω)/ω_s, or the table linear between its points and
    along its end segments beyond them."""
    if MP[o] == 0.0:
        s = (MP[o + 1] - w) / MP[o + 1]
        return 2.0 * MP[o + 2] * s * MP[o + 3] / (s * s + MP[o + 3] * MP[o + 3])
    n = int(MP[o + 4])
    i = 1
    while i < n - 1 and w > MP[o + 5 + i]:
        i += 1
    x0 = MP[o + 4 + i]
    y0 = MP[o + 4 + n + i]
    return y0 + (w - x0) * (MP[o + 5 + n + i] - y0) / (MP[o + 5 + i] - x0)


@_jit_inline
def shaft_mode(PV):
    """0 for a scene, 1 for the shaft in θ, 2 for the shaft in time (PV[8])."""
    return int(PV[8]) if PV.shape[0] > 8 else 0


@_jit_inline
def shaft_speed(Y, PV, npart):
    """The shaft's speed θ̇ from its state (in θ: 1/t', 0 for t' = 0; in time: θ̇)."""
    if PV[8] != 1.0:
        return Y[npart]
    return 1.0 / Y[npart] if Y[npart] != 0.0 else 0.0


@_jit_inline
def deriv(t, y, PV, FI, FF, tabs, MI_, MW, EI, EF, MOI, MOF, PRIG, BI, dy, aux, work, zy, zd):
    """The derivatives :func:`rk_run` integrates: the scene's :func:`rhs`, or the shaft's
    :func:`shaft_rhs` when PV says so (``zy``, ``zd``: its scratch).  Inlined into its
    callers, so the scene's steps call :func:`rhs` as directly as before."""
    if shaft_mode(PV) == 0:
        rhs(t, y, PV, FI, FF, tabs, MI_, MW, EI, EF, MOI, MOF, PRIG, BI, dy, aux, work)
    else:
        shaft_rhs(t, y, PV, FI, FF, tabs, MI_, MW, EI, EF, MOI, MOF, PRIG, BI, dy, aux, work,
                  zy, zd)


@_leaf
def shaft_rhs(t, Y, PV, FI, FF, tabs, MI_, MW, EI, EF, MOI, MOF, PRIG, BI, dY, aux, work, zy,
              zd):
    """dY of the shaft and the free parts (q, q̇ = z, :func:`rhs` at the crank's θ, θ̇ with
    t = 0), q₀ = c θ the drive's coordinate and

        (J_f + c² m₀) θ̈ = T_motor(θ̇) + c Q₀ − ½ c³ m₀' θ̇²    (work rows 3–5, column 0).

    In time (PV[8] = 2): Y = [θ, q, θ̇, q̇] and dY/dt.  In θ (PV[8] = 1, θ = t the
    independent variable): Y = [t, q, t', q'] with ' = d/dθ (t' = 1/θ̇, q' = q̇/θ̇) and
    dY/dθ = [t', q', −θ̈ t'³, t'² (q̈ − θ̈ q')]: positions and their rates in both, so that
    the step's output is quintic in the positions (:func:`mechcirc._ode.hermite_point`).
    ``zy``, ``zd``: scratch for z and ż.  Returns θ̈."""
    npart = PRIG.shape[0]
    nf = npart - 1
    in_theta = PV[8] == 1.0
    if in_theta:
        PV[1] = t
        u = Y[npart]
        w = 1.0 / u
    else:
        PV[1] = Y[0]
        w = Y[npart]
        u = 1.0
    PV[0] = w
    for i in range(nf):
        zy[i] = Y[1 + i]
        zy[nf + i] = Y[npart + 1 + i] * w if in_theta else Y[npart + 1 + i]
    rhs(0.0, zy, PV, FI, FF, tabs, MI_, MW, EI, EF, MOI, MOF, PRIG, BI, zd, aux, work)
    c = PV[10]
    acc = (motor_torque(PV, w, 12) + c * work[5, 0] - 0.5 * work[4, 0] * c * c * c * w * w) / \
        (PV[9] + c * c * work[3, 0])
    if in_theta:
        u2 = u * u
        dY[0] = u
        dY[npart] = -acc * u2 * u
        for i in range(nf):
            dY[1 + i] = Y[npart + 1 + i]
            dY[npart + 1 + i] = u2 * (zd[nf + i] - acc * Y[npart + 1 + i])
    else:
        dY[0] = w
        dY[npart] = acc
        for i in range(nf):
            dY[1 + i] = zy[nf + i]
            dY[npart + 1 + i] = zd[nf + i]
    return acc


def shaft_eval(ys, out, PV, FI, FF, tabs, MI_, MW, EI, EF, MOI, MOF, PRIG, BI, naux):
    """The shaft's equations (:func:`shaft_rhs` in time, PV[8] = 2) at the states ys[i] =
    [θ, q, θ̇, q̇]: out[i] = [aux (naux), θ̈, T_motor(θ̇), m₀, m₀', Q₀] (:func:`output_pass`;
    ``out`` naux + 5 wide)."""
    output_pass(_NONE, ys, out, 2, PV, FI, FF, tabs, MI_, MW, EI, EF, MOI, MOF, PRIG, BI)
