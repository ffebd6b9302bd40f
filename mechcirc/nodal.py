"""Modified nodal analysis of a mechanical circuit, in the mobility analogy.

Force plays the part of current and velocity that of voltage.  Unknowns are
the velocities of the nodes (the frame is the reference, velocity 0) and one
force per lever.  Each element stamps its admittance S = 1/K between its
nodes, so that the system matrix is

    A(ω) = D + C + j (ω M − Kₛ / ω)

with M the masses (S = jωm·η), Kₛ the springs (S = k·η/(jω)), D the dampers
(S = c·η) and C the constant lever block: a lever of ratio r adds the unknown
Q_S with KCL entries (r at p1, −r at p2, −1 at s1, +1 at s2) and the
constraint row r(v_p1 − v_p2) − (v_s1 − v_s2) = 0; C is symmetric.

K seen by the drive is the velocity difference between its nodes for a unit
force injected at n1 and taken out at n2.

This module is the one place the nodal equations are written:
:func:`stamps` stamps every element and lever, :func:`assemble` builds the
matrices (of the loaded part, or with ``whole=True`` of the whole network,
as the time domain and two-ports need them), and :func:`combine` forms
A(ω) from them.  :func:`solve` solves A(ω) x = e_a − e_b: small systems as
batched dense solves, large ones by a sparse LU per ω on a fixed pattern
(ordering found once; LAPACK's banded LU where the band is narrow).  Each
solution is refined with residuals in extended precision reusing the
factors, and the last correction gives the error estimate of K
(:class:`Solution`).  At a singular point K is +∞·j (a pole) or 0 (a zero),
with an infinite error, as the series–parallel method gives it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .circuit import FRAME, Circuit, Element, Lever
from .errors import TopologyError
from .topology import check_frame_paths, force_groups, loaded_groups, node_names

__all__ = ["NodalSystem", "Solution", "assemble", "stamps", "combine", "matrix",
           "dense_matrices", "solve", "solve_unit", "mobility", "mobility_and_error",
           "evaluate_complex", "held",
           "KINDS", "DENSE_LIMIT"]

#: Systems with at most this many unknowns use batched dense solves.
DENSE_LIMIT = 60
#: Memory bound for one chunk of batched dense matrices [bytes].
_CHUNK_BYTES = 32 * 2**20


@dataclass(frozen=True, eq=False)
class NodalSystem:
    """The nodal matrices of the loaded part of a circuit.

    Attributes
    ----------
    nodes : tuple of str
        Unknown node velocities, in matrix order (the reference node excluded).
    levers : tuple of Lever
        Lever force unknowns follow the nodes, in this order.
    elements : tuple of Element
        The elements that carry force.
    unloaded : tuple of str
        Elements and levers on no path between the drive's nodes.
    M, D, Ks, C : scipy.sparse.csr_matrix, shape (n, n)
        Mass [kg], damping [N·s/m], stiffness [N/m] and lever matrices.
    a, b : int
        Indices of the drive's nodes, −1 for the reference node.
    stamps : dict
        The unsummed entries ``kind -> (rows, cols, values)`` of M, D, Kₛ and C,
        for residuals in extended precision (a summed diagonal is already rounded).
    """

    nodes: tuple[str, ...]
    levers: tuple[Lever, ...]
    elements: tuple[Element, ...]
    unloaded: tuple[str, ...]
    M: object
    D: object
    Ks: object
    C: object
    a: int
    b: int
    stamps: dict = None

    @property
    def size(self) -> int:
        """Number of unknowns (node velocities and lever forces)."""
        return self.M.shape[0]

    def injection(self) -> NDArray[np.float64]:
        """Right-hand side: unit force into node a, out of node b."""
        rhs = np.zeros(self.size)
        if self.a >= 0:
            rhs[self.a] += 1.0
        if self.b >= 0:
            rhs[self.b] -= 1.0
        return rhs

    def difference(self, x: NDArray) -> NDArray:
        """Velocity difference v_a − v_b from solutions ``x`` of shape (..., n)."""
        out = np.zeros(x.shape[:-1], dtype=x.dtype)
        if self.a >= 0:
            out = out + x[..., self.a]
        if self.b >= 0:
            out = out - x[..., self.b]
        return out


def assemble(circuit: Circuit, whole: bool = False) -> NodalSystem:
    """Build the nodal matrices of the part of ``circuit`` that carries force.

    With ``whole=True`` every element and lever is kept, loaded by the drive
    or not, no drive is needed, and nothing is checked: the matrices of
    M ẍ + D ẋ + Kₛ x = f for the whole network (velocities referred to the
    frame ``"0"``, or to the drive's second node where there is no frame), as
    the time-domain (:mod:`mechcirc.transient`) and two-port analyses need
    them.  ``a`` and ``b`` index the drive's nodes (−1 where a node is the
    reference or there is no drive).

    Raises
    ------
    TopologyError
        If the drive's nodes are not connected or a node is reached only
        through a lever's other side (singular at every frequency); not
        with ``whole=True``.
    """
    d = circuit.drive
    if whole:
        elements, levers, unloaded = tuple(circuit.elements), tuple(circuit.levers), ()
    else:
        check_frame_paths(circuit)
        groups = force_groups(circuit.elements, circuit.levers)
        kept = set(loaded_groups(groups, d.n1, d.n2, drive_line=d.line,
                                 source=circuit.source))
        n_el = len(circuit.elements)
        elements = tuple(e for i, e in enumerate(circuit.elements) if i in kept)
        levers = tuple(lv for i, lv in enumerate(circuit.levers) if n_el + i in kept)
        unloaded = tuple(e.name for i, e in enumerate(circuit.elements) if i not in kept) + \
            tuple(lv.name for i, lv in enumerate(circuit.levers) if n_el + i not in kept)

    names = node_names(elements, levers)
    reference = FRAME if FRAME in names or d is None or not names else d.n2
    nodes = tuple(n for n in names if n != reference)
    index = {n: i for i, n in enumerate(nodes)}
    index[reference] = -1
    import scipy.sparse as sp

    n = len(nodes) + len(levers)
    triplets: dict[str, tuple[list, list, list]] = {k: ([], [], []) for k in KINDS}
    for kind, row, col, sign, source, ratio in stamps(elements, levers, index):
        rows, cols, vals = triplets[kind]
        rows.append(row)
        cols.append(col)
        vals.append(sign * (source.ratio if ratio else 1.0) if kind == "lever"
                    else sign * source.value * source.eta)
    M, D, Ks, C = (sp.csr_matrix((v, (r, c)), shape=(n, n))
                   for r, c, v in (triplets[k] for k in KINDS))
    stamped = {kind: tuple(np.asarray(a) for a in t) for kind, t in triplets.items()}
    return NodalSystem(nodes, levers, elements, unloaded, M, D, Ks, C,
                       index.get(d.n1, -1) if d else -1, index.get(d.n2, -1) if d else -1,
                       stamped)


#: The four matrices of a nodal system, in the order of :class:`NodalSystem`.
KINDS = ("mass", "damper", "spring", "lever")


def stamps(elements, levers, index: dict[str, int]):
    """Every unsummed entry of the nodal matrices — the one place elements are stamped.

    Yields ``(kind, row, col, sign, source, ratio)``: ``kind`` one of
    :data:`KINDS`; ``source`` the :class:`Element` or :class:`Lever`; the entry
    is ``sign × value × eta`` of an element, and ``sign × ratio`` (``ratio``
    true) or ``sign × 1`` of a lever.  ``index`` maps node names to rows (−1
    for the reference node, whose rows are dropped); lever force unknowns
    follow the ``max(index) + 1`` node rows, in order.  The numeric matrices
    (:func:`assemble`) and the symbolic ones (:mod:`mechcirc.interop.formula`)
    are both built from these entries.
    """
    n_nodes = sum(1 for i in index.values() if i >= 0)
    for e in elements:
        i, j = index[e.n1], index[e.n2]
        for r, c, s in ((i, i, 1.0), (j, j, 1.0), (i, j, -1.0), (j, i, -1.0)):
            if r >= 0 and c >= 0:
                yield e.kind, r, c, s, e, False
    for k, lv in enumerate(levers):
        col = n_nodes + k
        for node, s, ratio in ((lv.p1, 1.0, True), (lv.p2, -1.0, True),
                               (lv.s1, -1.0, False), (lv.s2, 1.0, False)):
            i = index[node]
            if i >= 0:
                yield "lever", i, col, s, lv, ratio
                yield "lever", col, i, s, lv, ratio


def combine(dc, m, k, omega):
    """A(ω) = D + C + j(ωM − Kₛ/ω) from its parts — the one place A(ω) is formed.

    ``dc``, ``m``, ``k`` are arrays of one shape (dense matrices, or the
    aligned nonzeros of a sparse pattern, in any float precision) and
    ``omega`` broadcasts against them.  Entries beyond float64 (ω·m above
    1.8e308) come out non-finite; callers flag them.
    """
    with np.errstate(over="ignore", invalid="ignore"):
        return dc + 1j * susceptance(m, k, omega)


def susceptance(m, k, omega):
    """The imaginary part ωM − Kₛ/ω of A(ω) (see :func:`combine`)."""
    with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
        return omega * m - k / omega


class _Pattern:
    """The sparsity pattern of A(ω), fixed over ω, with the parts' values aligned to it.

    ``dc``, ``m``, ``k`` are the summed nonzeros (CSC order) of D + C, M and
    Kₛ; ``l_*`` the same sums in extended precision (for residuals: a
    diagonal summed in float64 is already rounded); ``u_*`` the unsummed
    stamps (for the sensitivity of K to rounding each of them).
    """

    def __init__(self, system: NodalSystem):
        n = system.size
        r = [np.asarray(system.stamps[k][0], dtype=np.int64) for k in KINDS]
        c = [np.asarray(system.stamps[k][1], dtype=np.int64) for k in KINDS]
        v = [np.asarray(system.stamps[k][2], dtype=float) for k in KINDS]
        rows, cols, vals = np.concatenate(r), np.concatenate(c), np.concatenate(v)
        kind = np.concatenate([np.full(len(x), i) for i, x in enumerate(r)])
        self.n = n
        key = cols * n + rows
        uniq, inv = np.unique(key, return_inverse=True)
        self.indices = (uniq % n).astype(np.int32)
        self.indptr = np.searchsorted(uniq // n, np.arange(n + 1)).astype(np.int32)
        nnz = uniq.size
        parts = [np.bincount(inv, weights=np.where(kind == i, vals, 0.0), minlength=nnz)
                 for i in range(4)]
        self.m, self.k, self.dc = parts[0], parts[2], parts[1] + parts[3]
        # The same sums in extended precision, for b − A x: A is symmetric, so
        # the CSC pattern read as CSR gives its rows.
        ext = np.longdouble
        summed = []
        for sel in ((kind == 0), (kind == 2), (kind == 1) | (kind == 3)):
            acc = np.zeros(nnz, dtype=ext)
            np.add.at(acc, inv[sel], vals[sel].astype(ext))
            summed.append(acc)
        self.l_m, self.l_k, self.l_dc = summed
        lengths = np.diff(self.indptr)
        self.l_rows = np.flatnonzero(lengths > 0)
        self.l_starts = self.indptr[:-1][self.l_rows]
        # Unsummed stamps, for the sensitivity of K to rounding each one.
        self.u_rows, self.u_cols = rows, cols
        self.u_m, self.u_k = np.where(kind == 0, vals, 0.0), np.where(kind == 2, vals, 0.0)
        self.u_dc = np.where((kind == 1) | (kind == 3), vals, 0.0)
        self._elements(system)

    def csc(self, omega: float):
        """A(ω) as a ``scipy.sparse.csc_matrix`` on the fixed pattern."""
        import scipy.sparse as sp

        data = combine(self.dc, self.m, self.k, omega)
        return sp.csc_matrix((data, self.indices, self.indptr), shape=(self.n, self.n))

    def residual(self, omega: NDArray, x: NDArray, rhs: NDArray) -> NDArray[np.complex128]:
        """b − A(ω) x for each ω (rows of ``x``), accumulated in extended precision.

        The same A(ω) as :func:`combine`, with its real part D + C and imaginary
        part ωM − Kₛ/ω kept apart: real ``longdouble`` arithmetic is several
        times faster than complex.
        """
        ext = np.longdouble
        if np.iscomplexobj(omega):          # complex frequency (resonance polishing)
            w = np.asarray(omega).astype(np.clongdouble)[:, None]
            sus = susceptance(self.l_m, self.l_k, w)
            re, im = self.l_dc - sus.imag, sus.real
        else:
            w = np.asarray(omega).astype(ext)[:, None]
            re, im = self.l_dc, susceptance(self.l_m, self.l_k, w)
        xc = x[:, self.indices]
        xr, xi = xc.real.astype(ext), xc.imag.astype(ext)
        Ax = np.zeros((w.shape[0], self.n), dtype=np.clongdouble)
        if self.l_rows.size:
            pr = re * xr - im * xi
            pi = re * xi + im * xr
            Ax.real[:, self.l_rows] = np.add.reduceat(pr, self.l_starts, axis=1)
            Ax.imag[:, self.l_rows] = np.add.reduceat(pi, self.l_starts, axis=1)
        r = rhs.astype(ext)[None, :] - Ax
        return r.astype(complex)

    def sensitivity(self, omega: NDArray, x: NDArray) -> NDArray[np.float64]:
        """Σ |x_r · a_rc · x_c| over the unsummed stamps, for each ω.

        A is complex symmetric, so the adjoint solution of K = cᵀ A⁻¹ c is x
        itself and a relative change ε of every stamp moves K by at most ε
        times this sum: the sensitivity of K to rounding the data.
        """
        w = np.asarray(omega)[:, None]
        xa = np.abs(x).astype(float)
        with np.errstate(all="ignore"):
            a = np.abs(combine(self.u_dc, self.u_m, self.u_k, w))
            return np.einsum("ij,ij,ij->i", xa[:, self.u_rows], a, xa[:, self.u_cols])


    def _elements(self, system: NodalSystem) -> None:
        index = {n: i for i, n in enumerate(system.nodes)}
        n = self.n

        def at(node):
            return index.get(node, n)         # the reference: a zero column at n
        els = system.elements
        self.e_i = np.array([at(e.n1) for e in els], dtype=np.int64)
        self.e_j = np.array([at(e.n2) for e in els], dtype=np.int64)
        val = np.array([e.value * e.eta for e in els], dtype=float)
        kind = np.array([e.kind for e in els])
        self.e_m = np.where(kind == "mass", val, 0.0)
        self.e_k = np.where(kind == "spring", val, 0.0)
        self.e_c = np.where(kind == "damper", val, 0.0)
        n_nodes = len(system.nodes)
        lv = system.levers
        self.l_p1 = np.array([at(v.p1) for v in lv], dtype=np.int64)
        self.l_p2 = np.array([at(v.p2) for v in lv], dtype=np.int64)
        self.l_col = n_nodes + np.arange(len(lv), dtype=np.int64)
        self.l_r = np.array([abs(v.ratio) for v in lv], dtype=float)

    def data_sensitivity(self, omega: NDArray, x: NDArray) -> NDArray[np.float64]:
        """Σ_e |y_e| |x_n1 − x_n2|² + Σ_levers 2|r| |x_p1 − x_p2| |q|, for each ω.

        Rounding an element's value by a relative ε changes its four stamps
        together, δA = ε·y·(e_i − e_j)(e_i − e_j)ᵀ, and K by ε·y·(x_i − x_j)²
        (the adjoint of the complex symmetric A is x itself); a lever's ratio
        enters its two primary stamps.  This sum times eps bounds the change
        of K when every value is rounded, without the cancellation that a
        bound stamp by stamp would count many times over.
        """
        w = np.asarray(omega)[:, None]
        xe = np.concatenate([np.asarray(x), np.zeros((x.shape[0], 1), x.dtype)], axis=1)
        with np.errstate(all="ignore"):
            y = np.abs(combine(self.e_c, self.e_m, self.e_k, w))
            d = np.abs(xe[:, self.e_i] - xe[:, self.e_j]).astype(float)
            out = np.sum(y * d * d, axis=1)
            if self.l_r.size:
                dl = np.abs(xe[:, self.l_p1] - xe[:, self.l_p2]).astype(float)
                out = out + np.sum(2 * self.l_r * dl * np.abs(xe[:, self.l_col]).astype(float),
                                   axis=1)
        return out


def _pattern(system: NodalSystem) -> _Pattern:
    cached = system.__dict__.get("_pattern")
    if cached is None:
        cached = _Pattern(system)
        object.__setattr__(system, "_pattern", cached)
    return cached


def matrix(system: NodalSystem, omega: float):
    """A(ω) = D + C + j(ωM − Kₛ/ω) of ``system`` as a sparse CSC matrix."""
    return _pattern(system).csc(float(omega))


def dense_matrices(system: NodalSystem, omega: ArrayLike) -> NDArray[np.complex128]:
    """A(ω) for each ω as one dense array of shape (n_ω, n, n)."""
    omega = np.asarray(omega)
    omega = omega.astype(complex if np.iscomplexobj(omega) else float).reshape(-1, 1, 1)
    dc = (system.D + system.C).toarray()
    return combine(dc, system.M.toarray(), system.Ks.toarray(), omega)


@dataclass(frozen=True)
class Solution:
    """Solutions of A(ω) x = b over ω, with their error estimates.

    Attributes
    ----------
    x : ndarray, shape (n_ω, n)
        ``clongdouble`` if refined, NaN rows where A(ω) could not be solved.
    K : ndarray of complex, shape (n_ω,)
        x_a − x_b (the drive's velocity difference per unit force).
    error : ndarray of float, shape (n_ω,)
        Estimated relative error of K: the drive component of the last
        correction of the iterative refinement, plus its own uncertainty
        (the observed contraction × the correction's size), floored at the
        rounding to float64; ``inf`` where the refinement does not contract
        (A(ω) numerically singular) or A(ω) is not finite.
    singular : ndarray of bool, shape (n_ω,)
        Points on a singularity of A(ω) (exact, or within rounding).
    """

    x: NDArray
    K: NDArray[np.complex128]
    error: NDArray[np.float64]
    singular: NDArray[np.bool_]


def solve(system: NodalSystem, omega: ArrayLike, *, refine: bool = True,
          steps: int = 4, limits: bool = True) -> Solution:
    """Solve A(ω) x = e_a − e_b at each ω, refined, with an error estimate of K.

    Small systems (≤ :data:`DENSE_LIMIT` unknowns) are solved as batched dense
    systems; large ones by a sparse LU per ω whose column ordering is computed
    once and reused.  Refinement reuses the factors: each step is one
    residual in extended precision and one triangular solve.
    """
    omega = np.asarray(omega, dtype=float).reshape(-1)
    n = system.size
    m = omega.size
    dtype = np.clongdouble if refine else complex
    x = np.full((m, n), np.nan, dtype=dtype)
    err = np.full(m, np.inf)
    ok = np.isfinite(omega) & (omega > 0)
    idx = np.flatnonzero(ok)
    rhs = system.injection()
    pat = _pattern(system)
    if n <= DENSE_LIMIT:
        chunk = max(1, _CHUNK_BYTES // (16 * n * n))
        for start in range(0, idx.size, chunk):
            sel = idx[start:start + chunk]
            A = dense_matrices(system, omega[sel])
            finite = np.isfinite(A).all(axis=(1, 2))
            sel, A = sel[finite], A[finite]
            if not sel.size:
                continue
            lu = _DenseLU(A)
            xs, es = _refined(lu.solve, pat, omega[sel], rhs, system, refine, steps)
            x[sel], err[sel] = xs, es
    else:
        solver = _SparseSolver(pat)
        for i in idx:
            lu = solver.factor(omega[i])
            if lu is None:
                continue
            xs, es = _refined(lambda r: lu(r[0])[None, :], pat, omega[i:i + 1], rhs,
                              system, refine, steps)
            x[i], err[i] = xs[0], es[0]
    K = system.difference(x).astype(complex)
    # No correct digit from the refinement itself (it did not contract): A(ω)
    # is numerically singular.  The residual-rounding bound below is a worst
    # case and is not used for this verdict.
    singular = ok & (~np.isfinite(K) | (err >= 1.0))
    S = pat.sensitivity(omega, x)
    with np.errstate(all="ignore"):
        err = err + _residual_rounding(K, S)
    with np.errstate(all="ignore"):
        err = np.where(ok, _total(K, pat.data_sensitivity(omega, x), err), np.inf)
    if limits:
        K, err = _singular_points(system, omega, x, K, err, singular, steps)
    return Solution(x, K, err, singular)


def _refined(solve_fn, pat: _Pattern, omega, rhs, system, refine: bool, steps: int):
    """x from one solve and up to ``steps`` refinement steps; returns (x, relative error of K)."""
    eps = np.finfo(float).eps
    b = np.broadcast_to(rhs.astype(complex), (omega.size, rhs.size))
    x0 = solve_fn(b)
    if not refine:
        # No refinement: the first correction is still the error estimate.
        d = solve_fn(pat.residual(omega, x0.astype(np.clongdouble), rhs))
        return x0, _estimate(system, x0, d, x0)
    x = x0.astype(np.clongdouble)
    prev = x0
    est = np.full(omega.size, np.inf)
    for _ in range(steps):
        d = solve_fn(pat.residual(omega, x, rhs))
        est = _estimate(system, x, d, prev)
        x = x + d
        prev = d
        # est bounds the error before this correction; after it, the error is
        # smaller still (by the contraction): stop once est is near rounding.
        if not np.any(est > 16 * eps):
            break
    return x, est


def _residual_rounding(K, S):
    """Relative error of K left by residuals rounded in extended precision.

    Each residual row is rounded by about eps_ld × Σ_c |a_rc x_c|, which K
    (through the adjoint solution, x itself) feels as eps_ld × S; the
    refinement cannot see it.  Four times that, for the accumulation.
    """
    eps_ld = float(np.finfo(np.longdouble).eps)
    with np.errstate(all="ignore"):
        out = 4 * eps_ld * S / np.abs(K)
    return np.where(np.isnan(out), np.inf, out)


def _total(K, S, est, *, data: str = "flag"):
    """The solve's error ``est``, and the sensitivity of K to rounding its data.

    Each value (m, k, c, r) carries a rounding of up to eps relative; that
    moves K by eps × S / |K| (S from :meth:`_Pattern.data_sensitivity`), far more than the solve near a zero of K.
    With ``data="flag"`` (sweeps) that figure replaces the estimate only where
    it exceeds :data:`~mechcirc.sweep.NEAR_SINGULAR_ERROR` (1e-6): a point
    within rounding of a zero is flagged, as the series–parallel method flags
    it, while everywhere else the estimate stays that of the computation
    (K exact for the binary inputs, as mpmath would compute it).  With
    ``data="add"`` (resonances) it is always added: the error then bounds
    the distance to the root of the values as written, before rounding.
    The result is rounded to float64 at the end: at least eps.
    """
    eps = np.finfo(float).eps
    with np.errstate(all="ignore"):
        rounding = eps * S / np.abs(K)
        rounding = np.where(np.isnan(rounding), np.inf, rounding)
        if data == "add":
            total = est + rounding
        else:
            total = np.where(rounding > 1e-6, np.maximum(est, rounding), est)
    return np.maximum(total, eps)


def _estimate(system, x, d, prev):
    """Relative error of K = x_a − x_b before applying the correction ``d``.

    |d_a − d_b| estimates the error of K; ``d`` itself is wrong by about the
    contraction ρ = ‖d‖/‖prev‖ times the size of its drive components, which
    is added.  A correction
    as large as x itself that does not contract means A is numerically
    singular: inf.
    """
    tiny = np.finfo(np.longdouble).eps
    with np.errstate(all="ignore"):
        nd = np.max(np.abs(d), axis=-1).astype(float)
        nx = np.max(np.abs(x), axis=-1).astype(float)
        npv = np.maximum(np.max(np.abs(prev), axis=-1).astype(float), tiny * nx)
        rho = np.where(npv > 0, nd / npv, 0.0)
        K = np.abs(system.difference(x)).astype(float)
        dK = np.abs(system.difference(d)).astype(float)
        # The drive's own components: a norm over all of d would mix scales
        # (a lever of ratio 1e150 puts velocities 1e150 apart).
        da = np.abs(d[..., system.a]).astype(float) if system.a >= 0 else 0.0
        db = np.abs(d[..., system.b]).astype(float) if system.b >= 0 else 0.0
        est = (dK + np.minimum(rho, 1.0) * (da + db)) / K
        # Stagnation at the residual's own rounding level (corrections of
        # eps_ld·cond(A) relative) is not divergence: only corrections of the
        # size of x itself that do not shrink mean a singular A.
        diverged = (rho >= 0.5) & (nd > 1e-2 * nx)
        est = np.where(diverged | np.isnan(est), np.inf, est)
    return est


class _DenseLU:
    """The inverses of a batch of small dense matrices, reused for every right-hand side.

    An explicit inverse is no less accurate here than LU factors: every
    solution is refined with residuals in extended precision, and the batch
    is applied as one matrix product (small systems, many ω).
    """

    def __init__(self, A: NDArray):
        try:
            self.inv = np.linalg.inv(A)
        except np.linalg.LinAlgError:
            # Some matrix of the batch is exactly singular: invert one by one and
            # leave that frequency as NaN (rare; only on the failure path).
            self.inv = np.full(A.shape, np.nan, dtype=complex)
            for k in range(A.shape[0]):
                try:
                    self.inv[k] = np.linalg.inv(A[k])
                except np.linalg.LinAlgError:
                    pass

    def solve(self, r: NDArray) -> NDArray:
        return np.einsum("kij,kj->ki", self.inv, r)


class _SparseSolver:
    """LU of A(ω) on its fixed pattern, with what does not change with ω found once.

    Two factorisations are tried at the first ω and the faster kept for the
    rest: SuperLU (``scipy.sparse.linalg.splu``) with the minimum-degree
    column ordering of that first factorisation reused (``permc_spec=
    "NATURAL"`` on the pre-permuted matrix), and LAPACK's banded LU (``zgbtrf``) after a
    reverse Cuthill–McKee ordering, which wins on chains and narrow networks
    (the ladder's band is 1–2 wide).  Both are partial-pivoting LUs; the
    refinement and its error estimate are the same for either.
    """

    def __init__(self, pat: _Pattern):
        self.pat = pat
        self.kind = None

    def factor(self, omega: float):
        A = self.pat.csc(omega)
        if not np.isfinite(A.data).all():
            return None
        if self.kind is None:
            return self._choose(A)
        return self._banded(A) if self.kind == "band" else self._superlu(A)

    def _choose(self, A):
        import time

        from scipy.sparse.linalg import splu

        t0 = time.perf_counter()
        try:
            # A is symmetric: a minimum-degree ordering of its pattern fills less
            # than the default COLAMD (20k against 30k entries on the 30×30 grid).
            lu = splu(A, permc_spec="MMD_AT_PLUS_A")
        except RuntimeError:            # exactly singular here: decide at the next ω
            return None
        # Reused as A[:, iperm] with no further ordering: x = y[perm].
        self.perm = np.asarray(lu.perm_c)
        self.iperm = np.argsort(self.perm)
        t_super = time.perf_counter() - t0
        self.kind = "superlu"
        band = self._band_setup(A)
        if band:
            t0 = time.perf_counter()
            solve = self._banded(A)
            if time.perf_counter() - t0 < t_super and solve is not None:
                self.kind = "band"
                return solve
        return lu.solve

    def _superlu(self, A):
        from scipy.sparse.linalg import splu

        try:
            lu = splu(A[:, self.iperm], permc_spec="NATURAL")
        except RuntimeError:            # exactly singular at this frequency
            return None
        perm = self.perm

        def solve(b):
            return lu.solve(np.ascontiguousarray(b, dtype=complex))[perm]
        return solve

    def _band_setup(self, A) -> bool:
        from scipy.sparse.csgraph import reverse_cuthill_mckee

        n = A.shape[0]
        p = np.asarray(reverse_cuthill_mckee(A.tocsr(), symmetric_mode=True))
        q = np.empty_like(p)
        q[p] = np.arange(n)
        cols = np.repeat(np.arange(n), np.diff(self.pat.indptr))
        ri, ci = q[self.pat.indices], q[cols]             # permuted positions
        kl = int(np.max(np.abs(ri - ci), initial=0))
        # Banded LU costs about n·kl·3kl; not worth trying on wide bands.
        if n * kl * kl > 2e7:
            return False
        self.p, self.kl = p, kl
        self.band_rows = 2 * kl + kl + 1
        self.dest = (kl + kl + ri - ci, ci)
        return True

    def _banded(self, A):
        from scipy.linalg.lapack import zgbtrf, zgbtrs

        n, kl = A.shape[0], self.kl
        ab = np.zeros((self.band_rows, n), dtype=complex)
        ab[self.dest] = A.data
        lu, piv, info = zgbtrf(ab, kl, kl, overwrite_ab=True)
        if info != 0:
            return None
        p = self.p

        def solve(b):
            b = np.atleast_2d(b)
            out = np.empty(b.shape, dtype=complex)
            rhs = np.ascontiguousarray(b[:, p].T, dtype=complex)
            x, info = zgbtrs(lu, kl, kl, rhs, piv)
            out[:, p] = x.T
            return out if out.shape[0] > 1 else out[0]
        return solve


def _singular_points(system, omega, x, K, err, singular, steps):
    """Apply the singular-point convention where A(ω) is (numerically) singular.

    Where the solution blows up along a mode seen from the drive (a pole of
    K), K = +∞·j (the series–parallel method's convention); where K carries no correct digit otherwise, K = 0 (a
    zero of K within rounding).  The estimate there is inf; ``Sweep.flags``
    marks both as singular (flag 1).
    """
    K = K.copy()
    err = err.copy()
    for i in np.flatnonzero(singular):
        xi, Ki = x[i], K[i]
        if not np.isfinite(Ki):
            # Exactly singular: look just above ω, where the solution is the mode.
            w = omega[i] * (1 + 2.0 ** -40)
            s = solve(system, [w], refine=False, steps=steps, limits=False) \
                if np.isfinite(w) else None
            if s is None or not np.isfinite(s.K[0]):
                continue                    # undetermined: NaN, flagged singular
            xi, Ki = s.x[0], s.K[0]
        scale = float(np.max(np.abs(xi)))
        if abs(Ki) >= 1e-3 * scale:
            K[i] = complex(0.0, np.inf)     # the tree's convention: +∞·j at a pole
        else:
            K[i] = 0.0
        err[i] = np.inf
    return K, err


def solve_unit(system: NodalSystem, omega: ArrayLike, *, refine: bool = True
               ) -> NDArray[np.complex128]:
    """Solutions x(ω) of A(ω) x = e_a − e_b, shape (n_omega, n) (``clongdouble`` if refined).

    With ``refine`` (the default) each solution gets iterative refinement
    with the residual b − A x computed in extended precision
    (``numpy.longdouble``), reusing the LU factors: the forward error then no
    longer grows with the condition number of A (masses and springs of very
    different size in series).  See :func:`solve` for the error estimate.

    Frequencies where A is exactly singular, or ω is 0 or ∞ (where A is not
    finite), give rows of NaN; callers flag them.
    """
    return solve(system, omega, refine=refine).x


def held(system: NodalSystem) -> NodalSystem:
    """The system with the drive held: one more unknown q and the row v_a − v_b = 1.

    [[A, c], [cᵀ, 0]] [x; q] = [0; 1] with c = e_a − e_b gives q = −1/K (the
    force through the drive per unit velocity difference, negated), computed
    without the near-singular A at an anti-resonance.  Like a lever, the
    constraint goes into the symmetric C block; the drive of the returned
    system points at q (``a = n``, ``b = −1``).
    """
    import scipy.sparse as sp

    n = system.size
    rows, cols, vals = (list(v) for v in system.stamps["lever"])
    for i, s in ((system.a, 1.0), (system.b, -1.0)):
        if i >= 0:
            rows += [i, n]
            cols += [n, i]
            vals += [s, s]
    stamped = dict(system.stamps)
    stamped["lever"] = (np.asarray(rows, dtype=int), np.asarray(cols, dtype=int),
                        np.asarray(vals, dtype=float))
    grow = [sp.csr_matrix((v, (r, c)), shape=(n + 1, n + 1))
            for r, c, v in (stamped[k] for k in KINDS)]
    return NodalSystem(system.nodes, system.levers, system.elements, system.unloaded,
                       *grow, n, -1, stamped)


def evaluate_complex(system: NodalSystem, s: ArrayLike
                     ) -> tuple[NDArray[np.complex128], NDArray[np.float64]]:
    """K(s) at complex frequencies s (jω on the axis) and its estimated absolute error.

    A(s) = D + C + sM + Kₛ/s is :func:`combine` at ω = −js.  Each solution is
    refined with residuals in extended precision as in :func:`solve`, and the
    error is the same estimate (the last correction, the residual's own
    rounding and the sensitivity to rounding the data, eps × Σ|x_r a_rc x_c|):
    used to polish resonances on the circuit's own K.  NaN where A(s) is
    singular.
    """
    s = np.asarray(s, dtype=complex).reshape(-1)
    omega = -1j * s
    pat = _pattern(system)
    rhs = system.injection()
    x = np.full((s.size, system.size), np.nan, dtype=np.clongdouble)
    est = np.full(s.size, np.inf)
    if system.size <= DENSE_LIMIT:
        for start in range(0, s.size, 4096):
            sel = np.arange(start, min(start + 4096, s.size))
            A = dense_matrices(system, omega[sel])
            sel = sel[np.isfinite(A).all(axis=(1, 2))]
            if sel.size:
                lu = _DenseLU(dense_matrices(system, omega[sel]))
                x[sel], est[sel] = _refined(lu.solve, pat, omega[sel], rhs, system, True, 4)
    else:
        from scipy.sparse.linalg import splu

        for i, w in enumerate(omega):
            A = pat.csc(w)
            if not np.isfinite(A.data).all():
                continue
            try:
                lu = splu(A, permc_spec="MMD_AT_PLUS_A")
            except RuntimeError:
                continue
            x[i], est[i] = (v[0] for v in _refined(
                lambda r: lu.solve(np.ascontiguousarray(r[0]))[None, :], pat,
                omega[i:i + 1], rhs, system, True, 4))
    K = system.difference(x).astype(complex)
    S = pat.sensitivity(omega, x)
    est = _total(K, pat.data_sensitivity(omega, x), est + _residual_rounding(K, S),
                 data="add")
    with np.errstate(all="ignore"):
        return K, est * np.abs(K)


def mobility(system: NodalSystem, omega: ArrayLike) -> NDArray[np.complex128]:
    """K(ω) [m/(N·s)] seen by the drive, by nodal analysis."""
    return solve(system, omega).K


def mobility_and_error(system: NodalSystem, omega: ArrayLike
                       ) -> tuple[NDArray[np.complex128], NDArray[np.float64]]:
    """K(ω) [m/(N·s)] and its estimated relative error, from one refined solve.

    See :class:`Solution` for the estimate and the singular-point convention.
    """
    s = solve(system, omega)
    return s.K, s.error


def mobility_unrefined(system: NodalSystem, omega: ArrayLike) -> NDArray[np.complex128]:
    """K(ω) [m/(N·s)] by one plain solve per ω, without refinement (the fast path).

    Its relative error is about eps × cond(A(ω)), see :func:`condition_error`.
    """
    return system.difference(solve(system, omega, refine=False).x)


def element_response(system: NodalSystem, omega: ArrayLike, scale: NDArray) -> dict[str, tuple]:
    """``{name: (Q, v)}`` for every loaded element, for a drive force ``scale`` [N] per ω."""
    omega = np.asarray(omega, dtype=float)
    x = solve_unit(system, omega)
    index = {n: i for i, n in enumerate(system.nodes)}
    out = {}
    with np.errstate(all="ignore"):
        for e in system.elements:
            v = np.zeros(omega.shape, dtype=complex)
            if e.n1 in index:
                v = v + x[:, index[e.n1]]
            if e.n2 in index:
                v = v - x[:, index[e.n2]]
            v = v.astype(complex) * scale
            out[e.name] = (v / e.mobility(omega), v)
    return out


def condition_error(system: NodalSystem, omega: ArrayLike) -> NDArray[np.float64]:
    """Estimated relative error of an unrefined solve: eps × cond(A(ω)).

    Dense systems: the 2-norm condition number from the singular values.
    Sparse systems: the 1-norm condition number, ‖A‖₁ times Higham's estimate
    of ‖A⁻¹‖₁ (``scipy.sparse.linalg.onenormest`` on the LU factors); inf
    where A(ω) is singular.  (The sweep's own estimate, :class:`Solution`,
    is that of the refined solution and far smaller.)
    """
    omega = np.asarray(omega, dtype=float)
    out = np.full(omega.shape, np.nan)
    ok = np.isfinite(omega) & (omega > 0)
    out[~ok] = np.inf
    if system.size > DENSE_LIMIT:
        from scipy.sparse.linalg import LinearOperator, onenormest, splu

        n = system.size
        for i in np.flatnonzero(ok):
            A = matrix(system, omega[i])
            try:
                lu = splu(A, permc_spec="MMD_AT_PLUS_A")
            except RuntimeError:
                out[i] = np.inf
                continue
            inv = LinearOperator((n, n), dtype=complex, matvec=lu.solve,
                                 rmatvec=lambda v, lu=lu: lu.solve(v, trans="H"))
            with np.errstate(all="ignore"):
                norm = float(abs(A).sum(axis=0).max())
                out[i] = np.finfo(float).eps * norm * onenormest(inv)
        return np.where(np.isnan(out), np.inf, out)
    n = system.size
    idx = np.flatnonzero(ok)
    chunk = max(1, _CHUNK_BYTES // (16 * n * n))
    for start in range(0, idx.size, chunk):
        sel = idx[start:start + chunk]
        A = dense_matrices(system, omega[sel])
        # Entries beyond float64 (a huge ω·m or k/ω) leave the error unknown:
        # inf, so the point is flagged rather than the SVD failing.
        finite = np.isfinite(A).all(axis=(1, 2))
        out[sel[~finite]] = np.inf
        if finite.any():
            sv = np.linalg.svd(A[finite], compute_uv=False)
            with np.errstate(divide="ignore", invalid="ignore"):
                out[sel[finite]] = np.finfo(float).eps * sv[:, 0] / sv[:, -1]
    return out


def require_nonsingular(system: NodalSystem) -> None:
    """Raise if A(ω) is singular at every frequency (checked at two generic ω).

    Dense systems are judged by their smallest singular value, and the null
    vector names the undetermined unknowns; large ones by a sparse LU.
    """
    if system.size == 0:
        raise TopologyError(
            "nothing between the drive's nodes carries force (no unknowns left; unloaded: "
            f"{', '.join(system.unloaded[:12]) or 'none'})", elements=system.unloaded)
    scale = _frequency_scale(system)
    trial = [0.731 * scale, 1.913 * scale]
    if system.size > DENSE_LIMIT:
        x = solve_unit(system, trial)
        if np.isfinite(x).all(axis=1).any():
            return
        raise TopologyError("the network is singular at every frequency (tried "
                            f"ω = {trial[0]:.4g} and {trial[1]:.4g} rad/s)")
    judged = None
    for A in dense_matrices(system, trial):
        if not np.isfinite(A).all():
            continue            # values at float64's edge: no verdict at this ω
        # Judge the equilibrated matrix: a lever of ratio 1e-8 puts entries of
        # 1e-8 beside 1, and the raw singular values then look singular.
        A = _equilibrate(A)
        sv = np.linalg.svd(A, compute_uv=False)
        if sv[-1] > 1e-13 * sv[0]:
            return
        judged = A
    if judged is None:
        return                  # the sweep flags the non-finite points itself
    _, _, vh = np.linalg.svd(judged)
    null = np.abs(vh[-1].conj())
    names = list(system.nodes) + [f"lever {lv.name}" for lv in system.levers]
    culprits = [names[i] for i in np.flatnonzero(null > 1e-6 * null.max())]
    raise TopologyError(
        "the network is singular at every frequency (its velocities or lever forces "
        f"are not determined): {', '.join(culprits[:12])}; check for levers in parallel "
        "or nodes tied only by levers", nodes=[c for c in culprits if not c.startswith("lever")],
        elements=[c[6:] for c in culprits if c.startswith("lever")])


def _equilibrate(A: NDArray) -> NDArray:
    """Rows and columns scaled to max-norm 1 (Ruiz iteration; singular stays singular)."""
    A = A.copy()
    for _ in range(8):
        mag = np.abs(A)
        r, c = np.sqrt(mag.max(axis=1)), np.sqrt(mag.max(axis=0))
        r[r == 0] = 1.0
        c[c == 0] = 1.0
        A /= r[:, None]
        A /= c[None, :]
    return A


def _frequency_scale(system: NodalSystem) -> float:
    """A characteristic ω [rad/s] of the system: sqrt(trace Kₛ / trace M), or 1."""
    # Sum after scaling by the largest entry: masses near 1e308 would overflow.
    dm, dk = np.abs(system.M.diagonal()), np.abs(system.Ks.diagonal())
    if dm.size and dm.max() > 0 and dk.max() > 0:
        mm, mk = dm.max(), dk.max()
        with np.errstate(all="ignore"):
            scale = np.sqrt(mk) / np.sqrt(mm) * np.sqrt((dk / mk).sum() / (dm / mm).sum())
        if np.isfinite(scale) and scale > 0:
            return float(scale)
    return 1.0
