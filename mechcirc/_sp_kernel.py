"""Compiled evaluation of a series–parallel plan (see :func:`mechcirc.reduction.plan`).

One loop over ω, and inside it one pass over the plan's nodes in postorder,
with K and the running error bound of each node kept in scalars: no
temporary arrays, and the bound costs a few flops per node in the same pass.
It computes K exactly as :func:`mechcirc.reduction.evaluate`'s numpy path
does, operation for operation and in the same order (the leaf laws enter
only as the plan's coefficients, built from :func:`mechcirc.circuit.law_terms`;
a lever node divides by its ratio twice, :meth:`mechcirc.circuit.Lever.reflect`),
and the same error bound with fewer divisions, so rounded otherwise (within 1e-13
of the numpy path's: :func:`_parent_term`).

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


#: |a + jb| is √(a² + b²) where the larger part lies in this range (no square
#: overflows or underflows), else hypot: the one criterion of both passes of
#: :func:`_store_with_error`.
_ABS_LO, _ABS_HI = 1e-150, 1e150


@_leaf
def _children(i, nb, series, kstart, kids, slot, cplx, re, im, ai, cr, ci, has_i, has_c):
    """Add node i's internal children (impedances in series, admittances in
    parallel) to the complex sum (cr, ci) or the imaginary one (ai)."""
    for q in range(kstart[i], kstart[i + 1]):
        c = slot[kids[q]]
        cc = cplx[kids[q]]
        first_c = cc and not has_c
        first_i = not cc and not has_i
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
        has_c = has_c or cc
        has_i = has_i or not cc
    return has_i, has_c


#: A child's term through the one division E + c(|S| − E) over |S|(|S| − E) (see
#: :func:`_parent_term`) where that product lies in this range, else the two-division
#: form (:func:`_old_term`): nothing overflows or underflows, and E ≥ |S|, 0, ∞ and NaN
#: give what they gave before.
_P_LO, _P_HI = 1e-300, 1e300


@_leaf
def _triple(ck, mg, ig, rh):
    """``(|K|, 1/|K|, ρ)`` of a node of kind ``ck`` from its row of (``mg``, ``ig``,
    ``rh``): a lever's as stored; a series or parallel node, or a single leaf, keeps its
    sum's (|S|, E) in (``mg``, ``rh``) (:func:`_node_bound`)."""
    if ck == 2:
        return mg, ig, rh
    return _node_bound(ck == 3, ck != 1, rh, mg)


@_leaf
def _old_term(series, ck, m_u, mg, ig, rh):
    """A child's term of its parent's error bound from its (|K|, 1/|K|, ρ) (:func:`_triple`)."""
    mg, ig, rh = _triple(ck, mg, ig, rh)
    if series:
        return (rh + m_u) * mg
    return (_through_reciprocal(rh) + (_U_RECIP + m_u)) * ig


@_leaf
def _parent_term(mode, series, m_u, mag, e):
    """Node's term of its parent's error bound from its sum's |S| (``mag``) and E ≥ |Ŝ − S|
    (``e``); ``mode`` 1: a series child of a series parent, 2: K or 1/K is 1/S (a series
    child in parallel, a parallel child in series), 3: a parallel child in parallel;
    ``m_u`` the parent's m·u.  Its term t = K (a series parent, K = S) or t = 1/K (a
    parallel one, K = 1/S) is bounded by

    - S itself (mode 1): |t̂ − t| ≤ E, plus m·u·|S| for the parent's additions:
      E + m·u·|S|, no division;
    - 1/S (mode 2): |1/Ŝ − 1/S| = |S − Ŝ|/(|Ŝ||S|) ≤ E/(|S|(|S| − E)) as |S| ≥ |Ŝ| − E,
      plus (4u + m·u)/|S| for the reciprocal's rounding and the parent's additions: one
      division, (E + (4u + m·u)(|S| − E)) / (|S|(|S| − E)), the bound
      (ρ/(1 − ρ) + 4u + m·u)/|S| of the numpy path with ρ = E/|S|, rounded otherwise;
    - 1/(1/S) (mode 3), and where |S|(|S| − E) is outside [``_P_LO``, ``_P_HI``] (E ≥ |S|,
      |S| 0 or ∞, a sum near the ends of the exponent range): from (|K|, 1/|K|, ρ)
      (:func:`_old_term`).

    The store's second pass takes this where its loop's form of mode 2 does not apply, and
    for the other modes (:func:`_store_with_error`)."""
    x = mag - e
    p = mag * x
    if mode == 3 or not (_P_LO < p < _P_HI):
        return _old_term(mode == 1 or (mode == 2 and not series), 0 if series else 1, m_u,
                         mag, 0.0, e)
    if mode == 1:
        return e + m_u * mag
    return (e + (_U_RECIP + m_u) * x) / p


#: Points per block: every node is evaluated over a block of ω at once, so the
#: iterations of the inner loop are independent (a ladder's nodes form one long
#: chain of divisions; node by node at one ω the loop would wait on each).  A sweep of
#: 401 points is one block: each node's helper calls and loop set-ups cost per block
#: (512 against 128: K 0.58–0.89x, K + bound 0.69–0.91x at 401 points, 0.68–0.89x and
#: 0.77–0.93x at 4001; 1024 no faster than 512).
BLOCK = 512


@_leaf
def _reflect(s, c, ck, r, nb, want_error, mode, m_u, re, im, mg, ig, rh):
    """A lever node: its child's value (slot ``c``, kind ``ck``) reflected by the ratio ``r``;
    its (|K|, 1/|K|, ρ), or with a series or parallel parent (``mode`` > 0, parent's m·u
    ``m_u``) its term of that parent's bound (:func:`_old_term`)."""
    for j in range(nb):
        re[s, j] = re[c, j] / r / r
        im[s, j] = im[c, j] / r / r
    if want_error:
        for j in range(nb):
            m, g, h = _triple(ck, mg[c, j], ig[c, j], rh[c, j])
            m = m / r / r
            g = g * r * r
            h = h + 2 * _U
            if mode:
                rh[s, j] = _old_term(mode == 1, 2, m_u, m, g, h)
            else:
                mg[s, j] = m
                ig[s, j] = g
                rh[s, j] = h


@_leaf
def _leaf_terms(nb, a_inv, a_om, b_inv, b_om, want_error, w, iw, ai, bb, rh, c1):
    """A node's leaf terms a_inv/ω + a_om·ω into ``ai`` (and their error terms, then its
    first internal child's term of its bound, row ``c1`` of ``rh``, into ``bb``); True if
    there is a leaf term."""
    for j in range(nb):             # (LLVM makes it one loop per case)
        if a_inv != 0.0:
            ai[j] = iw[j] * a_inv
            if want_error:
                bb[j] = b_inv * iw[j]
        if a_om != 0.0:
            ai[j] = ai[j] + w[j] * a_om if a_inv != 0.0 else w[j] * a_om
            if want_error:
                bb[j] = bb[j] + b_om * w[j] if a_inv != 0.0 else b_om * w[j]
        if want_error:
            bb[j] = (bb[j] if a_inv != 0.0 or a_om != 0.0 else 0.0) + rh[c1, j]
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


#: 1 + 2u, 1 − 6u; 1/√2 and sec(π/8) rounded down and up with room for the roundings of
#: :func:`_low` and its uses (checked in 200-bit mpmath).
_ONE_2U, _ONE_6U, _HALF_SQRT2_DOWN, _SEC_PI_8_UP = (1.0 + 2 * _U, 1.0 - 6 * _U,
                                                    0.7071067811865474, 1.082392200292396)
#: The loop's term needs |S|² = a² + b² in this range (no square overflows, none
#: underflows far enough to matter); outside it, the second pass.
_Q_LO, _Q_HI = 1e-290, 1e290


@_leaf
def _low(x, y):
    """ℓ = max(|x|, |y|, (|x| + |y|)/√2) ∈ [cos(π/8)|z|, |z|] for z = x + jy, without a square
    root (Cauchy–Schwarz with the directions 0, π/4 and π/2, the nearest at most π/8 away),
    1/√2 taken a few ulps low so that its two roundings keep ℓ ≤ |z|; ℓ·``_SEC_PI_8_UP`` ≥
    |z|/(1 − 4u) with its rounding.  NaN in, NaN out (a select takes h where a comparison
    is false, and h is NaN if x or y is)."""
    a = abs(x)
    b = abs(y)
    m = a if a > b else b
    h = _HALF_SQRT2_DOWN * (a + b)
    return m if m > h else h


@_leaf
def _store_with_error(s, nb, series, has_c, mode, m_u, with_real, extra, re, im, mg, rh, cr,
                      ci, ai, bb):
    """:func:`_store` with the node's share of the error bound, from E ≥ |Ŝ − S| (its leaf
    and children's terms summed in ``bb``, plus ``extra`` ``with_real``), into ``rh`` (and
    ``mg``): with a series or parallel parent (``mode`` > 0, the parent's m·u ``m_u``) the
    node's term of that parent's bound, which the parent adds in its leaf loop
    (:func:`_leaf_terms`), else |Ŝ| and E (:func:`_triple`).

    The loop over the block forms the term of the common case, K or 1/K being 1/S
    (``mode`` 2: a series child in parallel, a parallel child in series), without a square
    root: |t̂ − t| ≤ |1/Ŝ − 1/S| + 4u/|Ŝ| and the parent's additions m·u/|Ŝ|, where
    |1/Ŝ − 1/S| = |S − Ŝ|/(|Ŝ||S|) ≤ E/(|Ŝ|(|Ŝ| − E)) = E/(q − E|Ŝ|), q = |Ŝ|² = a² + b²
    (|S| ≥ |Ŝ| − E).  With ℓ of Ŝ (:func:`_low`) and U = ℓ·sec(π/8) ≥ |Ŝ| the denominator
    q(1 − 6u) − E·U is at most q − E|Ŝ|, its roundings included: the first term is
    E/(q(1 − 6u) − E·U), as tight as E/(|Ŝ|(|Ŝ| − E)) but for E·(U − |Ŝ|) ≤ 0.083·E|Ŝ|
    against q (second order in E/|Ŝ|: the bound does not grow along a chain).  The
    second, (4u + m·u)/|Ŝ|, takes 1/|Ŝ| ≤ (1 + 2u)/ℓ (a series child: one division with the
    first) or ≤ ℓ(K̂)·sec(π/8)/(1 − 4u) from its reciprocal K̂ (a parallel child, no
    division): at most 8.3 % above (4u + m·u)/|Ŝ|, a rounding term, not carried along.
    Where the denominator is not positive the term is ∞ (E ≥ |Ŝ|/sec(π/8) at least, where
    (E + (4u + m·u)(|Ŝ| − E))/(|Ŝ|(|Ŝ| − E)) was finite up to E < |Ŝ|).  A second pass
    takes, with |Ŝ| itself (√(a² + b²), hypot where the larger part is outside
    [``_ABS_LO``, ``_ABS_HI``], where a square could overflow or underflow) and
    :func:`_parent_term`, the points whose q is outside [``_Q_LO``, ``_Q_HI``] (if the
    block has one), and every point of the other modes.  One loop per case
    (:func:`_store_case`)."""
    if not has_c:
        wide = _store_case(series, False, s, nb, m_u, with_real, extra, re, im, rh, cr, ci,
                           ai, bb)
    elif series:
        wide = _store_case(True, True, s, nb, m_u, with_real, extra, re, im, rh, cr, ci, ai,
                           bb)
    else:
        wide = _store_case(False, True, s, nb, m_u, with_real, extra, re, im, rh, cr, ci, ai,
                           bb)
    if mode != 2:
        for j in range(nb):
            sr = cr[j] if has_c else 0.0
            si = ci[j] if has_c else ai[j]
            mg[s, j] = math.sqrt(sr * sr + si * si) if has_c else abs(si)
            rh[s, j] = bb[j] + extra if with_real else bb[j]
    if wide or mode != 2:
        for j in range(nb):
            sr = cr[j] if has_c else 0.0
            si = ci[j] if has_c else ai[j]
            if mode == 2 and _Q_LO <= sr * sr + si * si <= _Q_HI:
                continue
            mag = math.sqrt(sr * sr + si * si) if has_c else abs(si)
            if has_c and not (_ABS_LO < max(abs(sr), abs(si)) < _ABS_HI):
                mag = math.hypot(sr, si)
            if mode:
                rh[s, j] = _parent_term(mode, series, m_u, mag,
                                        bb[j] + extra if with_real else bb[j])
            else:
                mg[s, j] = mag


@jit_inline     # its sites pass series and has_c as constants: a loop without their branches
def _store_case(series, has_c, s, nb, m_u, with_real, extra, re, im, rh, cr, ci, ai, bb):
    """The loop of :func:`_store_with_error`; returns the number of points whose |Ŝ|² lies
    outside [``_Q_LO``, ``_Q_HI``] (an integer count: a float one would not vectorise)."""
    cj = _U_RECIP + m_u
    wide = 0
    for j in range(nb):
        b = bb[j]
        if with_real:
            b += extra
        if has_c:
            sr = cr[j]
            si = ci[j]
        else:
            sr = 0.0
            si = ai[j]
        if series:
            kr = sr
            ki = si
        elif has_c:
            kr, ki = _recip(sr, si)
        else:
            kr = 0.0
            ki = -1.0 / si
        re[s, j] = kr
        im[s, j] = ki
        q = sr * sr + si * si
        wide += (q < _Q_LO) | (q > _Q_HI)
        low = _low(sr, si)
        den = q * _ONE_6U - b * (low * _SEC_PI_8_UP)
        pos = den > 0.0
        if series:      # (the divisor 1 where the term is ∞: no division by 0 as Python)
            t = (b * low + cj * _ONE_2U * den) / (low * den if pos else 1.0)
        else:
            t = b / (den if pos else 1.0) + cj * (_low(kr, ki) * _SEC_PI_8_UP)
        rh[s, j] = t if pos else math.inf
    return wide


@_leaf
def _more_terms(i, nb, kstart, kids, slot, rh, bb):
    """Node i's internal children after the first: their terms of its bound into ``bb``."""
    for q in range(kstart[i] + 1, kstart[i + 1]):
        c = slot[kids[q]]
        for j in range(nb):
            bb[j] += rh[c, j]


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
    # Per node: re, im, |K|, 1/|K| (a lever's) and ρ (or its parent's term) over a block
    # of ω, and a row of zero terms (of a node with no internal child); per block: the
    # sums and ω, 1/ω.  Allocated once for all designs.
    work = np.empty((5, n_slots + 1, BLOCK))
    work[4, n_slots] = 0.0
    vec = np.empty((6, BLOCK))
    # Each node's parent, and how its term of its parent's bound is formed
    # (:func:`_parent_term`): 0 none (a lever's child, the root).
    par = np.zeros(M, np.int64)
    mode = np.zeros(M, np.int64)
    for i in range(M):
        for q in range(kstart[i], kstart[i + 1]):
            c = kids[q]
            par[c] = i
            if kind[i] < 2:
                mode[c] = 1 + (kind[i] == 1) + (kind[c] == 1)
    for d in range(K.shape[0]):
        dw = d if omega.shape[0] > 1 else 0
        rd = d if want_error else 0
        _evaluate_design(omega[dw], kind, cplx, c_real[d], c_inv[d], c_om[d], e_real[d],
                         e_inv[d], e_om[d], mu[d], kstart, kids, ratio[d], slot, want_error,
                         K[d], rho_out[rd], M, work, vec, par, mode, n_slots)


@jit_inline     # its one site: compiled apart, LLVM optimised and emitted its code twice
def _evaluate_design(omega, kind, cplx, c_real, c_inv, c_om, e_real, e_inv, e_om, mu,
                     kstart, kids, ratio, slot, want_error, K, rho_out, M, work, vec, par,
                     mode, zero):
    """One design of :func:`evaluate_plan`: its rows of the plan, its row of K."""
    n = omega.shape[0]
    B = BLOCK
    re, im, mg, ig, rh = work[0], work[1], work[2], work[3], work[4]
    ai, cr, ci, bb, iw, w = vec[0], vec[1], vec[2], vec[3], vec[4], vec[5]
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
                _reflect(s, slot[cn], kind[cn], ratio[i], nb, want_error, mode[i], mu[par[i]],
                         re, im, mg, ig, rh)
                continue
            series = k != 1           # 0 series, 3 a single leaf
            # Leaf terms and imaginary children (numpy's "imag"), complex
            # children (numpy's "cplx"): each starts with its first term.
            has_c = False
            first = slot[kids[kstart[i]]] if kstart[i + 1] > kstart[i] else zero
            has_i = _leaf_terms(nb, c_inv[i], c_om[i], e_inv[i], e_om[i], want_error, w, iw,
                                ai, bb, rh, first)
            has_i, has_c = _children(i, nb, series, kstart, kids, slot, cplx, re, im, ai, cr,
                                     ci, has_i, has_c)
            if want_error:
                _more_terms(i, nb, kstart, kids, slot, rh, bb)
            has_c, has_i, with_real = _merge(nb, c_real[i], has_c, has_i, cr, ci, ai)
            if want_error:
                _store_with_error(s, nb, series, has_c, mode[i], mu[par[i]], with_real,
                                  e_real[i] if with_real else 0.0, re, im, mg, rh, cr, ci, ai,
                                  bb)
            else:
                _store(s, nb, series, has_c, re, im, cr, ci, ai)
        top = slot[M - 1]
        for j in range(nb):
            K[j0 + j] = complex(re[top, j], im[top, j])
        if want_error:
            for j in range(nb):
                h = _triple(kind[M - 1], mg[top, j], ig[top, j], rh[top, j])[2]
                r = _through_reciprocal(h)
                rho_out[j0 + j] = math.inf if math.isnan(r) else r
