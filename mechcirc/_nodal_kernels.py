"""Compiled kernels of the nodal solve: the residual b − A(ω) x in double-double, the
banded LU with its first-step bound, and the error sensitivities.

The residual does the same arithmetic (the double-double functions of
:mod:`mechcirc._dd`, the one copy, here compiled), operation for operation
and in the same order, as the vectorised numpy code of
:meth:`mechcirc._nodal_residual.Pattern.residual` (real ω):
each term (an element's ±value·(x_i − x_j), a lever stamp's value·x_c) is
formed exactly (TwoSum, TwoProduct), the terms of one (row, kind) bucket are
added by cascaded TwoSum in ascending term order, and the sums are combined
as (A x)_r = S_c + S_l + j(ω S_m − S_k/ω) in double-double.  Compiled by
numba when the ``fast`` extra is installed (see :mod:`mechcirc._jit`); the
numpy code is used otherwise, so this module is imported only when numba is.
"""

from __future__ import annotations

import numpy as np

from . import _dd, _nodal_steps
from ._jit import decorators, load

HAVE_NUMBA, _jit, _jit_inline = decorators(bool(globals().get("_FORCE_PYTHON")))

if HAVE_NUMBA:        # the one double-double source (:mod:`mechcirc._dd`), compiled
    _dd = load("mechcirc._dd", _COMPILE=True)
    # and the refinement's arithmetic between the kernels, point by point
    _nodal_steps = load("mechcirc._nodal_steps", _COMPILE=True)
_estimate_point, _bound_point = _nodal_steps.estimate_point, _nodal_steps.bound_point
_split, _two_sum, _two_prod = _dd.split, _dd.two_sum, _dd.two_prod
_dd_add, _dd_mul_d, _dd_div_d = _dd.dd_add, _dd.dd_mul_d, _dd.dd_div_d
_dd_difference = _dd.dd_difference


#: ω handled side by side by :func:`residual` and :func:`band_solve_perm`, innermost (the
#: loops over them vectorise).
SOLVE_BLOCK = 16


@_jit_inline
def _add(acc, bk, b, th_r, tl_r, th_i, tl_i):
    """Add the term (th_r + tl_r) + j(th_i + tl_i) to bucket ``bk`` at ω ``b`` by TwoSum."""
    a, ea = _two_sum(acc[bk, 0, b], th_r)
    acc[bk, 0, b] = a
    acc[bk, 1, b] += ea + tl_r
    a, ea = _two_sum(acc[bk, 2, b], th_i)
    acc[bk, 2, b] = a
    acc[bk, 3, b] += ea + tl_i


@_jit_inline
def _element_term(v, vh, vl, ar, ai, br, bi, alr, ali, blr, bli, has_lo):
    """v·(a − b) in double-double, (re_hi, re_lo, im_hi, im_lo): a = (ar + j ai) +
    (alr + j ali) and b likewise, the difference by TwoSum, the product by TwoProduct."""
    dh_r, dl_r = _two_sum(ar, -br)
    dh_i, dl_i = _two_sum(ai, -bi)
    if has_lo:
        # Renormalised: the low parts of x_i ≈ x_j are ~u|x|, not ~u|d|.
        dh_r, dl_r = _two_sum(dh_r, dl_r + (alr - blr))
        dh_i, dl_i = _two_sum(dh_i, dl_i + (ali - bli))
    th_r, tl_r = _two_prod(v, vh, vl, dh_r)
    th_i, tl_i = _two_prod(v, vh, vl, dh_i)
    return th_r, tl_r + v * dl_r, th_i, tl_i + v * dl_i


@_jit_inline
def _row_residual(acc, r, b, w, wh, wl, rhs):
    """b − (A x)_r at ω ``b`` rounded to (re + (0·im − 0), 0 + (0 + im)), numpy's
    ``re + 1j * im``, from row r's sums by kind in ``acc``: (A x)_r = S_c + S_l +
    j(ω S_m − S_k/ω) in double-double."""
    m_ = 4 * r
    wm_rh, wm_rl = _dd_mul_d(acc[m_, 0, b], acc[m_, 1, b], w, wh, wl)
    wm_ih, wm_il = _dd_mul_d(acc[m_, 2, b], acc[m_, 3, b], w, wh, wl)
    kw_rh, kw_rl = _dd_div_d(acc[m_ + 1, 0, b], acc[m_ + 1, 1, b], w, wh, wl)
    kw_ih, kw_il = _dd_div_d(acc[m_ + 1, 2, b], acc[m_ + 1, 3, b], w, wh, wl)
    su_rh, su_rl = _dd_add(wm_rh, wm_rl, -kw_rh, -kw_rl)
    su_ih, su_il = _dd_add(wm_ih, wm_il, -kw_ih, -kw_il)
    g_rh, g_rl = _dd_add(acc[m_ + 2, 0, b], acc[m_ + 2, 1, b], acc[m_ + 3, 0, b],
                         acc[m_ + 3, 1, b])
    g_ih, g_il = _dd_add(acc[m_ + 2, 2, b], acc[m_ + 2, 3, b], acc[m_ + 3, 2, b],
                         acc[m_ + 3, 3, b])
    ax_rh, ax_rl = _dd_add(g_rh, g_rl, -su_ih, -su_il)
    ax_ih, ax_il = _dd_add(g_ih, g_il, su_rh, su_rl)
    rr_h, rr_l = _dd_add(rhs, 0.0, -ax_rh, -ax_rl)
    ri_h, ri_l = -ax_ih, -ax_il
    if not np.isfinite(rr_l) and np.isfinite(rr_h):
        rr_l = 0.0
    if not np.isfinite(ri_l) and np.isfinite(ri_h):
        ri_l = 0.0
    im = ri_h + ri_l
    return (rr_h + rr_l) + (0.0 * im - 0.0), 0.0 + (0.0 + im)


@_jit_inline
def _at(x, k, i, n):
    """x[k, i] (x real or complex), and +0.0 for the reference (i = n: no such column)."""
    return x[k, i] if i < n else 0.0


@_jit_inline
def _block_in(omega, xr, xi, xlr, xli, k0, m, W, X):
    """ω ``k0`` … ``k0 + m − 1`` into ``W`` (ω, split) and x's parts into ``X``, ω innermost."""
    for b in range(m):
        W[0, b] = omega[k0 + b]
        W[1, b], W[2, b] = _split(W[0, b])
        for i in range(X.shape[1] - 1):
            X[0, i, b], X[1, i, b] = xr[k0 + b, i], xi[k0 + b, i]
            X[2, i, b], X[3, i, b] = xlr[k0 + b, i], xli[k0 + b, i]


@_jit_inline
def _bucket_plan(b_i, b_j, b_s, n_buckets):
    """(start, code): the terms of bucket k at ``code[start[k]:start[k + 1]]`` in the order
    they are added — the + terms by element (code e), then the − terms (n_e + e), then
    the lever stamps (2·n_e + s) — by a stable counting sort (bucket n_buckets, the
    reference's row, dropped)."""
    n_e = b_i.size
    start = np.zeros(n_buckets + 3, dtype=np.int64)     # (the last: the dropped, counted)
    for src in (b_i, b_j, b_s):
        for t in range(src.size):
            start[src[t] + 2] += 1
    for k in range(2, n_buckets + 2):
        start[k] += start[k - 1]
    code = np.empty(start[n_buckets + 1], dtype=np.int64)
    for base, src in ((0, b_i), (n_e, b_j), (2 * n_e, b_s)):
        for t in range(src.size):
            bk = src[t]
            if bk < n_buckets:
                code[start[bk + 1]] = base + t
                start[bk + 1] += 1
    return start, code


@_jit_inline
def _row_sums(acc, code, start, bk, T, X, has_lo, s_col, SV):
    """The four sums by kind of the row of buckets ``bk`` … ``bk + 3`` into ``acc`` (re_hi,
    re_lo, im_hi, im_lo by kind) from their terms (:func:`_bucket_plan`): +T[e], −T[e]
    (code n_e + e) and lever stamps (2·n_e + s, the block's values and their halves in
    ``SV``), each added by TwoSum in order."""
    n_e, nb = T.shape[0], SOLVE_BLOCK
    acc[:] = 0.0
    for kind in range(4):
        for t in range(start[bk + kind], start[bk + kind + 1]):
            e = code[t]
            if e < n_e:
                for b in range(nb):
                    _add(acc, kind, b, T[e, 0, b], T[e, 1, b], T[e, 2, b], T[e, 3, b])
            elif e < 2 * n_e:                   # −y·(x_i − x_j) into the second row
                e -= n_e
                for b in range(nb):
                    _add(acc, kind, b, -T[e, 0, b], -T[e, 1, b], -T[e, 2, b], -T[e, 3, b])
            else:
                s = e - 2 * n_e
                c = s_col[s]
                for b in range(nb):
                    v, vh, vl = SV[0, s, b], SV[1, s, b], SV[2, s, b]
                    th_r, tl_r = _two_prod(v, vh, vl, X[0, c, b])
                    th_i, tl_i = _two_prod(v, vh, vl, X[1, c, b])
                    if has_lo:
                        tl_r = tl_r + v * X[2, c, b]
                        tl_i = tl_i + v * X[3, c, b]
                    _add(acc, kind, b, th_r, tl_r, th_i, tl_i)


@_jit_inline
def _block_values(val, vh, vl, k0, n_w, V):
    """The values (and their halves) of ω ``k0`` … of a block into ``V`` (3, n, block): each
    ω's own row of the (n_ω, n) tables, or the one row of (1, n) ones (written once, at
    the first block)."""
    own = val.shape[0] > 1
    if own or k0 == 0:
        for e in range(val.shape[1]):
            for b in range(V.shape[2]):
                q = min(k0 + b, n_w - 1) if own else 0
                V[0, e, b], V[1, e, b], V[2, e, b] = val[q, e], vh[q, e], vl[q, e]


@_jit
def residual(omega, xr, xi, xlr, xli, has_lo, rhs, b_i, b_j, b_s,
             e_i, e_j, e_val, e_vh, e_vl, s_col, s_val, s_vh, s_vl, out):
    """b − A(ω) x into ``out`` (complex, shape (n_ω, n)); x = (xr + j xi) + (xlr + j xli).

    ``x*`` (real, shape (n_ω, n), any strides: the parts of complex arrays) are
    copied :data:`SOLVE_BLOCK` ω at a time with ω innermost (``X``, the
    reference's row n kept at +0.0), and each ω's operations run for the block
    at once, so that the loops over ω vectorise.  ``b_i``, ``b_j``, ``b_s`` are
    the buckets 4·row + kind (kind: mass, spring, damper, lever) of +element e,
    −element e and lever stamp s (4·n: the reference's row, dropped).  Each
    bucket receives its terms in the numpy code's order — the + terms by
    element, then the − terms, then the lever stamps (:func:`_bucket_plan`) — and
    adds them by TwoSum into ``acc`` (re_hi, re_lo, im_hi, im_lo by kind), one row
    at a time: the terms y·(x_i − x_j) formed once for the block (``T``), each row's
    four sums then its residual formed from them.  Each residual, rounded to its real
    parts re and im, is stored as numpy forms ``re + 1j * im``, so a signed zero or a
    NaN comes out as the numpy code's.  ``e_val``, ``e_vh``, ``e_vl`` (an element's
    value·η split as vh + vl), and ``s_val``, ``s_vh``, ``s_vl`` (a lever stamp's value
    likewise) are (1, n) tables, every ω's, or (n_ω, n), each ω's own (stacked designs,
    :func:`mechcirc.batch._stacked_solve`).
    """
    n_w, n = out.shape
    n_e, nb = e_i.size, SOLVE_BLOCK
    start, code = _bucket_plan(b_i, b_j, b_s, 4 * n)
    X = np.zeros((4, n + 1, nb))
    T = np.empty((n_e, 4, nb))                  # +y·(x_i − x_j), formed once
    acc = np.empty((4, 4, nb))                  # one row's sums by kind
    W = np.ones((3, nb))                        # ω, split
    R = np.empty((2, nb))                     # one row's residuals
    V = np.empty((3, n_e, nb))                  # the block's element values, split
    SV = np.empty((3, s_col.size, nb))          # and its lever stamps' values
    for k0 in range(0, n_w, nb):
        m = min(nb, n_w - k0)                   # (past m, the last block's stale ω: unused)
        _block_in(omega, xr, xi, xlr, xli, k0, m, W, X)
        _block_values(e_val, e_vh, e_vl, k0, n_w, V)
        _block_values(s_val, s_vh, s_vl, k0, n_w, SV)
        for e in range(n_e):
            i, j = e_i[e], e_j[e]
            for b in range(nb):
                T[e, 0, b], T[e, 1, b], T[e, 2, b], T[e, 3, b] = _element_term(
                    V[0, e, b], V[1, e, b], V[2, e, b], X[0, i, b], X[1, i, b], X[0, j, b],
                    X[1, j, b], X[2, i, b], X[3, i, b], X[2, j, b], X[3, j, b], has_lo)
        for r in range(n):
            _row_sums(acc, code, start, 4 * r, T, X, has_lo, s_col, SV)
            for b in range(nb):
                R[0, b], R[1, b] = _row_residual(acc, 0, b, W[0, b], W[1, b], W[2, b], rhs[r])
            for b in range(m):
                out[k0 + b, r] = complex(R[0, b], R[1, b])


@_jit_inline
def _max_step(m, z):
    """max(m, |z|) as a running max of |z| takes it (NaN once one is): numba's |z| (a hypot)
    only where |re| + |im| is not below m (|z| ≤ |re| + |im|: elsewhere |z| < m)."""
    if not (abs(z.real) + abs(z.imag) < m):
        v = abs(z)
        if v > m or np.isnan(v):
            return v
    return m


@_jit
def estimate(xh, xl, d, prev, r, a, b, lo, first, est, rho):
    """:func:`mechcirc._nodal_steps.estimate_point` at each ω (rows of xh + xl, the
    correction ``d``, the one before it ``prev`` unless ``first``, the residual ``r``; the
    drive's ends ``a``, ``b``, n for the reference) into ``est`` and ``rho``:
    :func:`mechcirc.nodal._estimate`'s reductions by loops, the four of a row in one pass
    (each in its own order; their chains of dependent additions and comparisons overlap)."""
    n = xh.shape[1]
    for k in range(est.size):
        K = abs(_dd_difference(_at(xh, k, a, n), _at(xh, k, b, n), _at(xl, k, a, n),
                               _at(xl, k, b, n), lo))
        da, db = _at(d, k, a, n), _at(d, k, b, n)
        xr = 0j
        nx = nd = npv = 0.0
        for i in range(n):
            xr += xh[k, i] * r[k, i]
            nx = _max_step(nx, xh[k, i])
            nd = _max_step(nd, d[k, i])
            if not first:
                npv = _max_step(npv, prev[k, i])
        est[k], rho[k] = _estimate_point(nd, nx, nx if first else npv, K, abs(da - db),
                                         abs(da), abs(db), abs(xr), first)


@_jit
def update(s, d, xl, lo, r, rounding, first):
    """s + d = s' + e exactly, s' into ``s`` and e (xl + e where ``lo``) into ``r`` in place
    (complex: TwoSum of the real and the imaginary parts, as :func:`mechcirc._dd.two_sum`
    on complex arrays): :func:`mechcirc.nodal.refine_dd`'s step without numpy's
    temporaries, the residual ``r`` no longer needed but, where ``first``, for
    ``rounding`` = |s'|ᵀ|r| (|z| as |re| + |im|: :func:`step_bound`'s), formed here first."""
    for k in range(s.shape[0]):
        acc = 0.0
        for i in range(s.shape[1]):
            hr, lr = _two_sum(s[k, i].real, d[k, i].real)
            hi, li = _two_sum(s[k, i].imag, d[k, i].imag)
            if lo:
                lr, li = xl[k, i].real + lr, xl[k, i].imag + li
            s[k, i] = complex(hr, hi)
            if first:
                acc += _l1(s[k, i]) * _l1(r[k, i])
            r[k, i] = complex(lr, li)
        rounding[k] = acc


@_jit
def step_bound(rows, omega, xh, xl, d, rounding, lu, a, b, e_i, e_j, e_abs, s_row, s_col,
               s_abs, m, out):
    """:func:`mechcirc._nodal_steps.bound_point` at the ω ``rows[q]`` into ``out[q]``: the
    sums of :func:`mechcirc.nodal.first_step_bound` by loops (|z| as |re| + |im|; index n,
    the reference, reads 0: ``a``, ``b`` too), |x|ᵀ|r̂| given (:func:`update`'s), each
    array but ``lu`` (one per q) read at row ``rows[q]``."""
    n = xh.shape[1]
    for q in range(rows.size):
        k = rows[q]
        by_c = by_m = by_k = lever = 0.0
        for e in range(e_i.size):
            i, j = e_i[e], e_j[e]
            t = (_l1(_at(xh, k, i, n)) + _l1(_at(xh, k, j, n))) * \
                (_l1(_at(d, k, i, n)) + _l1(_at(d, k, j, n)))
            by_c += t * e_abs[e, 0]
            by_m += t * e_abs[e, 1]
            by_k += t * e_abs[e, 2]
        for s in range(s_row.size):
            lever += _l1(_at(xh, k, s_row[s], n)) * _l1(_at(d, k, s_col[s], n)) * s_abs[s]
        K = abs(_dd_difference(_at(xh, k, a, n), _at(xh, k, b, n), _at(xl, k, a, n),
                               _at(xl, k, b, n), True))
        out[q] = _bound_point(lu[q], rounding[k], by_c, by_m, by_k, lever, abs(omega[k]), K, n, m)


@_jit_inline
def _cdiv(ar, ai, br, bi, live):
    """(ar + j ai)/(br + j bi) with the bits of numba's (CPython's) complex division, which
    branches on the larger part of the divisor; here both cases are formed and one is
    selected, so that a loop over ω vectorises (the divisor finite and nonzero; where
    not ``live``, 1).  Case |br| ≥ |bi|: ρ = bi/br, δ = br + bi·ρ, ((ar + ai·ρ)/δ,
    (ai − ar·ρ)/δ); otherwise ρ = br/bi, δ = br·ρ + bi, ((ar·ρ + ai)/δ, (ai·ρ − ar)/δ).
    """
    s = abs(br) < abs(bi)
    p = bi if s else br
    q = br if s else bi
    p = p if live else 1.0
    ratio = q / p
    denom = p + q * ratio
    re = ((ai if s else ar) + (ar if s else ai) * ratio) / denom
    return re, ((ai * ratio if s else ai) - (ar if s else ar * ratio)) / denom


@_jit_inline
def _band_lu(re, im, kl, ipiv, ok, best, jp, rr, ri):
    """LU with partial pivoting of banded matrices in place (LAPACK's zgbtf2), ω innermost.

    ``re[c, 2·kl + i − c, k]`` + j ``im[…]`` holds A_k[i, c] (kl = ku; the first kl of
    the 3·kl + 1 places of a column are room for the fill).  Each ω's operations are
    those of the LU one ω at a time (the pivot the largest |re| + |im|, as LAPACK's
    izamax; the multipliers an entry times the pivot's reciprocal; complex products as
    numba's), for all ω of a column at once with selects instead of branches, so that
    the loops over ω vectorise: rows swapped and columns updated up to j + 2·kl, past an
    ω's own fill (zeros: swapped with zeros, a zero multiplier's update not applied).
    ``ok[k]`` cleared where a pivot is 0 or not finite (its factors then unused).
    """
    n, _, nw = re.shape
    kv = 2 * kl
    for j in range(n):                  # (indexed in place: a view costs a reference count)
        km = min(kl, n - 1 - j)
        ju = min(j + kv, n - 1)
        best[:] = -1.0
        jp[:] = 0
        for t in range(km + 1):
            for k in range(nw):
                m = abs(re[j, kv + t, k]) + abs(im[j, kv + t, k])
                g = m > best[k]
                best[k] = m if g else best[k]
                jp[k] = t if g else jp[k]
        for k in range(nw):
            ipiv[j, k] = j + jp[k]
            ok[k] = ok[k] and best[k] != 0.0 and np.isfinite(best[k])
        for c in range(j, ju + 1):
            d = kv + j - c
            for t in range(1, km + 1):
                for k in range(nw):
                    sw = jp[k] == t
                    xr, yr, xi, yi = re[c, d, k], re[c, d + t, k], im[c, d, k], im[c, d + t, k]
                    re[c, d, k], re[c, d + t, k] = (yr, xr) if sw else (xr, yr)
                    im[c, d, k], im[c, d + t, k] = (yi, xi) if sw else (xi, yi)
        if km > 0:
            for k in range(nw):
                rr[k], ri[k] = _cdiv(1.0, 0.0, re[j, kv, k], im[j, kv, k], ok[k])
            for t in range(1, km + 1):
                for k in range(nw):
                    a, b = re[j, kv + t, k], im[j, kv + t, k]
                    re[j, kv + t, k] = a * rr[k] - b * ri[k]
                    im[j, kv + t, k] = a * ri[k] + b * rr[k]
            for c in range(j + 1, ju + 1):
                d = kv + j - c
                for t in range(1, km + 1):
                    for k in range(nw):
                        ur, ui = re[c, d, k], im[c, d, k]
                        lr, li = re[j, kv + t, k], im[j, kv + t, k]
                        nz = ur != 0.0 or ui != 0.0
                        a = re[c, d + t, k] - (lr * ur - li * ui)
                        b = im[c, d + t, k] - (lr * ui + li * ur)
                        re[c, d + t, k] = a if nz else re[c, d + t, k]
                        im[c, d + t, k] = b if nz else im[c, d + t, k]


@_jit
def band_assemble_factor(dc, m, kk, omega, dest_c, dest_r, kl, F, ipiv, ok):
    """Form A(ω_k) = dc + j(ω_k m − kk/ω_k) (:func:`mechcirc.nodal.combine`) and factorise
    it (:func:`_band_lu`), all ω of the call together: A_k[i, c] at ``F[:, c, 2·kl + i − c,
    k]`` (real and imaginary parts, shape (2, n, 3·kl + 1, n_ω)), its pivots ``ipiv[:, k]``.

    ``ok[k]`` is cleared where an entry is not finite or A is singular.
    """
    nw = omega.size
    re, im = F[0], F[1]
    re[:] = 0.0
    im[:] = 0.0
    ok[:] = True
    for t in range(dc.size):
        zr, zi = re[dest_c[t], dest_r[t]], im[dest_c[t], dest_r[t]]
        for k in range(nw):
            zr[k] = dc[t]
            zi[k] = omega[k] * m[t] - kk[t] / omega[k]
    for t in range(dc.size):                # (a loop of its own: the one above vectorises)
        zr, zi = re[dest_c[t], dest_r[t]], im[dest_c[t], dest_r[t]]
        for k in range(nw):
            ok[k] &= np.isfinite(zr[k]) & np.isfinite(zi[k])
    _band_lu(re, im, kl, ipiv, ok, np.empty(nw), np.empty(nw, dtype=np.int64), np.empty(nw),
             np.empty(nw))


@_jit_inline
def _consecutive(w):
    """Whether the ω ``w`` are consecutive (w[b] = w[0] + b)."""
    step = True
    for b in range(1, w.size):
        step = step and w[b] - w[b - 1] == 1
    return step


@_jit_inline
def _gather_room(F, rows):
    """Scratch (G, P) for :func:`_block_factors`: room for a block's factors where a block
    of ``rows`` is not consecutive, none otherwise (the usual case: nothing to allocate).
    (In the solve the copy costs no more than reading through ``rows``: its loops then
    vectorise.  Every other ω of the 999-element ladder's solves: 5.6–6.1 ms, 5.4–6.8 so.)"""
    need = 0
    for k0 in range(0, rows.size, SOLVE_BLOCK):
        need = need if _consecutive(rows[k0:k0 + SOLVE_BLOCK]) else F.shape[1]
    return (np.empty((2, need, F.shape[2], SOLVE_BLOCK)),
            np.empty((need, SOLVE_BLOCK), dtype=np.int64))


@_jit_inline
def _block_factors(fr, fi, ipiv, w, G, P):
    """The factors of the ω ``w`` (one block): (real parts, imaginary parts, pivots, the
    first ω's place) read in place when the ω are consecutive (the usual case), else
    copied into the scratch ``G``, ``P`` (gathered once, not at every use)."""
    if _consecutive(w):
        return fr, fi, ipiv, np.uint64(w[0])
    nb = w.size
    for j in range(fr.shape[0]):
        for b in range(nb):
            P[j, b] = ipiv[j, w[b]]
        for d in range(fr.shape[1]):
            for b in range(nb):
                G[0, j, d, b], G[1, j, d, b] = fr[j, d, w[b]], fi[j, d, w[b]]
    return G[0], G[1], P, np.uint64(0)


@_jit
def band_solve_perm(F, kl, ipiv, rows, p, r, out):
    """out[k, p] = A_p⁻¹ r[k, p] with the factors ``F[..., rows[k]]`` of :func:`_band_lu` (A's
    rows and columns in the order ``p``): each ω's operations in LAPACK's zgbtrs order
    (complex products and quotients as numba forms them), for :data:`SOLVE_BLOCK` ω at a
    time, ω innermost and the row swaps by selects (as :func:`_band_lu`)."""
    G, P = _gather_room(F, rows)
    _solve_blocks(F, kl, ipiv, rows, p, r, out, np.empty((2, F.shape[1], SOLVE_BLOCK)), G, P)


@_jit
def _solve_blocks(F, kl, ipiv, rows, p, r, out, x, G, P):
    """:func:`band_solve_perm` with its scratch ``x``, ``G``, ``P`` given: arrays allocated in
    the kernel itself keep LLVM from vectorising its loops over ω (seen in the assembly)."""
    n = F.shape[1]
    kv = 2 * kl
    xr, xi = x[0], x[1]
    for k0 in range(0, rows.size, SOLVE_BLOCK):
        nb = min(SOLVE_BLOCK, rows.size - k0)
        fr, fi, piv, q = _block_factors(F[0], F[1], ipiv, rows[k0:k0 + nb], G, P)
        for i in range(n):
            for b in range(nb):
                xr[i, b], xi[i, b] = r[k0 + b, p[i]].real, r[k0 + b, p[i]].imag
        for j in range(n - 1):                 # L, with the row swaps
            km = min(kl, n - 1 - j)
            for t in range(1, km + 1):
                for b in range(nb):
                    sw = piv[j, q + np.uint64(b)] - j == t
                    xr[j, b], xr[j + t, b] = (xr[j + t, b], xr[j, b]) if sw else (xr[j, b], xr[j + t, b])
                    xi[j, b], xi[j + t, b] = (xi[j + t, b], xi[j, b]) if sw else (xi[j, b], xi[j + t, b])
            for t in range(1, km + 1):
                for b in range(nb):
                    lr, li, ar, ai = fr[j, kv + t, q + np.uint64(b)], fi[j, kv + t, q + np.uint64(b)], xr[j, b], xi[j, b]
                    xr[j + t, b] -= lr * ar - li * ai
                    xi[j + t, b] -= lr * ai + li * ar
        for j in range(n - 1, -1, -1):         # U, by columns
            for b in range(nb):
                xr[j, b], xi[j, b] = _cdiv(xr[j, b], xi[j, b], fr[j, kv, q + np.uint64(b)], fi[j, kv, q + np.uint64(b)],
                                           True)
            for i in range(max(0, j - kv), j):
                for b in range(nb):
                    ur, ui = fr[j, kv + i - j, q + np.uint64(b)], fi[j, kv + i - j, q + np.uint64(b)]
                    xr[i, b] -= ur * xr[j, b] - ui * xi[j, b]
                    xi[i, b] -= ur * xi[j, b] + ui * xr[j, b]
        for i in range(n):
            for b in range(nb):
                out[k0 + b, p[i]] = complex(xr[i, b], xi[i, b])


@_jit_inline
def _l1(z):
    """|re| + |im| (≥ |z|)."""
    return abs(z.real) + abs(z.imag)


@_jit
def band_bound(F, kl, ipiv, rows, p, x, d, out):
    """out[k] = |x|ᵀP̃|L||U||d| at the ω ``rows[k]``, from the factors ``F[..., rows[k]]`` of
    :func:`_band_lu` and the rows ``x[rows[k]]``, ``d[rows[k]]`` (|z| as |re| + |im|; x and
    d in A's order, the factors in the order ``p``): what
    :func:`mechcirc._nodal_solvers.band_bound_batch` forms from numpy's factors, for
    :data:`SOLVE_BLOCK` ω at a time, ω innermost (each ω's sums in the same order).  The
    factors, x and d are read through ``rows`` where they are: each once (a copy of a
    block's, as the solve makes where its ω are not consecutive, cost more than it saved;
    copies of x's and d's rows stacked (ω, n) arrays on the factors, see
    :func:`mechcirc.nodal.refine_dd`)."""
    n = F.shape[1]
    kv = 2 * kl
    fr, fi = F[0], F[1]
    u = np.empty((n, SOLVE_BLOCK))
    ad = np.empty((n, SOLVE_BLOCK))         # |d| in the order p
    acc = np.empty(SOLVE_BLOCK)
    for k0 in range(0, rows.size, SOLVE_BLOCK):
        nb = min(SOLVE_BLOCK, rows.size - k0)
        w = rows[k0:k0 + nb]
        for j in range(n):
            for b in range(nb):
                ad[j, b] = _l1(d[w[b], p[j]])
        for i in range(n):                  # |U||d|: U[i, j] is F[:, j, kv + i − j]
            for b in range(nb):             # (loops, not slices: a view costs a reference count)
                u[i, b] = 0.0
            for j in range(i, min(n, i + kv + 1)):
                for b in range(nb):
                    u[i, b] += (abs(fr[j, kv + i - j, w[b]]) + abs(fi[j, kv + i - j, w[b]])) \
                        * ad[j, b]
        for j in range(n - 2, -1, -1):      # then |L_j| and P_j, innermost first
            for t in range(1, min(kl, n - 1 - j) + 1):
                for b in range(nb):
                    u[j + t, b] += (abs(fr[j, kv + t, w[b]]) + abs(fi[j, kv + t, w[b]])) * u[j, b]
            for b in range(nb):
                q = ipiv[j, w[b]]
                keep = u[j, b]
                u[j, b] = u[q, b]
                u[q, b] = keep
        for b in range(nb):
            acc[b] = 0.0
        for i in range(n):
            for b in range(nb):
                acc[b] += _l1(x[w[b], p[i]]) * u[i, b]
        for b in range(nb):                 # (a loop: a slice assignment compiles numba's
            out[k0 + b] = acc[b]            # shape-mismatch message, 1.5 s of CPU)


@_jit_inline
def _hypot2(re, im):
    """|re + j im| for |z| ≤ about 1 (x scaled to max-norm 1): no hypot needed."""
    return np.sqrt(re * re + im * im)


@_jit
def sensitivities(omega, x, scale, e_i, e_j, e_m, e_k, e_c, s_row, s_col, s_val,
                  l_p1, l_p2, l_col, l_r, S, Sd):
    """S and S_data of :meth:`mechcirc._nodal_residual.Pattern.sensitivities` for x/scale (real ω),
    for :data:`SOLVE_BLOCK` ω at a time, ω innermost (each ω's sums in the same order).

    ``x`` (complex, shape (n_ω, n)) reads 0 at index n, the reference.
    """
    n_w, n = x.shape
    nb = SOLVE_BLOCK
    xr, xi = np.zeros((n + 1, nb)), np.zeros((n + 1, nb))   # x/scale, the reference's 0 at n
    mag = np.zeros((n + 1, nb))             # |x_i|/scale
    W, acc = np.ones(nb), np.empty((2, nb))
    for k0 in range(0, n_w, nb):
        m = min(nb, n_w - k0)               # (past m, the last block's stale ω: unused)
        for b in range(m):                  # once per unknown, not per element end
            W[b] = omega[k0 + b]
            f = 1.0 / scale[k0 + b]
            for i in range(n):              # x·f as numba's complex × real: (a + jb)(f + j0)
                z = x[k0 + b, i]
                xr[i, b], xi[i, b] = z.real * f - z.imag * 0.0, z.real * 0.0 + z.imag * f
                mag[i, b] = np.sqrt(xr[i, b] * xr[i, b] + xi[i, b] * xi[i, b])
        acc[:] = 0.0
        for e in range(e_i.size):
            i, j = e_i[e], e_j[e]
            c, mm, k = abs(e_c[e]), e_m[e], e_k[e]
            for b in range(nb):
                # One of c, m, k is nonzero: |c + j(ωm − k/ω)| without a hypot.
                y = c + abs(W[b] * mm - k / W[b])
                d = _hypot2(xr[i, b] - xr[j, b], xi[i, b] - xi[j, b])
                acc[0, b] += y * (mag[i, b] + mag[j, b]) * d
                acc[1, b] += y * d * d
        for s in range(s_row.size):
            v, r, c = abs(s_val[s]), s_row[s], s_col[s]
            for b in range(nb):
                acc[0, b] += v * mag[r, b] * mag[c, b]
        for v in range(l_r.size):
            p1, p2, c, lr = l_p1[v], l_p2[v], l_col[v], 2 * l_r[v]
            for b in range(nb):
                d = _hypot2(xr[p1, b] - xr[p2, b], xi[p1, b] - xi[p2, b])
                acc[1, b] += lr * d * mag[c, b]
        for b in range(m):                  # (a loop, as in band_bound)
            S[k0 + b] = acc[0, b]
            Sd[k0 + b] = acc[1, b]
