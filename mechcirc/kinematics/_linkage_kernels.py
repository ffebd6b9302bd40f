"""The linkage Newton continuation as one compiled loop over the crank positions.

One source, two backends, as :mod:`mechcirc.scene._motion_kernels`: compiled with
numba's ``@njit(cache=True)`` when numba is importable (the ``fast`` extra),
plain Python otherwise.  :mod:`.linkage_solver` uses :func:`newton_path` only
when it is compiled (``HAVE_NUMBA``, and in numba's cache); otherwise its batched
numpy ``Newton`` runs.  That twin stays by measurement (28 Nov,
``benchmarks/bench_linkage_newton.py``; docs/performance.md, "The numpy Newton
beside newton_path"): run as Python this loop costs 240–12,000 µs per position
(the FNF six-bar 880 µs at 361 and 3,601 positions), 6–66× the numpy Newton's
time on the shipped linkages at 37–3,601 positions (the six-bar 3.1–3.2 s against
0.05 s at 3,601), and ``mechcirc simulate examples/fnf_sixbar_scene.toml``
without numba would take 1.8 s (1.5×) more.  Single positions are the
exception (the numpy path imports scipy.linalg, 0.2 s): not worth a third route.

The closed-form dyads have no kernel here, by the same measurement (28 Nov,
sections 4–5 of that script; docs/performance.md, "The dyads: one source"): a
compiled RRR loop (``dyads_path``, removed) was faster in the solve (the numpy
``_DyadSolver`` took 0.9–3.8× its time, up to 4.4 ms more a call) but made no
shipped command faster, and run as Python it was 14–47× slower than numpy; the
numpy form alone also serves sliders, crossings and lock searches.

The equations are those of :mod:`.linkage` (Φ(q, t) = 0: coincident joint
points, 2 rows per revolute pair, then φ_c − ω_c t for each crank), written on
the index arrays of :func:`.linkage_solver.plan`:

* row pair k: P_a − P_b, with P = (x_i, y_i) + R(φ_i) s for a moving body i and
  P = s (the pose coordinate) for the ground (index ``nb``);
* Jacobian: ±1 on the (x, y) columns, ±(−(R s)_y, (R s)_x) on the φ column;
* γ (constant crank speeds): R_a s_a φ̇_a² − R_b s_b φ̇_b²;
* sliders (:mod:`.linkage`): after the 2m joint rows, one row u × d per slider
  (u its guide's direction, d = P_slider − P_guide) and one row φ_b − φ_a;
  the crank rows come last.  Jacobian and γ as in :class:`.linkage_solver.Newton`.

The loop visits the targets in order; between two it takes continuation steps
of at most ``dt_max`` (Taylor predictor from q, q̇, q̈; Newton with partial
pivoting LU; the step halves when Newton fails or J is near singular) and
tracks the sign of det J: a change is a branch jump.  At every target q̇, q̈
and the conditional-stop parts come from the LU of J at the converged q.
"""

from __future__ import annotations

import math

from .._jit import decorators, internal

HAVE_NUMBA, _jit, _jit_inline = decorators(bool(globals().get("_FORCE_PYTHON")))
# A kernel or piece that allocates nothing (its scratch from the caller, or none):
# compiled without reference counting, which inlined into a loop would cost an atomic
# increment and decrement of every array argument per call (newton_path +25 %).
_leaf = decorators(bool(globals().get("_FORCE_PYTHON")), nrt=False)[1]
# The pieces newton_path calls (the equations, the LU): compiled for it alone, without the
# CPython and C-callable wrappers of a kernel (:func:`mechcirc._jit.internal`); the layers
# between them (_converge, _rates) inlined at their one site each, so no piece is compiled
# twice and none is linked into more than newton_path (docs/performance.md, "jit50").
_piece = internal(bool(globals().get("_FORCE_PYTHON")), nrt=False)

#: Status codes of :func:`newton_path`.
OK, SINGULAR_POSE, LOCK, BRANCH_JUMP = 0, 1, 2, 3


@_jit_inline
def _turn(c, s, x, y):
    """(x, y) turned by the angle whose cosine and sine are ``c``, ``s``."""
    return c * x - s * y, s * x + c * y


@_piece
def _sides(q, nb, ia, ib, sa, sb, cs, sn, R):
    """R(φ) s of both sides of every joint row into R (m, 4): (Rax, Ray, Rbx, Rby)."""
    for i in range(nb):
        cs[i] = math.cos(q[3 * i + 2])
        sn[i] = math.sin(q[3 * i + 2])
    for k in range(ia.shape[0]):
        a, b = ia[k], ib[k]
        if a < nb:
            R[k, 0], R[k, 1] = _turn(cs[a], sn[a], sa[k, 0], sa[k, 1])
        else:
            R[k, 0], R[k, 1] = sa[k, 0], sa[k, 1]
        if b < nb:
            R[k, 2], R[k, 3] = _turn(cs[b], sn[b], sb[k, 0], sb[k, 1])
        else:
            R[k, 2], R[k, 3] = sb[k, 0], sb[k, 1]


@_piece
def _prism(q, nb, ga, gb, gs, gu, bs, cs, sn, P):
    """Per slider into P (ns, 8): u, R_a s_a, R_b s_b, d = P_b − P_a (x, y each)."""
    for k in range(ga.shape[0]):
        a, b = ga[k], gb[k]
        ca, sa_ = (cs[a], sn[a]) if a < nb else (1.0, 0.0)
        P[k, 0], P[k, 1] = _turn(ca, sa_, gu[k, 0], gu[k, 1])
        P[k, 2], P[k, 3] = _turn(ca, sa_, gs[k, 0], gs[k, 1])
        P[k, 4], P[k, 5] = _turn(cs[b], sn[b], bs[k, 0], bs[k, 1])
        P[k, 6] = q[3 * b] + P[k, 4] - P[k, 2]
        P[k, 7] = q[3 * b + 1] + P[k, 5] - P[k, 3]
        if a < nb:
            P[k, 6] -= q[3 * a]
            P[k, 7] -= q[3 * a + 1]


@_piece
def _residual(q, t, nb, ia, ib, R, crank_idx, omega, r, ga, gb, P):
    """Φ(q, t) into r; returns max |Φ|."""
    m, ns = ia.shape[0], ga.shape[0]
    for k in range(m):
        a, b = ia[k], ib[k]
        xa, ya = R[k, 0], R[k, 1]
        if a < nb:
            xa += q[3 * a]
            ya += q[3 * a + 1]
        xb, yb = R[k, 2], R[k, 3]
        if b < nb:
            xb += q[3 * b]
            yb += q[3 * b + 1]
        r[2 * k] = xa - xb
        r[2 * k + 1] = ya - yb
    for k in range(ns):
        r[2 * m + k] = P[k, 0] * P[k, 7] - P[k, 1] * P[k, 6]
        r[2 * m + ns + k] = q[3 * gb[k] + 2] - (q[3 * ga[k] + 2] if ga[k] < nb else 0.0)
    for j in range(crank_idx.shape[0]):
        r[2 * m + 2 * ns + j] = q[3 * crank_idx[j] + 2] - omega[j] * t
    size = 0.0
    for i in range(r.shape[0]):
        v = abs(r[i])
        if not v <= size:           # NaN propagates
            size = v
    return size


@_piece
def _jacobian(nb, ia, ib, R, crank_idx, J, ga, gb, P):
    m, ns = ia.shape[0], ga.shape[0]
    J[:, :] = 0.0
    for k in range(m):
        a, b = ia[k], ib[k]
        if a < nb:
            J[2 * k, 3 * a] = 1.0
            J[2 * k + 1, 3 * a + 1] = 1.0
            J[2 * k, 3 * a + 2] = -R[k, 1]
            J[2 * k + 1, 3 * a + 2] = R[k, 0]
        if b < nb:
            J[2 * k, 3 * b] -= 1.0
            J[2 * k + 1, 3 * b + 1] -= 1.0
            J[2 * k, 3 * b + 2] += R[k, 3]
            J[2 * k + 1, 3 * b + 2] -= R[k, 2]
    for k in range(ns):
        a, b = ga[k], gb[k]
        row = 2 * m + k
        ux, uy, dx, dy = P[k, 0], P[k, 1], P[k, 6], P[k, 7]
        J[row, 3 * b] = -uy
        J[row, 3 * b + 1] = ux
        J[row, 3 * b + 2] = ux * P[k, 4] + uy * P[k, 5]
        J[2 * m + ns + k, 3 * b + 2] = 1.0
        if a < nb:
            J[row, 3 * a] = uy
            J[row, 3 * a + 1] = -ux
            J[row, 3 * a + 2] = -(ux * (dx + P[k, 2]) + uy * (dy + P[k, 3]))
            J[2 * m + ns + k, 3 * a + 2] = -1.0
    for j in range(crank_idx.shape[0]):
        J[2 * m + 2 * ns + j, 3 * crank_idx[j] + 2] = 1.0


@_piece
def _lu(A, piv):
    """LU with partial pivoting in place; returns the sign of det A, 0 if near singular.

    Near singular: min |U_kk| ≤ 1e-12 max |U_kk| (the test the numpy path
    applies to LAPACK's factors).
    """
    n = A.shape[0]
    sign = 1.0
    for k in range(n):
        p, big = k, abs(A[k, k])
        for i in range(k + 1, n):
            v = abs(A[i, k])
            if v > big:
                big, p = v, i
        piv[k] = p
        if not big > 0.0:
            return 0.0
        if p != k:
            sign = -sign
            for j in range(n):
                A[k, j], A[p, j] = A[p, j], A[k, j]
        inv = 1.0 / A[k, k]
        for i in range(k + 1, n):
            f = A[i, k]
            if f != 0.0:
                f *= inv
                A[i, k] = f
                for j in range(k + 1, n):
                    A[i, j] -= f * A[k, j]
    lo, hi = math.inf, 0.0
    for k in range(n):
        v = abs(A[k, k])
        lo = min(lo, v)
        hi = max(hi, v)
        if A[k, k] < 0.0:
            sign = -sign
    if not lo > 1e-12 * hi:
        return 0.0
    return sign


@_piece
def _lu_solve(A, piv, b):
    """Solve with the factors of :func:`_lu`, b overwritten by the solution."""
    n = A.shape[0]
    for k in range(n):
        p = piv[k]
        if p != k:
            b[k], b[p] = b[p], b[k]
    for i in range(n):
        s = b[i]
        for j in range(i):
            s -= A[i, j] * b[j]
        b[i] = s
    for i in range(n - 1, -1, -1):
        s = b[i]
        for j in range(i + 1, n):
            s -= A[i, j] * b[j]
        b[i] = s / A[i, i]


@_jit_inline
def _converge(trial, t_new, nb, geo, crank_idx, omega, tol, work, r, J, piv):
    """Newton from ``trial`` (in place) at time ``t_new``.

    Returns the sign of det J at the converged q, with J's LU left in (J,
    piv) and R, P at that q; 0.0 when Newton fails or J is near singular.
    """
    ia, ib, sa, sb, ga, gb, gs, gu, bs = geo
    cs, sn, R, P = work
    n = trial.shape[0]
    previous = math.inf
    done = False
    # at most 30 Newton steps, and once converged one more pass for J and its LU at the
    # converged q (for the sign and the rates), without the residual: each piece at one
    # site, which numba inlines once
    for it in range(31):
        if it == 30 and not done:
            break
        _sides(trial, nb, ia, ib, sa, sb, cs, sn, R)
        _prism(trial, nb, ga, gb, gs, gu, bs, cs, sn, P)
        size = 0.0
        if not done:
            size = _residual(trial, t_new, nb, ia, ib, R, crank_idx, omega, r, ga, gb, P)
            if not size < math.inf or (it >= 2 and size > previous):
                return 0.0
            previous = size
        _jacobian(nb, ia, ib, R, crank_idx, J, ga, gb, P)
        sign = _lu(J, piv)
        if done or sign == 0.0:
            return sign
        _lu_solve(J, piv, r)
        for i in range(n):
            trial[i] -= r[i]
        # converged; that last step polished it to rounding
        done = size < tol
    return 0.0


@_jit_inline
def _rates(nb, geo, omega, work, J, piv, qd, qdd, parts, e):
    """q̇ = Σ_c J⁻¹ ω_c e_c (the parts) and q̈ = J⁻¹ γ from the LU of J (see the module)."""
    ia, ib, sa, sb, ga, gb, gs, gu, bs = geo
    R, P = work[2], work[3]
    n, m, ns = qd.shape[0], ia.shape[0], ga.shape[0]
    nc = omega.shape[0]
    qd[:] = 0.0
    # the crank parts, then γ (which needs all of q̇): one solve site, which numba inlines once
    for c in range(nc + 1):
        e[:] = 0.0
        if c < nc:
            e[2 * m + 2 * ns + c] = omega[c]
        else:
            _gamma(nb, ia, ib, ga, gb, R, P, qd, e)
        _lu_solve(J, piv, e)
        for i in range(n):
            if c < nc:
                parts[i, c] = e[i]
                qd[i] += e[i]
            else:
                qdd[i] = e[i]


@_jit_inline
def _gamma(nb, ia, ib, ga, gb, R, P, qd, e):
    """γ (the q̈-free part of −Φ̈) into ``e``, from q̇ (see the module)."""
    m, ns = ia.shape[0], ga.shape[0]
    for kk in range(m):
        a, b = ia[kk], ib[kk]
        wa = qd[3 * a + 2] ** 2 if a < nb else 0.0
        wb = qd[3 * b + 2] ** 2 if b < nb else 0.0
        e[2 * kk] = R[kk, 0] * wa - R[kk, 2] * wb
        e[2 * kk + 1] = R[kk, 1] * wa - R[kk, 3] * wb
    for kk in range(ns):
        # −(ü × d + 2 u̇ × ḋ + u × d̈) without q̈: u̇ = ω_a i u, ü = −ω_a² u
        a, b = ga[kk], gb[kk]
        wa = qd[3 * a + 2] if a < nb else 0.0
        wb = qd[3 * b + 2]
        ux, uy, dx, dy = P[kk, 0], P[kk, 1], P[kk, 6], P[kk, 7]
        ddx = qd[3 * b] - wb * P[kk, 5] + wa * P[kk, 3]
        ddy = qd[3 * b + 1] + wb * P[kk, 4] - wa * P[kk, 2]
        if a < nb:
            ddx -= qd[3 * a]
            ddy -= qd[3 * a + 1]
        # ü × d = −ω_a² u × d;  2 u̇ × ḋ = −2 ω_a u · ḋ;  u × d̈ (its q̈-free part)
        t1 = -wa * wa * (ux * dy - uy * dx)
        t2 = 2.0 * wa * (-(uy * ddy) - ux * ddx)
        ex = wa * wa * P[kk, 2] - wb * wb * P[kk, 4]
        ey = wa * wa * P[kk, 3] - wb * wb * P[kk, 5]
        t3 = ux * ey - uy * ex
        e[2 * m + kk] = -(t1 + t2 + t3)


@_jit_inline
def _store_target(k, q, qd, qdd, parts, Q, QD, QDD, PARTS):
    """Target k reached: its q, q̇, q̈ and the conditional-stop parts into row k."""
    for i in range(q.shape[0]):
        Q[k, i] = q[i]
        QD[k, i] = qd[i]
        QDD[k, i] = qdd[i]
        for c in range(parts.shape[1]):
            PARTS[k, i, c] = parts[i, c]


# The start itself first (its sign of det J is the branch's), then continuation steps of
# dt from (t_now, q) to t_new: a Taylor predictor from q, q̇, q̈ into the trial, then
# Newton; the step halves while Newton fails.  One loop, so one site of the Newton and of
# the rates (numba inlines every site: the start's own Newton and rates were a second copy).
@_leaf
def newton_path(t0, targets, ia, ib, sa, sb, crank_idx, omega, tol, dt_max, wmax,
                Q, QD, QDD, PARTS, info, ga, gb, gs, gu, bs, work, J, piv, vec, parts):
    """Continue from q (``vec[0]``) at time t0 (the pose, or past a change point) through
    ``targets``.

    Fills Q, QD, QDD (N, n) and PARTS (N, n, nc).  Its scratch comes from the caller (it
    allocates nothing, so it runs without reference counting): ``work`` (cs, sn of the
    bodies, R (m, 4), P (slider, 8)), J (n, n), piv (n), ``vec`` rows q (the start), q̇,
    q̈ (zeros), the trial, e, r; ``parts`` (n, nc) zeros.  Returns a status:
    ``OK``; ``SINGULAR_POSE``; ``LOCK`` (info[0] = time of the lock estimate);
    ``BRANCH_JUMP`` (info[0], info[1] = the step's ends).
    """
    n = vec.shape[1]
    nb = n // 3
    N = targets.shape[0]
    geo = (ia, ib, sa, sb, ga, gb, gs, gu, bs)
    q, qd, qdd, trial, e, r = vec[0], vec[1], vec[2], vec[3], vec[4], vec[5]
    t_now = t_new = t0
    dt = 0.0
    sign0 = 0.0
    k = 0
    while True:
        if sign0 == 0.0:
            for i in range(n):
                trial[i] = q[i]
        else:
            for i in range(n):
                trial[i] = q[i] + dt * (qd[i] + 0.5 * dt * qdd[i])
        sgn = _converge(trial, t_new, nb, geo, crank_idx, omega, tol, work, r, J, piv)
        if sign0 == 0.0:
            if sgn == 0.0:
                return SINGULAR_POSE
            sign0 = sgn
        elif sgn == 0.0:
            dt *= 0.5
            t_new = t_now + dt
            if abs(dt) * wmax < 1e-9:       # the step has shrunk to nothing: a lock
                info[0] = t_now + 2.0 * dt
                return LOCK
            continue
        elif sgn != sign0:
            info[0], info[1] = t_now, t_new
            return BRANCH_JUMP
        t_now = t_new
        for i in range(n):
            q[i] = trial[i]
        _rates(nb, geo, omega, work, J, piv, qd, qdd, parts, e)
        # the targets reached, then the next step towards the next one
        while k < N:
            t_new = targets[k]
            dt = t_new - t_now
            if dt != 0.0:
                break
            _store_target(k, q, qd, qdd, parts, Q, QD, QDD, PARTS)
            k += 1
        if k == N:
            return OK
        if dt > dt_max or dt < -dt_max:
            dt = dt_max if dt > 0.0 else -dt_max
            t_new = t_now + dt
