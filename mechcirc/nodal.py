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
force injected at n1 and taken out at n2.  Small systems are solved as one
batched dense solve over ω (in chunks of bounded memory); large ones with a
sparse LU per frequency.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .circuit import FRAME, Circuit, Element, Lever
from .errors import TopologyError
from .topology import check_frame_paths, loaded_groups

__all__ = ["NodalSystem", "assemble", "solve_unit", "DENSE_LIMIT"]

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

    With ``whole`` every element and lever is kept, and no drive is needed
    (time-domain integration of the whole network, :mod:`mechcirc.transient`).

    Raises
    ------
    TopologyError
        If the drive's nodes are not connected or a node is reached only
        through a lever's other side (singular at every frequency).
    """
    d = circuit.drive
    if whole:
        kept = set(range(len(circuit.elements) + len(circuit.levers)))
    else:
        check_frame_paths(circuit)
        groups = [[(e.n1, e.n2)] for e in circuit.elements]
        for lv in circuit.levers:
            t = (lv.p1, lv.p2, lv.s1, lv.s2)
            groups.append([(t[i], t[j]) for i in range(4) for j in range(i + 1, 4)])
        kept = set(loaded_groups(groups, d.n1, d.n2, drive_line=d.line,
                                     source=circuit.source))
    n_el = len(circuit.elements)
    elements = tuple(e for i, e in enumerate(circuit.elements) if i in kept)
    levers = tuple(lv for i, lv in enumerate(circuit.levers) if n_el + i in kept)
    unloaded = tuple(e.name for i, e in enumerate(circuit.elements) if i not in kept) + \
        tuple(lv.name for i, lv in enumerate(circuit.levers) if n_el + i not in kept)

    names: dict[str, None] = {}
    for e in elements:
        names.setdefault(e.n1)
        names.setdefault(e.n2)
    for lv in levers:
        for n in (lv.p1, lv.p2, lv.s1, lv.s2):
            names.setdefault(n)
    reference = FRAME if FRAME in names or d is None else d.n2
    nodes = tuple(n for n in names if n != reference)
    index = {n: i for i, n in enumerate(nodes)}
    index[reference] = -1
    import scipy.sparse as sp

    n = len(nodes) + len(levers)
    triplets = {"mass": ([], [], []), "damper": ([], [], []), "spring": ([], [], []),
                "lever": ([], [], [])}
    for e in elements:
        _stamp(triplets[e.kind], index[e.n1], index[e.n2], e.value * e.eta)
    rows, cols, vals = triplets["lever"]
    for k, lv in enumerate(levers):
        col = len(nodes) + k
        for node, coef in ((lv.p1, lv.ratio), (lv.p2, -lv.ratio), (lv.s1, -1.0), (lv.s2, 1.0)):
            i = index[node]
            if i >= 0:
                rows += [i, col]
                cols += [col, i]
                vals += [coef, coef]
    M, D, Ks, C = (sp.csr_matrix((v, (r, c)), shape=(n, n))
                   for r, c, v in (triplets[k] for k in ("mass", "damper", "spring", "lever")))
    stamps = {kind: tuple(np.asarray(a) for a in t) for kind, t in triplets.items()}
    return NodalSystem(nodes, levers, elements, unloaded, M, D, Ks, C,
                       index.get(d.n1, -1) if d else -1, index.get(d.n2, -1) if d else -1,
                       stamps)


def _stamp(triplet, i: int, j: int, y: float) -> None:
    rows, cols, vals = triplet
    for r, c, v in ((i, i, y), (j, j, y), (i, j, -y), (j, i, -y)):
        if r >= 0 and c >= 0:
            rows.append(r)
            cols.append(c)
            vals.append(v)


def solve_unit(system: NodalSystem, omega: ArrayLike, *, refine: bool = True
               ) -> NDArray[np.complex128]:
    """Solutions x(ω) of A(ω) x = e_a − e_b, shape (n_omega, n) (``clongdouble`` if refined).

    With ``refine`` (the default) each solution gets up to two steps of
    iterative refinement with the residual b − A x computed in extended
    precision (``numpy.longdouble``): the forward error then no longer grows
    with the condition number of A (masses and springs of very different
    size in series), at about twice the cost of one solve.

    Frequencies where A is exactly singular, or ω is 0 or ∞ (where A is not
    finite), give rows of NaN; callers flag them.
    """
    omega = np.asarray(omega, dtype=float)
    n = system.size
    out = np.full((omega.size, n), np.nan, dtype=np.clongdouble if refine else complex)
    ok = np.isfinite(omega) & (omega > 0)
    idx = np.flatnonzero(ok)
    rhs = system.injection()
    tri = _Triplets(system) if refine else None
    if n <= DENSE_LIMIT:
        base = (system.D + system.C).toarray()
        M, Ks = system.M.toarray(), system.Ks.toarray()
        chunk = max(1, _CHUNK_BYTES // (16 * n * n))
        for start in range(0, idx.size, chunk):
            sel = idx[start:start + chunk]
            w = omega[sel][:, None, None]
            with np.errstate(over="ignore", invalid="ignore"):   # ω·m beyond 1.8e308: flagged
                A = base + 1j * (w * M - Ks / w)
            x = _batched_solve(A, rhs)
            if refine:
                x = _refine(x, lambda r: _batched_solve(A, r), tri, omega[sel], rhs)
            out[sel] = x
        return out
    from scipy.sparse.linalg import splu

    base = (system.D + system.C).tocsc()
    Ms, Kss = system.M.tocsc(), system.Ks.tocsc()
    b = rhs.astype(complex)
    for i in idx:     # one sparse LU per frequency: each is far costlier than the loop
        w = omega[i]
        try:
            lu = splu((base + 1j * (w * Ms - Kss / w)).tocsc())
        except RuntimeError:            # exactly singular at this frequency
            continue
        x = lu.solve(b)
        if refine:
            x = _refine(x[None, :], lambda r: lu.solve(r[0])[None, :], tri,
                        omega[i:i + 1], rhs)[0]
        out[i] = x
    return out


def _refine(x, solve, tri: "_Triplets", omega, rhs, steps: int = 3):
    """Iterative refinement with x and the residual held in extended precision.

    Keeping x itself in ``longdouble`` matters: the solution's components can
    be far larger than the velocity difference wanted from them, and a
    double-precision x cannot carry it to full accuracy.
    """
    x = x.astype(np.clongdouble)
    for _ in range(steps):
        dx = solve(tri.residual(omega, x, rhs))
        x = x + dx
        if not np.any(np.abs(dx) > 1e-18 * np.abs(x)):
            break
    return x


class _Triplets:
    """The nonzeros of A(ω) = D + C + j(ωM − Kₛ/ω), for residuals in extended precision."""

    def __init__(self, system: NodalSystem):
        ext = np.longdouble
        rows, cols, m, k, dc = [], [], [], [], []
        for kind, (r, c, v) in system.stamps.items():
            v = np.asarray(v, dtype=ext)
            zero = np.zeros_like(v)
            rows.append(np.asarray(r, dtype=int))
            cols.append(np.asarray(c, dtype=int))
            m.append(v if kind == "mass" else zero)
            k.append(v if kind == "spring" else zero)
            dc.append(v if kind in ("damper", "lever") else zero)
        self.rows, self.cols = np.concatenate(rows), np.concatenate(cols)
        self.m, self.k, self.dc = np.concatenate(m), np.concatenate(k), np.concatenate(dc)
        self.n = system.size

    def residual(self, omega: NDArray, x: NDArray, rhs: NDArray) -> NDArray[np.complex128]:
        """b − A(ω) x for each ω (rows of ``x``), accumulated in extended precision."""
        ext = np.longdouble
        w = omega.astype(ext)[:, None]
        a = self.dc + 1j * (w * self.m - self.k / w)          # clongdouble, (n_ω, nnz)
        prod = a * x[:, self.cols]
        Ax = np.zeros((omega.size, self.n), dtype=np.clongdouble)
        np.add.at(Ax, (np.arange(omega.size)[:, None], self.rows[None, :]), prod)
        r = rhs.astype(ext)[None, :] - Ax
        return r.astype(complex)


def _batched_solve(A: NDArray, rhs: NDArray) -> NDArray:
    """Solve A[k] x[k] = rhs (or rhs[k]) for a batch; exactly singular members give NaN."""
    b = np.broadcast_to(rhs.astype(complex), A.shape[:-1])[..., None]
    try:
        return np.linalg.solve(A, b)[..., 0]
    except np.linalg.LinAlgError:
        # Some matrix of the batch is exactly singular: solve one by one and leave
        # that frequency as NaN (rare; only on the failure path).
        x = np.full(A.shape[:-1], np.nan, dtype=complex)
        for k in range(A.shape[0]):
            try:
                x[k] = np.linalg.solve(A[k], b[k])[..., 0]
            except np.linalg.LinAlgError:
                pass
        return x


def mobility(system: NodalSystem, omega: ArrayLike) -> NDArray[np.complex128]:
    """K(ω) [m/(N·s)] seen by the drive, by nodal analysis."""
    return system.difference(solve_unit(system, omega)).astype(complex)


def mobility_unrefined(system: NodalSystem, omega: ArrayLike) -> NDArray[np.complex128]:
    """K(ω) [m/(N·s)] by one plain solve per ω, without refinement (the fast path).

    Its relative error is about eps × cond(A(ω)), see :func:`condition_error`.
    """
    return system.difference(solve_unit(system, omega, refine=False))


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
    """Estimated relative error of the solve: eps × cond₂(A(ω)); NaN for sparse systems."""
    omega = np.asarray(omega, dtype=float)
    out = np.full(omega.shape, np.nan)
    ok = np.isfinite(omega) & (omega > 0)
    out[~ok] = np.inf
    if system.size > DENSE_LIMIT:
        return out
    base = (system.D + system.C).toarray()
    M, Ks = system.M.toarray(), system.Ks.toarray()
    n = system.size
    idx = np.flatnonzero(ok)
    chunk = max(1, _CHUNK_BYTES // (16 * n * n))
    for start in range(0, idx.size, chunk):
        sel = idx[start:start + chunk]
        w = omega[sel][:, None, None]
        with np.errstate(over="ignore", invalid="ignore"):
            A = base + 1j * (w * M - Ks / w)
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
    base = (system.D + system.C).toarray()
    M, Ks = system.M.toarray(), system.Ks.toarray()
    judged = None
    for w in trial:
        with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
            A = base + 1j * (w * M - Ks / w)
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
