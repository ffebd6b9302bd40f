"""Compiled evaluation of a series–parallel plan (see :func:`mechcirc.reduction.plan`).

One loop over ω, and inside it one pass over the plan's nodes in postorder,
with K and the running error bound of each node kept in scalars: no
temporary arrays, and the bound costs a few flops per node in the same pass.
It computes K exactly as :func:`mechcirc.reduction.evaluate`'s numpy path
does, operation for operation and in the same order (the leaf laws enter
only as the plan's coefficients, built from :func:`mechcirc.circuit.law_terms`;
a lever node divides by its ratio twice, :meth:`mechcirc.circuit.Lever.reflect`),
and the same error bound with fewer divisions, so rounded otherwise (within 1e-13
of the numpy path's: :func:`_children_bound`).

Compiled with numba when it is installed (:mod:`mechcirc._jit`); numba is
imported only when the first sweep asks for this module.  Without numba the
reduction uses its numpy path instead of running this loop as Python.
"""

from __future__ import annotations

import math

import numpy as np

from ._jit import decorators, internal

# The helpers are compiled apart (inlined at numba's level into the plan's loop, the cold
# compile took 5.8 s instead of 4.1 s of CPU and the bound's loops ran up to 2.4x slower)
# and without numba's reference counting: an atomic increment and decrement of every array
# argument at every call, which waits for the divisions in flight (half of K's time on the
# 999-element ladder).  Each is called once per node and block of ω, not inlined by LLVM.
# Only evaluate_plan calls them: compiled for it without a kernel's CPython and C-callable
# wrappers (:func:`mechcirc._jit.internal`; 0.2 s less of the cold compile, docs/performance.md,
# "jit50").
HAVE_NUMBA, jit, jit_inline = decorators()
_leaf = internal(nrt=False)

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
#: :func:`_children_bound`) where that product lies in this range, else the two-division
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
def _children_bound(i, nb, series, m_u, kind, kstart, kids, slot, mg, ig, rh, bb, tv, have_b):
    """Each internal child's term of node i's error bound, added to ``bb``.

    A series or parallel child keeps its sum's |S| and E ≥ |Ŝ − S| (not ρ and 1/|K|: each
    costs a division).  Its term t = K (a series parent, K = S) or t = 1/K (a parallel one,
    K = 1/S) is bounded by

    - S itself (series in series): |t̂ − t| ≤ E, plus m·u·|S| for the parent's additions:
      E + m·u·|S|, no division;
    - 1/S (a series child in parallel, a parallel child in series): |1/Ŝ − 1/S| =
      |S − Ŝ|/(|Ŝ||S|) ≤ E/(|S|(|S| − E)) as |S| ≥ |Ŝ| − E, plus (4u + m·u)/|S| for the
      reciprocal's rounding and the parent's additions: one division,
      (E + (4u + m·u)(|S| − E)) / (|S|(|S| − E)), where before 1/|S| and ρ/(1 − ρ) were
      two (the same bound, (ρ/(1 − ρ) + 4u + m·u)/|S| with ρ = E/|S|, rounded otherwise);
    - 1/(1/S) and a lever's or a single leaf's K: from (|K|, 1/|K|, ρ) (:func:`_old_term`).

    Where |S|(|S| − E) is outside [``_P_LO``, ``_P_HI``] (E ≥ |S|, |S| 0 or ∞, a sum near
    the ends of the exponent range) a second pass takes :func:`_old_term`."""
    for q in range(kstart[i], kstart[i + 1]):
        cn = kids[q]
        c = slot[cn]
        ck = kind[cn]
        wide = 0
        if ck > 1 or (ck == 1 and not series):
            for j in range(nb):
                tv[j] = _old_term(series, ck, m_u, mg[c, j], ig[c, j], rh[c, j])
        else:
            direct = series and ck == 0
            cj = _U_RECIP + m_u
            for j in range(nb):         # (LLVM makes it two loops, on ``direct``)
                e = rh[c, j]
                a = mg[c, j]
                x = a - e
                p = a * x
                wide += not (_P_LO < p < _P_HI)
                if direct:
                    tv[j] = e + m_u * a
                else:
                    tv[j] = (e + cj * x) / p if p != 0.0 else 0.0    # (0: redone below)
        if wide:
            for j in range(nb):
                a = mg[c, j]
                if not (_P_LO < a * (a - rh[c, j]) < _P_HI):
                    tv[j] = _old_term(series, ck, m_u, a, ig[c, j], rh[c, j])
        for j in range(nb):
            bb[j] = bb[j] + tv[j] if have_b else tv[j]
        have_b = True


#: Points per block: every node is evaluated over a block of ω at once, so the
#: iterations of the inner loop are independent (a ladder's nodes form one long
#: chain of divisions; node by node at one ω the loop would wait on each).  A sweep of
#: 401 points is one block: each node's helper calls and loop set-ups cost per block
#: (512 against 128: K 0.58–0.89x, K + bound 0.69–0.91x at 401 points, 0.68–0.89x and
#: 0.77–0.93x at 4001; 1024 no faster than 512).
BLOCK = 512


@_leaf
def _reflect(s, c, ck, r, nb, want_error, re, im, mg, ig, rh):
    """A lever node: its child's value (slot ``c``, kind ``ck``) reflected by the ratio ``r``."""
    for j in range(nb):
        re[s, j] = re[c, j] / r / r
        im[s, j] = im[c, j] / r / r
    if want_error:
        for j in range(nb):
            m, g, h = _triple(ck, mg[c, j], ig[c, j], rh[c, j])
            mg[s, j] = m / r / r
            ig[s, j] = g * r * r
            rh[s, j] = h + 2 * _U


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
    """A node's value into slot ``s``: the sum (series), or its reciprocal (parallel).
    :func:`_store_case` without the bound (its ``mg``, ``rh`` and ``bb`` not read)."""
    if not has_c:
        _store_case(series, False, False, s, nb, False, False, 0.0, re, im, re, im, cr, ci, ai, ai)
    elif series:
        _store_case(True, True, False, s, nb, False, False, 0.0, re, im, re, im, cr, ci, ai, ai)
    else:
        _store_case(False, True, False, s, nb, False, False, 0.0, re, im, re, im, cr, ci, ai, ai)


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
def _store_with_error(s, nb, series, has_c, have_b, with_real, extra, re, im, mg, rh, cr, ci,
                      ai, bb):
    """:func:`_store` with its sum's magnitude |Ŝ| and the bound E of |Ŝ − S| (:func:`_triple`).

    |S| is √(a² + b²) in the loop over the block, without a branch (a branch to
    hypot there cost about as much as the rest of the bound: 1.6–1.8x K on ladders
    against 1.4–1.5x with this second pass); a second pass redoes, with hypot, the points
    where the larger part is outside [``_ABS_LO``, ``_ABS_HI``] (where a square could
    overflow or underflow), if the first pass counted any.  The same numbers as one
    pass that branches.  One loop per case (:func:`_store_case`)."""
    if not has_c:
        wide = _store_case(series, False, True, s, nb, have_b, with_real, extra, re, im, mg, rh,
                           cr, ci, ai, bb)
    elif series:
        wide = _store_case(True, True, True, s, nb, have_b, with_real, extra, re, im, mg, rh, cr,
                           ci, ai, bb)
    else:
        wide = _store_case(False, True, True, s, nb, have_b, with_real, extra, re, im, mg, rh, cr,
                           ci, ai, bb)
    if wide:
        for j in range(nb):
            if not (_ABS_LO < max(abs(cr[j]), abs(ci[j])) < _ABS_HI):
                mg[s, j] = math.hypot(cr[j], ci[j])


@jit_inline     # its sites pass series, has_c and bound as constants: loops without their branches
def _store_case(series, has_c, bound, s, nb, have_b, with_real, extra, re, im, mg, rh, cr, ci,
                ai, bb):
    """The first pass of :func:`_store_with_error` (``bound``), or :func:`_store`; returns the
    number of wide points."""
    wide = 0
    for j in range(nb):
        b = bb[j] if have_b else 0.0
        if with_real:
            b += extra
        if has_c:
            sr = cr[j]
            si = ci[j]
            mag = math.sqrt(sr * sr + si * si)
            wide += not (_ABS_LO < max(abs(sr), abs(si)) < _ABS_HI)
        else:
            sr = 0.0
            si = ai[j]
            mag = abs(si)
        if series:
            re[s, j] = sr
            im[s, j] = si
        elif has_c:
            re[s, j], im[s, j] = _recip(sr, si)
        else:
            re[s, j] = 0.0
            im[s, j] = -1.0 / si
        if bound:
            mg[s, j] = mag
            rh[s, j] = b
    return wide


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
    work, vec = np.empty((5, n_slots, BLOCK)), np.empty((7, BLOCK))
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
            has_i, has_c = _children(i, nb, series, kstart, kids, slot, cplx, re, im, ai, cr,
                                     ci, has_i, has_c)
            if want_error:
                _children_bound(i, nb, series, m_u, kind, kstart, kids, slot, mg, ig, rh, bb,
                                tv, have_b)
                have_b = have_b or kstart[i + 1] > kstart[i]
            has_c, has_i, with_real = _merge(nb, c_real[i], has_c, has_i, cr, ci, ai)
            if want_error:
                _store_with_error(s, nb, series, has_c, have_b, with_real,
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
