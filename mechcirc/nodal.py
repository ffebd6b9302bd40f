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
(a banded LU where the band is narrow, SuperLU otherwise; the choice and
the ordering made once from the pattern, see :class:`_SparseSolver`).  Each
solution is refined with residuals in double-double arithmetic reusing the
factors (compiled by numba on the sparse path when it is installed:
:mod:`mechcirc._nodal_kernels`), and the last correction gives the error
estimate of K (:class:`Solution`).  Where float64 factors cannot refine
(cond(A) beyond 1/u, as on stiff networks whose K is well conditioned),
a dense LU in double-double of the balanced matrix takes over
(:class:`_DDSolver`).  At a singular point K is +∞·j (a pole) or 0 (a zero),
with an infinite error, as the series–parallel method gives it.
"""

from __future__ import annotations

import contextvars

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
        for residuals in double-double (a summed diagonal is already rounded).
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


# ---------------------------------------------------------------------------
# Double-double arithmetic (error-free transformations, elementwise in numpy).
# A value is a pair (hi, lo) with hi + lo exact to about 2⁻¹⁰⁴ relative; real
# and complex arrays alike (complex addition, and complex times real, work
# component by component).

_SPLITTER = 134217729.0                 # 2²⁷ + 1 (Veltkamp's split)


def _split(a):
    """a = hi + lo exactly, hi and lo of 26 significant bits each."""
    with np.errstate(all="ignore"):
        c = _SPLITTER * a
        hi = c - (c - a)
        if not np.isfinite(np.sum(np.abs(hi))):
            # |a| above 2⁹⁹⁶: split a·2⁻²⁸ (exact) and scale back.
            big = np.abs(a) > 2.0 ** 995
            c = _SPLITTER * (a * 2.0 ** -28)
            hi = np.where(big, (c - (c - a * 2.0 ** -28)) * 2.0 ** 28, hi)
        return hi, a - hi


def _two_sum(a, b):
    """a + b = s + e exactly (Knuth's TwoSum)."""
    s = a + b
    bb = s - a
    return s, (a - (s - bb)) + (b - bb)


def _two_prod(a, ah, al, b):
    """a·b = p + e exactly (Dekker's TwoProduct; ``a`` split beforehand as ah + al, real)."""
    p = a * b
    bh, bl = _split(b)
    return p, ((ah * bh - p) + ah * bl + al * bh) + al * bl


def _dd_add(ah, al, bh, bl):
    s, e = _two_sum(ah, bh)
    return s, e + (al + bl)


def _dd_mul_d(h, lo, w):
    """(h + lo)·w for a double w (real)."""
    wh, wl = _split(w)
    p, e = _two_prod(w, wh, wl, h)
    return p, e + lo * w


def _dd_div_d(h, lo, w):
    """(h + lo)/w for a double w (real)."""
    q = h / w
    wh, wl = _split(w)
    p, e = _two_prod(w, wh, wl, q)
    return q, (((h - p) - e) + lo) / w


def _dd_norm(h, lo):
    """(h, lo) renormalised: |lo| ≤ ulp(h)/2 (Fast2Sum)."""
    s = h + lo
    return s, lo - (s - h)


def _dd_mul(ah, al, bh, bl):
    """(ah + al)(bh + bl) in double-double (real)."""
    a1, a2 = _split(ah)
    p, e = _two_prod(ah, a1, a2, bh)
    return _dd_norm(p, e + (ah * bl + al * bh))


def _dd_sub(ah, al, bh, bl):
    s, e = _two_sum(ah, -bh)
    return _dd_norm(s, e + (al - bl))


def _cdd_mul(a, b):
    """Complex double-double product; a value is (re_hi, re_lo, im_hi, im_lo)."""
    rr, ii = _dd_mul(a[0], a[1], b[0], b[1]), _dd_mul(a[2], a[3], b[2], b[3])
    ri, ir = _dd_mul(a[0], a[1], b[2], b[3]), _dd_mul(a[2], a[3], b[0], b[1])
    return (*_dd_sub(*rr, *ii), *_dd_norm(*_dd_add(*ri, *ir)))


def _cdd_div(a, b):
    """Complex double-double quotient a / b (b of moderate size: no overflow check)."""
    den = _dd_norm(*_dd_add(*_dd_mul(b[0], b[1], b[0], b[1]), *_dd_mul(b[2], b[3], b[2], b[3])))
    re = _dd_norm(*_dd_add(*_dd_mul(a[0], a[1], b[0], b[1]), *_dd_mul(a[2], a[3], b[2], b[3])))
    im = _dd_sub(*_dd_mul(a[2], a[3], b[0], b[1]), *_dd_mul(a[0], a[1], b[2], b[3]))
    return (*_dd_norm(*_dd_div_dd(*re, *den)), *_dd_norm(*_dd_div_dd(*im, *den)))


def _balance(mag, diag):
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


class _DDSolver:
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
        n = system.size
        self.n = n
        # About 2¹⁹ matrix entries per batch (some 30 temporaries of that size).
        self.max_chunk = max(1, min(64, 2 ** 19 // max(1, n * n)))
        self.parts = []
        for kinds in (("damper", "lever"), ("mass",), ("spring",)):
            h, lo = np.zeros((n, n)), np.zeros((n, n))
            for kind in kinds:
                for r, c, v in zip(*system.stamps[kind]):
                    h[r, c], e = _two_sum(h[r, c], float(v))
                    lo[r, c] += e
            self.parts.append(_dd_norm(h, lo))
        self.absdiag = [np.abs(np.diagonal(p[0])) for p in self.parts]

    def factor(self, omega, strict: bool = False):
        omega = np.asarray(omega, dtype=float)
        w = omega[:, None, None]
        (ch, cl), (mh, ml), (kh, kl) = self.parts
        with np.errstate(all="ignore"):
            im = _dd_norm(*_dd_sub(*_dd_mul_d(mh, ml, w), *_dd_div_d(kh, kl, w)))
            B, n = omega.size, self.n
            X = [np.broadcast_to(ch, (B, n, n)).copy(), np.broadcast_to(cl, (B, n, n)).copy(),
                 im[0], im[1]]
            mag = np.abs(X[0] + 1j * X[2])
            cd, md, kd = self.absdiag
            d = _balance(mag, cd + omega[:, None] * md + kd / omega[:, None])
            good = np.isfinite(mag).all(axis=(1, 2)) & (omega > 0)
            dd = d[:, :, None] * d[:, None, :]
            X = [x * dd for x in X]
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
                lk = _cdd_div([x[:, k + 1:, k] for x in X], [v[:, None] for v in piv])
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
                upd = _cdd_mul([v[:, ri - k - 1, None] for v in lk],
                               [x[:, None, k, ci] for x in X])
                re = _dd_sub(X[0][at], X[1][at], *upd[:2])
                im = _dd_sub(X[2][at], X[3][at], *upd[2:])
                for x, v in zip(X, (*re, *im)):
                    x[at] = v
            good &= np.isfinite(X[0]).all(axis=(1, 2)) & np.isfinite(X[2]).all(axis=(1, 2))
        X, perm, d = [x[good] for x in X], perm[good], d[good]
        every = np.arange(perm.shape[0])

        def solve(r, rows=None):
            rows = every if rows is None else np.asarray(rows)
            b = np.take_along_axis(np.asarray(r, dtype=complex) * d[rows], perm[rows], axis=1)
            F = [x[rows] for x in X]
            y = [b.real.copy(), np.zeros(b.shape), b.imag.copy(), np.zeros(b.shape)]
            with np.errstate(all="ignore"):
                for k in range(self.n - 1):          # L (unit diagonal)
                    t = _cdd_mul([f[:, k + 1:, k] for f in F], [v[:, k, None] for v in y])
                    re = _dd_sub(y[0][:, k + 1:], y[1][:, k + 1:], *t[:2])
                    im = _dd_sub(y[2][:, k + 1:], y[3][:, k + 1:], *t[2:])
                    for v, u in zip(y, (*re, *im)):
                        v[:, k + 1:] = u
                for k in range(self.n - 1, -1, -1):  # U
                    q = _cdd_div([v[:, k] for v in y], [f[:, k, k] for f in F])
                    for v, u in zip(y, q):
                        v[:, k] = u
                    if k:
                        t = _cdd_mul([f[:, :k, k] for f in F], [u[:, None] for u in q])
                        re = _dd_sub(y[0][:, :k], y[1][:, :k], *t[:2])
                        im = _dd_sub(y[2][:, :k], y[3][:, :k], *t[2:])
                        for v, u in zip(y, (*re, *im)):
                            v[:, :k] = u
            return ((y[0] + y[1]) + 1j * (y[2] + y[3])) * d[rows]
        return good, solve


class _Pattern:
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
        self._elements(system)
        self._plan(system)

    def csc(self, omega: float):
        """A(ω) as a ``scipy.sparse.csc_matrix`` on the fixed pattern."""
        import scipy.sparse as sp

        data = combine(self.dc, self.m, self.k, omega)
        return sp.csc_matrix((data, self.indices, self.indptr), shape=(self.n, self.n))

    def _elements(self, system: NodalSystem) -> None:
        index = {n: i for i, n in enumerate(system.nodes)}
        n = self.n

        def at(node):
            return index.get(node, n)         # the reference: a zero column at n
        els = system.elements
        self.e_i = np.array([at(e.n1) for e in els], dtype=np.int64)
        self.e_j = np.array([at(e.n2) for e in els], dtype=np.int64)
        self.e_val = np.array([e.value * e.eta for e in els], dtype=float)
        kind = np.array([e.kind for e in els])
        self.e_kind = np.select([kind == "mass", kind == "spring"], [0, 1], 2).astype(np.int64)
        self.e_m = np.where(self.e_kind == 0, self.e_val, 0.0)
        self.e_k = np.where(self.e_kind == 1, self.e_val, 0.0)
        self.e_c = np.where(self.e_kind == 2, self.e_val, 0.0)
        n_nodes = len(system.nodes)
        lv = system.levers
        self.l_p1 = np.array([at(v.p1) for v in lv], dtype=np.int64)
        self.l_p2 = np.array([at(v.p2) for v in lv], dtype=np.int64)
        self.l_col = n_nodes + np.arange(len(lv), dtype=np.int64)
        self.l_r = np.array([abs(v.ratio) for v in lv], dtype=float)
        # The lever block's stamps (the held drive's constraint included).
        lr, lc, lval = (np.asarray(a) for a in system.stamps["lever"])
        self.s_row = lr.astype(np.int64)
        self.s_col = lc.astype(np.int64)
        self.s_val = lval.astype(float)

    def _plan(self, system: NodalSystem) -> None:
        """Terms of b − A x and their summation order, per (row, kind) bucket.

        Terms: +y·d of each element into its first node's row, −y·d into its
        second's (the reference row dropped), v·x_c of each lever stamp.  A
        bucket is (row, kind) with kinds mass, spring, damper, lever; buckets
        are ranked by their number of terms, so that the s-th terms of all
        buckets with more than s terms form one slot, added in one
        vectorised double-double step.
        """
        n, E = self.n, self.e_i.size
        self.e_vs = _split(self.e_val)
        self.s_vs = _split(self.s_val)
        bucket = np.concatenate([self.e_i * 4 + self.e_kind, self.e_j * 4 + self.e_kind,
                                 self.s_row * 4 + 3])
        term = np.arange(bucket.size)
        keep = bucket < 4 * n                  # rows of the reference dropped
        bucket, term = bucket[keep], term[keep]
        uniq, inv, counts = np.unique(bucket, return_inverse=True, return_counts=True)
        order = np.argsort(-counts, kind="stable")
        rank = np.empty_like(order)
        rank[order] = np.arange(order.size)
        r = rank[inv]
        srt = np.lexsort((term, r))
        r, term = r[srt], term[srt]
        first = np.searchsorted(r, np.arange(uniq.size))
        pos = np.arange(r.size) - first[r]
        self.slots = []
        for s in range(int(counts.max(initial=0))):
            sel = pos == s
            self.slots.append(term[sel][np.argsort(r[sel], kind="stable")])
        self.buckets = uniq[order]             # bucket of each rank
        # The compiled kernel adds each bucket's terms in the same order: the
        # + terms by element, then the − terms, then the lever stamps.
        self.k_bi = np.minimum(self.e_i * 4 + self.e_kind, 4 * n).astype(np.int64)
        self.k_bj = np.minimum(self.e_j * 4 + self.e_kind, 4 * n).astype(np.int64)
        self.k_bs = np.minimum(self.s_row * 4 + 3, 4 * n).astype(np.int64)
        self.n_terms = 2 * E + self.s_row.size
        self.max_terms = int(counts.max(initial=0))

    def residual(self, omega: NDArray, xh: NDArray, xl: NDArray | None,
                 rhs: NDArray) -> NDArray[np.complex128]:
        """b − A(ω) x for each ω (rows of x = xh + xl), in double-double, rounded at the end.

        The same A(ω) as :func:`combine`: (A x)_r = Σ dampers + Σ levers +
        jω Σ masses − j Σ springs / ω, each sum Σ ±value·(x_i − x_j) exact to
        about 2⁻¹⁰⁴ (TwoSum of the differences, TwoProduct of the products,
        cascaded TwoSum per bucket), and the ω factors applied to the sums in
        double-double.  Complex ω (resonance polishing) are accepted.
        """
        c, n = xh.shape
        if not np.iscomplexobj(omega) and n > DENSE_LIMIT and _kernels() is not None:
            return self._residual_compiled(omega, xh, xl, rhs)
        z = np.zeros((c, 1), dtype=complex)
        xe = np.concatenate([xh.astype(complex, copy=False), z], axis=1)
        d_h, d_l = _two_sum(xe[:, self.e_i], -xe[:, self.e_j])
        xs = xe[:, self.s_col]
        if xl is not None:
            xle = np.concatenate([xl.astype(complex, copy=False), z], axis=1)
            # Renormalised (TwoSum): where x_i ≈ x_j their low parts (~u|x|)
            # would leave a low part far above u|d|, and every later sum of
            # low parts would round at u²|x| per row instead of u²|y d|.
            d_h, d_l = _two_sum(d_h, d_l + (xle[:, self.e_i] - xle[:, self.e_j]))
        vh, vl = self.e_vs
        p_h, p_l = _two_prod(self.e_val, vh, vl, d_h)
        p_l = p_l + self.e_val * d_l
        sh, sl = self.s_vs
        q_h, q_l = _two_prod(self.s_val, sh, sl, xs)
        if xl is not None:
            q_l = q_l + self.s_val * xle[:, self.s_col]
        T_h = np.concatenate([p_h, -p_h, q_h], axis=1)
        T_l = np.concatenate([p_l, -p_l, q_l], axis=1)
        S_h = np.zeros((c, 4 * n), dtype=complex)
        S_l = np.zeros((c, 4 * n), dtype=complex)
        if self.slots:
            acc_h, acc_l = T_h[:, self.slots[0]], T_l[:, self.slots[0]]
            for s in self.slots[1:]:
                k = s.size
                a, e = _two_sum(acc_h[:, :k], T_h[:, s])
                acc_h[:, :k] = a
                acc_l[:, :k] += e + T_l[:, s]
            S_h[:, self.buckets], S_l[:, self.buckets] = acc_h, acc_l
        S_h, S_l = S_h.reshape(c, n, 4), S_l.reshape(c, n, 4)
        with np.errstate(all="ignore"):
            w = np.asarray(omega)[:, None]
            m_h, m_l = S_h[..., 0], S_l[..., 0]
            k_h, k_l = S_h[..., 1], S_l[..., 1]
            if np.iscomplexobj(w):
                wr, wi = w.real, w.imag
                # jω·S_m = (−wi + j wr)·S_m, component by component.
                a_h, a_l = _dd_mul_d(m_h.real, m_l.real, wr)    # S_m.re wr
                b_h, b_l = _dd_mul_d(m_h.imag, m_l.imag, wi)    # S_m.im wi
                c_h, c_l = _dd_mul_d(m_h.real, m_l.real, wi)
                d_h2, d_l2 = _dd_mul_d(m_h.imag, m_l.imag, wr)
                # ω S_m = (re wr − im wi) + j(re wi + im wr)
                wm_re = _dd_add(a_h, a_l, -b_h, -b_l)
                wm_im = _dd_add(c_h, c_l, d_h2, d_l2)
                # S_k/ω = S_k·conj(ŵ)/(|ŵ|²·2ᵉ), ŵ = ω/2ᵉ (exact scaling).
                e2 = np.ldexp(1.0, np.frexp(np.maximum(np.abs(wr), np.abs(wi)))[1])
                ur, ui = wr / e2, wi / e2
                p1 = _dd_mul_d(k_h.real, k_l.real, ur)
                p2 = _dd_mul_d(k_h.imag, k_l.imag, ui)
                p3 = _dd_mul_d(k_h.imag, k_l.imag, ur)
                p4 = _dd_mul_d(k_h.real, k_l.real, ui)
                num_re = _dd_add(*p1, *p2)              # re·ur + im·ui
                num_im = _dd_add(*p3, -p4[0], -p4[1])   # im·ur − re·ui
                n2 = _dd_add(*_dd_mul_d(ur, 0.0, ur), *_dd_mul_d(ui, 0.0, ui))
                den = (n2[0] * e2, n2[1] * e2)
                kw_re = _dd_div_dd(*num_re, *den)
                kw_im = _dd_div_dd(*num_im, *den)
            else:
                wm_re = _dd_mul_d(m_h.real, m_l.real, w)
                wm_im = _dd_mul_d(m_h.imag, m_l.imag, w)
                kw_re = _dd_div_d(k_h.real, k_l.real, w)
                kw_im = _dd_div_d(k_h.imag, k_l.imag, w)
            # susceptance part: ω S_m − S_k/ω; A x = S_c + S_l + j·sus
            sus_re = _dd_add(*wm_re, -kw_re[0], -kw_re[1])
            sus_im = _dd_add(*wm_im, -kw_im[0], -kw_im[1])
            g_h, g_l = _dd_add(S_h[..., 2], S_l[..., 2], S_h[..., 3], S_l[..., 3])
            ax_re = _dd_add(g_h.real, g_l.real, -sus_im[0], -sus_im[1])
            ax_im = _dd_add(g_h.imag, g_l.imag, *sus_re)
            r_re = _dd_add(rhs[None, :], 0.0, -ax_re[0], -ax_re[1])
            r_im = (-ax_im[0], -ax_im[1])
            out = np.empty((c, n), dtype=complex)
            for part, (hi, lo) in ((out.real, r_re), (out.imag, r_im)):
                lo = np.where(np.isfinite(lo) | ~np.isfinite(hi), lo, 0.0)
                part[...] = hi + lo
            return out

    def _residual_compiled(self, omega, xh, xl, rhs):
        """:meth:`residual` by the compiled kernel (the same operations in the same order)."""
        c, n = xh.shape
        z = np.zeros((c, 1))
        xr = np.concatenate([xh.real, z], axis=1)
        xi = np.concatenate([xh.imag, z], axis=1)
        if xl is not None:
            xlr = np.concatenate([xl.real, z], axis=1)
            xli = np.concatenate([xl.imag, z], axis=1)
        else:
            xlr = xli = xr
        out_r, out_i = np.empty((c, n)), np.empty((c, n))
        with np.errstate(all="ignore"):
            _kernels().residual(np.ascontiguousarray(omega, dtype=float), xr, xi, xlr, xli,
                                xl is not None, np.asarray(rhs, dtype=float), self.k_bi,
                                self.k_bj, self.k_bs, self.e_i, self.e_j, self.e_val,
                                self.e_vs[0], self.e_vs[1], self.s_col, self.s_val,
                                self.s_vs[0], self.s_vs[1], np.zeros((4 * n + 4, 4)),
                                out_r, out_i)
        return out_r + 1j * out_i

    def sensitivities(self, omega: NDArray, x: NDArray, K: NDArray) -> tuple[NDArray, NDArray]:
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
        and K are near float64's limits), and divided by |K|.
        """
        w = np.asarray(omega)[:, None]
        c = x.shape[0]
        with np.errstate(all="ignore"):
            scale = np.max(np.abs(x), axis=1, initial=0.0)
            scale = np.where((scale > 0) & np.isfinite(scale), scale, 1.0)
            kern = _kernels() if self.n > DENSE_LIMIT else None
            if kern is not None and not np.iscomplexobj(omega):
                S, Sd = np.empty(c), np.empty(c)
                xe = np.concatenate([np.asarray(x, dtype=complex), np.zeros((c, 1), complex)],
                                    axis=1)
                kern.sensitivities(np.asarray(omega, dtype=float), xe, scale, self.e_i,
                                   self.e_j, self.e_m, self.e_k, self.e_c, self.s_row,
                                   self.s_col, self.s_val, self.l_p1, self.l_p2, self.l_col,
                                   self.l_r, S, Sd)
                f = scale / np.abs(K)
                return S * f * scale, Sd * f * scale
            xe = np.concatenate([np.asarray(x, dtype=complex) / scale[:, None],
                                 np.zeros((c, 1), complex)], axis=1)
            y = np.abs(combine(self.e_c, self.e_m, self.e_k, w))
            ax = np.abs(xe)
            ai, aj = ax[:, self.e_i], ax[:, self.e_j]
            d = np.abs(xe[:, self.e_i] - xe[:, self.e_j])
            S = np.einsum("ij,ij->i", y, (ai + aj) * d)
            if self.s_row.size:
                S = S + np.abs(self.s_val) @ (ax[:, self.s_row] * ax[:, self.s_col]).T \
                    if c else S
            Sd = np.einsum("ij,ij->i", y, d * d)
            if self.l_r.size:
                dl = np.abs(xe[:, self.l_p1] - xe[:, self.l_p2])
                Sd = Sd + np.sum(2 * self.l_r * dl * ax[:, self.l_col], axis=1)
            f = scale / np.abs(K)
            return S * f * scale, Sd * f * scale


#: Use the compiled residual kernel when numba is installed (set False to force numpy).
USE_NUMBA = True
#: A sweep uses the compiled kernels only from this many unknowns × ω points
#: on: importing numba and loading the kernels from their cache costs about
#: 0.6 s once per process (and compiling them in a fresh environment about
#: 12 s), while the numpy path takes about 1 µs per unknown and point (about
#: 3× the compiled one).  Decided per sweep from its size alone, so the same
#: call always takes the same path.
KERNEL_MIN_WORK = 1_000_000
_KERNELS = []
_WANTED = contextvars.ContextVar("mechcirc_nodal_kernels", default=True)


def _kernels():
    """The compiled kernel module, or None (numba not installed or not wanted).

    Used on the sparse path only (above :data:`DENSE_LIMIT` unknowns): small
    systems are vectorised over many ω at once, and need no compilation.
    Inside a sweep smaller than :data:`KERNEL_MIN_WORK`, None.
    """
    if not USE_NUMBA or not _WANTED.get():
        return None
    if not _KERNELS:
        from . import _nodal_kernels

        _KERNELS.append(_nodal_kernels if _nodal_kernels.HAVE_NUMBA else None)
    return _KERNELS[0]


def _dd_div_dd(ah, al, bh, bl):
    """(ah + al)/(bh + bl) in double-double (real)."""
    q = ah / bh
    qh, ql = _split(q)
    p, e = _two_prod(q, qh, ql, bh)
    return q, ((((ah - p) - e) + al) - q * bl) / bh


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
        float64; ``inf`` where the refinement does not contract or stalls
        even with double-double factors (:class:`_DDSolver`, up to
        :data:`DD_LIMIT` unknowns), or A(ω) is not finite.
    singular : ndarray of bool, shape (n_ω,)
        Points on a singularity of A(ω) (exact, or within rounding).
    """

    x: NDArray | None
    K: NDArray[np.complex128]
    error: NDArray[np.float64]
    singular: NDArray[np.bool_]


#: SuperLU points whose refinement leaves a larger estimate than this are
#: factorised again with partial pivoting (:class:`_SparseSolver`).
_STRICT_AFTER = 1e-10

#: Work per chunk of frequencies: about this many (ω, term) pairs at once.
_CHUNK_TERMS = 2 ** 17


def _sweep(system: NodalSystem, omega: NDArray, refine: bool, steps: int, keep: NDArray):
    """Factor, solve and refine at each ω (real or complex, already checked), chunk by chunk.

    Returns (K, error of the solve, S, S_data, x rows or None, the rows of x
    at ``keep``).  What does not change with ω — the pattern, the solver's
    choice and ordering, the residual's plan — comes from :func:`_pattern`
    and :func:`_solver`.  The compiled kernels serve it only if it is large
    enough (:data:`KERNEL_MIN_WORK`).
    """
    token = _WANTED.set(system.size * omega.size >= KERNEL_MIN_WORK)
    try:
        return _sweep_chunks(system, omega, refine, steps, keep)
    finally:
        _WANTED.reset(token)


def _sweep_chunks(system: NodalSystem, omega: NDArray, refine: bool, steps: int,
                  keep: NDArray):
    """:func:`_sweep`'s work: the loop over chunks of ω."""
    n = system.size
    m = omega.size
    pat = _pattern(system)
    rhs = system.injection()
    K = np.full(m, complex(np.nan, np.nan))
    err = np.full(m, np.inf)
    S = np.full(m, np.nan)
    Sd = np.full(m, np.nan)
    x_all = np.full((m, n), complex(np.nan, np.nan)) if keep is None else None
    kept = {}
    checked = np.zeros(m, dtype=bool)
    solver = _solver(system)
    if solver.kind != "dense" and _kernels() is not None:
        # Compiled: no (ω, term) temporaries; the chunk's (ω, n) arrays stay in cache.
        chunk = max(1, min(solver.max_chunk, 2 ** 16 // max(1, n)))
    else:
        chunk = max(1, min(solver.max_chunk, _CHUNK_TERMS // max(1, pat.n_terms + n)))
    use_dd = refine and n <= DD_LIMIT and not np.iscomplexobj(omega)

    def store(sel, xh, xl, est, rho):
        K[sel] = _difference_dd(system, xh, xl)
        x = xh + xl if xl is not None else xh
        S[sel], Sd[sel] = pat.sensitivities(omega[sel], x, K[sel])
        # A refinement that stalls (corrections not shrinking: the factors
        # are too inaccurate, cond(A)·u ≳ 1) has not converged, unless it
        # stalls at the residual's own rounding: its last correction says
        # nothing of the error (seen: 2.8e-9 and 2.8e-12 with corrections of
        # 1e-11 and 2.6e-16 on a stiff tree, cond(A) ≈ 1e17).  No estimate: inf.
        floor = 16 * _residual_rounding(system, S[sel])
        err[sel] = np.where((rho >= 0.5) & (est > floor), np.inf, est)
        if x_all is not None:
            x_all[sel] = x
        elif keep is not None:
            for k in np.flatnonzero(keep[sel]):
                kept[int(sel[k])] = x[k]

    for start in range(0, m, chunk):
        every = np.arange(start, min(start + chunk, m))
        good, solve_fn = solver.factor(omega[every])
        sel = every[good]
        if sel.size:
            xh, xl, est, rho = _refined(solve_fn, pat, omega[sel], rhs, system, refine, steps)
            redo = np.flatnonzero(~(est <= _STRICT_AFTER)) if solver.kind == "superlu" else []
            if len(redo):
                # Diagonal pivoting was not stable enough here: partial pivoting.
                ok2, strict_fn = solver.factor(omega[sel[redo]], strict=True)
                if ok2.all():
                    xh2, xl2, est2, rho2 = _refined(strict_fn, pat, omega[sel[redo]], rhs,
                                                    system, refine, steps)
                    better = ~(est2 >= est[redo])
                    take = redo[better]
                    xh[take], est[take], rho[take] = xh2[better], est2[better], rho2[better]
                    if xl is not None:
                        xl[take] = xl2[better]
            store(sel, xh, xl, est, rho)
        if use_dd:
            # Float64 factors failed (A(ω) exactly singular as rounded to float64),
            # could not refine, or had not converged after ``steps`` (then the
            # last correction is not a safe estimate: 6.6e-14 for a true
            # 1.7e-13 on a stiff tree): the double-double LU.
            done = np.isfinite(err[every]) & (
                err[every] <= np.maximum(16 * np.finfo(float).eps,
                                         16 * _residual_rounding(system, S[every])))
            todo = every[~done]
            checked[todo] = True
            dd = _dd_solver(system)
            for at in range(0, todo.size, dd.max_chunk):
                redo = todo[at:at + dd.max_chunk]
                ok2, dd_fn = dd.factor(omega[redo])
                redo = redo[ok2]
                xh2, xl2, est2, rho2 = _refined(dd_fn, pat, omega[redo], rhs, system, refine,
                                                steps)
                better = ~(est2 >= err[redo])
                store(redo[better], xh2[better], xl2[better], est2[better], rho2[better])
    return K, err, S, Sd, x_all, kept, checked


def _difference_dd(system, xh, xl):
    """K = x_a − x_b from x = xh + xl, rounded once."""
    zero = np.zeros(xh.shape[0], dtype=complex)
    ah = xh[:, system.a] if system.a >= 0 else zero
    bh = xh[:, system.b] if system.b >= 0 else zero
    with np.errstate(all="ignore"):
        s, e = _two_sum(ah, -bh)
        if xl is not None:
            al = xl[:, system.a] if system.a >= 0 else zero
            bl = xl[:, system.b] if system.b >= 0 else zero
            e = e + (al - bl)
        return np.asarray(s + e, dtype=complex)


def solve(system: NodalSystem, omega: ArrayLike, *, refine: bool = True,
          steps: int = 4, limits: bool = True, keep_x: bool = True) -> Solution:
    """Solve A(ω) x = e_a − e_b at each ω, refined, with an error estimate of K.

    Small systems (≤ :data:`DENSE_LIMIT` unknowns) are solved as batched dense
    systems; large ones by a sparse LU per ω on the fixed pattern (the choice
    of solver and its ordering made once, deterministically: see
    :class:`_SparseSolver`).  Refinement reuses the factors: each step is one
    residual in double-double arithmetic (:meth:`_Pattern.residual`) and one
    triangular solve, done for a chunk of frequencies at once.  With
    ``keep_x=False`` the solutions are not kept (``Solution.x`` is None),
    which bounds the memory of long sweeps of large networks.
    """
    omega = np.asarray(omega, dtype=float).reshape(-1)
    ok = np.isfinite(omega) & (omega > 0)
    idx = np.flatnonzero(ok)
    m = omega.size
    K = np.full(m, complex(np.nan, np.nan))
    err = np.full(m, np.inf)
    S = np.full(m, np.nan)
    Sd = np.full(m, np.nan)
    x = np.full((m, system.size), complex(np.nan, np.nan)) if keep_x else None
    kept = {}
    checked = np.zeros(m, dtype=bool)
    if idx.size:
        Ki, ei, Si, Sdi, xi, kept_i, ci = _sweep(system, omega[idx], refine, steps,
                                                 None if keep_x else np.ones(idx.size, bool))
        K[idx], err[idx], S[idx], Sd[idx], checked[idx] = Ki, ei, Si, Sdi, ci
        if keep_x:
            x[idx] = xi
        else:
            # Only the rows needed at singular points are kept.
            sing = ~np.isfinite(Ki) | (ei >= 1.0)
            kept = {int(idx[k]): v for k, v in kept_i.items() if sing[k]}
    # No correct digit even from the double-double LU (cond(A) beyond about
    # 1e30), or A(ω) exactly singular: a singular point.  Where only float64
    # factors were tried (no refinement, or more than DD_LIMIT unknowns), a
    # refinement that does not contract says no more than "no digit known":
    # K stays finite with an infinite error (flag 2), never a pole.  The
    # residual-rounding bound below is a worst case and not used here.
    singular = ok & (~np.isfinite(K) | (err >= 1.0) & checked)
    rows = x if keep_x else kept
    for i in np.flatnonzero(ok & (err >= 1.0) & ~checked & np.isfinite(K)):
        # Only float64 factors: singular if the iterate's element-wise
        # backward error says A(ω) is within rounding of its values of a
        # singular matrix; a stiff network's garbage iterate is not.
        singular[i] = _backward_error(system, omega[i], rows[i]) <= SINGULAR_BACKWARD
    with np.errstate(all="ignore"):
        err = err + _residual_rounding(system, S)
        err = np.where(ok, np.maximum(err, np.finfo(float).eps), np.inf)
    if limits:
        K, err = _singular_points(system, omega, rows, K, err, singular, steps)
    return Solution(x, K, err, singular)


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
    pat = _pattern(system)
    rhs = system.injection()
    with np.errstate(all="ignore"):
        ax = rhs - pat.residual(np.array([omega]), x[None, :], None, rhs)[0]
        xe = np.append(np.asarray(x, dtype=complex), 0.0)
        y = np.abs(combine(pat.e_c, pat.e_m, pat.e_k, omega))
        t = y * np.abs(xe[pat.e_i] - xe[pat.e_j])
        n1 = pat.n + 1
        den = np.bincount(pat.e_i, t, n1) + np.bincount(pat.e_j, t, n1) + \
            np.bincount(pat.s_row, np.abs(pat.s_val * xe[pat.s_col]), n1)
        eta = np.abs(ax) / den[:-1]
        return float(np.max(np.where(np.abs(ax) == 0, 0.0, eta), initial=0.0))


def _refined(solve_fn, pat: _Pattern, omega, rhs, system, refine: bool, steps: int):
    """x from one solve and up to ``steps`` refinement steps.

    Returns (xh, xl, relative error of K, contraction of the last step):
    x = xh + xl in double-double (xl None without refinement).
    """
    eps = np.finfo(float).eps
    b = np.broadcast_to(rhs.astype(complex), (omega.size, rhs.size))
    x0 = solve_fn(b)
    if not refine:
        # No refinement: the first correction is still the error estimate.
        d = solve_fn(pat.residual(omega, x0, None, rhs))
        return (x0, None, *_estimate(system, x0, None, d, x0))
    xh, xl = x0.copy(), np.zeros_like(x0)
    prev = x0
    est = np.full(omega.size, np.inf)
    rho = np.zeros(omega.size)
    active = np.arange(omega.size)
    for step in range(steps):
        # Only the points not yet converged take a further step (their
        # factors chosen by ``rows``).
        rows = None if active.size == omega.size else active
        xa, xla = xh[active], (xl[active] if step else None)
        d = solve_fn(pat.residual(omega[active], xa, xla, rhs), *(() if rows is None else (rows,)))
        est[active], rho[active] = _estimate(system, xa, xla, d, prev[active])
        with np.errstate(all="ignore"):
            s, e = _two_sum(xa, d)
        xh[active] = s
        xl[active] = e if xla is None else xla + e
        prev = prev.copy() if step == 0 else prev
        prev[active] = d
        # est bounds the error before this correction; after it, the error is
        # smaller still (by the contraction): stop once est is near rounding.
        active = active[est[active] > 16 * eps]
        if not active.size:
            break
    return xh, xl, est, rho


def _residual_rounding(system, S):
    """Relative error of K left by residuals rounded in double-double.

    Each residual row is summed to about (terms + 4)·u² × Σ_e |y_e (x_i − x_j)|
    (+ its lever stamps; u = 2⁻⁵³), which K (through the adjoint solution,
    x itself) feels as that times S (:meth:`_Pattern.sensitivities`); the
    refinement cannot see it.
    """
    pat = _pattern(system)
    u2 = (np.finfo(float).eps / 2) ** 2
    with np.errstate(all="ignore"):
        out = 4 * (pat.max_terms + 4) * u2 * S
    return np.where(np.isnan(out), np.inf, out)


def _total(S, est):
    """The solve's error ``est`` plus the sensitivity of K to rounding its data (resonances).

    Each value (m, k, c, r) carries a rounding of up to eps relative; that
    moves K by eps × S_data / |K| (``S``, from :meth:`_Pattern.sensitivities`),
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


def _estimate(system, xh, xl, d, prev):
    """(Relative error of K = x_a − x_b before applying the correction ``d``, contraction ρ).

    |d_a − d_b| estimates the error of K; ``d`` itself is wrong by about the
    contraction ρ = ‖d‖/‖prev‖ times the size of its drive components, which
    is added.  A correction
    as large as x itself that does not contract means A is numerically
    singular: inf.
    """
    tiny = np.finfo(float).eps ** 2
    with np.errstate(all="ignore"):
        nd = np.max(np.abs(d), axis=-1)
        nx = np.max(np.abs(xh), axis=-1)
        npv = np.maximum(np.max(np.abs(prev), axis=-1), tiny * nx)
        rho = np.where(npv > 0, nd / npv, 0.0)
        K = np.abs(_difference_dd(system, xh, xl))
        dK = np.abs(system.difference(d))
        # The drive's own components: a norm over all of d would mix scales
        # (a lever of ratio 1e150 puts velocities 1e150 apart).
        da = np.abs(d[..., system.a]) if system.a >= 0 else 0.0
        db = np.abs(d[..., system.b]) if system.b >= 0 else 0.0
        est = (dK + np.minimum(rho, 1.0) * (da + db)) / K
        # Stagnation at the residual's own rounding level is not divergence:
        # only corrections of the size of x itself that do not shrink mean a
        # singular A.
        diverged = (rho >= 0.5) & (nd > 1e-2 * nx)
        est = np.where(diverged | np.isnan(est), np.inf, est)
    return est, rho


def _dd_solver(system: NodalSystem) -> _DDSolver:
    cached = system.__dict__.get("_dd_solver")
    if cached is None:
        cached = _DDSolver(system)
        object.__setattr__(system, "_dd_solver", cached)
    return cached


def _solver(system: NodalSystem):
    """The solver of ``system`` (dense batch or sparse), built once per system."""
    cached = system.__dict__.get("_solver")
    if cached is None:
        pat = _pattern(system)
        cached = _DenseSolver(system, pat) if system.size <= DENSE_LIMIT \
            else _SparseSolver(pat)
        object.__setattr__(system, "_solver", cached)
    return cached


class _DenseSolver:
    """Batched dense solves: the inverses of A(ω) for a chunk of ω, applied as one product.

    An explicit inverse is no less accurate here than LU factors: every
    solution is refined with residuals in double-double, and the batch
    is applied as one matrix product (small systems, many ω).
    """

    kind = "dense"

    def __init__(self, system: NodalSystem, pat: _Pattern):
        self.dc = (system.D + system.C).toarray()
        self.m, self.k = system.M.toarray(), system.Ks.toarray()
        n = system.size
        self.max_chunk = max(1, _CHUNK_BYTES // (16 * n * n))

    def factor(self, omega):
        A = combine(self.dc, self.m, self.k, np.asarray(omega)[:, None, None])
        good = np.isfinite(A).all(axis=(1, 2))
        A = A[good]
        try:
            inv = np.linalg.inv(A)
        except np.linalg.LinAlgError:
            # Some matrix of the batch is exactly singular: invert one by one and
            # leave that frequency as NaN (rare; only on the failure path).
            inv = np.full(A.shape, np.nan, dtype=complex)
            for k in range(A.shape[0]):
                try:
                    inv[k] = np.linalg.inv(A[k])
                except np.linalg.LinAlgError:
                    pass
            ok = np.isfinite(inv).all(axis=(1, 2))
            good[np.flatnonzero(good)[~ok]] = False
            inv = inv[ok]
        return good, lambda r, rows=slice(None): np.einsum("kij,kj->ki", inv[rows], r)


#: The sparse path uses a banded LU when the half band width kl after a reverse
#: Cuthill–McKee ordering is at most this, SuperLU otherwise.
BAND_MAX = 12
#: SuperLU's threshold for keeping the diagonal pivot (symmetric mode).
DIAG_PIVOT_THRESH = 0.001


class _SparseSolver:
    """LU of A(ω) on its fixed pattern, with what does not change with ω found once.

    The choice is made from the pattern alone, so that the same network
    gives the same factorisation, bit for bit, on every run: after a reverse
    Cuthill–McKee ordering of the (symmetric) pattern, of half band width
    kl, a banded LU with partial pivoting when kl ≤ :data:`BAND_MAX`
    (chains, ladders and narrow strips: the ladder's band is 1 wide) — the
    compiled kernels of :mod:`mechcirc._nodal_kernels` when numba is
    installed, LAPACK's ``zgbtrf``/``zgbtrs`` otherwise; for wider bands
    (grids: the 30×30 grid's band is 30) SuperLU (``scipy.sparse.linalg.
    splu``) on A permuted symmetrically by a minimum-degree ordering of
    Aᵀ + A found once from the pattern, in its symmetric mode (diagonal
    pivots kept unless below :data:`DIAG_PIVOT_THRESH` of the column's
    largest entry), which fills 2–3× less than partial pivoting on these
    complex symmetric matrices; where the refinement then does not reach
    1e-10, the point is factorised again with partial pivoting.  The
    refinement and its error estimate are the same for either.
    """

    def __init__(self, pat: _Pattern):
        import scipy.sparse as sp
        from scipy.sparse.csgraph import reverse_cuthill_mckee

        self.pat = pat
        n = pat.n
        nnz = pat.indices.size
        ones = np.ones(nnz)
        A = sp.csc_matrix((ones, pat.indices, pat.indptr), shape=(n, n))
        p = np.asarray(reverse_cuthill_mckee(A.tocsr(), symmetric_mode=True))
        q = np.empty_like(p)
        q[p] = np.arange(n)
        cols = np.repeat(np.arange(n), np.diff(pat.indptr))
        ri, ci = q[pat.indices], q[cols]                  # permuted positions
        kl = int(np.max(np.abs(ri - ci), initial=0))
        self.kl = kl
        if kl <= BAND_MAX:
            self.kind = "band"
            self.p = p
            self.band_rows = 3 * kl + 1
            self.dest = (ci, 2 * kl + ri - ci)            # in the (n, rows) C-order array
            self.max_chunk = max(1, min(64, 2 ** 22 // max(1, n * self.band_rows)))
        else:
            from scipy.sparse.linalg import splu

            self.kind = "superlu"
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

    def factor(self, omega, strict: bool = False):
        """(good, solve): the frequencies factorised, and a solver for their rows.

        ``strict``: SuperLU with partial pivoting (threshold 1) instead of
        the symmetric mode, where the refinement did not converge.
        """
        pat = self.pat
        if self.kind == "band" and _kernels() is not None and not np.iscomplexobj(omega):
            return self._banded_compiled(np.asarray(omega, dtype=float))
        data = combine(pat.dc, pat.m, pat.k, np.asarray(omega)[:, None])
        good = np.isfinite(data).all(axis=1)
        if self.kind == "band":
            return self._banded(data, good)
        return self._superlu(data, good, strict)

    def _banded_compiled(self, omega):
        """The banded LU by the compiled kernels (the same unblocked LU as LAPACK's zgbtf2).

        No per-ω call overhead, and none of zgbtrf's BLAS calls per column,
        which on a band 1–2 wide cost many times the arithmetic.
        """
        kern = _kernels()
        pat, n, kl = self.pat, self.pat.n, self.kl
        ab = np.empty((omega.size, n, self.band_rows), dtype=complex)
        ipiv = np.empty((omega.size, n), dtype=np.int64)
        good = np.ones(omega.size, dtype=bool)
        kern.band_assemble_factor(pat.dc, pat.m, pat.k, omega, self.dest[0], self.dest[1],
                                  kl, ab, ipiv, good)
        if not good.all():
            ab, ipiv = ab[good], ipiv[good]
        p = self.p

        every = np.arange(ab.shape[0])

        def solve(r, rows=None):
            rows = every if rows is None else np.asarray(rows, dtype=np.int64)
            out = np.empty((rows.size, n), dtype=complex)
            kern.band_solve_perm(ab, kl, ipiv, rows, p, np.ascontiguousarray(r, dtype=complex),
                                 out)
            return out
        return good, solve

    def _banded(self, data, good):
        from scipy.linalg.lapack import zgbtrf, zgbtrs

        n, kl = self.pat.n, self.kl
        ab = np.zeros((data.shape[0], n, self.band_rows), dtype=complex)
        ab[:, self.dest[0], self.dest[1]] = data
        p = self.p
        factors = []
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

        n = self.pat.n
        factors = []
        for k in np.flatnonzero(good):
            A = sp.csc_matrix((data[k, self.take], self.indices_p, self.indptr_p),
                              shape=(n, n))
            try:
                factors.append(
                    splu(A, permc_spec="NATURAL", diag_pivot_thresh=1.0) if strict else
                    splu(A, permc_spec="NATURAL", diag_pivot_thresh=DIAG_PIVOT_THRESH,
                         options={"SymmetricMode": True}))
            except RuntimeError:            # exactly singular at this frequency
                good[k] = False
        perm, iperm = self.perm, self.iperm

        def solve(r, rows=None):
            r = np.asarray(r, dtype=complex)[:, iperm]
            use = factors if rows is None else [factors[i] for i in rows]
            return np.stack([lu.solve(r[k])[perm] for k, lu in enumerate(use)]) if use \
                else np.zeros((0, n), complex)
        return good, solve


def _singular_points(system, omega, x, K, err, singular, steps):
    """Apply the singular-point convention where A(ω) is (numerically) singular.

    Where the solution blows up along a mode seen from the drive (a pole of
    K), K = +∞·j (the series–parallel method's convention); where K carries no correct digit otherwise, K = 0 (a
    zero of K within rounding).  The estimate there is inf; ``Sweep.flags``
    marks both as singular (flag 1).  ``x`` gives the solution's row at
    each singular point (an array, or a dict of rows).
    """
    K = K.copy()
    err = err.copy()
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
        if abs(Ki) >= 1e-3 * scale:
            K[i] = complex(0.0, np.inf)     # the tree's convention: +∞·j at a pole
        else:
            K[i] = 0.0
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
    refined with residuals in double-double as in :func:`solve`, and the
    error is the same estimate (the last correction, the residual's own
    rounding and the sensitivity to rounding the data, eps × Σ|x_r a_rc x_c|):
    used to polish resonances on the circuit's own K.  NaN where A(s) is
    singular.
    """
    s = np.asarray(s, dtype=complex).reshape(-1)
    omega = -1j * s
    K, est, S, Sd, _, _, _ = _sweep(system, omega, True, 4, None)
    est = _total(Sd, est + _residual_rounding(system, S))
    with np.errstate(all="ignore"):
        return K, est * np.abs(K)


def mobility(system: NodalSystem, omega: ArrayLike) -> NDArray[np.complex128]:
    """K(ω) [m/(N·s)] seen by the drive, by nodal analysis."""
    return solve(system, omega, keep_x=False).K


def mobility_and_error(system: NodalSystem, omega: ArrayLike
                       ) -> tuple[NDArray[np.complex128], NDArray[np.float64]]:
    """K(ω) [m/(N·s)] and its estimated relative error, from one refined solve.

    See :class:`Solution` for the estimate and the singular-point convention.
    """
    s = solve(system, omega, keep_x=False)
    return s.K, s.error


def mobility_unrefined(system: NodalSystem, omega: ArrayLike) -> NDArray[np.complex128]:
    """K(ω) [m/(N·s)] by one plain solve per ω, without refinement (the fast path).

    Its relative error is about eps × cond(A(ω)), see :func:`condition_error`.
    """
    return solve(system, omega, refine=False, limits=False, keep_x=False).K


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

    Dense systems are first judged by the smallest singular value of the
    balanced matrix (:func:`_balance`), and the null vector names the
    undetermined unknowns.  Where that does not clear a system, or it is
    large, the refined solve decides (in double-double where float64 factors
    cannot refine, see :class:`_DDSolver`): the system is regular at a trial
    ω if the solve gives a finite K and its solution's element-wise backward
    error as a null vector is above rounding (:func:`_backward_error`) — so a
    stiff network (cond(A) of 1e20, K well conditioned) is not refused.
    """
    if system.size == 0:
        raise TopologyError(
            "nothing between the drive's nodes carries force (no unknowns left; unloaded: "
            f"{', '.join(system.unloaded[:12]) or 'none'})", elements=system.unloaded)
    scale = _frequency_scale(system)
    trial = [0.731 * scale, 1.913 * scale]
    judged, overflow = None, False
    if system.size <= DENSE_LIMIT:
        absdiag = [np.abs(p.diagonal()) for p in (system.D + system.C, system.M, system.Ks)]
        for w, A in zip(trial, dense_matrices(system, trial)):
            if not np.isfinite(A).all():
                return          # values at float64's edge: the sweep flags such points
            # Judge the balanced matrix: a lever of ratio 1e-8 puts entries of
            # 1e-8 beside 1, every value scaled by 1e-100 puts admittances of
            # 1e-100 beside the lever's ±1, and the raw singular values then
            # look singular.
            diag = absdiag[0] + w * absdiag[1] + absdiag[2] / w
            d = _balance(np.abs(A)[None], diag[None])[0]
            with np.errstate(all="ignore"):
                A = A * d[:, None] * d[None, :]
            if not np.isfinite(A).all():    # values over ~600 decades (a lever ratio of
                overflow = True             # 1e300): balancing overflows; the solve decides
                continue
            sv = np.linalg.svd(A, compute_uv=False)
            if sv[-1] > 1e-13 * sv[0]:
                return
            judged = A
    s = solve(system, trial, limits=False)
    for i, w in enumerate(trial):
        if np.isfinite(s.K[i]) and not s.singular[i] and \
                _backward_error(system, w, s.x[i]) > SINGULAR_BACKWARD:
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
