"""Compiled evaluation of a series–parallel plan (see :func:`mechcirc.reduction.plan`).

One loop over ω, and inside it one pass over the plan's nodes in postorder,
with K and the running error bound of each node kept in scalars: no
temporary arrays, and the bound costs a few flops per node in the same pass.
It computes exactly what :func:`mechcirc.reduction.evaluate`'s numpy path
computes, operation for operation and in the same order (the leaf laws enter
only as the plan's coefficients, built from :func:`mechcirc.circuit.law_terms`;
a lever node divides by its ratio twice, :meth:`mechcirc.circuit.Lever.reflect`).

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
            if cc:          # (selects: see _children_with_error)
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


@_leaf
def _children_with_error(i, nb, series, m_u, kstart, kids, slot, cplx, re, im, mg, ig, rh,
                         ai, cr, ci, bb, has_i, has_c, have_b):
    """:func:`_children` and, in the same loop, each child's term of the error
    bound: |tᵢ|(ρᵢ + m·u) in series, |1/Kᵢ|(ρᵢ/(1 − ρᵢ) + 4u + m·u) in parallel."""
    for q in range(kstart[i], kstart[i + 1]):
        cn = kids[q]
        c = slot[cn]
        cc = cplx[cn]
        first_c = cc and not has_c
        first_i = not cc and not has_i
        for j in range(nb):
            if series:
                tr = re[c, j]
                ti = im[c, j]
                t = (rh[c, j] + m_u) * mg[c, j]
            else:
                if cc:
                    tr, ti = _recip(re[c, j], im[c, j])
                else:
                    tr = 0.0
                    ti = -1.0 / im[c, j]
                t = (_through_reciprocal(rh[c, j]) + (_U_RECIP + m_u)) * ig[c, j]
            # The sums read before they are written and the first term a select: as
            # branches, LLVM stored with a mask and read the same address back with one,
            # which does not forward (a stall per point, a third of this loop's time).
            if cc:
                sr = cr[j]
                si = ci[j]
                cr[j] = tr if first_c else sr + tr
                ci[j] = ti if first_c else si + ti
            else:
                si = ai[j]
                ai[j] = ti if first_i else si + ti
            bb[j] = bb[j] + t if have_b else t
        have_b = True
        if cc:
            has_c = True
        else:
            has_i = True
    return has_i, has_c


#: Points per block: every node is evaluated over a block of ω at once, so the
#: iterations of the inner loop are independent (a ladder's nodes form one long
#: chain of divisions; node by node at one ω the loop would wait on each).  A sweep of
#: 401 points is one block: each node's helper calls and loop set-ups cost per block
#: (512 against 128: K 0.58–0.89x, K + bound 0.69–0.91x at 401 points, 0.68–0.89x and
#: 0.77–0.93x at 4001; 1024 no faster than 512).
BLOCK = 512


@_leaf
def _reflect(s, c, r, nb, want_error, re, im, mg, ig, rh):
    """A lever node: its child's value (slot ``c``) reflected by the ratio ``r``."""
    for j in range(nb):
        re[s, j] = re[c, j] / r / r
        im[s, j] = im[c, j] / r / r
    if want_error:
        for j in range(nb):
            mg[s, j] = mg[c, j] / r / r
            ig[s, j] = ig[c, j] * r * r
            rh[s, j] = rh[c, j] + 2 * _U


@_leaf
def _leaf_terms(nb, a_inv, a_om, b_inv, b_om, want_error, w, iw, ai, bb):
    """A node's leaf terms a_inv/ω + a_om·ω into ``ai`` (and their error terms into
    ``bb``); True if there is one."""
    if a_inv != 0.0:
        for j in range(nb):
            ai[j] = iw[j] * a_inv
        if want_error:
            for j in range(nb):
                bb[j] = b_inv * iw[j]
    if a_om != 0.0:
        if a_inv != 0.0:
            for j in range(nb):
                ai[j] += w[j] * a_om
        else:
            for j in range(nb):
                ai[j] = w[j] * a_om
        if want_error:
            if a_inv != 0.0:
                for j in range(nb):
                    bb[j] += b_om * w[j]
            else:
                for j in range(nb):
                    bb[j] = b_om * w[j]
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
def _store_with_error(s, leaf, nb, series, has_c, have_b, with_real, extra, re, im, mg, ig,
                      rh, cr, ci, ai, bb):
    """:func:`_store` with the node's magnitude, its reciprocal and its error bound ρ.

    |S| is √(a² + b²) in the loop over the block, without a branch (a branch to
    hypot there cost about as much as the rest of the bound: 1.6–1.8x K on ladders
    against 1.4–1.5x with this second pass); a second pass redoes, with hypot, the points
    where the larger part is outside [``_ABS_LO``, ``_ABS_HI``] (where a square could
    overflow or underflow), if the first pass counted any.  The same numbers as one
    pass that branches.  One loop per case (:func:`_store_case`)."""
    if not has_c:
        wide = _store_case(series, False, s, leaf, nb, have_b, with_real, extra, re, im, mg,
                           ig, rh, cr, ci, ai, bb)
    elif series:
        wide = _store_case(True, True, s, leaf, nb, have_b, with_real, extra, re, im, mg, ig,
                           rh, cr, ci, ai, bb)
    else:
        wide = _store_case(False, True, s, leaf, nb, have_b, with_real, extra, re, im, mg,
                           ig, rh, cr, ci, ai, bb)
    if wide:
        for j in range(nb):
            big = max(abs(cr[j]), abs(ci[j]))
            if not (_ABS_LO < big < _ABS_HI):
                b = bb[j] if have_b else 0.0
                if with_real:
                    b += extra
                mg[s, j], ig[s, j], rh[s, j] = _node_bound(leaf, series, b,
                                                           math.hypot(cr[j], ci[j]))


@jit_inline     # its sites pass series and has_c as constants: a loop without their branches
def _store_case(series, has_c, s, leaf, nb, have_b, with_real, extra, re, im, mg, ig, rh,
                cr, ci, ai, bb):
    """The first pass of :func:`_store_with_error`; returns the number of wide points."""
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
        mg[s, j], ig[s, j], rh[s, j] = _node_bound(leaf, series, b, mag)
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
    work = np.empty((5, n_slots, BLOCK))
    vec = np.empty((6, BLOCK))
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
                _reflect(s, slot[kids[kstart[i]]], ratio[i], nb, want_error, re, im, mg, ig, rh)
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
                has_i, has_c = _children_with_error(
                    i, nb, series, m_u, kstart, kids, slot, cplx, re, im, mg, ig, rh,
                    ai, cr, ci, bb, has_i, has_c, have_b)
                have_b = have_b or kstart[i + 1] > kstart[i]
            else:
                has_i, has_c = _children(i, nb, series, kstart, kids, slot, cplx, re, im,
                                         ai, cr, ci, has_i, has_c)
            has_c, has_i, with_real = _merge(nb, c_real[i], has_c, has_i, cr, ci, ai)
            if want_error:
                _store_with_error(s, k == 3, nb, series, has_c, have_b, with_real,
                                  e_real[i] if with_real else 0.0, re, im, mg, ig, rh, cr, ci,
                                  ai, bb)
            else:
                _store(s, nb, series, has_c, re, im, cr, ci, ai)
        top = slot[M - 1]
        for j in range(nb):
            K[j0 + j] = complex(re[top, j], im[top, j])
        if want_error:
            for j in range(nb):
                r = _through_reciprocal(rh[top, j])
                rho_out[j0 + j] = math.inf if math.isnan(r) else r
