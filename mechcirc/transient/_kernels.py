"""The clearance (ElastoBacklash) law and an embedded Dormand–Prince 5(4) loop, on plain arrays.

One source, two backends, as :mod:`mechcirc.scene._motion_kernels`: compiled with
numba's ``@njit(cache=True)`` when numba is importable (the ``fast`` extra),
ordinary Python otherwise or through :func:`load_python`.  Imported only when a
transient with clearances runs, so ``import mechcirc`` never imports numba.

The law (Modelica ``Rotational.Components.ElastoBacklash``), for relative
displacement e, relative velocity w, stiffness c, damping d, total gap b:

* b < 1e-10: f = c e + d w (plain spring ∥ damper);
* |e| ≤ b/2: f = 0 (in the gap);
* e > b/2: f_c = c (e − b/2), f_d = d w; f = 0 if f_c + f_d ≤ 0, else f_c + min(f_c, f_d);
* e < −b/2: mirror image (f_c = c (e + b/2); f = 0 if f_c + f_d ≥ 0, else f_c + max(f_c, f_d)).

So the contact never pulls and the damping part never exceeds the spring part:
the force is continuous at first contact (f_c = 0 there).
"""

from __future__ import annotations

import functools
import math

import numpy as np

from .._jit import decorators, load

HAVE_NUMBA, _jit, _jit_inline = decorators(bool(globals().get("_FORCE_PYTHON")))
# A piece of a kernel that allocates nothing (a loop, or a step of one): compiled without
# reference counting.  Inlined (inline="always") into a kernel that counts references, its
# array arguments would cost an atomic increment and decrement per call: modal_run's
# sample loop as such a helper measured 4.8x slower.
_leaf = decorators(bool(globals().get("_FORCE_PYTHON")), nrt=False)[1]

B_EPS = 1e-10
#: A step cut at a kink ends KINK_MARGIN (relative) past the root found, and is cut again
#: if the kink lies more than KINK_RECUT of it before its end, so the law's kink stays
#: within the last 1e-8 of a step (the MSL example's x error at rtol 1e-10 against an
#: event-located reference: 3.9e-11 … 1.1e-10 as the inputs' last bits move the steps,
#: tests/test_transient_kinks.py; 2.7e-10 with 1e-5, about 4.6e-10 with 1e-3, one draw).
#: The root is bracketed to 1e-10 of the step.
KINK_MARGIN, KINK_RECUT = 1e-9, 1e-8


@_jit
def law_branch(e, w, c, d, b):
    """(total force, spring part, branch code) of one clearance element; see the module
    docstring.  Branch code: 0 in the gap (and a plain spring); ±1 contact with the damping
    part limiting (f_d > f_c in magnitude); ±2 contact with the full damping; ±3 at the
    wall but separating (f = 0).  The law is smooth inside one code; a change of code is a
    kink (its switching functions: :func:`_switch_g`)."""
    if abs(b) <= B_EPS:
        fc = c * e
        return fc + d * w, fc, 0
    half = 0.5 * b
    if e > half:
        fc = c * (e - half)
        fd = d * w
        if fc + fd <= 0.0:
            return 0.0, 0.0, 3
        return (fc + fd, fc, 2) if fd <= fc else (fc + fc, fc, 1)
    if e < -half:
        fc = c * (e + half)
        fd = d * w
        if fc + fd >= 0.0:
            return 0.0, 0.0, -3
        return (fc + fd, fc, -2) if fd >= fc else (fc + fc, fc, -1)
    return 0.0, 0.0, 0


@_jit
def law_many(e, w, c, d, b, total, spring):
    """:func:`law_branch` on arrays (force and spring part written into ``total`` and
    ``spring``)."""
    for i in range(e.shape[0]):
        total[i], spring[i], _ = law_branch(e[i], w[i], c, d, b)


@_jit
def drive_at(t, t0, dt, u):
    """The drive between its samples on the grid t0 + k dt (held beyond the ends).

    ``u[0]`` holds the values; ``u[1]`` their time derivatives, or NaN first for
    none: then linear interpolation, else the cubic Hermite through values and
    derivatives (a motion drive: smooth, so a stiff contact is not rung by the
    kinks of a piecewise-linear velocity).
    """
    s = (t - t0) / dt
    n = u.shape[1]
    if s <= 0.0:
        return u[0, 0]
    k = int(math.floor(s))
    if k >= n - 1:
        return u[0, n - 1]
    f = s - k
    a = u[0, k]
    b = u[0, k + 1]
    if math.isnan(u[1, 0]):
        return a + f * (b - a)
    f2 = f * f
    f3 = f2 * f
    return ((2 * f3 - 3 * f2 + 1) * a + (f3 - 2 * f2 + f) * dt * u[1, k]
            + (3 * f2 - 2 * f3) * b + (f3 - f2) * dt * u[1, k + 1])


def pack_rows(M):
    """Rows of a matrix as (column index, value) arrays padded to the longest row's nonzeros.

    The right-hand side works on these: the matrices of a network (A, the
    clearance rows, the force columns) are sparse, and a padded row costs its
    nonzeros only.  Padding entries have value 0 and column 0.
    """
    M = np.atleast_2d(np.asarray(M, dtype=float))
    if M.size == 0:
        return np.zeros((M.shape[0], 1), dtype=np.int64), np.zeros((M.shape[0], 1))
    nz = M != 0.0
    w = max(1, int(nz.sum(axis=1).max()))
    # each row's nonzero columns first (in order), then zero entries as padding
    idx = np.ascontiguousarray(np.argsort(~nz, axis=1, kind="stable")[:, :w], dtype=np.int64)
    val = np.ascontiguousarray(np.take_along_axis(M, idx, axis=1))
    return idx, val


def kernel_args(A, B, cx, dx, cv, dv, extra, prm):
    """The matrices of ż = A z + B u + Σ_e extra_e f_e as :func:`dopri_run` takes them."""
    def flat(a):
        return np.ascontiguousarray(a, dtype=float)

    return (*pack_rows(A), flat(B), *pack_rows(cx), flat(dx), *pack_rows(cv), flat(dv),
            *pack_rows(np.asarray(extra).T), flat(prm))


@_jit_inline
def _row_dot(start, val, idx, i, z):
    """``start`` + row i of a matrix packed by :func:`pack_rows` times z, summed in order."""
    acc = start
    for j in range(idx.shape[1]):
        acc += val[i, j] * z[idx[i, j]]
    return acc


@_jit_inline
def rhs(t, z, Ai, Av, B, xi, xv, dx, vi, vv, dv, ei, ev, prm, t0, dt, u, dz, codes):
    """dz = A z + B u(t) + Σ_e extra[:, e] · f_e(cx_e·z + dx_e u, cv_e·z + dv_e u), and the
    elements' branch codes (:func:`law_branch`) at (t, z) into ``codes``.

    A, cx, cv and the columns of extra as :func:`pack_rows` gives them.
    """
    ut = drive_at(t, t0, dt, u)
    for i in range(z.shape[0]):
        dz[i] = _row_dot(B[i] * ut, Av, Ai, i, z)
    for k in range(prm.shape[0]):
        e = _row_dot(dx[k] * ut, xv, xi, k, z)
        w = _row_dot(dv[k] * ut, vv, vi, k, z)
        f, fc, code = law_branch(e, w, prm[k, 0], prm[k, 1], prm[k, 2])
        codes[k] = code
        if f != 0.0:
            for j in range(ei.shape[1]):
                dz[ei[k, j]] += ev[k, j] * f


# Dormand–Prince 5(4) coefficients; the 5th-order weights are the last row of _A (the
# last stage is taken at the 5th-order solution: FSAL), so they are not stored twice.
_C = np.array([0.0, 1 / 5, 3 / 10, 4 / 5, 8 / 9, 1.0, 1.0])
_A = np.array([
    [0, 0, 0, 0, 0, 0],
    [1 / 5, 0, 0, 0, 0, 0],
    [3 / 40, 9 / 40, 0, 0, 0, 0],
    [44 / 45, -56 / 15, 32 / 9, 0, 0, 0],
    [19372 / 6561, -25360 / 2187, 64448 / 6561, -212 / 729, 0, 0],
    [9017 / 3168, -355 / 33, 46732 / 5247, 49 / 176, -5103 / 18656, 0],
    [35 / 384, 0, 500 / 1113, 125 / 192, -2187 / 6784, 11 / 84]])
_B4 = np.array([5179 / 57600, 0, 7571 / 16695, 393 / 640, -92097 / 339200, 187 / 2100, 1 / 40])


#: Dense output of Dormand–Prince (Hairer, Nørsett & Wanner, DOPRI5 ``contd5``): a
#: 4th-order continuous extension from the stages of the step itself.
_D = np.array([-12715105075 / 11282082432, 0.0, 87487479700 / 32700410799,
               -10690763975 / 1880347072, 701980252875 / 199316789632,
               -1453857185 / 822651844, 69997945 / 29380423])


@_jit_inline
def _switch_g(kind, side, e, w, c, d, half):
    """A switching function of the law at (e, w), zero where a branch ends: ``kind`` 0
    the gap's edge e ∓ b/2, 1 separation f_c + f_d, 2 the damping limit f_c − f_d;
    ``side`` the wall's sign (±1)."""
    g = e - side * half
    if kind == 0:
        return g
    return c * g + (d * w if kind == 1 else -d * w)


@_jit_inline
def _dense_at(z, P, th, i):
    """State i at the fraction ``th`` of the step on its continuous extension
    (coefficients ``P`` from :func:`dense_coefficients`)."""
    s1 = 1.0 - th
    return z[i] + th * (P[0, i] + s1 * (P[1, i] + th * (P[2, i] + s1 * P[3, i])))


@_jit_inline
def _switch_on_dense(k, kind, side, th, t, hh, z, P, xi, xv, dx, vi, vv, dv, prm, t0, dt, u):
    """The switching function of clearance element k at the fraction ``th`` of the step,
    on the step's continuous extension (its coefficients in ``P``, :func:`dense_coefficients`)."""
    ut = drive_at(t + th * hh, t0, dt, u)
    e = dx[k] * ut
    for j in range(xi.shape[1]):
        e += xv[k, j] * _dense_at(z, P, th, xi[k, j])
    w = dv[k] * ut
    for j in range(vi.shape[1]):
        w += vv[k, j] * _dense_at(z, P, th, vi[k, j])
    return _switch_g(kind, side, e, w, prm[k, 0], prm[k, 1], 0.5 * prm[k, 2])


@_jit_inline
def _root_on_dense(k, kind, side, t, hh, z, P, xi, xv, dx, vi, vv, dv, prm, t0, dt, u):
    """The first switch of kind ``kind`` of element k in the step (fraction, the upper
    end of the final Illinois bracket on the continuous extension), or 2.0 if its
    switching function keeps its sign from start to end."""
    a, b = 0.0, 1.0
    ga = gb = 0.0
    # the ends (it 0, 1), then at most 60 Illinois steps: one call site, which numba
    # inlines once
    for it in range(62):
        c = (a * gb - b * ga) / (gb - ga) if it > 1 else float(it)
        gc = _switch_on_dense(k, kind, side, c, t, hh, z, P, xi, xv, dx, vi, vv, dv, prm, t0,
                              dt, u)
        if it == 0:
            ga = gc
        elif it == 1:
            gb = gc
            if not ga * gb < 0.0:
                return 2.0
        else:
            if gc * gb < 0.0:
                a, ga = b, gb
            else:
                ga *= 0.5
            b, gb = c, gc
            if gc == 0.0 or abs(b - a) <= 1e-10:
                break
    return max(a, b)


@_jit_inline
def branch_changes(codes0, codes1):
    """Whether any clearance element's branch code at a step's end (``codes1``, left by
    its last stage) differs from its code at the start (``codes0``)."""
    for k in range(codes0.shape[0]):
        if codes1[k] != codes0[k]:
            return True
    return False


@_leaf
def kink_theta(t, hh, z, y5, K, P, coefD, xi, xv, dx, vi, vv, dv, prm, t0, dt, u, codes0,
               codes1):
    """Fraction of the step t → t + hh (states z → y5) at which the first clearance
    element changes branch, or 2.0 if none does.

    For an element whose branch code (:func:`law_branch`) differs at the ends:
    the earliest root of the switching functions that can end its branch (from
    the gap: the wall's edge e ∓ b/2; in contact: separation f_c + f_d and the
    damping limit f_c − f_d; separating at the wall: the edge and f_c + f_d),
    found on the step's continuous extension (no right-hand sides); 0.5 if none
    changes sign.  A first switch within the step's first KINK_RECUT is at its
    start: then the element's next root, of any of its switching functions, or none."""
    theta = 2.0
    have_p = False
    for k in range(prm.shape[0]):
        c0, c1 = codes0[k], codes1[k]
        if c0 == c1:
            continue
        if not have_p:
            dense_coefficients(z, y5, K, hh, coefD, P)
            have_p = True
        # the switches' kinds: from the gap one (kinds[0], the edge), in contact two
        # (kinds[1:]: separation, then the edge or the damping limit); one call site in a
        # loop, so numba inlines its body once
        kinds = (0, 1, 0 if abs(c0) == 3 else 2)
        side = 1.0 if (c1 if c0 == 0 else c0) > 0 else -1.0
        hi = 1 if c0 == 0 else 3
        th = 2.0
        for j in range(0 if c0 == 0 else 1, hi + 3):
            # a first switch in the step's first KINK_RECUT is at its start, within rounding
            # (the cam follower's e − b/2 at 1 ulp after a cut: cut there, 53,914 steps of
            # 4e-14 s in a row as its root stayed a rounding ahead): the step is cut at the
            # element's next switch instead, the first later root of any kind (4: none)
            if j == hi:
                if th > KINK_RECUT:
                    break
                th = 4.0
            root = _root_on_dense(k, kinds[j] if j < hi else j - hi, side, t, hh, z, P, xi, xv,
                                  dx, vi, vv, dv, prm, t0, dt, u)
            if j < hi or KINK_RECUT < root <= 1.0:
                th = min(th, root)
        if th > 1.0:                 # no sign change on the extension: halve the step
            th = 0.5 if th < 3.0 else 2.0
        theta = min(theta, th)
    return theta


@_jit_inline
def dense_coefficients(z, y5, K, hh, coefD, P):
    """The vectors of Dormand–Prince's continuous extension of the step (z → y5, stages
    K) into P[0..3]: y(θ) = z + θ (P₀ + (1−θ) (P₁ + θ (P₂ + (1−θ) P₃)))."""
    for i in range(z.shape[0]):
        ydiff = y5[i] - z[i]
        bspl = hh * K[0, i] - ydiff
        r5 = 0.0
        for r in range(7):
            r5 += coefD[r] * K[r, i]
        P[0, i] = ydiff
        P[1, i] = bspl
        P[2, i] = ydiff - hh * K[6, i] - bspl
        P[3, i] = hh * r5


# dopri_stages, step_error, accept_step: inlined at their one site in dopri_run, which
# counts no references (its scratch is the caller's): compiled apart, each was a layer
# whose code LLVM optimised and emitted again in dopri_run
@_jit_inline
def dopri_stages(t, hh, z, K, ytmp, Ai, Av, B, xi, xv, dx, vi, vv, dv, ei, ev, prm, t0, dt, u,
                 coefA, coefC, codes):
    """Stages 2–7 of a Dormand–Prince step of hh from (t, z; K[0] = f(z)) into K[1 .. 6];
    ``ytmp`` is left at the 5th-order solution (the last stage is taken there: FSAL), and
    ``codes`` at the branch codes there."""
    for s in range(1, 7):
        for i in range(z.shape[0]):
            acc = z[i]
            for r in range(s):
                acc += hh * coefA[s, r] * K[r, i]
            ytmp[i] = acc
        rhs(t + coefC[s] * hh, ytmp, Ai, Av, B, xi, xv, dx, vi, vv, dv, ei, ev, prm, t0, dt,
            u, K[s], codes)


@_jit_inline
def step_error(z, ytmp, y5, K, hh, coefB4, atol, rtol):
    """The step's embedded error: RMS of (5th − 4th-order solution) scaled by
    atol_i + rtol max(|z_i|, |ŷ_i|); copies the 5th-order solution ``ytmp`` into ``y5``."""
    N = z.shape[0]
    err = 0.0
    for i in range(N):
        a4 = z[i]
        for r in range(7):
            a4 += hh * coefB4[r] * K[r, i]
        y5[i] = ytmp[i]
        sc = atol[i] + rtol * max(abs(z[i]), abs(ytmp[i]))
        q = (ytmp[i] - a4) / sc
        err += q * q
    return math.sqrt(err / N)


@_jit_inline
def accept_step(t, t_new, hh, z, y5, K, P, t0, dt, nout, k_out, coefD, out):
    """Take the step t → t_new: the outputs inside (t, t_new] by the continuous extension
    (from row ``k_out`` on), then z ← y5 and K[0] ← K[6] (FSAL).  Returns the next output row."""
    have_p = False
    while k_out < nout and t0 + k_out * dt <= t_new + 1e-12 * abs(t_new):
        if not have_p:
            dense_coefficients(z, y5, K, hh, coefD, P)
            have_p = True
        th = min((t0 + k_out * dt - t) / hh, 1.0)
        row = out[k_out]
        for i in range(z.shape[0]):
            row[i] = _dense_at(z, P, th, i)
        k_out += 1
    for i in range(z.shape[0]):
        z[i] = y5[i]
        K[0, i] = K[6, i]
    return k_out


@_leaf
def dopri_run(z, t0, dt, nout, Ai, Av, B, xi, xv, dx, vi, vv, dv, ei, ev, prm, u, rtol, atol,
              hmax, coefA, coefB4, coefC, coefD, dense, out, K, V, P, codes, kink_tol=0.0):
    """Integrate from t0 and store z at t0 + k dt (k < nout) in ``out``; returns the step count.

    A step is accepted when the embedded error, scaled by atol_i + rtol |z_i|
    (``atol`` one value per state), is ≤ 1
    (RMS).  With ``dense`` steps run across output times (which are filled by the
    method's continuous extension) and are limited only by ``hmax``; without it
    they end on every output time, i.e. on every sample of the piecewise-linear
    drive, so its kinks are always at step boundaries.  A trial step longer than
    ``kink_tol`` in which a clearance element changes branch is cut to end just
    past the switch (:func:`kink_theta`, :data:`KINK_MARGIN`).  Negative return:
    the step size underflowed.  The matrices come from :func:`kernel_args`; the scratch
    (zeros) from :func:`scratch`: it allocates nothing, so it runs without reference counts.
    """
    N = z.shape[0]
    ytmp, y5 = V[0], V[1]
    # branch codes of the clearance elements at the step's start (kept from the last
    # accepted step's end) and at a trial step's end
    codes0, codes1 = codes[0], codes[1]
    h_resume = 0.0
    t = t0
    for i in range(N):          # loops, not slices: numba compiles a slice's setitem
        out[0, i] = z[i]            # for 1.9 s more (the transient warm-up 5.5 → 7.4 s)
    t_end = t0 + (nout - 1) * dt
    h = min(hmax, dt)
    steps = 0
    k_out = int(1)         # not 1: a literal would have numba compile accept_step twice
    rhs(t, z, Ai, Av, B, xi, xv, dx, vi, vv, dv, ei, ev, prm, t0, dt, u, K[0], codes0)
    while k_out < nout:
        stop = t_end if dense else t0 + k_out * dt
        last = False
        if t + h >= stop - 1e-14 * abs(stop):
            hh = stop - t
            last = True
        else:
            hh = h
        dopri_stages(t, hh, z, K, ytmp, Ai, Av, B, xi, xv, dx, vi, vv, dv, ei, ev, prm, t0, dt,
                     u, coefA, coefC, codes1)
        err = step_error(z, ytmp, y5, K, hh, coefB4, atol, rtol)
        steps += 1
        # Kink location: if a clearance element changes branch inside the step
        # (whether or not the step passed: a kink inside it inflates its error),
        # shorten it to end just past the switch, so the law is smooth inside
        # every step; the next step starts again from the size cut short.
        changed = err < math.inf and branch_changes(codes0, codes1)
        if changed and hh > kink_tol:
            # (a separate, not inlined call: rare, and inlined it slowed every step)
            theta = kink_theta(t, hh, z, y5, K, P, coefD, xi, xv, dx, vi, vv, dv, prm, t0, dt,
                               u, codes0, codes1)
            if theta < 2.0:
                h_new = hh * min(1.0, theta * (1.0 + KINK_MARGIN) + KINK_MARGIN)
                if h_new < (1.0 - KINK_RECUT) * hh:
                    h_resume = max(h_resume, hh)
                    h = h_new
                    continue
        if err <= 1.0:
            t_new = stop if last else t + hh
            k_out = accept_step(t, t_new, hh, z, y5, K, P, t0, dt, nout, k_out, coefD, out)
            t = t_new
            fac = 5.0 if err == 0.0 else min(5.0, 0.9 * err ** -0.2)
            if not last or dense:
                h = min(hmax, max(hh * fac, h_resume))
            h_resume = 0.0
            if changed:
                for k in range(prm.shape[0]):
                    codes0[k] = codes1[k]
            # after a step cut short by an output time, keep the previous h
        else:
            h = hh * max(0.1, 0.9 * err ** -0.2)
            if h < 1e-14 * max(1.0, abs(t)):
                return -steps
    return steps


def scratch(N, nprm):
    """:func:`dopri_run`'s scratch for N states and nprm clearance elements: the stages K
    (7, N), its 5th-order solutions (2, N), the continuous extension's P (4, N) and the
    branch codes (2, nprm)."""
    return np.zeros((7, N)), np.zeros((2, N)), np.zeros((4, N)), np.zeros((2, nprm), np.int64)


def _wdot(wr, qr, wi, qi):
    """Σ_j wr_j qr_j + wi_j qi_j.  Compiled with reassociation allowed, so the sum
    is a vector sum and not a chain of dependent additions (that chain was
    two thirds of :func:`modal_run`'s time on 100 modes); the result differs
    from the sequential sum by rounding only."""
    s = 0.0
    for j in range(wr.shape[0]):
        s += wr[j] * qr[j] + wi[j] * qi[j]
    return s


if HAVE_NUMBA:
    from numba import njit

    _wdot = njit(cache=True, error_model="numpy", fastmath={"reassoc", "contract"})(_wdot)


# One kernel, its sample loop included: the loop as a kernel of its own (and the stored
# columns' count, and each split array allocated apart) cost 0.3 s more of a cold compile;
# its arrays allocated here, where the compiler knows they overlap nothing (the caller's
# scratch instead: the loop 4–5 % slower at 10 modes).
@_jit
def modal_run(mu, g1, g2, q0, u, cre, cim, out, qmax, wout, yout, qlast):
    """Diagonal first-order-hold recurrence q⁺ = μ q + g₁ u + g₂ (u⁺ − u), every mode.

    ``mu``, ``g1``, ``g2``, ``q0``: complex (m,) per mode; ``u`` real (nt,); ``out`` real
    (nt, ncols) receives Re q_j in column ``cre[j]`` and Im q_j in column ``cim[j]``
    (negative: a real mode), columns ≥ ncols not stored; ``qmax[j]`` receives max_k |q_j|;
    ``yout[k]`` Σ wout[c] · (column c of step k) over every column, stored or not (a scalar
    output); ``qlast`` (complex (m,)) the state at the last sample, from which a run over
    the next samples continues.  Real arithmetic on split arrays: the update vectorises.
    """
    m, ncols = mu.shape[0], out.shape[1]
    work, iwork = np.empty((11, m)), np.empty((2, m), np.int64)
    # μ = mr + j mi, g₁ = ar + j ai, g₂ = br + j bi, q = qr + j qi from q0 on, output
    # weights wr, wi, q2 the running max of |q|²; identity: column j is Re q_j; n_im modes
    # have their Im q stored (iwork: the modes, their columns)
    mr, mi, ar, ai, br, bi = work[0], work[1], work[2], work[3], work[4], work[5]
    qr, qi, wr, wi, q2 = work[6], work[7], work[8], work[9], work[10]
    identity, n_im = True, 0
    for j in range(m):
        mr[j], mi[j] = mu[j].real, mu[j].imag
        ar[j], ai[j] = g1[j].real, g1[j].imag
        br[j], bi[j] = g2[j].real, g2[j].imag
        qr[j], qi[j] = q0[j].real, q0[j].imag
        wr[j] = wout[cre[j]]
        wi[j] = wout[cim[j]] if cim[j] >= 0 else 0.0
        q2[j] = 0.0
        identity = identity and cre[j] == j
        if 0 <= cim[j] < ncols:
            iwork[0, n_im] = j
            iwork[1, n_im] = cim[j]
            n_im += 1
    im_mode, im_col = iwork[0, :n_im], iwork[1, :n_im]
    for k in range(u.shape[0]):
        if k > 0:
            uk = u[k - 1]
            du = u[k] - uk
            for j in range(m):
                xr = mr[j] * qr[j] - mi[j] * qi[j] + ar[j] * uk + br[j] * du
                xi = mr[j] * qi[j] + mi[j] * qr[j] + ai[j] * uk + bi[j] * du
                qr[j] = xr
                qi[j] = xi
        for j in range(m):
            a = qr[j] * qr[j] + qi[j] * qi[j]
            q2[j] = a if not a <= q2[j] else q2[j]      # (a NaN stays: it is absorbing)
        yout[k] = _wdot(wr, qr, wi, qi)
        if identity:
            for j in range(min(m, ncols)):
                out[k, j] = qr[j]
        else:
            for j in range(m):
                c = cre[j]
                if c < ncols:
                    out[k, c] = qr[j]
        for p in range(im_mode.shape[0]):
            out[k, im_col[p]] = qi[im_mode[p]]
    for j in range(m):
        qmax[j] = math.sqrt(q2[j])
        qlast[j] = complex(qr[j], qi[j])


@functools.cache
def load_python():
    """A copy of this module that never uses numba (:func:`mechcirc._jit.load`), loaded once
    per process."""
    return load(__name__, _FORCE_PYTHON=True)
