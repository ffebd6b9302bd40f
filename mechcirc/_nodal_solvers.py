"""The factorisations of A(ω) a sweep refines with: dense batches, banded or sparse LU,
and a dense LU in double-double where float64 factors cannot refine.

:func:`solver` picks one per system from its size and pattern alone (so that
the same network is solved the same way, bit for bit, every time);
:func:`dd_solver` is the double-double fallback.  Each ``factor(omega)``
returns ``(good, solve)``: the frequencies factorised and a function solving
for their rows (or a subset ``rows`` of them).
"""

from __future__ import annotations

import contextlib

import numpy as np

from ._dd import cdd_div, cdd_mul, dd_add, dd_div_d, dd_mul_d, dd_norm, dd_sub, split, two_sum
from ._nodal_equations import NodalSystem, combine
from ._nodal_residual import Pattern, _complex_omega_terms, pattern

__all__ = ["solver", "dd_solver", "balance", "DENSE_LIMIT", "DD_LIMIT", "BAND_MAX"]

#: Systems with at most this many unknowns use batched dense solves (or
#: batched banded LUs, :data:`SMALL_BAND`).
DENSE_LIMIT = 60
#: Memory bound for one chunk of batched dense matrices [bytes].
_CHUNK_BYTES = 32 * 2**20

def balance(mag, diag):
    """Symmetric scaling d (powers of two) so that d_i |a_ij| d_j ≤ 1 with rows near 1.

    ``mag`` holds |A| (batch, n, n), ``diag`` the diagonal's Σ|stamp| (batch,
    n).  Rows with a diagonal start at 1/√diag, the others (lever forces,
    nodes tied only by levers) at 1/max_j |a_ij| d_j: so a lever's force
    unknown is scaled to the admittance level around it, which Ruiz's
    iteration alone (started at 1) does not find when every element value is
    1e±100 and the lever entries are ±1, r.  A few symmetric Ruiz steps
    follow.  Powers of two: the scaled matrix carries no new rounding, and a
    singular matrix stays singular.
    """
    with np.errstate(all="ignore"):
        d = np.where(diag > 0, 1.0 / np.sqrt(diag), 0.0)
        for _ in range(mag.shape[-1]):      # outward from the rows with a diagonal
            unset = d == 0
            if not unset.any():
                break
            off = np.max(mag * d[:, None, :], axis=2)
            d = np.where(unset & (off > 0), 1.0 / off, d)
            if not (unset & (off > 0)).any():
                break
        d = np.where(d > 0, d, 1.0)
        for _ in range(8):
            r = np.max(mag * d[:, :, None] * d[:, None, :], axis=2)
            d = d / np.sqrt(np.where((r > 0) & np.isfinite(r), r, 1.0))
        d = np.where(np.isfinite(d) & (d > 0), d, 1.0)
        return np.ldexp(1.0, np.round(np.log2(d)).astype(int))


#: Systems up to this many unknowns are solved again by a dense LU in
#: double-double where the refinement with float64 factors does not reach
#: :data:`_STRICT_AFTER` (A(ω) too ill-conditioned for float64 factors).
DD_LIMIT = 200


class DDSolver:
    """Dense LU in double-double of the scaled A(ω), assembled exactly from its stamps.

    The fallback where float64 factors cannot give a contracting refinement:
    a summed diagonal already loses an admittance below 1e-16 of its
    neighbour's (a soft spring beside a stiff one), and elimination loses
    more; here every entry is the double-double sum of its stamps, the
    matrix is scaled symmetrically by powers of two (:func:`_balance`), and
    the LU (partial pivoting) runs in double-double, so that the refinement
    contracts up to cond(A) ≈ 1e30.  Dense and vectorised over a batch of
    ω, about 100 array operations per column: only for the points that need
    it, and only up to :data:`DD_LIMIT` unknowns.
    """

    kind = "dd"

    def __init__(self, system: NodalSystem):
        self.n = n = system.size
        # About 2¹⁹ matrix entries per batch (some 30 temporaries of that size).
        self.max_chunk = max(1, min(64, 2 ** 19 // max(1, n * n)))
        self.parts = []
        for kinds in (("damper", "lever"), ("mass",), ("spring",)):
            h, lo = np.zeros((n, n)), np.zeros((n, n))
            with np.errstate(all="ignore"):          # entries beyond float64: not finite
                for kind in kinds:
                    for r, c, v in zip(*system.stamps[kind]):
                        h[r, c], e = two_sum(h[r, c], float(v))
                        lo[r, c] += e
                self.parts.append(dd_norm(h, lo))
        self.absdiag = [np.abs(np.diagonal(p[0])) for p in self.parts]

    def factor(self, omega, strict: bool = False):
        """(good, solve) at real ω, or at complex ω (the resonances' checks near a close
        pair): A(ω) = D + C + j(ωM − Kₛ/ω) in double-double, then its LU."""
        omega = np.asarray(omega)
        omega = omega if np.iscomplexobj(omega) else omega.astype(float)
        w = omega[:, None, None]
        (ch, cl), (mh, ml), (kh, kl) = self.parts
        B, n = omega.size, self.n
        with np.errstate(all="ignore"):
            re = [np.broadcast_to(ch, (B, n, n)).copy(), np.broadcast_to(cl, (B, n, n)).copy()]
            if np.iscomplexobj(omega):
                # j(ωM − Kₛ/ω) = −Im(ωM − Kₛ/ω) + j Re(ωM − Kₛ/ω), each part double-double.
                wm_re, wm_im, kw_re, kw_im = _complex_omega_terms(mh + 0j, ml + 0j, kh + 0j,
                                                                  kl + 0j, w)
                re = dd_norm(*dd_add(*dd_sub(*re, *wm_im), *kw_im))
                im = dd_norm(*dd_sub(*wm_re, *kw_re))
            else:
                ws = split(w)
                im = dd_norm(*dd_sub(*dd_mul_d(mh, ml, w, *ws), *dd_div_d(kh, kl, w, *ws)))
            X = [*re, im[0], im[1]]
            mag = np.abs(X[0] + 1j * X[2])
            cd, md, kd = self.absdiag
            a = np.abs(omega)[:, None]
            d = balance(mag, cd + a * md + kd / a)
            good = np.isfinite(mag).all(axis=(1, 2)) & (np.abs(omega) > 0)
            dd = d[:, :, None] * d[:, None, :]
            X = [x * dd for x in X]
            perm = _dd_lu(X, good)
            good &= np.isfinite(X[0]).all(axis=(1, 2)) & np.isfinite(X[2]).all(axis=(1, 2))
        X, perm, d = [x[good] for x in X], perm[good], d[good]
        every = np.arange(perm.shape[0])
        with np.errstate(all="ignore"):     # the factors' Veltkamp splits, once for every solve
            X = [X[0], *split(X[0]), X[1], X[2], *split(X[2]), X[3]]

        def solve(r, rows=None):
            rows = every if rows is None else np.asarray(rows)
            b = np.take_along_axis(np.asarray(r, dtype=complex) * d[rows], perm[rows], axis=1)
            F = [x[rows] for x in X]

            def entries(at):                # F[at] as cdd_mul's split operand
                return tuple(f[at] for f in F[:4]), tuple(f[at] for f in F[4:])
            y = [b.real.copy(), np.zeros(b.shape), b.imag.copy(), np.zeros(b.shape)]
            with np.errstate(all="ignore"):
                for k in range(self.n - 1):          # L (unit diagonal)
                    t = cdd_mul(None, [v[:, k, None] for v in y],
                                entries((slice(None), slice(k + 1, None), k)))
                    _csub_at(y, (slice(None), slice(k + 1, None)), t)
                for k in range(self.n - 1, -1, -1):  # U
                    q = cdd_div([v[:, k] for v in y], [F[i][:, k, k] for i in (0, 3, 4, 7)])
                    for v, u in zip(y, q):
                        v[:, k] = u
                    if k:
                        t = cdd_mul(None, [u[:, None] for u in q],
                                    entries((slice(None), slice(None, k), k)))
                        _csub_at(y, (slice(None), slice(None, k)), t)
            return ((y[0] + y[1]) + 1j * (y[2] + y[3])) * d[rows]
        return good, solve


def _dd_lu(X, good):
    """LU with partial pivoting, in place, of a batch of complex matrices in double-double
    (X = [re hi, re lo, im hi, im lo], each (batch, n, n)); returns the row permutations.
    ``good`` is cleared where a pivot is exactly 0."""
    B, n = X[0].shape[:2]
    perm = np.broadcast_to(np.arange(n), (B, n)).copy()
    rows = np.arange(B)
    for k in range(n):
        p = k + np.argmax(np.abs(X[0][:, k:, k]) + np.abs(X[2][:, k:, k]), axis=1)
        for x in X + [perm]:
            x[rows, k], x[rows, p] = x[rows, p], x[rows, k].copy()
        piv = [x[:, k, k] for x in X]
        zero = (piv[0] == 0) & (piv[2] == 0)
        good &= ~zero
        piv[0] = np.where(zero, 1.0, piv[0])
        if k + 1 == n:
            break
        lk = cdd_div([x[:, k + 1:, k] for x in X], [v[:, None] for v in piv])
        for x, v in zip(X, lk):
            x[:, k + 1:, k] = v
        # Only the rows and columns the update reaches (the nodal
        # matrices are sparse: a tree fills little).
        ri = k + 1 + np.flatnonzero(((lk[0] != 0) | (lk[2] != 0)).any(axis=0))
        ci = k + 1 + np.flatnonzero(((X[0][:, k, k + 1:] != 0) |
                                     (X[2][:, k, k + 1:] != 0)).any(axis=0))
        if not (ri.size and ci.size):
            continue
        at = (slice(None), ri[:, None], ci[None, :])
        upd = cdd_mul([v[:, ri - k - 1, None] for v in lk],
                       [x[:, None, k, ci] for x in X])
        _csub_at(X, at, upd)
    return perm


def _csub_at(y, at, t) -> None:
    """y[at] −= t in place in complex double-double (y and t as re hi, re lo, im hi, im lo)."""
    re, im = dd_sub(y[0][at], y[1][at], *t[:2]), dd_sub(y[2][at], y[3][at], *t[2:])
    for v, u in zip(y, (*re, *im)):
        v[at] = u


def dd_solver(system: NodalSystem) -> DDSolver:
    """The :class:`DDSolver` of ``system``, built once per system."""
    return system.memo("_dd_solver", lambda: DDSolver(system))


def solver(system: NodalSystem):
    """The solver of ``system`` (dense batch, banded or sparse), built once per system."""
    def build():
        if system.size > DENSE_LIMIT:
            return SparseSolver(pattern(system))
        # Small: banded when the band is narrow (a ladder's is 1 wide: no n³
        # inverse per ω), otherwise dense.
        if system.size >= SMALL_BAND[0]:
            band = SparseSolver(pattern(system), SMALL_BAND[1])
            if band.kind == "band":
                return band
        return DenseSolver(system)
    return system.memo("_solver", build)


#: Systems of at most :data:`DENSE_LIMIT` unknowns are solved as bands from
#: SMALL_BAND[0] unknowns on when their half band width is at most
#: SMALL_BAND[1], as dense batches otherwise.  Measured on ladders at 401 ω
#: (numpy path): dense and banded cost the same at 8 unknowns, banded 2.2× less
#: at 23 and 4.2× less at 60.
SMALL_BAND = (12, 4)


class DenseSolver:
    """Batched dense solves: the inverses of A(ω) for a chunk of ω, applied as one product.

    An explicit inverse is no less accurate here than LU factors: every
    solution is refined with residuals in double-double, and the batch
    is applied as one matrix product (small systems, many ω).
    """

    kind = "dense"

    def __init__(self, system: NodalSystem):
        self.dc = system.dense("damper") + system.dense("lever")
        self.m, self.k = system.dense("mass"), system.dense("spring")
        self.max_chunk = max(1, _CHUNK_BYTES // (16 * system.size ** 2))

    def factor(self, omega, kern=None):
        A = combine(self.dc, self.m, self.k, np.asarray(omega)[:, None, None])
        good = np.isfinite(A).all(axis=(1, 2))
        inv, ok = stacked_inverse(A[good])
        if ok is not None:
            good[np.flatnonzero(good)[~ok]] = False
            inv = inv[ok]
        return good, lambda r, rows=slice(None): np.einsum("kij,kj->ki", inv[rows], r)


def stacked_inverse(A):
    """Inverses of the stacked matrices ``A`` (k, n, n), and None; or, when one is
    exactly singular, the matrices inverted one by one with NaN for those, and the
    mask of the inverted ones (rare; only on the failure path)."""
    try:
        return np.linalg.inv(A), None
    except np.linalg.LinAlgError:
        inv = np.full(A.shape, np.nan, dtype=complex)
        for k in range(A.shape[0]):
            with contextlib.suppress(np.linalg.LinAlgError):
                inv[k] = np.linalg.inv(A[k])
        return inv, np.isfinite(inv).all(axis=(1, 2))


#: The sparse path uses a banded LU when the half band width kl after a reverse
#: Cuthill–McKee ordering is at most this, SuperLU otherwise.
BAND_MAX = 12
#: SuperLU's threshold for keeping the diagonal pivot (symmetric mode).
DIAG_PIVOT_THRESH = 0.001


#: Bytes of factors per chunk of ω for the numpy banded LU (:func:`band_lu_batch`).
_BAND_BYTES = 64 * 2**20
#: Fewest ω per chunk for which the numpy banded LU (a Python loop over the
#: columns, vectorised over ω) is used; LAPACK per ω below (very long bands).
BATCH_MIN = 32


def band_lu_batch(G, n, kl):
    """LU with partial pivoting of a batch of banded matrices in place, vectorised over the batch.

    The elimination of LAPACK's ``zgbtf2`` (the pivot the largest |re| + |im|
    of the column, the first on ties), column by column for all matrices at
    once: the loop over the n columns runs in Python, each step a few numpy
    operations on arrays of the batch, so that a sweep costs no call per ω.

    Parameters
    ----------
    G : ndarray of complex, shape (n + kl, 3·kl + 1, B)
        Row i of each matrix by its band, ``G[i, kl + c − i] = A[i, c]``
        (room for the fill on the right), the rows past n zero.  On return
        U's row j is ``G[j, kl:]`` (its diagonal first) and the multiplier of
        row j + s at column j is ``G[j + s, kl − s]``.
    n : int
        Order of the matrices.
    kl : int
        Half band width (lower = upper).

    Returns
    -------
    tuple of (ndarray, ndarray)
        piv (n, B) of int8: row j was swapped with row j + piv[j, b];
        ok (B,): False where a pivot is 0 or not finite (singular).
    """
    B = G.shape[2]
    piv, best = np.zeros((n, B), dtype=np.int8), np.empty((n, B))
    e = 3 * kl + 1
    with np.errstate(all="ignore"):
        for j in range(n):
            z = G[j, kl]
            b = np.abs(z.real) + np.abs(z.imag)
            pivoted = False                 # (no swap to test for in the batch)
            for s in range(1, min(kl, n - 1 - j) + 1):
                z = G[j + s, kl - s]
                m = np.abs(z.real) + np.abs(z.imag)
                take = m > b
                if take.any():
                    b = np.where(take, m, b)
                    piv[j][take] = s
                    pivoted = True
            best[j] = b
            for s in range(1, kl + 1 if pivoted else 1):
                _swap_where(G[j, kl:], G[j + s, kl - s:e - s], piv[j] == s)
            for s in range(1, min(kl, n - 1 - j) + 1):
                lk = np.divide(G[j + s, kl - s], G[j, kl], out=G[j + s, kl - s])
                G[j + s, kl - s + 1:e - s] -= lk * G[j, kl + 1:]
    ok = np.all((best != 0) & np.isfinite(best), axis=0) if n else np.ones(B, dtype=bool)
    return piv, ok


def _swap_where(a, b, where) -> None:
    """Swap the entries of the rows ``a`` and ``b`` (views, the batch last) in place where
    ``where`` (a row swap of :func:`band_lu_batch` in the matrices that took it)."""
    if where.any():
        keep = a.copy()
        np.copyto(a, b, where=where)
        np.copyto(b, keep, where=where)


def band_solve_batch(G, piv, x, n, kl):
    """Solve with the factors of :func:`band_lu_batch`, each column of ``x`` in place.

    Parameters
    ----------
    G, piv : ndarray
        The factors and pivots of :func:`band_lu_batch` (batch last).
    x : ndarray of complex, shape (n + 2·kl, B)
        The right-hand sides in its first n rows (the rest zero); the solutions on return.
    n : int
        Order of the matrices.
    kl : int
        Half band width.
    """
    swapped = np.any(piv != 0, axis=1)       # the columns with a row swap in the batch
    with np.errstate(all="ignore"):
        for j in range(n - 1):
            pj = piv[j]
            for s in range(1, kl + 1 if swapped[j] else 1):
                _swap_where(x[j], x[j + s], pj == s)
            xj = x[j]
            for s in range(1, min(kl, n - 1 - j) + 1):
                x[j + s] -= G[j + s, kl - s] * xj
        for j in range(n - 1, -1, -1):
            if kl:
                x[j] -= np.einsum("tb,tb->b", G[j, kl + 1:], x[j + 1:j + 1 + 2 * kl])
            x[j] /= G[j, kl]


def band_bound_batch(G, piv, x, d, n, kl):
    """|x|ᵀ P̃|L||U| |d| for each column of the batch, |z| taken as |re| + |im| (≥ |z|).

    The factors of :func:`band_lu_batch` (``G``, ``piv``; P̃|L| in their factored
    form P₀|L₀|P₁|L₁|…, which has no sums of products: the absolute values of its
    entries), for :func:`mechcirc.nodal.first_step_bound`; the compiled LU's factors
    have theirs in :func:`mechcirc._nodal_kernels.band_bound`.

    Parameters
    ----------
    G, piv : ndarray
        The factors and pivots of :func:`band_lu_batch` (batch last).
    x, d : ndarray of complex, shape (n, B)
        Vectors in the factors' order.
    n : int
        Order of the matrices.
    kl : int
        Half band width.

    Returns
    -------
    ndarray of float, shape (B,)
    """
    with np.errstate(all="ignore"):
        ad = np.zeros((n + 2 * kl, d.shape[1]))
        ad[:n] = np.abs(d.real) + np.abs(d.imag)
        u = np.zeros(ad.shape)
        for t in range(2 * kl + 1):                 # |U||d|: row j's entry j + t
            u[:n] += (np.abs(G[:n, kl + t].real) + np.abs(G[:n, kl + t].imag)) * ad[t:t + n]
        for j in range(n - 2, -1, -1):              # then |L_j| and P_j, innermost first
            for s in range(1, min(kl, n - 1 - j) + 1):
                z = G[j + s, kl - s]
                u[j + s] += (np.abs(z.real) + np.abs(z.imag)) * u[j]
            for s in range(1, kl + 1):
                _swap_where(u[j], u[j + s], piv[j] == s)
        return np.einsum("ib,ib->b", np.abs(x.real) + np.abs(x.imag), u[:n])


class _BoundSolve:
    """A ``solve(r, rows=None)`` of banded factors with their ``bound(x, d, rows)`` (x, d of
    every ω, read at ``rows``: :func:`band_bound_batch`, or the compiled ``band_bound``),
    which :func:`mechcirc.nodal.refine_dd` uses after its first step."""

    def __init__(self, solve, bound):
        self.solve, self.bound = solve, bound

    def __call__(self, r, rows=None):
        return self.solve(r, rows)


def band_order(indptr, indices, reorder: bool = True) -> tuple:
    """A symmetric sparsity pattern's reverse Cuthill-McKee order and its band.

    Parameters
    ----------
    indptr, indices : ndarray
        The pattern in compressed form (CSR or CSC: the pattern is symmetric).
    reorder : bool
        False keeps the given order (no scipy).

    Returns
    -------
    tuple
        ``(p, ri, ci, kl)``: the order p (int64, as ``np.arange``'s: scipy's int32
        would compile the kernels a second time), each stored entry's permuted
        index and permuted compressed-axis position, and the half-bandwidth.
    """
    n = len(indptr) - 1
    if reorder:
        import scipy.sparse as sp
        from scipy.sparse.csgraph import reverse_cuthill_mckee

        A = sp.csr_matrix((np.ones(indices.size), indices, indptr), shape=(n, n))
        p = np.asarray(reverse_cuthill_mckee(A, symmetric_mode=True), dtype=np.int64)
    else:
        p = np.arange(n)
    q = np.empty_like(p)
    q[p] = np.arange(n)
    ri, ci = q[indices], q[np.repeat(np.arange(n), np.diff(indptr))]
    return p, ri, ci, int(np.max(np.abs(ri - ci), initial=0))


class SparseSolver:
    """LU of A(ω) on its fixed pattern, with what does not change with ω found once.

    The choice is made from the pattern alone, so that the same network
    gives the same factorisation, bit for bit, on every run: after a reverse
    Cuthill–McKee ordering of the (symmetric) pattern (past :data:`DENSE_LIMIT`
    unknowns; smaller systems keep their own order), of half band width
    kl, a banded LU with partial pivoting when kl ≤ :data:`BAND_MAX`
    (chains, ladders and narrow strips: the ladder's band is 1 wide) — the
    compiled kernels of :mod:`mechcirc._nodal_kernels` when numba is
    installed, otherwise :func:`band_lu_batch` (vectorised over ω) up to
    :data:`DENSE_LIMIT` unknowns and LAPACK's ``zgbtrf``/``zgbtrs`` per ω
    past it; for wider bands
    (grids: the 30×30 grid's band is 30) SuperLU (``scipy.sparse.linalg.
    splu``) on A permuted symmetrically by a minimum-degree ordering of
    Aᵀ + A found once from the pattern, in its symmetric mode (diagonal
    pivots kept unless below :data:`DIAG_PIVOT_THRESH` of the column's
    largest entry), which fills 2–3× less than partial pivoting on these
    complex symmetric matrices; where the refinement then does not reach
    1e-10, the point is factorised again with partial pivoting.  The
    refinement and its error estimate are the same for either.
    """

    def __init__(self, pat: Pattern, band_max: int | None = None):
        """``band_max``: the widest band solved as one (default :data:`BAND_MAX`); a
        narrower one given leaves ``kind`` "wide" for wider bands (no SuperLU set up)."""
        self.pat = pat
        n, nnz = pat.n, pat.indices.size
        # Small systems keep their own order: no scipy on a sweep's path for
        # the ordering alone (a command's start-up), and a band that only
        # an ordering would make narrow is solved densely (solver()).
        p, ri, ci, kl = band_order(pat.indptr, pat.indices, reorder=n > DENSE_LIMIT)
        self.kl = kl
        if band_max is not None and kl > band_max:
            self.kind = "wide"
        elif kl <= BAND_MAX:
            self.kind = "band"
            self.p = p
            self.band_rows = 3 * kl + 1
            self.dest = (ci, 2 * kl + ri - ci)            # in the (n, rows) C-order array
            self.max_chunk = max(1, min(512, 2 ** 22 // max(1, n * self.band_rows)))
            # The numpy path: the matrices by rows, rb[i, t] = A[i, i − kl + t].
            self.row_dest = (ri, kl + ci - ri)
            # ω per chunk for it, or 0 where LAPACK per ω is taken: past
            # DENSE_LIMIT unknowns (the Python loop over the columns then costs
            # more than a LAPACK call per ω: 5.9 s against 4.1 s on the numpy
            # path of a 5,000-unknown ladder at 401 ω), or too few ω fit.
            chunk = _BAND_BYTES // max(1, 16 * n * self.band_rows)
            self.batch_chunk = chunk if chunk >= BATCH_MIN and n <= DENSE_LIMIT else 0
        else:
            import scipy.sparse as sp
            from scipy.sparse.linalg import splu

            self.kind = "superlu"
            A = sp.csc_matrix((np.ones(nnz), pat.indices, pat.indptr), shape=(n, n))
            # The ordering depends on the pattern only: find it on a
            # nonsingular matrix of the same pattern (the diagonal does not
            # enter a minimum-degree ordering of Aᵀ + A).
            struct = A + sp.identity(n, format="csc") * (n + 1.0)
            perm = np.asarray(splu(struct.tocsc(), permc_spec="MMD_AT_PLUS_A").perm_c)
            iperm = np.argsort(perm)
            self.perm, self.iperm = perm, iperm
            # The pattern permuted symmetrically, and where its data come from.
            where = sp.csc_matrix((np.arange(1, nnz + 1, dtype=float), pat.indices,
                                   pat.indptr), shape=(n, n))[iperm][:, iperm].tocsc()
            where.sort_indices()
            self.take = where.data.astype(np.int64) - 1
            self.indices_p, self.indptr_p = where.indices, where.indptr
            self.max_chunk = 8

    def factor(self, omega, kern=None, strict: bool = False):
        """(good, solve): the frequencies factorised, and a solver for their rows.

        ``kern``: the compiled kernels (:mod:`mechcirc._nodal_kernels`) for
        the banded LU at real ω, or None.  ``strict``: SuperLU with partial pivoting (threshold 1) instead of
        the symmetric mode, where the refinement did not converge.
        """
        pat = self.pat
        if self.kind == "band" and kern is not None and not np.iscomplexobj(omega):
            return self._banded_compiled(kern, np.asarray(omega, dtype=float))
        data = combine(pat.dc, pat.m, pat.k, np.asarray(omega)[:, None])
        good = np.isfinite(data).all(axis=1)
        if self.kind == "band":
            return self._banded(data, good)
        return self._superlu(data, good, strict)

    def _banded_compiled(self, kern, omega):
        """The banded LU by the compiled kernels (the same unblocked LU as LAPACK's zgbtf2).

        No per-ω call overhead, and none of zgbtrf's BLAS calls per column,
        which on a band 1–2 wide cost many times the arithmetic.
        """
        pat, n, kl = self.pat, self.pat.n, self.kl
        F = np.empty((2, n, self.band_rows, omega.size))
        ipiv = np.empty((n, omega.size), dtype=np.int64)
        good = np.ones(omega.size, dtype=bool)
        kern.band_assemble_factor(pat.dc, pat.m, pat.k, omega, self.dest[0], self.dest[1],
                                  kl, F, ipiv, good)
        if not good.all():
            F, ipiv = np.ascontiguousarray(F[..., good]), np.ascontiguousarray(ipiv[:, good])
        p = self.p

        every = np.arange(F.shape[3])

        def solve(r, rows=None):
            rows = every if rows is None else np.asarray(rows, dtype=np.int64)
            out = np.empty((rows.size, n), dtype=complex)
            # writeable too: a read-only r (a broadcast b at one ω) would have numba compile
            # the kernel a second time, for that flag
            kern.band_solve_perm(F, kl, ipiv, rows, p, np.require(r, complex, ("C", "W")), out)
            return out

        def bound(x, d, rows):
            """|x|ᵀP̃|L||U||d| at ``rows`` of x, d (every ω's) and the factors
            (:func:`mechcirc._nodal_kernels.band_bound`)."""
            out = np.empty(rows.size)
            kern.band_bound(F, kl, ipiv, np.asarray(rows, dtype=np.int64), p,
                            np.ascontiguousarray(x, dtype=complex),
                            np.ascontiguousarray(d, dtype=complex), out)
            return out
        return good, _BoundSolve(solve, bound)

    def _banded(self, data, good):
        """The banded LU in numpy, vectorised over the chunk's ω (:func:`band_lu_batch`),
        for small systems; LAPACK's ``zgbtrf``/``zgbtrs`` per ω for larger ones."""
        n, kl, p = self.pat.n, self.kl, self.p
        if not self.batch_chunk:
            return self._banded_lapack(data, good)
        sel = np.flatnonzero(good)
        G = np.zeros((n + kl, 3 * kl + 1, sel.size), dtype=complex)
        G[self.row_dest[0], self.row_dest[1]] = data[sel].T
        piv, ok = band_lu_batch(G, n, kl)
        good[sel[~ok]] = False
        if not ok.all():
            G, piv = G[..., ok], piv[:, ok]
        every = np.arange(piv.shape[1])

        def solve(r, rows=None):
            rows = every if rows is None else np.asarray(rows)
            x = np.zeros((n + 2 * kl, rows.size), dtype=complex)
            x[:n] = np.asarray(r, dtype=complex)[:, p].T
            whole = rows.size == every.size
            band_solve_batch(G if whole else G[..., rows], piv if whole else piv[:, rows],
                             x, n, kl)
            out = np.empty((rows.size, n), dtype=complex)
            out[:, p] = x[:n].T
            return out

        def bound(x, d, rows):
            """|x|ᵀP̃|L||U||d| at ``rows`` of x, d (every ω's) and the factors
            (:func:`band_bound_batch`)."""
            return band_bound_batch(G[..., rows], piv[:, rows], x[rows][:, p].T,
                                    d[rows][:, p].T, n, kl)
        return good, _BoundSolve(solve, bound)

    def _banded_lapack(self, data, good):
        from scipy.linalg.lapack import zgbtrf, zgbtrs

        n, kl = self.pat.n, self.kl
        ab = np.zeros((data.shape[0], n, self.band_rows), dtype=complex)
        ab[:, self.dest[0], self.dest[1]] = data
        p, factors = self.p, []
        for k in np.flatnonzero(good):
            lu, piv, info = zgbtrf(ab[k].T, kl, kl, overwrite_ab=1)
            if info != 0:
                good[k] = False             # exactly singular at this frequency
                continue
            factors.append((lu, piv))

        def solve(r, rows=None):
            rp = np.ascontiguousarray(r[:, p], dtype=complex)
            out = np.empty_like(rp)
            use = factors if rows is None else [factors[i] for i in rows]
            for k, (lu, piv) in enumerate(use):
                out[k] = zgbtrs(lu, kl, kl, rp[k], piv, overwrite_b=1)[0]
            x = np.empty_like(out)
            x[:, p] = out
            return x
        return good, solve

    def _superlu(self, data, good, strict=False):
        import scipy.sparse as sp
        from scipy.sparse.linalg import splu

        n, factors = self.pat.n, []
        for k in np.flatnonzero(good):
            A = sp.csc_matrix((data[k, self.take], self.indices_p, self.indptr_p),
                              shape=(n, n))
            try:
                factors.append(splu(A, permc_spec="NATURAL", options={"SymmetricMode": True},
                                    diag_pivot_thresh=1.0 if strict else DIAG_PIVOT_THRESH))
            except RuntimeError:            # exactly singular at this frequency
                good[k] = False

        def solve(r, rows=None):
            r = np.asarray(r, dtype=complex)[:, self.iperm]
            use = factors if rows is None else [factors[i] for i in rows]
            return np.stack([lu.solve(r[k])[self.perm] for k, lu in enumerate(use)]) if use \
                else np.zeros((0, n), complex)
        return good, solve

