"""Modified nodal analysis of a mechanical circuit, in the mobility analogy.

The system A(ω) x = e_a − e_b, A(ω) = D + C + j(ωM − Kₛ/ω), and K = x_a − x_b
are written once, in :mod:`mechcirc._nodal_equations` (:func:`stamps`,
:func:`assemble`, :func:`combine`, re-exported here).
:func:`solve` solves A(ω) x = e_a − e_b: small systems as
batched dense solves (or batched banded LUs where the band is narrow), large ones by a sparse LU per ω on a fixed pattern
(a banded LU where the band is narrow, SuperLU otherwise; the choice and
the ordering made once from the pattern, see :class:`SparseSolver`).  Each
solution is refined with residuals in double-double arithmetic reusing the
factors (compiled by numba on the sparse path when it is installed:
:mod:`mechcirc._nodal_kernels`), and the last correction gives the error
estimate of K (:class:`Solution`).  Where float64 factors cannot refine
(cond(A) beyond 1/u, as on stiff networks whose K is well conditioned),
a dense LU in double-double of the balanced matrix takes over
(:class:`DDSolver`).  At a singular point K is +∞·j (a pole) or 0 (a zero),
with an infinite error, as the series–parallel method gives it.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, cast

import numpy as np
from numpy.typing import ArrayLike, NDArray

from . import _jit
from ._dd import dd_difference, two_sum
from ._nodal_equations import (KINDS, NodalSystem, assemble, combine, dense_matrices, held,
                               stamps)
from ._nodal_residual import pattern, residual_rounding, row_max, total_error
from ._nodal_steps import bound_point, estimate_point
from ._nodal_solvers import DD_LIMIT, DENSE_LIMIT, balance, dd_solver, solver
from .errors import TopologyError
from .topology import adjacency, reachable

__all__ = ["NodalSystem", "Solution", "assemble", "stamps", "combine", "matrix",
           "dense_matrices", "solve", "solve_unit", "mobility", "mobility_and_error",
           "evaluate_complex", "held",
           "KINDS", "DENSE_LIMIT"]


def matrix(system: NodalSystem, omega: float):
    """A(ω) = D + C + j(ωM − Kₛ/ω) of ``system`` as a sparse CSC matrix.

    Parameters
    ----------
    system : NodalSystem
    omega : float
        [rad/s].

    Returns
    -------
    scipy.sparse.csc_matrix
    """
    return pattern(system).csc(float(omega))


@dataclass(frozen=True)
class Solution:
    """Solutions of A(ω) x = b over ω, with their error estimates.

    Attributes
    ----------
    x : ndarray of complex, shape (n_ω, n), or None
        The refined solutions rounded to complex128 (K itself is formed
        from the unrounded double-double solution); NaN rows where A(ω)
        could not be solved; None when not kept (``keep_x=False``).
    K : ndarray of complex, shape (n_ω,)
        x_a − x_b (the drive's velocity difference per unit force).
    error : ndarray of float, shape (n_ω,)
        Estimated relative error of K: the drive component of the last
        correction of the iterative refinement, plus its own uncertainty
        (the observed contraction × the correction's size), plus the
        residual's rounding in double-double, floored at the rounding to
        float64 (unrefined on the numpy path: the first correction from a
        float64 residual plus the bound on its rounding,
        :func:`mechcirc._nodal_residual.residual_rounding`); where a
        banded LU's first correction is bounded below 16 eps, that bound
        (:func:`first_step_bound`; no second step); ``inf`` where the refinement does not contract or stalls
        even with double-double factors (:class:`DDSolver`, up to
        :data:`DD_LIMIT` unknowns), or A(ω) is not finite.
    singular : ndarray of bool, shape (n_ω,)
        Points on a singularity of A(ω) (exact, or within rounding).
    """

    x: NDArray | None
    K: NDArray[np.complex128]
    error: NDArray[np.float64]
    singular: NDArray[np.bool_]


#: SuperLU points whose refinement leaves a larger estimate than this are
#: factorised again with partial pivoting (:class:`SparseSolver`).
_STRICT_AFTER = 1e-10

#: Work per chunk of frequencies on the numpy path: about this many (ω, term)
#: pairs at once (the residual's temporaries then stay near the caches: at 2¹⁵
#: the numpy sweep of a 999-element ladder took 0.86× the time it took at 2¹⁷,
#: of a 9,999-element one 0.91×).
_CHUNK_TERMS = 2 ** 15
#: The same for the compiled kernels, in (ω, unknown) pairs: no (ω, term) temporaries;
#: each complex (ω, n) array of a chunk is then below 128 kB, from which glibc's malloc
#: maps fresh pages for a block (the numpy steps between the kernels otherwise fault in
#: their temporaries: 7,000 page faults per sweep of a 999-element ladder at 2¹⁴ and
#: 2¹⁶, none at 2¹²; 572 per sweep at 99 elements at 10,100, none at 8,000).  The ω are
#: shared out evenly over the fewest chunks.  Each in processes of its own, alternated
#: (27 Nov, load 3–4), the compiled sweep took at 2¹² 0.74–0.75× its time at 2¹⁶ at
#: 999 elements, 0.73–0.83× at 45, 0.77× at 9,999 (one ω per chunk); at 8,000 (eighth
#: session, load 2) 0.91× its time at 2¹² at 99 elements (3 chunks, not 5).  At 10,400
#: (sixteenth session, Xeon, load 1–2, alternated with 8,000 three times) the sweeps of 45
#: and 99 elements take one chunk and two, not two and three: 1.45–1.48 ms against
#: 1.55–1.57 and 3.22–3.26 against 3.27–3.33 (0 and 321 page faults a sweep against 0 and
#: 281), 999 and 9,999 elements as many chunks as before.  The factors are freed before
#: :meth:`_Solved.store` makes its arrays: a chunk's heap then stays below glibc's trim
#: threshold (twice the largest block freed, the factors), so a sweep does not fault its
#: scratch in again (99 elements alone in a process: 0 page faults a sweep, were 281;
#: 2.79–2.90 ms against 3.17–3.23; after a 45-element run still 278).
_KERNEL_CHUNK = 10400
#: But at least this many ω per chunk of a band, and a multiple of it: the compiled
#: banded LU's loops over ω vectorise (at 500 unknowns it factorises 16 ω in 0.55× the
#: time of 8, at 5,000 in 0.78× the time of 1 ω at a time; 27 Nov, seventh session),
#: more than the larger chunks' page faults cost (sweeps of 999 and 9,999 elements 0.94×
#: and 0.96× the time of the former chunks of 8 and 1 ω each solving with its part of 16 ω
#: factorised);
#: the kernels take 16 ω side by side (a chunk of 20 at 999 elements: 1.1× the time).
_KERNEL_MIN_OMEGA = 16


#: With :data:`mechcirc._jit.COMPILED` None (the default) a sweep of the sparse
#: path uses the compiled kernels (:mod:`mechcirc._nodal_kernels`) only from
#: this many unknowns × ω points on: importing numba and loading the kernels
#: from their cache costs about 0.6 s once per process, while the numpy path
#: takes about 1 µs per unknown and point (about 3× the compiled one).  Decided
#: per sweep from its size, so the same call always takes the same path and
#: gives the same bits: the residual kernel computes the numpy residual to the
#: bit, but the banded LUs differ in rounding (the kernel's against numpy's or
#: LAPACK's), and so do the error estimate's row sums and moduli (one source,
#: :mod:`mechcirc._nodal_steps`), so that K can differ in its last bit and the error estimate, which
#: starts from the first solve's error, by up to 16× (seen on ladders of 45 … 999
#: elements, the estimates between 2.2e-16 and 3.6e-15 on both); until numba's cache
#: holds them (compiling takes 7–12 s) the sweep runs numpy and a process of its
#: own compiles them (:func:`mechcirc._jit.warm_in_background`).
KERNEL_MIN_WORK = 1_000_000
_KERNELS: list = []


def kernels(work: int = 0):
    """The compiled kernel module for a sweep of ``work`` unknowns × points, or None.

    None where :data:`mechcirc._jit.COMPILED` is False, where it is None and
    ``work`` is below :data:`KERNEL_MIN_WORK`, and where numba is not installed.
    """
    if _jit.COMPILED is False or (_jit.COMPILED is None and work < KERNEL_MIN_WORK):
        return None
    if not _KERNELS:
        from . import _nodal_kernels as k

        if k.HAVE_NUMBA and not _jit.use(
                "from mechcirc.nodal import warm_kernels; warm_kernels()", k.residual,
                k.sensitivities, k.estimate, k.update, k.step_bound,
                k.band_assemble_factor, k.band_solve_perm, k.band_bound):
            # Not compiled yet: numpy now (the same numbers), the kernels compiled
            # into numba's cache by a process of their own for a later sweep.
            return None
        _KERNELS.append(k if k.HAVE_NUMBA else None)
    return _KERNELS[0]


def warm_kernels() -> None:
    """Compile the sparse path's kernels into numba's disk cache: a sweep of a
    banded ladder (past :data:`DENSE_LIMIT` unknowns) with the kernels forced on."""
    from .circuit import Circuit, Drive, Element

    n = DENSE_LIMIT + 8
    elements = [Element("damper", "c", "n0", "0", 1.0)]
    for i in range(n):
        elements += [Element("mass", f"m{i}", f"n{i}", f"n{i + 1}", 1.0),
                     Element("spring", f"k{i}", f"n{i + 1}", "0", 1e3)]
    system = assemble(Circuit(tuple(elements), Drive("V", "n0", "0", "velocity", 1.0)))
    saved = _jit.COMPILED
    _jit.COMPILED = True
    try:
        mobility(system, np.array([1.0, 2.0]))
        # The first-step bound, which those two points need not have asked for.
        one = np.ones((1, system.size), complex)
        lu = solver(system).factor(np.array([1.0]), kernels())[1].bound(one, one, np.arange(1))
        first_step_bound(system, np.array([1.0]), one, one, one, np.ones(1), lu, kernels())
    finally:
        _jit.COMPILED = saved


def _sweep(system: NodalSystem, omega: NDArray, refine: bool, steps: int,
           keep: NDArray | None, at: NDArray | None = None, data: bool = False):
    """Factor, solve and refine at each ω (real or complex, already checked) of ``omega[at]``
    (default all), chunk by chunk.

    Returns (K, error of the solve, S, S_data, x rows or None, the rows of x at ``keep``),
    NaN and inf off ``at``; S_data (:meth:`Pattern.sensitivities`) only with ``data``, NaN
    otherwise.  The double-double LU's retry serves real and complex ω alike; the pattern, the solver and the residual's plan come from :func:`pattern` and
    :func:`solver`; the compiled kernels serve the sparse path at real ω (:func:`kernels`).
    """
    pat, rhs = pattern(system), system.injection()
    solve_with, at = solver(system), (np.arange(omega.size) if at is None else at)
    kern = None if solve_with.kind == "dense" or np.iscomplexobj(omega) \
        else kernels(system.size * at.size)
    # Unrefined on the numpy path: the error estimate from a float64 residual (a
    # sixth of the double-double one's work there; the compiled double-double
    # residual costs less than it, and is kept).
    float64 = not refine and kern is None
    out = _Solved(system, pat, kern, omega, keep, float64_residual=float64, data=data)

    # Compiled: no (ω, term) temporaries; the chunk's (ω, n) arrays stay in cache.
    # numpy: the residual's (ω, term) temporaries bound its pieces.
    least = _KERNEL_MIN_OMEGA if kern is not None and solve_with.kind == "band" else 1
    terms = max(least, (_KERNEL_CHUNK // max(1, system.size) if kern is not None
                        else _CHUNK_TERMS // max(1, pat.n_terms + system.size)) // least * least)

    def residual(w, xh, xl, rhs, exact=True):
        if kern is not None or w.size <= terms:
            return pat.residual(w, xh, xl, rhs, kern, exact)
        return np.concatenate([pat.residual(w[i:i + terms], xh[i:i + terms],
                                            None if xl is None else xl[i:i + terms], rhs,
                                            None, exact)
                               for i in range(0, w.size, terms)])

    def refined(solve_fn, w):
        return refine_dd(solve_fn, residual, w, rhs, system, refine, steps, float64=float64,
                         kern=kern)

    # numpy's banded LU loops over columns: as many ω as its memory allows (residual: above).
    chunk = solve_with.batch_chunk if kern is None and solve_with.kind == "band" \
        and solve_with.batch_chunk else min(solve_with.max_chunk, terms)
    chunk = -(-at.size // -(-at.size // chunk)) if at.size else chunk    # even shares
    use_dd = refine and system.size <= DD_LIMIT
    for start in range(0, at.size, chunk):
        every, r = at[start:start + chunk], None    # (the last chunk's x freed first)
        good, solve_fn = solve_with.factor(omega[every], kern)
        sel = every[good]
        if sel.size:
            r = refined(solve_fn, omega[sel])
            solve_fn = None         # (the factors freed before store: see _KERNEL_CHUNK)
            if solve_with.kind == "superlu":
                _strict_retry(solve_with, kern, omega[sel], r, refined)
            out.store(sel, *r)
        if use_dd:
            out.dd_retry(every, refined)
    return out.K, out.err, out.S, out.Sd, out.x_all, out.kept


class _Solved:
    """What :func:`_sweep` finds at each ω, stored chunk by chunk."""

    def __init__(self, system: NodalSystem, pat, kern, omega: NDArray, keep: NDArray | None,
                 float64_residual: bool = False, data: bool = False):
        m = omega.size
        self.system, self.pat, self.kern, self.omega, self.keep = system, pat, kern, omega, keep
        self.K = np.full(m, complex(np.nan, np.nan))
        self.err = np.full(m, np.inf)
        self.S, self.Sd = np.full(m, np.nan), np.full(m, np.nan)
        self.x_all = np.full((m, system.size), complex(np.nan, np.nan)) if keep is None else None
        self.kept: dict[int, NDArray] = {}
        #: The estimates come from a float64 residual (:func:`refine_dd`, unrefined):
        #: its rounding, bounded by :func:`residual_rounding`, is added.
        self.float64_residual = float64_residual
        self.data = data                # S_data too (:func:`evaluate_complex`)

    def store(self, sel, xh, xl, est, rho) -> None:
        """K, its sensitivities and error estimate, and x, at the points ``sel``."""
        K = difference_dd(self.system, xh, xl)
        self.K[sel] = K
        x = xh + xl if xl is not None else xh
        S, Sd = self.pat.sensitivities(self.omega[sel], x, K, self.kern, self.data)
        self.S[sel] = S
        if Sd is not None:
            self.Sd[sel] = Sd
        # A refinement that stalls (corrections not shrinking: the factors
        # are too inaccurate, cond(A)·u ≳ 1) has not converged, unless it
        # stalls at the residual's own rounding: its last correction says
        # nothing of the error (seen: 2.8e-9 and 2.8e-12 with corrections of
        # 1e-11 and 2.6e-16 on a stiff tree, cond(A) ≈ 1e17).  No estimate: inf.
        floor = 16 * residual_rounding(self.system, S)
        if self.float64_residual:
            est = est + residual_rounding(self.system, S, double=False)
        err = np.where((rho >= 0.5) & (est > floor), np.inf, est)
        self.err[sel] = err
        if self.x_all is not None:
            self.x_all[sel] = x
        elif self.keep is not None:
            # Only the rows :func:`solve` may need: where no digit of K is known.
            maybe = self.keep[sel] & ~(np.isfinite(K) & (err < 1.0))
            self.kept.update({int(sel[k]): x[k] for k in np.flatnonzero(maybe)})

    def dd_retry(self, every, refined) -> None:
        """Solve again with the double-double LU where float64 did not converge."""
        # Float64 factors failed (A(ω) exactly singular as rounded to float64),
        # could not refine, or had not converged after ``steps`` (then the
        # last correction is not a safe estimate: 6.6e-14 for a true
        # 1.7e-13 on a stiff tree): the double-double LU.
        err = self.err[every]
        if np.all(err <= 16 * np.finfo(float).eps):
            return                  # (all converged: nothing below would be redone)
        done = np.isfinite(err) & (err <= np.maximum(
            16 * np.finfo(float).eps, 16 * residual_rounding(self.system, self.S[every])))
        todo = every[~done]
        if not todo.size:
            return                  # (nothing to redo: the double-double LU not even built)
        dd = dd_solver(self.system)
        for at in range(0, todo.size, dd.max_chunk):
            redo = todo[at:at + dd.max_chunk]
            ok2, dd_fn = dd.factor(self.omega[redo])
            redo = redo[ok2]
            xh2, xl2, est2, rho2 = refined(dd_fn, self.omega[redo])
            better = ~(est2 >= self.err[redo])
            self.store(redo[better], xh2[better], xl2[better], est2[better], rho2[better])


def _strict_retry(solve_with, kern, omega, refined, refine):
    """Where SuperLU's diagonal pivoting left an estimate above :data:`_STRICT_AFTER`,
    factor again with partial pivoting and keep the better of the two, in place in
    ``refined`` = (xh, xl, est, rho); ``refine(solve, ω)`` refines with a solver."""
    xh, xl, est, rho = refined
    redo = np.flatnonzero(~(est <= _STRICT_AFTER))
    if not len(redo):
        return
    ok2, strict_fn = solve_with.factor(omega[redo], kern, strict=True)
    if ok2.all():
        xh2, xl2, est2, rho2 = refine(strict_fn, omega[redo])
        better = ~(est2 >= est[redo])
        take = redo[better]
        xh[take], est[take], rho[take] = xh2[better], est2[better], rho2[better]
        if xl is not None:
            xl[take] = xl2[better]


def difference_dd(system, xh, xl):
    """K = x_a − x_b from x = xh + xl, rounded once (:func:`mechcirc._dd.dd_difference`)."""
    zero = np.zeros(xh.shape[0], dtype=complex)

    def ends(x):                    # (x_a, x_b), the reference's 0
        return [x[:, i] if i >= 0 else zero for i in (system.a, system.b)]
    with np.errstate(all="ignore"):
        return np.asarray(dd_difference(*ends(xh), *(ends(xl) if xl is not None else (0, 0)),
                                        xl is not None), dtype=complex)


def solve(system: NodalSystem, omega: ArrayLike, *, refine: bool = True,
          steps: int = 4, limits: bool = True, keep_x: bool = True) -> Solution:
    """Solve A(ω) x = e_a − e_b at each ω, refined, with an error estimate of K.

    Small systems (≤ :data:`DENSE_LIMIT` unknowns) are solved as batched dense
    systems, or as batched banded LUs where the band is narrow
    (:data:`mechcirc._nodal_solvers.SMALL_BAND`); large ones by a sparse LU per ω on the fixed pattern (the choice
    of solver and its ordering made once, deterministically: see
    :class:`SparseSolver`).  Refinement reuses the factors: each step is one
    residual in double-double arithmetic (:meth:`Pattern.residual`) and one
    triangular solve, done for a chunk of frequencies at once.  With
    ``keep_x=False`` the solutions are not kept (``Solution.x`` is None),
    which bounds the memory of long sweeps of large networks.

    Parameters
    ----------
    system : NodalSystem
    omega : array_like
        [rad/s].
    refine : bool
        Iterative refinement.
    steps : int
        Most refinement steps.
    limits : bool
        Apply the singular-point convention (K = ∞·j at a pole, 0 at a zero).
    keep_x : bool
        Keep the solutions.

    Returns
    -------
    Solution
        x, K [m/(N·s)], its relative error, the singular points.
    """
    omega = np.asarray(omega, dtype=float).reshape(-1)
    ok = np.isfinite(omega) & (omega > 0)
    K, err, S, Sd, x, kept = _sweep(system, omega, refine, steps, None if keep_x else ok,
                                    np.flatnonzero(ok))
    if not keep_x:
        # Only the rows needed at singular points are kept.
        sing = ~np.isfinite(K) | (err >= 1.0)
        kept = {i: v for i, v in kept.items() if sing[i]}
    rows: Any = x if keep_x else kept
    singular = _singular(system, omega, ok, K, err, rows)
    with np.errstate(all="ignore"):
        # + the rounding of K to float64 (u), which the refinement's
        # estimate of the double-double K does not include.
        err = err + residual_rounding(system, S) + np.finfo(float).eps / 2
        err = np.where(ok, np.maximum(err, np.finfo(float).eps), np.inf)
    if limits:
        K, err = _singular_points(system, omega, rows, K, err, singular, steps)
    return Solution(x, K, err, singular)


def _singular(system: NodalSystem, omega, ok, K, err, rows) -> np.ndarray:
    """Where A(ω) is singular: K not finite, or no digit known and the iterate ``rows[i]``
    a null vector within rounding."""
    # A(ω) exactly singular: a singular point.  A refinement that does not
    # contract (float64 factors, or even the double-double LU: cond(A)
    # beyond about 1e30) says no more than "no digit known": K stays finite
    # with an infinite error (flag 2), never a pole, unless the iterate's
    # backward error says A(ω) is singular within rounding.  The
    # residual-rounding bound in solve is a worst case and not used here.
    singular = ok & ~np.isfinite(K)
    for i in np.flatnonzero(ok & (err >= 1.0) & np.isfinite(K)):
        # Singular if the iterate's element-wise backward error says A(ω) is
        # within rounding of its values of a singular matrix; a stiff
        # network's garbage iterate is not (seen with the double-double LU
        # too, cond(A) beyond 1e30 at regular ω of a tree).
        singular[i] = _backward_error(system, omega[i], rows[i]) <= SINGULAR_BACKWARD
    return singular


#: A point whose refinement by float64 factors does not contract is singular
#: when changing every element value and lever ratio by at most this
#: (relative) makes A(ω) x = 0 for the iterate x (its element-wise backward error).
SINGULAR_BACKWARD = 2.0 ** -43


def _backward_error(system, omega: float, x: NDArray) -> float:
    """max_i |(A x)_i| / Σ |stamp·x| over row i, by element (see :data:`SINGULAR_BACKWARD`).

    An element's stamps enter as y_e·|x_i − x_j| (rounding its value moves
    all four together), a lever stamp as |value·x_c|.  A x from the
    residual in double-double.
    """
    pat, rhs = pattern(system), system.injection()
    with np.errstate(all="ignore"):
        ax = rhs - pat.residual(np.array([omega]), x[None, :], None, rhs,
                                kernels(system.size))[0]      # (the same bits either way)
        xe = np.append(np.asarray(x, dtype=complex), 0.0)
        y = np.abs(combine(pat.e_c, pat.e_m, pat.e_k, omega))
        t = y * np.abs(xe[pat.e_i] - xe[pat.e_j])
        n1 = pat.n + 1
        den = np.bincount(pat.e_i, t, n1) + np.bincount(pat.e_j, t, n1) + \
            np.bincount(pat.s_row, np.abs(pat.s_val * xe[pat.s_col]), n1)
        eta = np.abs(ax) / den[:-1]
        return float(np.max(np.where(np.abs(ax) == 0, 0.0, eta), initial=0.0))


def refine_dd(solve_fn, residual, omega, rhs, system, refine: bool, steps: int,
              float64: bool = False, kern=None):
    """x from one solve and up to ``steps`` refinement steps.

    Returns (xh, xl, relative error of K, contraction of the last step):
    x = xh + xl in double-double (xl None without refinement).  ``float64``:
    without refinement, the estimate from a float64 residual
    (``residual(..., exact=False)``), the rounding of b − A x̂ included
    (that of the terms is added by the caller, which has S).  ``kern``: the
    compiled kernels (:func:`kernels`), which run the steps between them too.
    """
    eps = np.finfo(float).eps
    x0 = solve_fn(np.repeat(rhs.astype(complex)[None, :], omega.size, axis=0))
    if not refine:
        # No refinement: the first correction is still the error estimate, from
        # a double-double residual or a float64 one (a sixth of its work); the
        # latter's rounding is bounded in _Solved.store (residual_rounding,
        # double=False) and here (that of b − A x̂ itself, u |x̂|ᵀ|r̂| / |K|).
        r = residual(omega, x0, None, rhs, exact=not float64)
        est, rho = _estimate(system, x0, None, solve_fn(r), None, r, kern)   # (kern None if float64)
        if not float64:
            return x0, None, est, rho
        with np.errstate(all="ignore"):
            own = eps / 2 * np.sum(np.abs(x0) * np.abs(r), axis=-1) / \
                np.abs(system.difference(x0))
        return x0, None, est + np.where(np.isnan(own), np.inf, own), rho
    # x0 a solve's own; the first step, over every point, sets xl and prev (read only
    # from the second step on), unless there is no step.
    xh = x0
    xl: Any = np.zeros_like(x0) if steps < 1 else None
    prev: Any = None
    est, rho = np.full(omega.size, np.inf), np.zeros(omega.size)
    active = np.arange(omega.size)
    for step in range(steps):
        # Only the points not yet converged take a further step (their
        # factors chosen by ``rows``); while all do, the arrays are used whole
        # (slices: the same values as indexed by ``active``, without the copies).
        whole = active.size == omega.size
        at: Any = slice(None) if whole else active
        xa, xla = xh[at], (xl[at] if step else None)
        r = residual(omega[at], xa, xla, rhs)
        d = solve_fn(r) if whole else solve_fn(r, active)
        est[at], rho[at] = _estimate(system, xa, xla, d, prev[at] if step else None, r, kern)
        if kern is not None:
            # In place: xa is xh's or a copy of its rows, and the residual becomes xl's
            # low parts (r is then |x₁|ᵀ|r| for the first-step bound).
            s, e = np.ascontiguousarray(xa), r
            r = np.empty(s.shape[0])
            kern.update(s, d, s if xla is None else xla, xla is not None, e, r, step == 0)
        else:
            with np.errstate(all="ignore"):
                s, e = two_sum(xa, d)
            if xla is not None:
                e = xla + e
        if whole:
            # Every point: the new arrays (each its own) are kept, not copied.
            xh, xl, prev = s, e, d
        else:
            xh[at], xl[at], prev[at] = s, e, d
        # est bounds the error before this correction; after it, the error is
        # smaller still (by the contraction): stop once est is near rounding.
        active = active[est[active] > 16 * eps]
        bound = getattr(solve_fn, "bound", None)
        if step == 0 and bound is not None and active.size:
            # Or once the error after it is bounded by 16 eps (first_step_bound), at the
            # active points, their rows read in place: copies of them would stack three
            # (ω, n) arrays on the factors, above glibc's trim threshold (twice the
            # factors), and every later sweep would fault its scratch in again (45
            # elements: 259 page faults a sweep, 1.67 against 1.32 ms).
            first = first_step_bound(system, omega, xh, xl, d, r, bound(xh, d, active),
                                     kern, rows=active)
            proven = first <= 16 * eps
            est[active[proven]] = first[proven]
            active = active[~proven]
        if not active.size:
            break
    return xh, xl, est, rho


def first_step_bound(system: NodalSystem, omega: NDArray, xh: NDArray, xl: NDArray,
                     d: NDArray, r: NDArray, lu: NDArray, kern=None,
                     rows: NDArray | None = None) -> NDArray:
    """A bound on the relative error of K at x₁ = xh + xl = x₀ + d after the first
    correction d, without the residual of x₁ (that residual pass is then not taken).

    The computed d solves (Â + ΔA) d = r̂ with |ΔA| ≤ γ P̃|L||U| (Higham, Accuracy and
    Stability of Numerical Algorithms, Thm 9.4: γ₃ₙ for real arithmetic, here 8(n + 2)u ≥
    √2·γ₃ₙ₊₆ for complex products; ``lu`` = |x|ᵀP̃|L||U||d| from the factors), where Â is
    A(ω) rounded to float64: each entry sums at most m stamps (the most of a row) and
    applies ω, |Â − A| ≤ (m + 4)u Σ|stamp|.  So r₁ = b − A x₁ = (r₀ − r̂) + ΔA d + (Â − A) d,
    and as A is complex symmetric and K = cᵀA⁻¹c, K − K₁ = xᵀr₁: |K − K₁| ≤ γ·lu +
    u |x|ᵀ|r̂| + (m + 4)u (Σ_e |y_e| (|x_i| + |x_j|)(|d_i| + |d_j|) + Σ_levers |v| |x_r| |d_c|)
    + |x|ᵀ|r₀ − r̂₀|, the last (the double-double residual's rounding) added to every
    estimate (:func:`solve`).  |z| is bounded by |re| + |im| and x by x₁ (first order): the
    sum is doubled.  Asked where the solver has a ``bound``: the banded LUs
    (:func:`mechcirc._nodal_solvers.band_bound_batch`, and the compiled
    :func:`mechcirc._nodal_kernels.band_bound`, whose multipliers, an entry times the
    pivot's reciprocal, carry a few u more than a quotient: within the (3.7n + 7.5)u that
    8(n + 2)u leaves above √2·γ₃ₙ₊₆, over 50u from the 12 unknowns of a band on).

    Parameters
    ----------
    system : NodalSystem
    omega : ndarray
        [rad/s], shape (c,).
    xh, xl, d, r : ndarray of complex, shape (c, n)
        x₁ in double-double, the first correction and its residual (with ``kern``, r is
        |x₁|ᵀ|r|, shape (c,)).
    lu : ndarray
        |x|ᵀP̃|L||U||d| at ``rows`` (:func:`mechcirc._nodal_solvers.band_bound_batch`).
    kern : module or None
        The compiled kernels (:func:`kernels`) or None.
    rows : ndarray of int, optional
        The rows asked for (default all), read in place by the kernels.

    Returns
    -------
    ndarray, shape (len(rows),)
    """
    pat = pattern(system)
    rows = np.arange(omega.size) if rows is None else np.asarray(rows, dtype=np.int64)
    if kern is not None:
        out = np.empty(rows.size)
        kern.step_bound(rows, *map(np.ascontiguousarray, (omega, xh, xl, d, r, lu)),
                        *_ends(system), pat.e_i, pat.e_j, pat.e_abs, pat.s_row, pat.s_col,
                        pat.s_abs, pat.max_row_terms, out)
        return out
    at: Any = slice(None) if rows.size == omega.size else rows      # (no copies of all)
    return _step_bound_numpy(system, pat, omega[at], xh[at], xl[at], d[at], r[at], lu)


def _step_bound_numpy(system, pat, omega, xh, xl, d, r, lu) -> NDArray:
    """:func:`first_step_bound` in numpy, at every row of the arrays given."""
    with np.errstate(all="ignore"):
        c, n = xh.shape
        zero = np.zeros((c, 1))                 # (the reference's column)
        ax, ad = (np.concatenate([np.abs(v.real) + np.abs(v.imag), zero], axis=1) for v in (xh, d))
        # |y_e| = |c_e| + |ω||m_e| + |k_e|/|ω| (one of the three is nonzero; ω complex
        # too): by kind, one product with the (c, E) array, no admittance array.
        ends = ax.take(pat.e_i, 1) + ax.take(pat.e_j, 1)     # (take: x[:, idx], faster)
        by_kind = (ends * (ad.take(pat.e_i, 1) + ad.take(pat.e_j, 1))) @ pat.e_abs
        lever = pat.s_abs @ (ax.take(pat.s_row, 1) * ad.take(pat.s_col, 1)).T \
            if pat.s_row.size else 0.0
        rounding = np.einsum("ci,ci->c", ax[:, :n], np.abs(r.real) + np.abs(r.imag))
        return bound_point(lu, rounding, *by_kind.T, lever, np.abs(omega),
                           np.abs(difference_dd(system, xh, xl)), n, pat.max_row_terms)


def _ends(system) -> tuple[int, int]:
    """The drive's rows a, b for the compiled kernels: n (a column of zeros) for the reference."""
    n = system.size
    return (system.a if system.a >= 0 else n, system.b if system.b >= 0 else n)


def _estimate(system, xh, xl, d, prev, r, kern=None):
    """(Relative error of K = x_a − x_b before applying the correction ``d``, contraction ρ).

    |d_a − d_b| estimates the error of K; ``d`` itself is wrong by about the
    contraction ρ = ‖d‖/‖prev‖ times the size of its drive components, which
    is added (the first correction, ``prev`` None, has no contraction measured
    yet: ρ = 1 there; the ρ returned compares it with x).  The error of K is also xᵀ r to first order, from the residual
    ``r`` alone (A is complex symmetric and K = cᵀ A⁻¹ c with A x = c: the
    adjoint solution is x), without the factors: where float64 factors are
    blind to a direction of r (cond(A)·u ≳ 1), d misses it and the larger
    of the two is kept.  A correction
    as large as x itself that does not contract means A is numerically
    singular: inf.
    """
    if kern is not None:            # (C arrays: the one signature warm_kernels compiles)
        est, rho = np.empty(xh.shape[0]), np.empty(xh.shape[0])
        kern.estimate(*map(np.ascontiguousarray, (xh, xh if xl is None else xl, d,
                                                  xh if prev is None else prev, r)),
                      *_ends(system), xl is not None, prev is None, est, rho)
        return est, rho
    with np.errstate(all="ignore"):
        nx = row_max(np.abs(xh))
        da, db = (np.abs(d[..., i]) if i >= 0 else 0.0 for i in (system.a, system.b))
        return estimate_point(row_max(np.abs(d)), nx, nx if prev is None else
                              row_max(np.abs(prev)), np.abs(difference_dd(system, xh, xl)),
                              np.abs(system.difference(d)), da, db,
                              np.abs(np.sum(xh * r, axis=-1)), prev is None)


def _singular_points(system, omega, x, K, err, singular, steps):
    """Apply the singular-point convention where A(ω) is (numerically) singular.

    Where the solution blows up along a mode seen from the drive (a pole of
    K), K = +∞·j (the series–parallel method's convention); where K carries no correct digit otherwise, K = 0 (a
    zero of K within rounding).  The estimate there is inf; ``Sweep.flags``
    marks both as singular (flag 1).  ``x`` gives the solution's row at
    each singular point (an array, or a dict of rows).
    """
    K, err = K.copy(), err.copy()
    for i in np.flatnonzero(singular):
        xi = x.get(i) if isinstance(x, dict) else x[i]
        Ki = K[i]
        if xi is None or not np.isfinite(Ki):
            # Exactly singular: look just above ω, where the solution is the mode.
            w = omega[i] * (1 + 2.0 ** -40)
            s = solve(system, [w], refine=False, steps=steps, limits=False) \
                if np.isfinite(w) else None
            if s is None or not np.isfinite(s.K[0]):
                continue                    # undetermined: NaN, flagged singular
            xi, Ki = s.x[0], s.K[0]
        scale = float(np.max(np.abs(xi)))
        # The tree's convention: +∞·j at a pole.
        K[i] = complex(0.0, np.inf) if abs(Ki) >= 1e-3 * scale else 0.0
        err[i] = np.inf
    return K, err


def solve_unit(system: NodalSystem, omega: ArrayLike, *, refine: bool = True
               ) -> NDArray[np.complex128]:
    """Solutions x(ω) of A(ω) x = e_a − e_b, shape (n_omega, n), complex128.

    With ``refine`` (the default) each solution gets iterative refinement
    with the residual b − A x computed in double-double arithmetic, reusing
    the LU factors: the forward error then no longer grows with the
    condition number of A (masses and springs of very different size in
    series).  See :func:`solve` for the error estimate.

    Frequencies where A is exactly singular, or ω is 0 or ∞ (where A is not
    finite), give rows of NaN; callers flag them.

    Parameters
    ----------
    system, omega, refine
        As in :func:`solve`.

    Returns
    -------
    ndarray of complex
    """
    return cast(NDArray[np.complex128], solve(system, omega, refine=refine).x)


def evaluate_complex(system: NodalSystem, s: ArrayLike
                     ) -> tuple[NDArray[np.complex128], NDArray[np.float64]]:
    """K(s) at complex frequencies s (jω on the axis) and its estimated absolute error.

    A(s) = D + C + sM + Kₛ/s is :func:`combine` at ω = −js.  Each solution is
    refined with residuals in double-double as in :func:`solve`, and the
    error is the same estimate (the last correction, the residual's own
    rounding and the sensitivity to rounding the data, eps × Σ|x_r a_rc x_c|):
    used to polish resonances on the circuit's own K.  Where float64 factors do
    not refine (A(s) within rounding of singular: a root of the other kind close
    by), the double-double LU solves again, off the jω axis as on it: float64
    refinement there gave K of no digit, or a wrong K with a small estimate (an
    anti-resonance 3.1e-13 off, said to be good to 2.1e-15).  NaN where A(s) is
    singular.

    Parameters
    ----------
    system : NodalSystem
    s : array_like of complex
        [rad/s].

    Returns
    -------
    tuple of (ndarray of complex, ndarray)
        K(s) [m/(N·s)] and its absolute error.
    """
    s = np.asarray(s, dtype=complex).reshape(-1)
    # On the jω axis A(s) is A(ω) at real ω = Im s: the real path (the compiled kernels
    # and the double-double LU's retry serve it).
    omega = s.imag.copy() if s.size and not s.real.any() else -1j * s
    K, est, S, Sd, _, _ = _sweep(system, omega, True, 4, None, data=True)
    est = total_error(Sd, est + residual_rounding(system, S))
    with np.errstate(all="ignore"):
        return K, est * np.abs(K)


def mobility(system: NodalSystem, omega: ArrayLike) -> NDArray[np.complex128]:
    """K(ω) [m/(N·s)] seen by the drive, by nodal analysis: :func:`mobility_and_error`'s K.

    Parameters
    ----------
    system : NodalSystem
    omega : array_like
        [rad/s].

    Returns
    -------
    ndarray of complex
    """
    return mobility_and_error(system, omega)[0]


def mobility_and_error(system: NodalSystem, omega: ArrayLike
                       ) -> tuple[NDArray[np.complex128], NDArray[np.float64]]:
    """K(ω) [m/(N·s)] and its estimated relative error, from one refined solve
    (:class:`Solution` tells the estimate and the singular-point convention).

    Parameters
    ----------
    system, omega
        As in :func:`mobility`.

    Returns
    -------
    tuple of (ndarray of complex, ndarray)
    """
    s = solve(system, omega, keep_x=False)
    return s.K, s.error


def mobility_unrefined(system: NodalSystem, omega: ArrayLike) -> NDArray[np.complex128]:
    """K(ω) [m/(N·s)] by one plain solve per ω, without refinement (the fast path).

    Its relative error is about eps × cond(A(ω)) (:func:`solve` refines it away).
    """
    return solve(system, omega, refine=False, limits=False, keep_x=False).K


def element_response(system: NodalSystem, omega: ArrayLike, scale: NDArray, *,
                     refine: bool = True) -> dict[str, tuple]:
    """``{name: (Q, v)}`` for every loaded element, for a drive force ``scale`` [N] per ω
    (solved with or without ``refine``, as :func:`solve_unit`)."""
    omega = np.asarray(omega, dtype=float)
    x = solve_unit(system, omega, refine=refine)
    index = {n: i for i, n in enumerate(system.nodes)}
    out = {}
    with np.errstate(all="ignore"):
        for e in system.elements:
            v = system.difference(x, index.get(e.n1, -1), index.get(e.n2, -1)) * scale
            out[e.name] = (v / e.mobility(omega), v)
    return out



def require_nonsingular(system: NodalSystem, source: str | None = None) -> None:
    """Raise if A(ω) is singular at every frequency (checked at two generic ω), or if
    the levers hold the drive's nodes together (K = 0 at every ω; ``source``, the
    netlist's name, locates that error at the first lever to blame).

    Dense systems are first judged by the smallest singular value of the
    matrix, as it is and then balanced (:func:`_balance`; balancing only
    keeps a regular matrix from looking singular), and the null vector of the
    balanced one names the undetermined unknowns.  Where that does not clear a system, or it is
    large, the refined solve decides (in double-double where float64 factors
    cannot refine, see :class:`DDSolver`): the system is regular at a trial
    ω if the solve gives a finite K and its solution's element-wise backward
    error as a null vector is above rounding (:func:`_backward_error`) — so a
    stiff network (cond(A) of 1e20, K well conditioned) is not refused.

    A network without levers whose elements' values v·η are all finite and
    positive is regular without a trial: its unknowns are the nodes of the
    connected block that holds the drive (:func:`assemble`), so A(s) =
    D + sM + Kₛ/s at real s > 0 is a weighted Laplacian of a connected graph
    with the reference's row dropped, positive definite; det A(s) is then not
    identically zero and vanishes at finitely many s only.
    """
    if system.size == 0:
        raise TopologyError(
            "nothing between the drive's nodes carries force (no unknowns left; unloaded: "
            f"{', '.join(system.unloaded[:12]) or 'none'})", elements=system.unloaded)
    _require_drive_free(system, source)
    values = pattern(system).e_val
    if not system.levers and ((values > 0) & (values < np.inf)).all():
        return
    scale = _frequency_scale(system)
    trial = [0.731 * scale, 1.913 * scale]
    regular, judged, overflow = _dense_verdict(system, trial)
    if regular:
        return
    s = solve(system, trial, limits=False)
    for i, w in enumerate(trial):
        # Values over ~600 decades: an iterate with no digit known (not even
        # from the double-double LU) does not show the network regular.
        if np.isfinite(s.K[i]) and not s.singular[i] and (s.error[i] < 1 or not overflow) \
                and _backward_error(system, w, cast(NDArray, s.x)[i]) > SINGULAR_BACKWARD:
            return
    if judged is None:
        raise TopologyError("the network is singular at every frequency (tried "
                            f"ω = {trial[0]:.4g} and {trial[1]:.4g} rad/s)" + (
                                ", or its values span more decades than float64 holds"
                                if overflow else ""))
    _, _, vh = np.linalg.svd(judged)
    null = np.abs(vh[-1].conj())
    names = list(system.nodes) + [f"lever {lv.name}" for lv in system.levers]
    culprits = [names[i] for i in np.flatnonzero(null > 1e-6 * null.max())]
    raise TopologyError(
        "the network is singular at every frequency (its velocities or lever forces "
        f"are not determined): {', '.join(culprits[:12])}; check for levers in parallel "
        "or nodes tied only by levers", nodes=[c for c in culprits if not c.startswith("lever")],
        elements=[c[6:] for c in culprits if c.startswith("lever")])


#: Most levers :func:`_require_drive_free` judges (those linked to the drive's nodes
#: through shared nodes; a dense SVD of theirs): beyond, the sweep's flags speak.
LOCK_DENSE_LEVERS = 2000


def _require_drive_free(system: NodalSystem, source: str | None = None) -> None:
    """Raise where the levers alone hold the drive's nodes together: K = 0 at every ω.

    The levers' rows G x = 0 (x the node velocities) fix x_a − x_b = cᵀx when c lies
    in the row space of G: two levers between the same nodes at ratios that do not
    agree, or a lever from the drive onto itself.  No force then moves the drive,
    whatever the masses, springs and dampers; the solve gave K of a few units of
    rounding (|Q0| of 1e67 N "located", random network 32 of seed 2) or a resonance
    that is not there (levers in parallel at ratios 2 and 3).  Judged on the levers
    linked to the drive's nodes, G balanced by powers of 2 (ratios span up to 600
    decades): c is in its row space when appending c does not raise the numerical
    rank (singular values above 10·max(shape)·u·max|entry|); the error names them all.
    """
    n = len(system.nodes)
    rows, cols, vals = (np.asarray(a) for a in system.stamps["lever"])
    rows, cols, vals = (x[(rows >= n) & (cols < n)] for x in (rows - n, cols, vals))
    ends = [i for i in (system.a, system.b) if i >= 0]
    # The levers ("L" r) linked to the drive's nodes through the nodes ("N" c) they share
    adj = adjacency((f"L{r}", f"N{c}") for r, c in zip(rows.tolist(), cols.tolist()))
    levers = sorted({int(x[1:]) for e in ends for x in reachable(adj, f"N{e}") if x[0] == "L"})
    if not levers or len(levers) > LOCK_DENSE_LEVERS or not np.isfinite(vals).all():
        return                          # (values beyond float64: the trial solves judge)
    pick = np.isin(rows, levers)
    nodes = np.unique(np.concatenate([cols[pick], ends]))
    G = np.zeros((len(levers), nodes.size))
    np.add.at(G, (np.searchsorted(levers, rows[pick]), np.searchsorted(nodes, cols[pick])),
              vals[pick])
    c = system.injection()[nodes]
    for _ in range(4):                  # rows, then columns, to a largest |entry| in [1, 2)
        G = np.ldexp(G, 1 - np.frexp(np.abs(G).max(axis=1, keepdims=True))[1])
        e = np.where(G.any(axis=0), 1 - np.frexp(np.abs(G).max(axis=0))[1], 0)
        G, c = np.ldexp(G, e), np.ldexp(c, e)
    rank = [np.linalg.matrix_rank(X, 10 * max(X.shape) * np.finfo(float).eps * np.abs(X).max())
            for X in (G, np.vstack([G, c / np.abs(c).max()]))]
    if rank[1] > rank[0]:
        return
    held = [system.levers[i] for i in levers]
    raise TopologyError(
        f"the lever(s) {', '.join(lv.name for lv in held[:12])} hold the drive's two nodes "
        "together: K = 0 at every frequency, no force moves the drive (check those "
        "levers' ratios and sides)", nodes=[system.nodes[i] for i in ends],
        elements=[lv.name for lv in held],
        location=f"{source}:{held[0].line}:1" if source and held[0].line else None)


def _dense_verdict(system: NodalSystem, trial):
    """(regular, judged, overflow) of a small system by the singular values at ``trial``.

    ``regular``: a trial ω's matrix, as it is or balanced, is clearly
    nonsingular (:func:`_clearly_regular`; or at float64's edge, which the
    sweep flags); ``judged``: the last balanced
    matrix that looked singular, for naming the null vector (None when none
    was judged: large systems, or balancing overflowed); ``overflow``:
    balancing overflowed (values over ~600 decades, such as a lever ratio of
    1e300), so the refined solve decides.
    """
    judged, overflow = None, False
    if system.size > DENSE_LIMIT:
        return False, judged, overflow
    for w in trial:
        A = pattern(system).dense(w)        # (dense_matrices' bits, without its four sums)
        # Values at float64's edge: the sweep flags them (balancing only keeps a regular A
        # from looking singular).
        if not np.isfinite(A).all() or _clearly_regular(A):
            return True, judged, overflow
        absdiag = [np.abs(system.diagonal("damper") + system.diagonal("lever")),
                   np.abs(system.diagonal("mass")), np.abs(system.diagonal("spring"))]
        # Judge the balanced matrix: a lever of ratio 1e-8 puts entries of 1e-8
        # beside 1, every value scaled by 1e-100 puts admittances of 1e-100 beside
        # the lever's ±1, and the raw singular values then look singular.
        diag = absdiag[0] + w * absdiag[1] + absdiag[2] / w
        d = balance(np.abs(A)[None], diag[None])[0]
        with np.errstate(all="ignore"):
            A = A * d[:, None] * d[None, :]
        if not np.isfinite(A).all():
            overflow = True
            continue
        if _clearly_regular(A):
            return True, judged, overflow
        judged = A
    return False, judged, overflow


def _clearly_regular(A) -> bool:
    """σ_min(A) > 1e-13 σ_max(A): A is nonsingular, far beyond the SVD's rounding (≈ u σ_max)."""
    sv = np.linalg.svd(A, compute_uv=False)
    return bool(sv[-1] > 1e-13 * sv[0])


def _frequency_scale(system: NodalSystem) -> float:
    """A characteristic ω [rad/s] of the system: sqrt(trace Kₛ / trace M), or 1."""
    # Sum after scaling by the largest entry: masses near 1e308 would overflow.
    dm, dk = np.abs(system.diagonal("mass")), np.abs(system.diagonal("spring"))
    if dm.size and dm.max() > 0 and dk.max() > 0:
        mm, mk = dm.max(), dk.max()
        with np.errstate(all="ignore"):
            scale = np.sqrt(mk) / np.sqrt(mm) * np.sqrt((dk / mk).sum() / (dm / mm).sum())
        if np.isfinite(scale) and scale > 0:
            return float(scale)
    return 1.0
