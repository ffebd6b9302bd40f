"""The residual b − A(ω) x in double-double, and the error bounds of K built on it.

What does not change with ω is found once per system (:func:`pattern`): the
CSC pattern of A(ω), its parts, the residual's summation plan, and the
element tables of the sensitivities S and S_data that bound the rounding of
the residual (:func:`residual_rounding`) and of the data (:func:`total_error`).
The compiled kernels of :mod:`mechcirc._nodal_kernels` do the same
operations in the same order, where the caller passes them (``kern``).
"""

from __future__ import annotations

from functools import cached_property
from itertools import accumulate

import numpy as np
from numpy.typing import NDArray

from ._dd import dd_add, dd_div_d, dd_div_dd, dd_mul_d, split, two_prod, two_sum
from ._nodal_equations import KINDS, NodalSystem, combine

__all__ = ["Pattern", "pattern", "residual_rounding", "total_error", "row_max"]


def row_max(a: NDArray) -> NDArray:
    """The largest entry of each row of the 2-D ``a`` (at least 0.0: for |values|).

    By columns over a transposed copy where the rows are the shorter side: numpy
    reduces each short row on its own (9 µs for 178 rows of 23, 3 µs by columns;
    the other way round for 8 rows of 500, 2 against 15 µs).  A maximum is exact:
    the same values either way.
    """
    if a.shape[0] > a.shape[1]:
        return np.ascontiguousarray(a.T).max(axis=0, initial=0.0)
    return a.max(axis=-1, initial=0.0)


class Pattern:
    """What does not change with ω: the pattern of A(ω), its parts, and the residual's plan.

    ``indices``/``indptr`` are the CSC pattern of A(ω) (symmetric); ``dc``,
    ``m``, ``k`` the summed nonzeros of D + C, M and Kₛ aligned to it, from
    which A(ω) is formed (:func:`combine`) as a data vector on the fixed
    pattern.  The residual b − A x (:meth:`residual`) is not formed from
    these sums (a summed diagonal is already rounded): each element's
    current y·(x_i − x_j) and each lever stamp's product is computed exactly
    in double-double arithmetic and summed per row and kind in double-double,
    following a plan (:attr:`slots`) made here once.
    """

    def __init__(self, system: NodalSystem):
        n = system.size
        r = [np.asarray(system.stamps[k][0], dtype=np.int64) for k in KINDS]
        c = [np.asarray(system.stamps[k][1], dtype=np.int64) for k in KINDS]
        v = [np.asarray(system.stamps[k][2], dtype=float) for k in KINDS]
        # The lever block's stamps (KINDS' last; the held drive's constraint included).
        self.s_row, self.s_col, self.s_val = r[-1], c[-1], v[-1]     # the lever stamps
        rows, cols = np.concatenate(r), np.concatenate(c)
        ends = list(accumulate([len(x) for x in r], initial=0))  # each kind's stamps, in order
        self.n = n
        uniq, inv = np.unique(cols * n + rows, return_inverse=True)
        self.key = uniq                         # col·n + row of each nonzero
        self.indices = (uniq % n).astype(np.int32)
        self.indptr = np.searchsorted(uniq // n, np.arange(n + 1)).astype(np.int32)
        parts = [np.bincount(inv[ends[i]:ends[i + 1]], weights=v[i], minlength=uniq.size)
                 .astype(float, copy=False) for i in range(4)]     # (int where no stamps)
        self.m, self.k, self.dc = parts[0], parts[2], parts[1] + parts[3]
        self._elements(system)
        self._plan()

    def csc(self, omega: float):
        """A(ω) as a ``scipy.sparse.csc_matrix`` on the fixed pattern."""
        import scipy.sparse as sp

        data = combine(self.dc, self.m, self.k, omega)
        return sp.csc_matrix((data, self.indices, self.indptr), shape=(self.n, self.n))

    def dense(self, omega: float) -> NDArray[np.complex128]:
        """A(ω) as a dense (n, n) array, the bits of :func:`mechcirc.nodal.dense_matrices`
        (the same stamps summed in the same order into each entry), without its dense sums."""
        flat = np.zeros(self.n * self.n, dtype=complex)
        flat[self.key] = combine(self.dc, self.m, self.k, omega)
        return flat.reshape(self.n, self.n).T           # (keys col·n + row: Aᵀ by rows)

    def _elements(self, system: NodalSystem) -> None:
        index = {n: i for i, n in enumerate(system.nodes)}
        at = index.get                          # (node, n): the reference, a zero column at n
        n = self.n
        els = system.elements
        self.e_i = np.array([at(e.n1, n) for e in els], dtype=np.int64)
        self.e_j = np.array([at(e.n2, n) for e in els], dtype=np.int64)
        self.e_val = np.array([e.value * e.eta for e in els], dtype=float)
        code = {"mass": 0, "spring": 1}
        self.e_kind = np.array([code.get(e.kind, 2) for e in els], dtype=np.int64)
        # Each element's value under its kind (mass, spring, damper), 0 under the others.
        self.e_m, self.e_k, self.e_c = (np.where(self.e_kind == i, self.e_val, 0.0)
                                        for i in range(3))
        # |c|, |m|, |k| by element, (E, 3): the first-step bound's sums by kind.
        self.e_abs = np.abs([self.e_c, self.e_m, self.e_k]).T
        lv = system.levers
        self.l_p1 = np.array([at(v.p1, n) for v in lv], dtype=np.int64)
        self.l_p2 = np.array([at(v.p2, n) for v in lv], dtype=np.int64)
        self.l_col = len(system.nodes) + np.arange(len(lv), dtype=np.int64)
        self.l_r = np.array([abs(v.ratio) for v in lv], dtype=float)
        self.s_abs = np.abs(self.s_val)

    def _plan(self) -> None:
        """What every residual needs: the split values, the compiled kernel's buckets, and
        the most terms of a bucket and of a row (:func:`residual_rounding`).

        A bucket is (row, kind) with kinds mass, spring, damper, lever, its
        terms +y·d of each element into its first node's row, −y·d into its
        second's (the reference row dropped) and v·x_c of each lever stamp.
        The numpy residuals' summation plans are built on first use
        (:attr:`slot_plan`, :attr:`row_plan`): a sweep on the compiled path
        needs neither, a refined one not the second.
        """
        n, E = self.n, self.e_i.size
        with np.errstate(all="ignore"):
            self.e_vs = split(self.e_val)
            self.s_vs = split(self.s_val)
        # The compiled kernel adds each bucket's terms in the same order: the
        # + terms by element, then the − terms, then the lever stamps.
        self.k_bi = np.minimum(self.e_i * 4 + self.e_kind, 4 * n).astype(np.int64)
        self.k_bj = np.minimum(self.e_j * 4 + self.e_kind, 4 * n).astype(np.int64)
        self.k_bs = np.minimum(self.s_row * 4 + 3, 4 * n).astype(np.int64)
        self.n_terms = 2 * E + self.s_row.size
        count = np.bincount(np.concatenate([self.k_bi, self.k_bj, self.k_bs]),
                            minlength=4 * n + 1)
        self.max_terms = int(count[:4 * n].max(initial=0))     # (not the reference's)
        self.term_rows = np.concatenate([self.e_i, self.e_j, self.s_row])   # each term's row
        self.max_row_terms = int(np.bincount(self.term_rows, minlength=n + 1)[:n].max(initial=0))

    @cached_property
    def slot_plan(self) -> tuple[list[NDArray], NDArray]:
        """(slots, buckets): the double-double residual's summation order.

        Buckets are ranked by their number of terms, so that the s-th terms
        of all buckets with more than s terms form one slot (the terms'
        indices, by rank), added in one vectorised double-double step;
        ``buckets`` is the bucket of each rank.
        """
        n = self.n
        bucket = np.concatenate([self.k_bi, self.k_bj, self.k_bs])   # (the reference's: 4n)
        keep = bucket < 4 * n                  # rows of the reference dropped
        bucket, term = bucket[keep], np.flatnonzero(keep)
        uniq, inv, counts = np.unique(bucket, return_inverse=True, return_counts=True)
        order = np.argsort(-counts, kind="stable")
        rank = np.empty_like(order)
        rank[order] = np.arange(order.size)
        r = rank[inv]
        srt = np.lexsort((term, r))
        r, term = r[srt], term[srt]
        first = np.searchsorted(r, np.arange(uniq.size))
        pos = np.arange(r.size) - first[r]
        slots = []
        for s in range(int(counts.max(initial=0))):
            sel = pos == s
            slots.append(term[sel][np.argsort(r[sel], kind="stable")])
        return slots, uniq[order]

    @cached_property
    def row_plan(self) -> tuple[NDArray, NDArray, NDArray]:
        """(order, rows, start): the float64 residual (:meth:`residual` with ``exact=False``)
        sums each row's terms at once: the terms sorted by row, the rows, where each starts."""
        order = np.argsort(self.term_rows, kind="stable")
        f_rows, f_start = np.unique(self.term_rows[order], return_index=True)
        return order, f_rows, f_start

    def residual(self, omega: NDArray, xh: NDArray, xl: NDArray | None,
                 rhs: NDArray, kern=None, exact: bool = True) -> NDArray[np.complex128]:
        """b − A(ω) x for each ω (rows of x = xh + xl), in double-double, rounded at the end.

        With ``exact=False`` (the unrefined solve's error estimate) in float64
        instead, from the same element currents y·(x_i − x_j) (each rounded
        about three times: the difference, the admittance, the product) summed
        row by row (:func:`residual_rounding` with ``double=False`` bounds what
        that rounding does to K); ``xl`` and ``kern`` are not used.

        The same A(ω) as :func:`combine`: (A x)_r = Σ dampers + Σ levers +
        jω Σ masses − j Σ springs / ω, each sum Σ ±value·(x_i − x_j) exact to
        about 2⁻¹⁰⁴ (TwoSum of the differences, TwoProduct of the products,
        cascaded TwoSum per bucket), and the ω factors applied to the sums in
        double-double.  Complex ω (resonance polishing) are accepted.  With
        ``kern`` (:mod:`mechcirc._nodal_kernels`) and real ω, by the compiled
        kernel: the same operations in the same order.
        """
        with np.errstate(all="ignore"):
            if not exact:
                return self._residual_float64(omega, xh, rhs)
            if kern is not None and not np.iscomplexobj(omega):
                return self._residual_compiled(kern, omega, xh, xl, rhs)
            return self._residual(omega, xh, xl, rhs)

    def _residual_float64(self, omega, x, rhs):
        c, n = x.shape
        xe = np.concatenate([x.astype(complex, copy=False), np.zeros((c, 1), complex)], axis=1)
        t = combine(self.e_c, self.e_m, self.e_k, np.asarray(omega)[:, None]) * \
            (xe[:, self.e_i] - xe[:, self.e_j])
        terms = np.concatenate([t, -t, self.s_val * xe[:, self.s_col]], axis=1)
        ax = np.zeros((c, n + 1), dtype=complex)
        f_order, f_rows, f_start = self.row_plan
        if f_rows.size:
            ax[:, f_rows] = np.add.reduceat(terms[:, f_order], f_start, axis=1)
        return rhs[None, :] - ax[:, :n]

    def _residual(self, omega, xh, xl, rhs):
        c, n = xh.shape
        z = np.zeros((c, 1), dtype=complex)
        xe = np.concatenate([xh.astype(complex, copy=False), z], axis=1)
        d_h, d_l = two_sum(xe[:, self.e_i], -xe[:, self.e_j])
        xs = xe[:, self.s_col]
        if xl is not None:
            xle = np.concatenate([xl.astype(complex, copy=False), z], axis=1)
            # Renormalised (TwoSum): where x_i ≈ x_j their low parts (~u|x|)
            # would leave a low part far above u|d|, and every later sum of
            # low parts would round at u²|x| per row instead of u²|y d|.
            d_h, d_l = two_sum(d_h, d_l + (xle[:, self.e_i] - xle[:, self.e_j]))
        p_h, p_l = two_prod(self.e_val, *self.e_vs, d_h)
        p_l = p_l + self.e_val * d_l
        q_h, q_l = two_prod(self.s_val, *self.s_vs, xs)
        if xl is not None:
            q_l = q_l + self.s_val * xle[:, self.s_col]
        T_h, T_l = (np.concatenate([p, -p, q], axis=1) for p, q in ((p_h, q_h), (p_l, q_l)))
        S_h, S_l = np.zeros((c, 4 * n), dtype=complex), np.zeros((c, 4 * n), dtype=complex)
        slots, buckets = self.slot_plan
        if slots:
            acc_h, acc_l = T_h[:, slots[0]], T_l[:, slots[0]]
            for s in slots[1:]:
                k = s.size
                a, e = two_sum(acc_h[:, :k], T_h[:, s])
                acc_h[:, :k] = a
                acc_l[:, :k] += e + T_l[:, s]
            S_h[:, buckets], S_l[:, buckets] = acc_h, acc_l
        S_h, S_l = S_h.reshape(c, n, 4), S_l.reshape(c, n, 4)
        w = np.asarray(omega)[:, None]
        m_h, m_l = S_h[..., 0], S_l[..., 0]
        k_h, k_l = S_h[..., 1], S_l[..., 1]
        if np.iscomplexobj(w):
            wm_re, wm_im, kw_re, kw_im = _complex_omega_terms(m_h, m_l, k_h, k_l, w)
        else:
            sw = split(w)
            wm_re = dd_mul_d(m_h.real, m_l.real, w, *sw)
            wm_im = dd_mul_d(m_h.imag, m_l.imag, w, *sw)
            kw_re = dd_div_d(k_h.real, k_l.real, w, *sw)
            kw_im = dd_div_d(k_h.imag, k_l.imag, w, *sw)
        # susceptance part: ω S_m − S_k/ω; A x = S_c + S_l + j·sus
        sus_re = dd_add(*wm_re, -kw_re[0], -kw_re[1])
        sus_im = dd_add(*wm_im, -kw_im[0], -kw_im[1])
        g_h, g_l = dd_add(S_h[..., 2], S_l[..., 2], S_h[..., 3], S_l[..., 3])
        ax_re = dd_add(g_h.real, g_l.real, -sus_im[0], -sus_im[1])
        ax_im = dd_add(g_h.imag, g_l.imag, *sus_re)
        r_re = dd_add(rhs[None, :], 0.0, -ax_re[0], -ax_re[1])
        r_im, out = (-ax_im[0], -ax_im[1]), np.empty((c, n), dtype=complex)
        for part, (hi, lo) in ((out.real, r_re), (out.imag, r_im)):
            lo = np.where(np.isfinite(lo) | ~np.isfinite(hi), lo, 0.0)
            part[...] = hi + lo
        return out

    def _residual_compiled(self, kern, omega, xh, xl, rhs):
        # The kernel reads the parts of x in place (no copies padded with the
        # reference's zero column) and writes the complex residual itself.
        c, n = xh.shape
        xh = np.asarray(xh, dtype=complex)
        xl = None if xl is None else np.asarray(xl, dtype=complex)
        low, out = xh if xl is None else xl, np.empty((c, n), dtype=complex)
        kern.residual(np.ascontiguousarray(omega, dtype=float), xh.real, xh.imag, low.real,
                      low.imag, xl is not None, np.asarray(rhs, dtype=float), self.k_bi,
                      self.k_bj, self.k_bs, self.e_i, self.e_j,
                      *(np.ascontiguousarray(np.atleast_2d(v))
                        for v in (self.e_val, *self.e_vs)), self.s_col,
                      *(np.ascontiguousarray(np.atleast_2d(v))
                        for v in (self.s_val, *self.s_vs)), out)
        return out

    def sensitivities(self, omega: NDArray, x: NDArray, K: NDArray,
                      kern=None, data: bool = True) -> tuple[NDArray, NDArray | None]:
        """(S/|K|, S_data/|K|) for each ω: the sensitivity of K to rounding the stamps and the data.

        S = Σ_e |y_e| |x_i − x_j| (|x_i| + |x_j|) + Σ_levers |v · x_r · x_c|:
        the residual forms each element's current y·(x_i − x_j) once and
        adds it to both rows, so its rounding (relative to the current, and
        u·|x| from the low parts of x_i, x_j in double-double) enters as
        δ·(e_i − e_j); A is complex symmetric, so the adjoint solution of
        K = cᵀ A⁻¹ c is x itself and K moves by δ·(x_i − x_j).  A row's own
        summation error, relative to Σ|y_e (x_i − x_j)| over its elements,
        meets |x_i|; a lever stamp's rounding meets |x_r|.  (The earlier
        Σ |y|(|x_i| + |x_j|)² counted a stiff element's currents as if
        they did not cancel: 1e14 × the true error on stiff networks.)

        S_data = Σ_e |y_e| |x_i − x_j|² + Σ_levers 2|r| |x_p1 − x_p2| |q|:
        rounding an element's value by a relative ε changes its four stamps
        together, δA = ε·y·(e_i − e_j)(e_i − e_j)ᵀ, and K by ε·y·(x_i − x_j)²;
        a lever's ratio enters its two primary stamps.  This sum times eps
        bounds the change of K when every value is rounded, without the
        cancellation that a bound stamp by stamp would count many times over.
        Both are computed with x scaled to max-norm 1 (no overflow where x
        and K are near float64's limits), and divided by |K|.  With ``kern``
        and real ω, by the compiled kernel.  ``data=False``: S alone (S_data None;
        a sweep's error needs only S).
        """
        w = np.asarray(omega)[:, None]
        c = x.shape[0]
        with np.errstate(all="ignore"):
            scale = row_max(np.abs(x))
            scale = np.where((scale > 0) & np.isfinite(scale), scale, 1.0)
            if kern is not None and not np.iscomplexobj(omega):
                S, Sd = np.empty(c), np.empty(c)
                kern.sensitivities(np.asarray(omega, dtype=float),
                                   np.ascontiguousarray(x, dtype=complex), scale, self.e_i,
                                   self.e_j, self.e_m, self.e_k, self.e_c, self.s_row,
                                   self.s_col, self.s_val, self.l_p1, self.l_p2, self.l_col,
                                   self.l_r, S, Sd)
                f = scale / np.abs(K)
                return S * f * scale, (Sd * f * scale if data else None)
            xe = np.concatenate([np.asarray(x, dtype=complex) / scale[:, None],
                                 np.zeros((c, 1), complex)], axis=1)
            y = np.abs(combine(self.e_c, self.e_m, self.e_k, w))
            ax = np.abs(xe)
            ai, aj = ax[:, self.e_i], ax[:, self.e_j]
            d = np.abs(xe[:, self.e_i] - xe[:, self.e_j])
            S = np.einsum("ij,ij->i", y, (ai + aj) * d)
            if self.s_row.size and c:       # (each point's own lever values: a row each)
                t = ax[:, self.s_row] * ax[:, self.s_col]
                S = S + (np.abs(self.s_val) @ t.T if self.s_val.ndim == 1 else
                         np.einsum("ij,ij->i", np.abs(self.s_val), t))
            f = scale / np.abs(K)
            if not data:
                return S * f * scale, None
            Sd = np.einsum("ij,ij->i", y, d * d)
            if self.l_r.size:
                dl = np.abs(xe[:, self.l_p1] - xe[:, self.l_p2])
                Sd = Sd + np.sum(2 * self.l_r * dl * ax[:, self.l_col], axis=1)
            return S * f * scale, Sd * f * scale


def _complex_omega_terms(m_h, m_l, k_h, k_l, w):
    """ω·S_m and S_k/ω in double-double at complex ω (resonance polishing), component by
    component: (re, im) pairs of (hi, lo)."""
    wr, wi = w.real, w.imag
    swr, swi = split(wr), split(wi)
    # jω·S_m = (−wi + j wr)·S_m, component by component.
    a_h, a_l = dd_mul_d(m_h.real, m_l.real, wr, *swr)    # S_m.re wr
    b_h, b_l = dd_mul_d(m_h.imag, m_l.imag, wi, *swi)    # S_m.im wi
    c_h, c_l = dd_mul_d(m_h.real, m_l.real, wi, *swi)
    d_h2, d_l2 = dd_mul_d(m_h.imag, m_l.imag, wr, *swr)
    # ω S_m = (re wr − im wi) + j(re wi + im wr)
    wm_re = dd_add(a_h, a_l, -b_h, -b_l)
    wm_im = dd_add(c_h, c_l, d_h2, d_l2)
    # S_k/ω = S_k·conj(ŵ)/(|ŵ|²·2ᵉ), ŵ = ω/2ᵉ (exact scaling).
    e2 = np.ldexp(1.0, np.frexp(np.maximum(np.abs(wr), np.abs(wi)))[1])
    ur, ui = wr / e2, wi / e2
    sur, sui = split(ur), split(ui)
    p1 = dd_mul_d(k_h.real, k_l.real, ur, *sur)
    p2 = dd_mul_d(k_h.imag, k_l.imag, ui, *sui)
    p3 = dd_mul_d(k_h.imag, k_l.imag, ur, *sur)
    p4 = dd_mul_d(k_h.real, k_l.real, ui, *sui)
    num_re = dd_add(*p1, *p2)              # re·ur + im·ui
    num_im = dd_add(*p3, -p4[0], -p4[1])   # im·ur − re·ui
    n2 = dd_add(*dd_mul_d(ur, 0.0, ur, *sur), *dd_mul_d(ui, 0.0, ui, *sui))
    den = (n2[0] * e2, n2[1] * e2)
    return wm_re, wm_im, dd_div_dd(*num_re, *den), dd_div_dd(*num_im, *den)


def pattern(system: NodalSystem) -> Pattern:
    """The :class:`Pattern` of ``system``, built once per system."""
    return system.memo("_pattern", lambda: Pattern(system))


def residual_rounding(system, S, double: bool = True):
    """Relative error of K left by residuals rounded in double-double (or float64).

    Each residual row is summed to about (terms + 4)·u² × Σ_e |y_e (x_i − x_j)|
    (+ its lever stamps; u = 2⁻⁵³), which K (through the adjoint solution,
    x itself) feels as that times S (:meth:`Pattern.sensitivities`); the
    refinement cannot see it.

    With ``double=False``, the float64 residual of the unrefined solve
    (:meth:`Pattern.residual` with ``exact=False``): K − K̂ = xᵀ r exactly
    (A complex symmetric, r = b − A x̂), and the computed r̂ differs from r
    by the rounding of each element current t_e = y_e·(x_i − x_j), at most
    γ₃|t_e| (each component of the difference, of the admittance ωm, k/ω or
    c — the other component of y is 0 — and of the product rounded once;
    a lever stamp's v·x_c once), and of each row's sum of m terms, at most
    γ_{m−1}·Σ|t| (componentwise, and so for the modulus: Minkowski); γ_k =
    k u/(1 − k u).  A current enters its two rows with opposite signs, so
    its rounding reaches xᵀ r through x_i − x_j, a row's through x_r:
    |xᵀ(r − r̂)| ≤ (γ₃ + γ_{m−1}(1 + γ₃))·S|K| with S|K| = Σ_e |t_e|(|x_i| +
    |x_j|) + Σ_levers |v x_c||x_r| (:meth:`Pattern.sensitivities`), to first
    order in x − x̂; bounded here by (m + 3)·u·S with m the most terms of a
    row.  The rounding of b − A x̂ itself (u |x̂|ᵀ|r̂|) is added by the
    caller, which has r̂.
    """
    pat = pattern(system)
    u = np.finfo(float).eps / 2
    with np.errstate(all="ignore"):
        out = 4 * (pat.max_terms + 4) * u * u * S if double else \
            (pat.max_row_terms + 3) * u * S
    return np.where(np.isnan(out), np.inf, out)


def total_error(S, est):
    """The solve's error ``est`` plus the sensitivity of K to rounding its data (resonances).

    Each value (m, k, c, r) carries a rounding of up to eps relative; that
    moves K by eps × S_data / |K| (``S``, from :meth:`Pattern.sensitivities`),
    far more than the solve near a zero of K.  It is added for resonances,
    whose error then bounds the distance to the root of the values as
    written, before rounding.  Sweeps do not add it: their error is that of
    the computation for the binary inputs (as the series–parallel bound's,
    and as a 40-digit reference measures it); flagging from it made half the
    points near a grid's poles false alarms, accurate to 1e-13.  At least
    eps (the result is rounded to float64).
    """
    eps = np.finfo(float).eps
    with np.errstate(all="ignore"):
        rounding = eps * S
        total = est + np.where(np.isnan(rounding), np.inf, rounding)
    return np.maximum(total, eps)

