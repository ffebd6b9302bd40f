"""Compiled evaluation of a series–parallel plan (see :func:`mechcirc.reduction.plan`).

One loop over ω, and inside it one pass over the plan's nodes in postorder,
with K and the running error bound of each node kept in scalars: no
temporary arrays, and the bound costs a few flops per node in the same pass.
It computes K exactly as :func:`mechcirc.reduction.evaluate`'s numpy path
does, operation for operation and in the same order (the leaf laws enter
only as the plan's coefficients, built from :func:`mechcirc.circuit.law_terms`;
a lever node divides by its ratio twice, :meth:`mechcirc.circuit.Lever.reflect`),
and its own bound of the same error, without square roots or divisions: at or above the
numpy path's, by at most 8.25 % (sec(π/8)) on each node's own roundings (:func:`_child_loop`).

Compiled with numba when it is installed (:mod:`mechcirc._jit`); numba is
imported only when the first sweep asks for this module.  Without numba the
reduction uses its numpy path instead of running this loop as Python.
"""

from __future__ import annotations

import math

import numpy as np

from ._jit import decorators

# The helpers are compiled apart (inlined at numba's level into the plan's loop, the cold
# compile took 5.8 s instead of 4.1 s of CPU and the bound's loops ran up to 2.4x slower)
# and without numba's reference counting: an atomic increment and decrement of every array
# argument at every call, which waits for the divisions in flight (half of K's time on the
# 999-element ladder).  Each is called once per node and block of ω, not inlined by LLVM.
HAVE_NUMBA, jit, jit_inline = decorators()
_leaf = decorators(nrt=False)[1]

_U = np.finfo(float).eps / 2
_U_RECIP = 4 * _U


@_leaf
def _recip(a, b):
    """1/(a + jb) with 1/0 = ∞, 1/∞ = 0 (Smith's algorithm otherwise, as numpy's)."""
    if math.isinf(a) or math.isinf(b):
        return 0.0, 0.0
    if a == 0.0 and b == 0.0:
        return math.inf, 0.0
    # Smith's two branches as one, selecting operands (3 divisions where a vectorised
    # loop computed both branches, 6): p the part of the larger magnitude.
    big = abs(a) >= abs(b)
    p = a if big else b
    q = b if big else a
    r = q / p
    d = p + q * r
    return (1.0 if big else r) / d, -(r if big else 1.0) / d


@_leaf
def _through_reciprocal(rho):
    """A bound of the relative error of 1/x̂ given that of x̂, ρ/(1 − ρ), ∞ from
    ρ ≥ 1 on and for NaN."""
    if rho < 1.0:
        return rho / (1.0 - rho)
    return math.inf


@_leaf
def _children(i, nb, series, kstart, kids, slot, cplx, re, im, ai, cr, ci, has_i, has_c):
    """Add node i's internal children (impedances in series, admittances in
    parallel) to the complex sum (cr, ci) or the imaginary one (ai)."""
    for q in range(kstart[i], kstart[i + 1]):
        c = slot[kids[q]]
        cc = cplx[kids[q]]
        _child_loop(False, nb, series, cc, cc and not has_c, not cc and not has_i, False, c, 0.0,
                    0.0, 0.0, re, im, re, ai, cr, ci, cr, cr, False)
        has_c = has_c or cc
        has_i = has_i or not cc
    return has_i, has_c


@_leaf
def _children_err(i, nb, series, m_u, kind, kstart, kids, slot, cplx, re, im, mg, ig, rh, ai, cr,
                  ci, bb, tv, has_i, has_c, have_b):
    """:func:`_children` and each child's term of the node's error bound added to ``bb``:
    in the same loop where the term allows it (:func:`_child_loop`), else by
    :func:`_old_term` after it."""
    for q in range(kstart[i], kstart[i + 1]):
        cn = kids[q]
        c = slot[cn]
        ck = kind[cn]
        cc = cplx[cn]
        direct = series and ck == 0
        sec = _SEC if cc else _K2          # (an imaginary term's ℓ is its |b|)
        # (rb_max −1: every point of a lever's, a leaf's or 1/(1/S) to _old_term)
        rb_max = _RHO_MAX / sec if ck == 0 or (ck == 1 and series) else -1.0
        first_c = cc and not has_c
        first_i = not cc and not has_i
        cs = (m_u if direct else _U_RECIP + m_u) * sec
        ks = _K87 * sec
        # series and cc as constants: one loop each, without the other cases' divisions
        if series and cc:
            wide = _child_loop(True, nb, True, True, first_c, first_i, direct, c, cs, ks, rb_max,
                               re, im, rh, ai, cr, ci, bb, tv, have_b)
        elif series:
            wide = _child_loop(True, nb, True, False, first_c, first_i, direct, c, cs, ks, rb_max,
                               re, im, rh, ai, cr, ci, bb, tv, have_b)
        elif cc:
            wide = _child_loop(True, nb, False, True, first_c, first_i, direct, c, cs, ks, rb_max,
                               re, im, rh, ai, cr, ci, bb, tv, have_b)
        else:
            wide = _child_loop(True, nb, False, False, first_c, first_i, direct, c, cs, ks,
                               rb_max, re, im, rh, ai, cr, ci, bb, tv, have_b)
        if wide:
            for j in range(nb):
                if tv[j] == 0.0:
                    bb[j] += _old_term(series, ck, m_u, re[c, j], im[c, j], mg[c, j], ig[c, j],
                                       rh[c, j])
        has_c = has_c or cc
        has_i = has_i or not cc
        have_b = True
    return has_i, has_c


# A series or parallel child keeps its sum's E ≥ |Ŝ − S| (:func:`_triple`).  With
# ℓ(a, b) = max(|a|, |b|, (|a| + |b|)/√2) ≥ cos(π/8)|a + jb| (the nearest of the
# directions 0, π/4, π/2 is within π/8 of (|a|, |b|): Cauchy–Schwarz), rounded ℓ̂ ≥
# ℓ(1 − 3u), and ``_SEC`` ≥ sec(π/8)(1 + 64u), ℓ̄ = ℓ̂·_SEC ≥ |a + jb|/(1 − 8u), with room
# for the few roundings of the terms it enters.  The term is bounded by
#
# - S itself (``direct``: series in series): E, plus m·u·|Ŝ| for the parent's m
#   additions: E + m·u·ℓ̄ (``cs`` = m·u·_SEC);
# - 1/S (a series child in parallel, a parallel child in series): t̂ = R̂ = fl(1/Ŝ) by
#   Smith's algorithm (:func:`_recip`), |R̂ − 1/Ŝ| ≤ 4u·r, r = 1/|Ŝ|: d = p + q·(q/p) adds two
#   numbers of one sign, the smaller perturbed by 2u, so d̂ = d(1 + 2u), and the parts
#   1/d̂ and (q/p)/d̂ are one and two roundings more (3u and 4u to first order, the 4u of
#   the numpy path).  With |1/Ŝ − 1/S| = |S − Ŝ|·r/|S| ≤ E·r²/(1 − ρ), ρ = E·r < 1
#   (|S| ≥ |Ŝ| − E), and m·u·|R̂| for the parent's additions, |t̂ − t| ≤ E·r²/(1 − ρ) +
#   (4u + m·u)·r: the numpy path's (ρ/(1 − ρ) + 4u + m·u)/|Ŝ|.  Here r² ≤ |R̂|²/(1 − 4u)² ≤
#   q̂/(1 − 11u), q̂ the rounded Rr² + Ri² (three roundings of terms ≥ 0; q̂ in
#   [1e-290, 1e290], where no underflow counts), r ≤ ℓ̄, and for ρ̄ = E·ℓ̄ ≤ 0.124 < 1/8,
#   1/(1 − ρ) ≤ 1 + ρ/(1 − 1/8) ≤ 1 + 1.15ρ̄: t = E·q̂·(_K2 + 1.15·_SEC·E·ℓ̂) + (4u + m·u)·ℓ̄, no
#   division and no square root, _K2 = 1 + 64u covering the roundings.  Above the numpy
#   path's term by at most 8.25 % in its second part (ℓ̄ against r) and 1.2 % in its first
#   ((1 + 1.15ρ̄)(1 − ρ)): a constant factor on each node's own roundings, not carried
#   multiplied along a ladder (the part carried, E·r², is exact up to _K2).  Where q̂ is
#   out of that range or ρ̄ > 0.124 (or NaN: E or Ŝ not finite) the term is left to
#   :func:`_old_term`, the numpy path's form.
#
# An imaginary term (a = 0) has ℓ̂ = |b| exactly: ``_SEC`` is 1 + 64u there.
@jit_inline     # its sites pass ``err`` as a constant: K alone runs the loop without the bound
def _child_loop(err, nb, series, cc, first_c, first_i, direct, c, cs, ks, rb_max, re, im, rh, ai,
                cr, ci, bb, tv, have_b):
    """One child's term t̂ (K, or its reciprocal in a parallel node) into the sums and, with
    ``err``, the bound of |t̂ − t| into ``bb`` (:func:`_children`); returns the number of
    points left to :func:`_old_term` (``tv`` 0 there).  The bound: the comment above."""
    wide = 0
    for j in range(nb):
        if series:
            tr = re[c, j]
            ti = im[c, j]
        elif cc:
            tr, ti = _recip(re[c, j], im[c, j])
        else:
            tr = 0.0
            ti = -1.0 / im[c, j]
        # The sums read before they are written and the first term a select: as
        # branches, LLVM stored with a mask and read the same address back with one,
        # which does not forward (a stall per point, a third of the bound's loop).
        if cc:
            sr = cr[j]
            si = ci[j]
            cr[j] = tr if first_c else sr + tr
            ci[j] = ti if first_c else si + ti
        else:
            si = ai[j]
            ai[j] = ti if first_i else si + ti
        if err:
            e = rh[c, j]
            x = abs(tr)
            y = abs(ti)
            h = _C4 * (x + y)
            m = x if x > y else y
            m = h if h > m else m
            # (selects, not branches: LLVM made the store to bb a scatter)
            p = tr * tr + ti * ti
            rb = e * m
            ok = direct | ((_Q_LO < p) & (p < _Q_HI) & (rb <= rb_max))
            t = (e if direct else e * p * (_K2 + ks * rb)) + cs * m
            b = bb[j]               # (read unconditionally: a masked load otherwise)
            b = b if have_b else 0.0
            bb[j] = b + t if ok else b
            tv[j] = 1.0 if ok else 0.0
            wide += not ok
    return wide


#: ℓ̂·_SEC ≥ |a + jb| (:func:`_child_loop`): 1/√2, sec(π/8)(1 + 64u) rounded up; 1 + 64u;
#: 1.15 ≥ (8/7)(1 + 8u)·_K2; ρ̄ ≤ 0.124 (< 1/8 with the roundings); q̂ = |R̂|² in range.
_C4, _SEC, _K2, _K87, _RHO_MAX = 0.7071067811865476, 1.082392200292402, 1.0 + 2.0 ** -47, 1.15, 0.124
_Q_LO, _Q_HI = 1e-290, 1e290


#: |a + jb| is √(a² + b²) where the larger part lies in this range (no square
#: overflows or underflows), else hypot (:func:`_mag`).
_ABS_LO, _ABS_HI = 1e-150, 1e150


@_leaf
def _mag(a, b):
    """|a + jb| as the bound forms it where it needs a magnitude itself (a lever, the root,
    a term :func:`_child_loop` leaves to :func:`_old_term`): √(a² + b²), or hypot where
    the larger part is outside [``_ABS_LO``, ``_ABS_HI``]."""
    if _ABS_LO < max(abs(a), abs(b)) < _ABS_HI:
        return math.sqrt(a * a + b * b)
    return math.hypot(a, b)


@_leaf
def _root_error(ck, s, nb, re, im, mg, ig, rh, out):
    """The root's (kind ``ck``, slot ``s``) bound relative to the true |K| into ``out``.  Its
    sum's |Ŝ| first, in a loop of its own (:func:`_mag` for the whole block where a point
    needs hypot: that call in the loop kept it from being vectorised, 1.7x K on
    ``stb_heald.mcir`` against 1.4x)."""
    a = mg if ck == 1 else re
    b = ig if ck == 1 else im
    wide = 0
    for j in range(nb):
        x = a[s, j]
        y = b[s, j]
        out[j] = math.sqrt(x * x + y * y)
        wide += not (_ABS_LO < max(abs(x), abs(y)) < _ABS_HI)
    if wide:
        for j in range(nb):
            out[j] = _mag(a[s, j], b[s, j])
    for j in range(nb):
        h = rh[s, j] if ck == 2 else _node_bound(ck == 3, ck != 1, rh[s, j], out[j])[2]
        r = _through_reciprocal(h)
        out[j] = math.inf if math.isnan(r) else r


@_leaf
def _triple(ck, re, im, mg, ig, rh):
    """``(|K|, 1/|K|, ρ)`` of a node of kind ``ck`` from its row of (``re``, ``im``, ``mg``,
    ``ig``, ``rh``) at one point: a lever's as stored in (``mg``, ``ig``, ``rh``); a series or
    parallel node, or a single leaf, keeps its sum's E ≥ |Ŝ − S| in ``rh`` and the sum Ŝ
    itself in (``re``, ``im``) (a series node or leaf: K = Ŝ) or (``mg``, ``ig``) (a
    parallel node, K = 1/Ŝ) (:func:`_store_case`)."""
    if ck == 2:
        return mg, ig, rh
    if ck == 1:
        return _node_bound(False, False, rh, _mag(mg, ig))
    return _node_bound(ck == 3, True, rh, _mag(re, im))


@_leaf
def _old_term(series, ck, m_u, re, im, mg, ig, rh):
    """A child's term of its parent's error bound from its (|K|, 1/|K|, ρ) (:func:`_triple`):
    the numpy path's form."""
    mg, ig, rh = _triple(ck, re, im, mg, ig, rh)
    if series:
        return (rh + m_u) * mg
    return (_through_reciprocal(rh) + (_U_RECIP + m_u)) * ig


#: Points per block: every node is evaluated over a block of ω at once, so the
#: iterations of the inner loop are independent (a ladder's nodes form one long
#: chain of divisions; node by node at one ω the loop would wait on each).  A sweep of
#: 401 points is one block: each node's helper calls and loop set-ups cost per block
#: (512 against 128: K 0.58–0.89x, K + bound 0.69–0.91x at 401 points, 0.68–0.89x and
#: 0.77–0.93x at 4001; 1024 no faster than 512).
BLOCK = 512


@_leaf
def _reflect(s, c, ck, r, nb, want_error, re, im, mg, ig, rh):
    """A lever node: its child's value (slot ``c``, kind ``ck``) reflected by the ratio ``r``
    (the bound first: it reads the child's K, and ``s`` may be ``c``)."""
    if want_error:
        for j in range(nb):
            m, g, h = _triple(ck, re[c, j], im[c, j], mg[c, j], ig[c, j], rh[c, j])
            mg[s, j] = m / r / r
            ig[s, j] = g * r * r
            rh[s, j] = h + 2 * _U
    for j in range(nb):
        re[s, j] = re[c, j] / r / r
        im[s, j] = im[c, j] / r / r


@_leaf
def _leaf_terms(nb, a_inv, a_om, b_inv, b_om, want_error, w, iw, ai, bb):
    """A node's leaf terms a_inv/ω + a_om·ω into ``ai`` (and their error terms into
    ``bb``); True if there is one."""
    for j in range(nb):             # (LLVM makes it one loop per case)
        if a_inv != 0.0:
            ai[j] = iw[j] * a_inv
            if want_error:
                bb[j] = b_inv * iw[j]
        if a_om != 0.0:
            ai[j] = ai[j] + w[j] * a_om if a_inv != 0.0 else w[j] * a_om
            if want_error:
                bb[j] = bb[j] + b_om * w[j] if a_inv != 0.0 else b_om * w[j]
    return a_inv != 0.0 or a_om != 0.0


@_leaf
def _store(s, nb, series, has_c, re, im, cr, ci, ai):
    """A node's value into slot ``s``: the sum (series), or its reciprocal (parallel)."""
    if has_c:
        if series:
            for j in range(nb):
                re[s, j] = cr[j]
                im[s, j] = ci[j]
        else:
            for j in range(nb):
                re[s, j], im[s, j] = _recip(cr[j], ci[j])
    else:
        if series:
            for j in range(nb):
                re[s, j] = 0.0
                im[s, j] = ai[j]
        else:
            for j in range(nb):
                re[s, j] = 0.0
                im[s, j] = -1.0 / ai[j]


@_leaf
def _merge(nb, real, has_c, has_i, cr, ci, ai):
    """A node's sums made one: its real leaf term ``real`` (if any: nonzero or NaN) into the
    complex sum (cr, ci), then the imaginary sum ``ai`` into ci where both exist; a node
    with neither sums to 0 (an imaginary sum).  Returns (has_c, has_i, with_real)."""
    with_real = real != 0.0 or math.isnan(real)
    if with_real:
        if has_c:
            for j in range(nb):
                cr[j] += real
        else:
            for j in range(nb):
                cr[j] = real
                ci[j] = 0.0
            has_c = True
    if not has_c and not has_i:
        for j in range(nb):
            ai[j] = 0.0
        has_i = True
    if has_c and has_i:
        for j in range(nb):
            ci[j] += ai[j]
    return has_c, has_i, with_real


@_leaf
def _node_bound(leaf, series, b, mag):
    """``(|K|, 1/|K|, ρ)`` of a node from the bound ``b`` of its sum's error and the
    sum's magnitude ``mag`` (scalars only: a helper taking the arrays cost a
    reference count per point).  1/0 is ∞ as compiled code gives it, also as plain
    Python (the main pass's √(a² + b²) is 0 where both squares underflow)."""
    inv = 1.0 / mag if mag != 0.0 else math.inf
    rho = b * inv
    if series:
        # A leaf alone (k = 3): value·η, 1/s, 1/ω and the product.
        return mag, inv, 4 * _U if leaf else rho
    return inv, mag, _through_reciprocal(rho) + _U_RECIP


@_leaf
def _store_with_error(s, nb, series, has_c, have_b, with_real, extra, re, im, mg, ig, rh, cr,
                      ci, ai, bb):
    """:func:`_store` with the bound E of its sum's error |Ŝ − S| and, a parallel node, the
    sum Ŝ itself in (``mg``, ``ig``) (:func:`_triple`): no magnitude is formed here (a
    parent's term needs none, :func:`_child_loop`).  One loop per case."""
    if not has_c:
        _store_case(series, False, s, nb, have_b, with_real, extra, re, im, mg, ig, rh, cr, ci,
                    ai, bb)
    elif series:
        _store_case(True, True, s, nb, have_b, with_real, extra, re, im, mg, ig, rh, cr, ci, ai,
                    bb)
    else:
        _store_case(False, True, s, nb, have_b, with_real, extra, re, im, mg, ig, rh, cr, ci,
                    ai, bb)


@jit_inline     # its sites pass series and has_c as constants: a loop without their branches
def _store_case(series, has_c, s, nb, have_b, with_real, extra, re, im, mg, ig, rh, cr, ci, ai,
                bb):
    """The loop of :func:`_store_with_error`."""
    for j in range(nb):
        b = bb[j]                   # (read unconditionally: a masked load otherwise)
        b = b if have_b else 0.0
        if with_real:
            b += extra
        if has_c:
            sr = cr[j]
            si = ci[j]
        else:
            sr = 0.0
            si = ai[j]
        if series:
            re[s, j] = sr
            im[s, j] = si
        else:
            if has_c:
                re[s, j], im[s, j] = _recip(sr, si)
            else:
                re[s, j] = 0.0
                im[s, j] = -1.0 / si
            mg[s, j] = sr
            ig[s, j] = si
        rh[s, j] = b


@jit
def evaluate_plan(omega, kind, cplx, c_real, c_inv, c_om, e_real, e_inv, e_om, mu,
                  kstart, kids, ratio, slot, n_slots, want_error, K, rho_out):
    """Fill ``K[d, j]`` (and ``rho_out[d, j]`` when ``want_error``) for every design d
    at ``omega[d, j]`` (``omega`` has one row for all designs, or one per design).

    Node i of the plan (children before parents, the root last): ``kind`` 0
    series, 1 parallel, 2 lever, 3 a single leaf (the root, or under a lever);
    ``cplx`` whether its K has a real part; leaf terms ``c_real + j(c_inv/ω +
    c_om·ω)`` (impedances in series, admittances in parallel; a zero
    coefficient is absent, as ``0·∞`` would be NaN) and their error constants
    ``e_*``; ``mu`` = m·u for its m terms; internal children
    ``kids[kstart[i]:kstart[i+1]]``; ``ratio`` of a lever node.  The
    value-dependent arrays have one row per design (``c_real[d, i]``).  Node
    values live in ``slot[i]`` of a stack of ``n_slots`` rows (postorder: a
    node's children are the rows just above it).
    """
    M = kind.shape[0]
    # Per node: re, im, |K|, 1/|K| (a parallel parent's weight) and ρ over a block
    # of ω; per block: the sums and ω, 1/ω.  Allocated once for all designs.
    work = np.empty((5, n_slots, BLOCK))
    vec = np.empty((7, BLOCK))
    for d in range(K.shape[0]):
        dw = d if omega.shape[0] > 1 else 0
        rd = d if want_error else 0
        _evaluate_design(omega[dw], kind, cplx, c_real[d], c_inv[d], c_om[d], e_real[d],
                         e_inv[d], e_om[d], mu[d], kstart, kids, ratio[d], slot, want_error,
                         K[d], rho_out[rd], M, work, vec)


@jit_inline     # its one site: compiled apart, LLVM optimised and emitted its code twice
def _evaluate_design(omega, kind, cplx, c_real, c_inv, c_om, e_real, e_inv, e_om, mu,
                     kstart, kids, ratio, slot, want_error, K, rho_out, M, work, vec):
    """One design of :func:`evaluate_plan`: its rows of the plan, its row of K."""
    n = omega.shape[0]
    B = BLOCK
    re, im, mg, ig, rh = work[0], work[1], work[2], work[3], work[4]
    ai, cr, ci, bb, iw, w, tv = vec[0], vec[1], vec[2], vec[3], vec[4], vec[5], vec[6]
    for j0 in range(0, n, B):
        nb = min(B, n - j0)
        for j in range(nb):
            w[j] = omega[j0 + j]
            iw[j] = 1.0 / w[j]
        for i in range(M):
            k = kind[i]
            s = slot[i]
            if k == 2:
                cn = kids[kstart[i]]
                _reflect(s, slot[cn], kind[cn], ratio[i], nb, want_error, re, im, mg, ig, rh)
                continue
            series = k != 1           # 0 series, 3 a single leaf
            m_u = mu[i]
            # Leaf terms and imaginary children (numpy's "imag"), complex
            # children (numpy's "cplx"): each starts with its first term.
            has_c = False
            has_i = _leaf_terms(nb, c_inv[i], c_om[i], e_inv[i], e_om[i], want_error, w, iw,
                                ai, bb)
            have_b = want_error and has_i
            if want_error:
                has_i, has_c = _children_err(i, nb, series, m_u, kind, kstart, kids, slot, cplx,
                                             re, im, mg, ig, rh, ai, cr, ci, bb, tv, has_i, has_c,
                                             have_b)
                have_b = have_b or kstart[i + 1] > kstart[i]
            else:
                has_i, has_c = _children(i, nb, series, kstart, kids, slot, cplx, re, im, ai, cr,
                                         ci, has_i, has_c)
            has_c, has_i, with_real = _merge(nb, c_real[i], has_c, has_i, cr, ci, ai)
            if want_error:
                _store_with_error(s, nb, series, has_c, have_b, with_real,
                                  e_real[i] if with_real else 0.0, re, im, mg, ig, rh, cr, ci,
                                  ai, bb)
            else:
                _store(s, nb, series, has_c, re, im, cr, ci, ai)
        top = slot[M - 1]
        for j in range(nb):
            K[j0 + j] = complex(re[top, j], im[top, j])
        if want_error:
            _root_error(kind[M - 1], top, nb, re, im, mg, ig, rh, rho_out[j0:])
