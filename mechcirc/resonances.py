"""Resonances and anti-resonances of a circuit, exactly, from its matrices.

Under kinematic excitation the force amplitude Q0 = V0/K is infinite where
K = 0: these are the *resonances*, the natural frequencies of the network with
the drive held (its two nodes moving together).  K is infinite at the
*anti-resonances*, the natural frequencies of the network with the drive
released (no force through it); under force excitation the velocity peaks
there.

Method.  The nodal matrices give the quadratic eigenproblem
(s² M + s D + Kₛ) v = 0 with the lever constraints (and, for resonances, the
drive constraint v_a = v_b) imposed exactly by projecting onto their null
space.  Undamped networks: massless directions are condensed out statically
(exact) and the symmetric problem Kₛ v = ω² M v is solved by
``numpy.linalg.eigvalsh`` (error bound eps·λ_max/λ, Weyl; small networks need
no scipy), or, when its rows reordered by reverse Cuthill–McKee form a narrow
band (a chain, a mesh), by the banded ``scipy.linalg.eigvals_banded`` in
O(n²b) instead of O(n³).  Damped networks:
the problem is linearised to a 2n generalised eigenproblem solved by QZ
(``scipy.linalg.eig``); s = −ζωₙ ± jωₙ√(1 − ζ²).  Networks above the dense
limits are solved in a band ``omega_max``: undamped ones by counting the
roots in the band first (Sylvester's inertia of K − ω²M from sparse symmetric
factorisations) and then shift-invert Lanczos on the symmetric pencil
(``scipy.sparse.linalg.eigsh``); damped ones by shift-invert Arnoldi on the
same linearisation (``scipy.sparse.linalg.eigs``).

Every damped root, and every undamped root whose eigenvalue bound is not
already at rounding level, is then polished on the circuit's own K(s) at
complex s (a complex secant; anti-resonances on the held system, which is
regular where A is singular), K being refined in double-double; the
reported ``error`` is the uncertainty of K there over its slope, plus the
last step, including the effect of rounding the element values.

A mode that appears in both problems at the same frequency is not seen from
the drive (it cancels in K) and is not reported; a close pair that K itself
shows (a weakly coupled mode, :func:`_pair_verdict`) is.  Zero-frequency
(rigid-body) modes are not reported.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal

import numpy as np

from . import nodal
from .circuit import Circuit
from .errors import InputError, NetlistError, SolverError, UnloadedElementWarning, warn
from .sources import data_frame, did_you_mean, real_number
from .units import FREQUENCY_UNITS, in_unit

__all__ = ["Resonance", "Resonances", "find_resonances", "MAX_UNKNOWNS", "MAX_UNKNOWNS_DAMPED"]

#: Largest eigenproblem solved (unknowns left after the constraints).  The
#: dense solve costs O(n³): 21.5 s CPU at 1999 unknowns undamped (one BLAS thread;
#: 80 % polishing the roots on K, docs/reliability.md; a chain is now banded:
#: 11.5 s, 93 % polishing, benchmarks/bench_resonances_limit.py), and the
#: damped 2n linearisation about 10 s at 500 (measured, docs/reliability.md).
#: Larger networks are refused at once instead of running for hours.
MAX_UNKNOWNS = 2000
#: The same for networks with dampers (QZ on a 2n × 2n pencil).
MAX_UNKNOWNS_DAMPED = 500
#: The most eigenvalues the band solver asks ARPACK for (roots and their mirror images).
MAX_BAND_ROOTS = 192
#: Roots whose ω differ by at most this (relative) are sorted as equal: the
#: anti-resonance first (:func:`tie_order`).
TIE_RTOL = 1e-14


#: Machine epsilon of float64, the unit of every error estimate here.
_EPS = np.finfo(float).eps
#: The two kinds of root of K: a zero and a pole.
Kind = Literal["resonance", "antiresonance"]


@dataclass(frozen=True)
class Resonance:
    """A zero (``"resonance"``) or pole (``"antiresonance"``) of K(ω).

    Attributes
    ----------
    kind : {"resonance", "antiresonance"}
    omega : float
        Undamped natural angular frequency ωₙ = |s| [rad/s].
    omega_d : float
        Damped natural angular frequency Im s [rad/s] (= ωₙ when undamped; 0
        for an overdamped mode).
    zeta : float
        Damping ratio −Re s / |s| [1] (0 when undamped).
    error : float
        Estimated relative error of ``omega`` [1].

    ``f_hz`` is ωₙ/2π; any frequency in Hz or rpm: :func:`mechcirc.units.in_unit`,
    e.g. ``in_unit(r.omega_d, "Hz")``, or the table of :meth:`Resonances.table`.
    """

    kind: Kind
    omega: float
    omega_d: float
    zeta: float
    error: float

    @property
    def f_hz(self) -> float:
        """Natural frequency ωₙ / 2π [Hz]."""
        return in_unit(self.omega, "Hz")

    def as_dict(self) -> dict:
        """Plain data for JSON output: the fields and ``f_hz``, in the one order every
        command writes them (``kind``, ``omega``, ``f_hz``, ``omega_d``, ``zeta``, ``error``).

        Returns
        -------
        dict
            str → str or float.
        """
        return {"kind": self.kind, "omega": self.omega, "f_hz": self.f_hz,
                "omega_d": self.omega_d, "zeta": self.zeta, "error": self.error}


class Resonances(list):
    """A list of :class:`Resonance` (sorted by ω) that shows itself as a table.

    It is a plain ``list`` in every other respect (indexing, pickling); a
    slice is a Resonances too (``found[:3]`` shows as a table).  ``repr`` and
    ``_repr_html_`` (notebooks) give the table ``mechcirc resonances`` prints;
    :meth:`table` gives it in Hz or rpm.
    """

    def __getitem__(self, i):
        got = super().__getitem__(i)
        return Resonances(got) if isinstance(i, slice) else got

    def table(self, unit: str = "rad/s") -> list[str]:
        """The table's lines: header, then one line per root; frequencies in ``unit``.

        ``unit`` is ``"rad/s"`` (ωₙ, f = ωₙ/2π [Hz] and ω_d columns), ``"Hz"``
        (f and f_d) or ``"rpm"`` (n and n_d); then ζ [1] and the relative error.
        """
        if unit not in FREQUENCY_UNITS:
            raise InputError(f"unit must be 'rad/s', 'Hz' or 'rpm', got {unit!r}"
                             f"{did_you_mean(str(unit), FREQUENCY_UNITS)}")
        name, _ = FREQUENCY_UNITS[unit]
        hz = unit == "rad/s"            # omega in rad/s has f in Hz beside it
        head = (f"{'kind':<14} {f'{name} [{unit}]':>17}" + (f" {'f [Hz]':>14}" if hz else "")
                + f" {f'{name}_d [{unit}]':>17} {'zeta':>10} {'rel. error':>10}")
        return [head] + [f"{r.kind:<14} {in_unit(r.omega, unit):>17.10g}"
                         + (f" {r.f_hz:>14.8g}" if hz else "")
                         + f" {in_unit(r.omega_d, unit):>17.10g} {r.zeta:>10.4g} {r.error:>10.1e}"
                         for r in self]

    def to_dataframe(self):
        """One row per root, the columns of :meth:`Resonance.as_dict` (``kind``, ``omega``
        [rad/s], ``f_hz`` [Hz], ``omega_d`` [rad/s], ``zeta`` [1], ``error`` [1]);
        ``attrs["units"]`` the unit of each column (as :meth:`mechcirc.Sweep.to_dataframe`)."""
        return data_frame([r.as_dict() for r in self], {"kind": "", "omega": "rad/s", "f_hz": "Hz",
                                                        "omega_d": "rad/s", "zeta": "1", "error": "1"})

    def __repr__(self) -> str:
        return "Resonances([])  (none found)" if not self else "\n".join(self.table())

    def _repr_html_(self) -> str:
        import html

        head = ("<tr><th>kind</th><th>omega [rad/s]</th><th>f [Hz]</th>"
                "<th>omega_d [rad/s]</th><th>zeta</th><th>rel. error</th></tr>")
        rows = "".join(f"<tr><td>{html.escape(r.kind)}</td><td>{r.omega:.10g}</td>"
                       f"<td>{r.f_hz:.8g}</td><td>{r.omega_d:.10g}</td><td>{r.zeta:.4g}</td>"
                       f"<td>{r.error:.1e}</td></tr>" for r in self)
        return f"<table>{head}{rows}</table>"


def find_resonances(circuit: Circuit, omega_max: float | None = None,
                    kind: Kind | None = None) -> Resonances:
    """All resonances and anti-resonances of ``circuit`` up to ``omega_max`` [rad/s].

    Returns them sorted by ``omega``, as a :class:`Resonances` list (a table
    when shown).  See the module docstring for the method.

    Parameters
    ----------
    circuit : Circuit
        Any circuit with a drive.
    omega_max : float, optional
        Upper end of the band searched [rad/s]; None: no upper end (networks
        above the dense limits need one, see the module docstring).
    kind : {"resonance", "antiresonance"}, optional
        Only the roots of this kind (only they are polished: half the work
        when the other kind is not wanted); None: both.  The roots reported
        are bit-identical to those of ``kind=None`` of that kind.

    Returns
    -------
    Resonances
        Resonances (K = 0) and anti-resonances (K = ∞), sorted by ``omega``.

    Examples
    --------
    >>> from mechcirc import parse
    >>> c = parse("drive V a 0 velocity=1\\nmass m a b 1\\nspring k b 0 100\\n")
    >>> [(r.kind, round(r.omega, 12)) for r in c.resonances()]
    [('resonance', 10.0)]
    """
    return Resonances(r for r, _ in resonance_pairs(circuit, omega_max, kind=kind))


def resonance_pairs(circuit: Circuit, omega_max: float | None = None,
                    vectors: bool = False, kind: Kind | None = None) -> list:
    """:func:`find_resonances` as ``(Resonance, v)`` pairs, sorted as there.

    ``v`` is the root's eigenvector from the eigen-solve, the node velocities
    of ``circuit.nodal.nodes`` (the drive held for a resonance, released for
    an anti-resonance; unnormalised); None without ``vectors``, and for roots
    found by the band solver (which computes no vectors).  ``kind`` as in
    :func:`find_resonances` (both eigenproblems are still solved: roots shared
    by them cancel).  With ``vectors`` the pairs are triples ``(Resonance, v,
    repeated)``, ``repeated`` true where the eigenproblem has another root
    within 1e-9 (relative) of this one (then v is one vector of a family), and
    the undamped roots are those of the solve with vectors (``eigh``; the held ones
    by :func:`_secular_held` where it applies), not the values-only one's (banded):
    unpolished, they can differ in the last bits (errors of order eps·λ_max/λ).
    """
    _check_arguments(circuit, omega_max, kind)
    system = circuit.nodal
    if system.unloaded:
        d = circuit.require_drive()
        warn(f"{len(system.unloaded)} element(s) lie on no path between the drive's nodes "
             f"{d.n1!r} and {d.n2!r} and carry no force: {', '.join(system.unloaded)}",
             UnloadedElementWarning)
    # Small networks: dense matrices from the stamps, and no scipy for undamped ones.
    M, D, Ks, G_released, G_held, damped = pencil(system, dense=system.size <= nodal.DENSE_LIMIT)
    held, v_held, released, v_released, keep_h, keep_r = _solved(
        M, D, Ks, G_released, G_held, damped, omega_max, vectors,
        lambda h, r: _pair_verdict(system, h, r, where=True))
    pairs = []          # ((kind, s, error, must polish), (vector, repeated)) of each root
    for name, found, V, keep in (("resonance", held, v_held, keep_h),
                                 ("antiresonance", released, v_released, keep_r)):
        rep = _repeated(found[:, 0]) if vectors else np.zeros(len(found), bool)
        pairs += [((name, *found[i]), (None if V is None else V[:, i], bool(rep[i])))
                  for i in np.flatnonzero(keep)]
    # Each root's distance to the nearest of the other kind (a pole of the g it is a zero
    # of), which bounds its polish's first step.  Then those of the kind asked (root by
    # root: the others' polish changes nothing here) and in the band, with a margin
    # (polishing may move a root across its edge).
    s_all = np.array([t[1] for t, _ in pairs], dtype=complex)
    anti = np.array([t[0] == "antiresonance" for t, _ in pairs], dtype=bool)
    spacing = np.empty(s_all.size)
    for here in (anti, ~anti):
        spacing[here] = _spacing(s_all[here], s_all[~here])
    asked = [i for i, (t, _) in enumerate(pairs) if (kind is None or t[0] == kind) and
             (omega_max is None or abs(t[1]) <= omega_max * (1 + 1e-6))]
    roots = [pairs[i][0] for i in asked]
    out = [(r, pairs[i][1]) for r, i in zip(_polish(system, roots, damped, spacing[asked]),
                                            asked)
           if omega_max is None or r.omega <= omega_max] if roots else []
    out = sorted(out, key=lambda rv: (rv[0].omega, rv[0].kind))
    ties = tie_order(np.array([[r.kind == "antiresonance" for r, _ in out]], bool),
                     np.array([[r.omega for r, _ in out]], float))[0]
    out = [out[i] for i in ties]
    return [(r, *v) for r, v in out] if vectors else [(r, v[0]) for r, v in out]


def _check_arguments(circuit: Circuit, omega_max: float | None, kind) -> None:
    """Refuse an ``omega_max`` that is not a real number > 0 or None (a bool is no number,
    though an int), a ``kind`` not known, and an element whose value × eta overflows."""
    check_omega_max(omega_max)
    if kind not in (None, "resonance", "antiresonance"):
        raise InputError(f"kind must be 'resonance', 'antiresonance' or None, got {kind!r}"
                         f"{did_you_mean(str(kind), ('resonance', 'antiresonance'))}")
    for e in circuit.elements:
        if not math.isfinite(e.value * e.eta):
            raise NetlistError(f"{e.kind} {e.name!r}: value × eta = {e.value:g} × {e.eta:g} "
                               "overflows float64", circuit.source, e.line, e.col,
                               "a product below 1.8e308")


def check_omega_max(omega_max) -> None:
    """Refuse an ``omega_max`` [rad/s] that is not a real number > 0 or None (InputError).

    Parameters
    ----------
    omega_max : object
        The argument given.
    """
    if not (omega_max is None or real_number(omega_max) and omega_max > 0):
        raise InputError(f"omega_max must be > 0 rad/s or None, got {omega_max!r}")


def _solved(M, D, Ks, G_released, G_held, damped: bool, omega_max, vectors: bool,
            verdict=None) -> tuple:
    """``(held, its vectors, released, its vectors, keep held, keep released)``: both
    eigenproblems (:func:`_modes`; LAPACK's failures reported as :class:`SolverError`) and
    which roots survive :func:`_cancel`."""
    try:
        released, v_released = _modes(M, D, Ks, G_released, damped, omega_max, vectors)
        # Held = released + the drive's row: with every released vector at hand (no lever,
        # no massless or rigid direction) the held roots and vectors follow from them.
        if vectors and G_released.size == 0 and v_released is not None and not damped and \
                v_released.shape[1] == M.shape[0] and \
                (found := _secular_held(v_released, released, G_held[-1], verdict)) is not None:
            return found[0], found[1], released, v_released, *found[2]
        held, v_held = _modes(M, D, Ks, G_held, damped, omega_max, vectors)
    except np.linalg.LinAlgError as exc:
        # Seen only for values spanning most of float64's range (1e-320 … 1e220).
        raise SolverError(f"resonances: the eigenvalue solver failed ({exc}); element "
                          "values span too many orders of magnitude", status="lapack") from None
    return held, v_held, released, v_released, *_cancel(held, released, verdict)


def _secular_held(V, released: np.ndarray, g: np.ndarray, verdict=None) -> tuple | None:
    """``(held, its vectors, (keep held, keep released))`` as :func:`_solved` gives them,
    from the complete released modes ``V`` (M-orthonormal) and roots ``released``; None
    where not confirmed.

    Held, (K − λM) v = σg with gᵀv = 0 (g the drive's row), so
    v = Σ vᵢ cᵢ/(μᵢ − λ) with cᵢ = vᵢᵀg, and λ is a root of the secular equation
    Σ cᵢ²/(μᵢ − λ) = 0, one between each two released roots μᵢ the drive sees.
    Each released root the drive does not see (cᵢ = 0) is a held one, and so is
    each repeat of a released root (within 8ε·μ_max; the repeats are deflated as
    LAPACK's divide and conquer deflates them, their cᵢ² summed).  The roots are
    LAPACK's ``dlasd4``'s (the safeguarded rational-interpolation solver of the
    divide-and-conquer SVD, in the singular values √μᵢ and √λ, with 1/ρ = 0),
    which also gives each μᵢ − λ without cancellation for the vectors.  Their error
    estimate is the released roots' (eps·λ_max/λ·√n, λ_max the released one, at
    least the held one) and so is the polish flag; a vector is kept when its angle
    to the constraint, |gᵀv|/(|g||v|), is at rounding level (64ε): otherwise (or
    where ``dlasd4`` fails) None.
    """
    from scipy.linalg.lapack import dlasd4

    top = np.abs(released[:, 0]).max(initial=0.0)
    w = np.abs(released[:, 0]) / top                # ω/ω_max: dlasd4's singular values
    c = V.T @ g
    live = np.abs(c) > 1e-13 * np.linalg.norm(c)  # cᵢ = 0: a mode the drive does not see
    first = np.r_[True, np.diff(w[live] ** 2) > 8 * _EPS]
    cluster = np.cumsum(first) - 1
    z = np.sqrt(np.bincount(cluster, c[live] ** 2) / np.sum(c[live] ** 2))
    found = [dlasd4(i, w[live][first], z, rho=np.inf) for i in range(cluster[-1])]
    if any(info for *_, info in found):
        return None
    w = np.concatenate([w[~live], w[live][~first], [x[1] for x in found]])
    order = np.argsort(w, kind="stable")
    w = w[order]
    # The released roots' estimate eps·λ_max/λ·√n (_undamped_roots) at λ_max, carried to λ.
    err = released[-1, 1].real / w ** 2
    held = np.column_stack([1j * top * w, err, np.full(w.size, released[0, 2])])
    keep = _cancel(held, released, verdict)
    which = order[keep[0]] - (w.size - len(found))          # among dlasd4's roots
    if np.any(which < 0):
        return None
    # (μᵢ − λ)/μ_max = (dᵢ − σ)(dᵢ + σ), dlasd4's delta and work, of each kept root.
    gaps = np.array([found[i][0] * found[i][2] for i in which]).reshape(-1, first.sum()).T
    with np.errstate(all="ignore"):
        Y = V[:, live] @ (c[live, None] / gaps[cluster])
        t = (g @ Y) / (g @ g)
        tilt = np.abs(t) * np.linalg.norm(g) / np.linalg.norm(Y, axis=0)
    if not np.all(tilt <= 64 * _EPS):
        return None
    out = np.zeros((V.shape[0], w.size))
    out[:, keep[0]] = Y - np.outer(g, t)        # onto the constraint (v_a = 0 when b is 0)
    return held, out, keep


def _repeated(s: np.ndarray) -> np.ndarray:
    """Whether another root of ``s`` lies within 1e-9 (relative) of each, |s_j − s_i| ≤
    1e-9·|s_i|.  Such a pair is as near in |s|: sorted by |s|, each root is compared
    only with those at most ``width`` places on (a window of 2e-9), not with every root."""
    m = np.abs(s)
    order = np.argsort(m, kind="stable")
    m, z = m[order], s[order]
    out = np.zeros(s.size, bool)
    width = np.max(np.searchsorted(m, m * (1 + 2e-9), side="right") - np.arange(m.size),
                   initial=1)
    for d in range(1, int(width)):
        gap = np.abs(z[d:] - z[:-d])
        out[order[:-d]] |= gap <= 1e-9 * m[:-d]
        out[order[d:]] |= gap <= 1e-9 * m[d:]
    return out


def pencil(system, dense: bool = False) -> tuple:
    """``(M, D, Kₛ, G_released, G_held, damped)``: the node blocks of the nodal
    matrices (sparse; dense arrays with ``dense``) and the constraint rows (dense)
    of the two eigenproblems — the lever constraints, and for the held drive also
    v_a − v_b = 0."""
    n_nodes = len(system.nodes)
    # Lever constraints are the rows of C below the node block; the lever forces
    # themselves drop out once the velocities are confined to the constraints' null space.
    if dense:
        G_levers = system.dense("lever")[n_nodes:, :n_nodes]
        M, D, Ks = (system.dense(k)[:n_nodes, :n_nodes] for k in ("mass", "damper", "spring"))
    else:
        G_levers = system.C[n_nodes:, :n_nodes].toarray()
        M, D, Ks = (X[:n_nodes, :n_nodes] for X in (system.M, system.D, system.Ks))
    drive_row = np.zeros((1, n_nodes))
    if system.a >= 0:
        drive_row[0, system.a] = 1.0
    if system.b >= 0:
        drive_row[0, system.b] = -1.0
    damped = bool(np.any(D)) if dense else D.nnz > 0 and bool(np.any(D.data))
    return M, D, Ks, G_levers, np.vstack([G_levers, drive_row]), damped


def constraint_basis(G: np.ndarray, n: int, dense: bool = False):
    """A basis Z (sparse, n × (n − rank G)) of the null space of the constraint rows ``G``.

    Each constraint eliminates one unknown (pivot chosen by a column-pivoted
    QR of G), so Z is the identity with the eliminated unknowns expressed in
    the others: projections Zᵀ X Z stay sparse and cheap.  With ``dense``, Z is
    a dense array; a single row (the drive's constraint, no levers) is then
    eliminated without scipy: its pivot is the entry of largest magnitude, as
    the pivoted QR chooses it.
    """
    if G.shape[0] == 0:
        if dense:
            return np.eye(n)
        import scipy.sparse as sp

        return sp.identity(n, format="csr")
    pivots, free = _pivots(G, dense)
    # G_p v_p + G_f v_f = 0  ->  v_p = -G_p⁺ G_f v_f (exact for consistent constraints)
    Gp, Gf = G[:, pivots], G[:, free]
    elim = _elimination(Gp, Gf) if free.size else np.zeros((pivots.size, 0))
    rows, cols = np.nonzero(elim)
    r = np.concatenate([free, pivots[rows]])
    c = np.concatenate([np.arange(free.size), cols])
    v = np.concatenate([np.ones(free.size), elim[rows, cols]])
    if dense:
        Z = np.zeros((n, free.size))
        Z[r, c] = v
        return Z
    import scipy.sparse as sp

    return sp.csr_matrix((v, (r, c)), shape=(n, free.size))


def _elimination(Gp: np.ndarray, Gf: np.ndarray) -> np.ndarray:
    """X with Gp X = −Gf, refined twice on residuals Gf + Gp X summed in double-double.

    The least-squares solve alone (rcond eps, scipy's default) is off by about
    cond(Gp)·eps — 300 eps for a lever of ratio 305 — and that error, in the basis the
    pencil is projected on, is beyond the eigenvalue bound (a root 1.8e-13 off with a
    bound of 8.9e-16).  Refined, X is correct to about eps while cond(Gp) is far below
    1/eps (:func:`exact_basis` asks for 1e8)."""
    from ._dd import split, two_prod, two_sum

    X = -np.linalg.lstsq(Gp, Gf, rcond=_EPS)[0]
    for _ in range(2):
        s, e = Gf.copy(), np.zeros(Gf.shape)
        for k in range(Gp.shape[1]):
            a = np.broadcast_to(Gp[:, k, None], Gf.shape)
            p, pe = two_prod(a, *split(a), X[k])
            s, se = two_sum(s, p)
            e += se + pe
        X = X - np.linalg.lstsq(Gp, s + e, rcond=_EPS)[0]
    return X


def _pivots(G: np.ndarray, dense: bool = False) -> tuple:
    """``(pivots, free)``: the unknowns the constraint rows ``G`` eliminate, chosen by a
    column-pivoted QR (a single row with ``dense``: its entry of largest magnitude, as
    the QR chooses it, without scipy), and the others, both sorted."""
    if dense and G.shape[0] == 1:
        perm = np.argsort(-np.abs(G[0]), kind="stable")
        rank = int(abs(G[0, perm[0]]) > 0)
    else:
        import scipy.linalg as la

        _, r, perm = la.qr(G, mode="economic", pivoting=True)
        rank = int(np.sum(np.abs(np.diag(r)) > 1e-12 * np.abs(r).max()))
    pivots, keep = np.sort(perm[:rank]), np.ones(G.shape[1], dtype=bool)
    keep[pivots] = False
    return pivots, np.flatnonzero(keep)     # not setdiff1d: its np.unique imports numpy.ma


def _modes(M, D, Ks, G, damped: bool, omega_max=None, vectors: bool = False):
    """Eigenvalues s (Im s ≥ 0, |s| > 0) of the constrained network, with their error estimates.

    ``M``, ``D``, ``Ks`` are sparse; returns ``(roots, V)``: ``roots`` of shape
    (k, 3), column 0 the complex s, column 1 the estimated relative error of
    |s|, column 2 nonzero where the root must be polished; ``V`` (n × k) the
    eigenvectors in the unknowns of ``M`` with ``vectors``, else None.
    Networks above the dense limits are solved in the band |s| ≤ ``omega_max``
    by shift-invert Arnoldi (:func:`_band_modes`, no vectors); without a band
    they are refused.
    """
    dense = isinstance(M, np.ndarray)
    Z = constraint_basis(G, M.shape[0], dense=dense)
    limit = MAX_UNKNOWNS_DAMPED if damped else MAX_UNKNOWNS
    if Z.shape[1] > limit and not dense:
        if omega_max is not None and math.isfinite(omega_max) and omega_max > 0:
            with np.errstate(all="ignore"):
                Mr, Dr, Kr = ((Z.T @ X @ Z).tocsc() for X in (M, D, Ks))
            return _band_modes(Mr, Dr, Kr, float(omega_max)), None
        raise SolverError(
            f"resonances: {Z.shape[1]} unknowns, the limit is {limit} for "
            f"{'damped' if damped else 'undamped'} networks (a dense O(n³) eigenproblem) "
            "unless a band omega_max is given; give omega_max, sweep K(ω) instead, or "
            "reduce the network", status="size")
    with np.errstate(all="ignore"):
        Mr, Dr, Kr = ((Z.T @ X @ Z) if dense else (Z.T @ X @ Z).toarray() for X in (M, D, Ks))
    if Mr.shape[0] == 0:
        return np.zeros((0, 3), dtype=complex), np.zeros((M.shape[0], 0)) if vectors else None
    if not (np.isfinite(Mr).all() and np.isfinite(Dr).all() and np.isfinite(Kr).all()):
        raise SolverError("resonances: the network's matrices overflow float64 (element "
                          "values or lever ratios near 1e308 combine beyond it)",
                          status="overflow")
    scale_m, scale_k = (np.abs(X).max() or 1.0 for X in (Mr, Kr))
    # sqrt of each: the quotient itself can leave float64 (1e-200 / 1e180).
    w_ref = math.sqrt(scale_k) / math.sqrt(scale_m)
    if not (math.isfinite(w_ref) and w_ref > 0):
        raise SolverError(f"resonances: the stiffness and mass scales ({scale_k:.3g} N/m, "
                          f"{scale_m:.3g} kg) are too far apart for float64", status="range")
    if not damped:
        s, err, must, U = _undamped_roots(Mr / scale_m, Kr / scale_k, w_ref, vectors)
        if not exact_basis(G):
            must = np.ones(s.size)
        elif G.shape[0]:            # (the rounding of ZᵀXZ, which Weyl's bound does not see)
            err = err * _product_growth(Z, (M, Ks), (Mr, Kr))
    else:
        with np.errstate(all="ignore"):
            scaled = (Mr / scale_m, Dr / (scale_m * w_ref), Kr / scale_k)
        if not all(np.isfinite(X).all() for X in scaled):
            raise SolverError("resonances: the damping, mass and stiffness scales are too far "
                              "apart for float64", status="range")
        scaled, static = _condensed(*scaled)
        s, err, U = _damped_roots(scaled, w_ref, vectors)
        if static is not None and vectors:
            R, N, X = static
            U = R @ U + N @ (-X @ U)        # the condensed directions follow statically
        must = np.ones(s.size)
    roots = np.column_stack([s, err, must]) if s.size else np.zeros((0, 3), dtype=complex)
    # Z is the identity without constraints: no product (and no fresh n × n array).
    return roots, (Z @ U if vectors and G.shape[0] else U)


def _product_growth(Z, parts, products) -> float:
    """How much larger than ZᵀXZ the bound of its rounding is: max over X of
    max|Zᵀ|X|Z| (elementwise, |Z| too) / max|ZᵀXZ|, at least 1.

    The computed ZᵀXZ is within γ·|Z|ᵀ|X||Z| of the exact product, which Weyl's bound
    (on the computed pencil) does not see: a spring between two nodes the levers move
    almost together (stretch 1.07 − 1) gives a product 400 times smaller than its
    bound, and the root was 6 ulps off with an error of 4 (random network 131 of
    seed 3, tests/fuzz/numeric_run.py roots).  1 where Z merges or keeps columns
    whose springs and masses do not cancel (no levers, most drive rows)."""
    with np.errstate(all="ignore"):     # (abs and max: numpy's and scipy.sparse's alike)
        return max([1.0] + [r for X, P in zip(parts, products) if np.isfinite(
            r := np.float64(abs(abs(Z).T @ abs(X) @ abs(Z)).max()) / np.abs(P).max())])


def _rounding_factor(n: int) -> float:
    """The factor of eps·λ_max/λ in the error estimate of an order-``n`` symmetric
    eigen-solve's roots ω: the reductions' rounding grows with n (against the grids'
    closed form, 225 … 1,600 unknowns, banded: 0.24–0.41·√n), so √n, at least 4."""
    return max(4.0, float(np.sqrt(n)))


def exact_basis(G: np.ndarray) -> bool:
    """Whether :func:`constraint_basis` of the rows ``G`` is correct to rounding, so that
    the eigenvalue bound of the projected pencil holds: no rows, one row of 0 and ±1
    (the drive's, v_a − v_b = 0), or rows whose pivot block has a condition below 1e8
    (:func:`_elimination` refines the elimination to about eps there).  Otherwise the
    roots are polished on K.  Over 1,000 roots of random undamped lever networks the
    worst error was 0.51 of the bound (before the refinement: 202 times it); a later
    campaign found one at 1.5 times it, from the rounding of the product ZᵀXZ, now
    in the bound (:func:`_product_growth`)."""
    if G.shape[0] == 0 or (G.shape[0] == 1 and bool(np.isin(G, (-1.0, 0.0, 1.0)).all())):
        return True
    pivots, _ = _pivots(G, isinstance(G, np.ndarray))
    return bool(np.linalg.cond(G[:, pivots]) < 1e8)


def _undamped_roots(M, K, w_ref: float, vectors: bool):
    """``(s, error, must polish, vectors)`` of the scaled undamped pencil (λ = (ω/w_ref)²)."""
    lam, direct, U = _undamped(M, K, vectors)
    factor = _rounding_factor(lam.size)
    up = lam > 1e-11 * max(1.0, lam.max(initial=0.0))
    lam, U = lam[up], (U[:, up] if vectors and not up.all() else U)
    s = 1j * w_ref * np.sqrt(lam)
    err = _EPS * (lam.max(initial=1.0) / lam) * factor
    # Weyl's bound holds for the scaled matrix, not through a static
    # condensation or an eigen-decomposition of M (their rounding is
    # amplified by the condition of the condensed block): not a bound
    # then, and these roots are always polished on K (column 2).
    return s, err, np.full(s.size, 0.0 if direct else 1.0), U


def _condensed(M: np.ndarray, D: np.ndarray, K: np.ndarray) -> tuple:
    """The directions with neither mass nor damping (null(M) ∩ null(D), both positive
    semi-definite) condensed out statically: K_c = K_rr − K_nrᵀ K_nn⁻¹ K_nr.

    There P(s) = K: no root.  Left in the pencil they are infinite roots in
    Jordan blocks, which QZ splits by about √eps into spurious finite ones (a
    resonance at 1.8e10 rad/s with ζ = 4e-6 on a five-node chain,
    ``tests/test_resonances.py``).  Returns ``((M, D, K) reduced, (R, N, X))``,
    the kept and condensed bases and x_N = −X x_R, or the matrices and None when
    there is nothing to condense.
    """
    mu, V = np.linalg.eigh(M + D)
    null = mu <= 1e-13 * max(mu.max(initial=0.0), 1e-300)
    if not null.any() or null.all():
        return (M, D, K), None
    R, N = V[:, ~null], V[:, null]
    Knr = N.T @ K @ R
    X = np.linalg.lstsq(N.T @ K @ N, Knr, rcond=_EPS)[0]
    return (R.T @ M @ R, R.T @ D @ R, R.T @ K @ R - Knr.T @ X), (R, N, X)


def _damped_roots(scaled: tuple[np.ndarray, np.ndarray, np.ndarray], w_ref: float,
                  vectors: bool):
    """``(s, error, vectors)`` of the scaled damped pencil, rigid-body roots left out."""
    s_all, U = _damped(*scaled, vectors=vectors)
    s_all = s_all * w_ref
    # Rigid-body (zero) roots come out of QZ split by about sqrt(eps)·w_ref.  More roots
    # that small than det has zeros: the largest of them are genuine slow roots (a motor's
    # inertia creeping through a small damper, 7e-3 rad/s beside 9.2e10), kept where the
    # estimate below leaves them a digit (1e2·eps·max|s|/|s| < 1).
    mag = np.abs(s_all) / w_ref
    live = ((mag > 1e-6) | _slow_roots(mag[None], scaled[1][None], scaled[2][None])[0])
    keep = np.flatnonzero(live & (s_all.imag >= -1e-12 * np.abs(s_all)))
    s, U = s_all[keep], U[:, keep] if vectors else None
    mag = np.abs(s)
    err = _EPS * 1e2 * (mag.max(initial=1.0) / mag)
    if s.size > 1 or s_all.size > 1:
        # Coalescing roots (critical damping, ζ → 1): a root at relative
        # distance δ from another moves by about eps/δ, and a double root
        # by about sqrt(eps) — far more than the simple-root estimate.
        gap = np.abs(s[:, None] - s_all[None, :])
        gap[np.arange(s.size), keep] = np.inf
        with np.errstate(divide="ignore"):
            near = np.minimum(np.sqrt(_EPS), _EPS / (gap.min(axis=1) / mag))
        err = np.maximum(err, 10 * near)
    s = np.where(np.abs(s.imag) <= 1e-12 * np.abs(s), s.real + 0j, s)
    return s, err, U


def _zero_roots(D, K) -> np.ndarray:
    """How many roots of det(s²M + sD + K) are 0, per matrix of a stack: the directions K
    does not hold, and again those D does not hold either (s² m = 0, a free mass); for
    a passive network's semidefinite matrices nullity(K) + nullity(K + D).  Ranks to
    1e-13 of each matrix's largest eigenvalue, as the massless directions' count."""
    return sum(np.sum(np.abs(mu) <= 1e-13 * np.maximum(np.abs(mu).max(axis=-1, keepdims=True),
                                                       1e-300), axis=-1)
               for mu in (np.linalg.eigvalsh(K), np.linalg.eigvalsh(K + D)))


def _slow_roots(mag: np.ndarray, D: np.ndarray, K: np.ndarray) -> np.ndarray:
    """Which roots below the rigid-body cut (``mag`` = |s|/w_ref ≤ 1e-6, rows of a stack
    of scaled D and K) are genuine: in a row with more of them than det has zero roots
    (:func:`_zero_roots`, counted for those rows only), the largest, where the estimate
    1e2·eps·max|s|/|s| leaves them a digit (a motor's inertia creeping through a small
    damper: 7e-3 rad/s beside 9.2e10)."""
    out, tiny = np.zeros(mag.shape, dtype=bool), mag <= 1e-6
    zeros, some = np.zeros(mag.shape[0], dtype=np.int64), tiny.any(axis=-1)
    zeros[some] = _zero_roots(D[some], K[some]) if some.any() else 0
    for d in np.flatnonzero(tiny.sum(axis=-1) > zeros):
        idx = np.flatnonzero(tiny[d])
        idx = idx[np.argsort(mag[d, idx])[zeros[d]:]]
        out[d, idx[mag[d, idx] > 1e2 * _EPS * mag[d][np.isfinite(mag[d])].max()]] = True
    return out


def _band_modes(M, D, K, omega_max: float) -> np.ndarray:
    """Roots s with |s| ≤ ``omega_max`` of (s²M + sD + K) v = 0, by shift-invert Arnoldi.

    Undamped networks: see :func:`_band_modes_undamped` (counted, then Lanczos).
    Otherwise, and where the count cannot be had, the companion pencil A − sB,
    A = [[0, I], [−K, −D]], B = [[I, 0], [0, M]], is factorised once at a shift
    σ = −omega_max·1e-3 (just off the rigid-body roots at 0) by a sparse LU;
    ARPACK (``scipy.sparse.linalg.eigs``) finds the largest ν of (A − σB)⁻¹B,
    ν = 1/(s − σ), that is the roots nearest σ, and the number asked doubles
    until a root beyond the band is found.  Massless directions (B singular)
    give ν = 0 and are never reached.  The error of each root is a first
    estimate only: every root is then polished on K.
    """
    import scipy.sparse as sp
    from scipy.sparse.linalg import LinearOperator, eigs, splu

    n = M.shape[0]
    # A fixed start vector: ARPACK's own is random, so two runs could differ
    # in the last bits of a root and in how long they take.
    rng = np.random.default_rng(20261123)
    if not (D.nnz and np.any(D.data)):
        found = _band_modes_undamped(M, K, omega_max, rng.standard_normal(n))
        if found is not None:
            return found
    k = min(24, 2 * n - 2)
    v0 = rng.standard_normal(2 * n) + 0j
    eye = sp.identity(n, format="csc")
    A = sp.bmat([[None, eye], [-K, -D]], format="csc")
    B = sp.bmat([[eye, None], [None, M]], format="csc")
    sigma = -1e-3 * omega_max
    lu = splu((A - sigma * B).tocsc().astype(complex))
    op = LinearOperator((2 * n, 2 * n), matvec=lambda v: lu.solve(B @ v), dtype=complex)
    while True:
        nu = eigs(op, k=k, which="LM", return_eigenvectors=False, tol=1e-13, v0=v0)
        with np.errstate(divide="ignore"):
            s_all = sigma + 1.0 / nu
        s_all = s_all[np.isfinite(s_all)]
        if np.abs(s_all).max(initial=0.0) > omega_max or k >= 2 * n - 2:
            break
        if 2 * k > MAX_BAND_ROOTS:
            # ARPACK's cost grows as k² n: a band holding hundreds of roots of a
            # large network would run for minutes (a 2,500-mass chain below
            # 10 rad/s: > 5 min).  Refuse with the count found so far.
            _refuse_band(k // 2, omega_max, n, exact=False)
        k = min(2 * k, 2 * n - 2)
    s = s_all[s_all.imag >= -1e-9 * np.abs(s_all)]
    return _in_band(np.where(np.abs(s.imag) <= 1e-9 * np.abs(s), s.real + 0j, s), omega_max)


def _band_modes_undamped(M, K, omega_max: float, v0: np.ndarray) -> np.ndarray | None:
    """The undamped band: roots s = jω, ω ≤ ``omega_max``, of K v = ω² M v, or None.

    The roots in the band are counted first (:func:`_inertia_counts`), so
    that a band holding too many is refused at once with their number, and the
    symmetric pencil is then solved by shift-invert Lanczos
    (``scipy.sparse.linalg.eigsh``, one factorisation of K − σM at
    σ = −(1e-3·omega_max)²) for exactly those roots, the rigid-body ones below
    them and a few above; the roots found must agree with the count and reach
    beyond the band.  None when the count cannot be had or they disagree (the
    caller then uses the general path).
    """
    from scipy.sparse.linalg import ArpackError, ArpackNoConvergence, eigsh

    n = M.shape[0]
    counts = _inertia_counts(M, K, omega_max)
    if counts is None:
        return None
    below, upto = counts
    found = upto - below
    if found > MAX_BAND_ROOTS // 2:
        _refuse_band(found, omega_max, n, exact=True)
    if found == 0:
        return np.zeros((0, 3), dtype=complex)
    k = upto + 2
    if 2 * k + 1 > n:           # Lanczos wants room (ncv = 2k + 1 ≤ n): a small network
        return None
    try:
        lam = eigsh(K.tocsc(), k=k, M=M.tocsc(), sigma=-(1e-3 * omega_max) ** 2,
                    which="LM", return_eigenvectors=False, tol=1e-13, v0=v0)
    except (ArpackError, ArpackNoConvergence):
        return None
    lo2, hi2 = (1e-6 * omega_max) ** 2, omega_max ** 2
    if lam.max() <= hi2 or np.count_nonzero((lam > lo2) & (lam < hi2)) != found:
        # Lanczos and the count disagree (a count spoiled by rounding in an
        # unpivoted factorisation): trust neither, take the general path.
        return None
    return _in_band(1j * np.sqrt(np.sort(lam[lam > 0])), omega_max)


def _in_band(s: np.ndarray, omega_max: float) -> np.ndarray:
    """The band solver's roots ``s`` with 1e-6·``omega_max`` < |s| ≤ ``omega_max`` (a
    margin of 1e-6 for the polish), as :func:`_modes` gives them: a first estimate
    of their error (1e-8), each to be polished on K."""
    s = s[(np.abs(s) > 1e-6 * omega_max) & (np.abs(s) <= omega_max * (1 + 1e-6))]
    return np.column_stack([s, np.full(s.size, 1e-8), np.ones(s.size)])


def _refuse_band(count: int, omega_max: float, n: int, exact: bool):
    raise SolverError(
        f"resonances: {'' if exact else 'more than '}{count} roots below omega_max = "
        f"{omega_max:g} rad/s in a network of {n} unknowns (the band solver stops at "
        f"{MAX_BAND_ROOTS // 2}); give a smaller omega_max or sweep K(ω) instead",
        status="size")


def _negative_pivots(A) -> int | None:
    """Number of negative eigenvalues of the sparse symmetric ``A``, or None if unknown.

    Sylvester's law of inertia: a symmetric factorisation P A Pᵀ = L D Lᵀ has as
    many negative pivots in D as A has negative eigenvalues.  SuperLU in its
    symmetric mode with diagonal pivoting gives that factorisation (U = D Lᵀ)
    when it kept the row order equal to the column order; otherwise, or if A is
    singular, the count is unknown.
    """
    from scipy.sparse.linalg import splu

    try:
        lu = splu(A.tocsc(), permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0,
                  options={"SymmetricMode": True})
    except RuntimeError:                          # exactly singular
        return None
    if not np.array_equal(lu.perm_r, lu.perm_c):
        return None
    d = lu.U.diagonal()
    ok = np.all(np.isfinite(d)) and not np.any(d == 0)
    return int(np.count_nonzero(d < 0)) if ok else None


def _inertia_counts(M, K, omega_max: float) -> tuple[int, int] | None:
    """Natural frequencies of the pencil (K, M) below 1e-6·omega_max and below omega_max.

    ``M`` and ``K`` are the sparse, symmetric, positive semidefinite mass and
    stiffness matrices of an undamped network (constraints already projected
    out).  Each count is the number of negative eigenvalues of K − ω²M
    (Sylvester's law of inertia), from one sparse factorisation; None when a
    factorisation cannot tell (see :func:`_negative_pivots`).
    """
    lo = _negative_pivots(K - (1e-6 * omega_max) ** 2 * M)
    hi = _negative_pivots(K - omega_max ** 2 * M)
    return None if lo is None or hi is None else (lo, hi)


def _undamped(M: np.ndarray, K: np.ndarray, vectors: bool = False) -> tuple:
    """λ with K v = λ M v, M positive semi-definite; massless directions condensed out.

    Returns ``(λ, direct, V)``: ``direct`` when M was diagonal and every
    direction had mass (no condensation), where eps·λ_max/λ bounds the error;
    ``V`` the eigenvectors v (columns, massless directions restored from the
    condensation) with ``vectors``, else None.

    A diagonal M (every mass to the frame, the usual mobility-analogy layout)
    is handled without an eigen-decomposition of M.
    """
    mu, V = (np.diag(M), None) if not np.any(M - np.diag(np.diag(M))) else np.linalg.eigh(M)
    massive = mu > 1e-13 * max(mu.max(initial=0.0), 1e-300)
    direct = V is None and bool(massive.all())
    if not massive.any():          # no inertia: no oscillation
        return np.zeros(0), direct, np.zeros((M.shape[0], 0)) if vectors else None
    if direct:                       # nothing to condense (no copies of K)
        Krr, Knn, Knr = K, K[:0, :0], K[:0]
    elif V is None:
        Krr, Knn, Knr = (K[np.ix_(rows, cols)] for rows, cols in
                         ((massive, massive), (~massive, ~massive), (~massive, massive)))
    else:
        R, N = V[:, massive], V[:, ~massive]
        Krr, Knn, Knr = R.T @ K @ R, N.T @ K @ N, N.T @ K @ R
    X = np.linalg.lstsq(Knn, Knr, rcond=_EPS)[0] if Knn.size else np.zeros((0, Krr.shape[0]))
    Kc = Krr - Knr.T @ X if Knn.size else Krr
    # Symmetric scaling by the masses gives a standard symmetric eigenproblem.
    d = 1.0 / np.sqrt(mu[massive])
    A = Kc * d[:, None] * d[None, :]
    A = (A + A.T) / 2
    if not vectors:
        return _symmetric_eigvals(A), direct, None
    # The roots from the same call as the vectors (divide and conquer, LAPACK syevd), not
    # to the bit _symmetric_eigvals': both backward stable, errors of order eps·λ_max/λ.
    lam, Ur = np.linalg.eigh(A)
    Ur *= d[:, None]                           # in place: n × n arrays cost page faults
    if direct:
        return lam, direct, Ur
    Un = -X @ Ur                     # the massless directions follow statically
    if V is None:
        U = np.empty((M.shape[0], lam.size))
        U[massive], U[~massive] = Ur, Un
    else:
        U = V[:, massive] @ Ur + V[:, ~massive] @ Un
    return lam, direct, U


#: Smallest symmetric problem tried as banded (below it the dense solve costs little).
BANDED_FROM = 200


def _symmetric_eigvals(A: np.ndarray) -> np.ndarray:
    """The eigenvalues of the symmetric matrix ``A``, ascending, by a banded solver where it pays.

    Lumped masses on a chain or a mesh give a sparse A whose rows, ordered by
    reverse Cuthill–McKee, form a narrow band b: LAPACK's banded reduction
    (``scipy.linalg.eigvals_banded``, O(n²b)) then replaces the dense O(n³)
    one.  Both are backward stable (orthogonal reductions): the error bound
    eps·λ_max/λ holds either way.  Other matrices (dense, wide band, fewer
    than :data:`BANDED_FROM` rows) go to ``numpy.linalg.eigvalsh``.

    Parameters
    ----------
    A : numpy.ndarray
        Real symmetric n × n.

    Returns
    -------
    numpy.ndarray
        The n eigenvalues, ascending.
    """
    n = A.shape[0]
    # The banded reduction costs about 6n²b flops, the dense one 4n³/3 (equal at b ≈ 2n/9);
    # a band below n/8 leaves a margin for the reordering and the copies.
    if n >= BANDED_FROM and np.count_nonzero(A) <= n * n // 8:
        import scipy.sparse as sp
        from scipy.linalg import eigvals_banded

        from ._nodal_solvers import band_order

        S = sp.csr_matrix(A)
        _, col, row, band = band_order(S.indptr, S.indices)
        if 8 * band <= n:
            low, ab = row >= col, np.zeros((band + 1, n))
            ab[(row - col)[low], col[low]] = S.data[low]
            return eigvals_banded(ab, lower=True, check_finite=False)
    return np.linalg.eigvalsh(A)


def _damped(M, D, K, vectors: bool = False) -> tuple:
    """Finite eigenvalues s of (s² M + s D + K) v = 0 by a companion linearisation.

    With no direction free of both mass and damping (:func:`_condensed`), each
    massless direction is one infinite root: the 2n − dim null(M) roots of least
    |s| are the finite ones (and below 1e12 of the scale, as before).  A threshold
    on |β/α| alone cannot tell them: QZ put an infinite root at 3.3e11·√(k/m),
    which then swamped every estimate and cancelled a resonance
    (``tests/test_resonances.py``).

    Returns ``(s, V)``: ``V`` the eigenvectors v (columns) with ``vectors``, else None.
    """
    n = M.shape[0]
    mu = np.linalg.eigvalsh(M)
    massless = int(np.sum(mu <= 1e-13 * max(mu.max(initial=0.0), 1e-300)))
    eye, zero = np.eye(n), np.zeros((n, n))
    A, B = np.block([[zero, eye], [-K, -D]]), np.block([[eye, zero], [zero, M]])
    from scipy.linalg import eig            # QZ: numpy has no generalised eig

    out = eig(A, B, right=vectors, homogeneous_eigvals=True)
    alpha, beta = out[0] if vectors else out
    with np.errstate(all="ignore"):
        size = np.where(beta != 0, np.abs(alpha) / np.abs(beta), np.inf)
    finite = np.zeros(2 * n, dtype=bool)
    finite[np.argsort(size, kind="stable")[:2 * n - massless]] = True
    finite &= size < 1e12               # and not beyond float64's reach (a mass of 1e-320)
    s = alpha[finite] / beta[finite]
    if not vectors:
        return s, None
    # The companion vector is [v; s·v]: the better-scaled half gives v.
    Z = out[1][:, finite]
    return s, np.where(np.abs(s) <= 1.0, Z[:n], Z[n:] / np.where(s == 0, 1.0, s))


#: Held and released roots closer than this (relative) whose estimates are not bounds
#: (roots polished on K: a pencil not solved directly, or constraints eliminated with
#: rounding) are asked of K itself whether they cancel (:func:`_cancel`).
UNBOUNDED_PAIR = 1e-6


def _cancel(held: np.ndarray, released: np.ndarray, verdict=None):
    """Which modes to keep (two masks): not those present in both problems (they
    do not appear in K).

    A held root within its and a released root's estimates of that root is the same
    mode.  Within 1e3 times the estimates it is too, unless K itself
    (``verdict(s_held, s_released)``, :func:`_pair_verdict`) shows the pair of a
    weakly coupled mode.  Farther, it is a distinct root, unless the estimates are no
    bounds (either root to be polished), the two within :data:`UNBOUNDED_PAIR`, and K
    shows that they cancel (a mode in both problems whose two eigen-solves differ by
    more than their estimates)."""
    keep_h, keep_r = np.ones(len(held), bool), np.ones(len(released), bool)
    for i, (s, err, must) in enumerate(held if len(released) else ()):
        d = np.abs(released[:, 0] - s) / abs(s)
        d[~keep_r] = np.inf
        j = int(np.argmin(d))
        # The same sub-network's mode, computed twice, agrees to rounding; distinct
        # modes of long chains can lie within 1e-8 of each other, so use the estimates.
        e = abs(err) + abs(released[j, 1])
        loose = np.real(must) > 0 or np.real(released[j, 2]) > 0
        if d[j] <= e:
            same = True
        elif d[j] < 1e3 * e or (loose and d[j] < UNBOUNDED_PAIR):
            said = None if verdict is None or not _alone(
                s, released[j, 0], held[:, 0], released[:, 0]) else verdict(s, released[j, 0])
            if isinstance(said, tuple):     # a pair, and where K has it: the polish's start
                said, held[i, 0], released[j, 0] = said
            same = said is False if d[j] >= 1e3 * e else said is not True
        else:
            same = False
        if same:
            keep_h[i] = keep_r[j] = False
    return keep_h, keep_r


def _alone(h: complex, r: complex, held: np.ndarray, released: np.ndarray) -> bool:
    """Whether no root but the pair ``h``, ``r`` lies within 4|h − r| of its midpoint."""
    near = np.abs(np.concatenate([held, released]) - (h + r) / 2) <= 4 * abs(h - r)
    return int(near.sum()) == 2


def _pair_verdict(system, h: complex, r: complex, where: bool = False):
    """Whether K of ``system`` has a zero at ``h`` and a pole at ``r`` (True: a mode the
    drive sees, weakly), or neither (False: one mode, unseen, in both problems); None
    where K cannot tell.

    Near the pair K ≈ K₀(s − h)/(s − r), K₀ about constant (:func:`_alone`: no other
    root within 4|h − r|): one step beyond each root, at 2r − h and 2h − r, the
    quotient of K is 2 / ½ = 4 where the pair is in K, 1 where it cancels.  Told
    apart at 2, when K is known there to 10 %.  Where that says "cancels", a zero and a
    pole found within ten spacings (:func:`_mobius_pair`) say a pair after all; with
    ``where``, ``(True, zero, pole)`` then, K's own, for the polish to start from.
    """
    K, dK = nodal.evaluate_complex(system, np.array([2 * r - h, 2 * h - r]))
    with np.errstate(all="ignore"):
        if not np.all(dK <= 0.1 * np.abs(K)):
            return None
        if abs(K[0]) > 2 * abs(K[1]):
            return True
    # "Cancels" where K was asked: but eigen-solves whose estimates are no bounds can
    # put h and r farther from K's zero and pole than these lie apart (1e-10 off for a
    # pair 4.3e-11 apart).  A zero and a pole found within ten spacings say a pair.
    found = _mobius_pair(system, h, r, 10 * abs(h - r))
    if found is None:
        return False
    zero, pole = found if h.real or r.real else (1j * found[0].imag, 1j * found[1].imag)
    return (True, zero, pole) if where else True


def _mobius_pair(system, h: complex, r: complex, scale: float):
    """``(zero, pole)`` of K of ``system`` where both lie within 3·``scale`` of
    (h + r)/2, else None (neither, or the fit below is not clear).

    Near an isolated pair K(s) = (α τ + β)/(τ − q) in τ = (s − c)/(scale·u), c the
    midpoint and u the direction from h to r: three samples of K along that line give
    α, β, q (a linear solve), a fourth checks the fit to 1 %; the zero is at −β/α.
    """
    u = (r - h) / abs(r - h) if r != h else 1j
    tau = np.array([-1.9, -0.6, 0.7, 1.8])
    K, dK = nodal.evaluate_complex(system, (h + r) / 2 + scale * u * tau)
    with np.errstate(all="ignore"):
        if not np.all(dK <= 1e-3 * np.abs(K)) or not np.all(np.isfinite(K)):
            return None
        A = np.column_stack([tau[:3], np.ones(3), K[:3]]).astype(complex)
        try:
            alpha, beta, q = np.linalg.solve(A, K[:3] * tau[:3])
        except np.linalg.LinAlgError:
            return None
        if not abs((alpha * tau[3] + beta) / (tau[3] - q) - K[3]) <= 1e-2 * abs(K[3]):
            return None
        zero = -beta / alpha
        if abs(q) <= 3 and abs(zero) <= 3 and abs(q - zero) > 1e-6:
            c = (h + r) / 2
            return c + scale * u * zero, c + scale * u * q
        return None


def _make(kind: Kind, s: complex, err: float) -> Resonance:
    s = complex(s)
    wn = abs(s)
    return Resonance(kind, float(wn), float(abs(s.imag)),
                     float(-s.real / wn) + 0.0 if wn else 0.0, float(err))


#: Roots whose eigen-solver bound is below this are not polished on K (undamped).
POLISH_BELOW = 1e-13

#: The largest error a damped root of a series–parallel design may keep from Newton on the
#: stacked float64 matrices (:func:`batched_roots`); a design with a larger one is solved by
#: :func:`find_resonances` (7.6e-12 at most on ``heald_damped.mcir``'s massless direction).
MAX_STACKED_ERROR = 1e-11


def _spacing(s: np.ndarray, other: np.ndarray) -> np.ndarray:
    """Each root of ``s``'s distance to the nearest of ``other`` (inf where none).

    ``other`` sorted by |s|, its k-th entries on each side of a root's place are
    compared for k = 0, 1, … until every root's next ones differ from it in |s| by
    more than its nearest yet (| |a| − |b| | ≤ |a − b|): no table of all distances."""
    best, order = np.full(s.size, np.inf), np.argsort(np.abs(other), kind="stable")
    z, m, ms = other[order], np.abs(other[order]), np.abs(s)
    pos = np.searchsorted(m, ms)
    for k in range(other.size):
        for at in (pos + k, pos - 1 - k):
            ok = (at >= 0) & (at < other.size)
            best[ok] = np.minimum(best[ok], np.abs(s[ok] - z[at[ok]]))
        up, down = pos + k + 1, pos - 2 - k
        if np.all((up >= other.size) | (m[np.minimum(up, other.size - 1)] - ms >= best)) and \
                np.all((down < 0) | (ms - m[np.maximum(down, 0)] >= best)):
            break
    return best


def row_spacing(s: np.ndarray, pole: np.ndarray) -> np.ndarray:
    """:func:`_spacing` for rows of roots (D, R) of many designs: each root's distance to
    the nearest root of the other kind (``pole``) in its row (NaN: an empty slot)."""
    D, R = s.shape
    out = np.full((D, R), np.inf)
    step = max(1, 2_000_000 // max(R * R, 1))         # (a few MB of distances at a time)
    for a in range(0, D, step):
        x, p = s[a:a + step], pole[a:a + step]
        with np.errstate(invalid="ignore"):
            dist = np.abs(x[:, :, None] - x[:, None, :])
        dist = np.where((p[:, :, None] != p[:, None, :]) & np.isfinite(dist), dist, np.inf)
        out[a:a + step] = dist.min(axis=2, initial=np.inf)
    return out


def _polish(system, roots: list, damped: bool, spacing) -> list[Resonance]:
    """Each root polished on the circuit's own K(s) by a complex secant iteration.

    K(s) comes from the nodal matrices at complex frequency, A(s) = D + C +
    sM + Kₛ/s (``nodal.combine`` at ω = −js); a resonance is a zero of K, an
    anti-resonance a zero of 1/K.  The error of the polished root is
    |δg| / |g'(s)| with δg the absolute error of g = K (or 1/K) at the root
    (K is refined in double-double; δK its estimate, at least eps·|K|,
    times a safety factor of 4), plus the last secant step.  Undamped roots whose eigenvalue bound (Weyl:
    eps·λ_max/λ) is already below :data:`POLISH_BELOW` keep it; a root the
    secant does not confirm (it leaves for another root) keeps its
    eigen-solver value and estimate.  The secant's first step stays within a quarter of
    the root's ``spacing``, the distance to the nearest root of the other kind (a pole of
    the g it is a zero of).
    """
    kinds = [k for k, _, _, _ in roots]
    s0 = np.array([complex(s) for _, s, _, _ in roots])
    e0 = np.array([float(np.real(e)) for _, _, e, _ in roots])
    must = np.array([float(np.real(f)) > 0 for _, _, _, f in roots])
    todo = np.flatnonzero((e0 > POLISH_BELOW) | must) if not damped else np.arange(s0.size)
    s_new, e_new = s0.copy(), e0.copy()
    if todo.size:
        pole = np.array([kinds[i] == "antiresonance" for i in todo])
        s_new[todo], e_new[todo] = secant_polish(lambda x: _g_and_delta(system, x, pole),
                                                 s0[todo], e0[todo], damped,
                                                 spacing[todo])
    for i in np.flatnonzero((e_new >= 1) & (s0.imag == 0) & (s0.real < 0)) if damped else ():
        s_new[i], e_new[i] = _real_root(system, kinds[i] == "antiresonance", s0[i], e_new[i])
    s_new = settled(s_new, e_new, damped)
    return [_make(k, s, max(e, _EPS)) for k, s, e in zip(kinds, s_new, e_new)]


def _real_root(system, pole: bool, s0: complex, e0: float) -> tuple:
    """``(s, error)`` of a real root that the secant did not confirm from ``s0``: g is real
    on the real axis, so its sign change nearest ``s0`` over s0·10⁻⁵ … 10 s0 (4 points a
    factor 10) brackets the root (or a pole of g: the secant then confirms nothing, and
    ``(s0, e0)`` stands), bisection narrows it to 1e-7 and the secant from there
    confirms it.  A
    slow root from below the rigid-body cut, whose eigen-solver value was 200 times off
    (1.79e-4 for 8.71e-7 rad/s, scene campaign seed 2, mechanism 143); else ``(s0, e0)``."""
    x = s0.real * np.geomspace(1e-5, 10.0, 25)
    g = _g_and_delta(system, x + 0j, np.full(x.size, pole))[0].real
    cross = np.flatnonzero(np.sign(g[:-1]) * np.sign(g[1:]) < 0)
    if not cross.size:
        return s0, e0
    k = cross[np.argmin(np.abs(np.log(x[cross] / s0.real)))]
    (lo, hi), g_lo = x[k:k + 2], g[k]
    while abs(hi - lo) > 1e-7 * abs(lo):        # bisection to within the secant's reach
        mid = 0.5 * (lo + hi)
        g_mid = _g_and_delta(system, np.array([mid + 0j]), np.array([pole]))[0][0].real
        lo, hi, g_lo = (mid, hi, g_mid) if np.sign(g_mid) == np.sign(g_lo) else (lo, mid, g_lo)
    s, e = secant_polish(lambda z: _g_and_delta(system, z, np.array([pole])),
                         np.array([0.5 * (lo + hi) + 0j]), np.array([1e-7]), True)
    return (s[0], e[0]) if e[0] < min(e0, 1e-8) else (s0, e0)     # (a pole of g brackets too)


def settled(s: np.ndarray, err: np.ndarray, damped: bool) -> np.ndarray:
    """Polished roots ``s`` put where they belong: undamped ones on the imaginary axis,
    damped ones real where within their error ``err`` of the real axis."""
    return np.where(np.abs(s.imag) <= err * np.abs(s), s.real + 0j, s) if damped else \
        1j * np.abs(s.imag)


def _g_and_delta(system, s: np.ndarray, pole: np.ndarray):
    """g(s) (K, or 1/K at anti-resonances) and its absolute rounding uncertainty."""
    # Anti-resonances on the held system (built once per system): 1/K = −q there, and A
    # is singular at the root while the held matrix is not.
    systems = (system, system.memo("_held", lambda: nodal.held(system)))
    return g_and_bound(pole, lambda i, want: nodal.evaluate_complex(systems[i], s[want]),
                       np.isfinite(s))


def g_and_bound(pole: np.ndarray, evaluate, live: np.ndarray):
    """g (K; −K of the drive-held system at anti-resonances ``pole``) and its bound, from
    ``evaluate(i, want) -> (K, bound of K)`` at the points ``want`` of system ``i`` (0:
    the network, 1: held) among the ``live`` ones (the others NaN, not evaluated: a
    secant step leaves its converged roots out).  The refined value is good to about eps
    relative at best (its rounding to float64), whatever the estimate of the solve says."""
    g, dg = np.full(pole.shape, np.nan, dtype=complex), np.full(pole.shape, np.inf)
    for i, want in enumerate((~pole & live, pole & live)):
        if want.any():
            K, dK = evaluate(i, want)
            g[want] = -K if i else K
            dg[want] = 4 * np.maximum(dK, _EPS * np.abs(K))
    return g, dg


def secant_steps(g_and_delta, admissible, s0, e0, offset, active=True, iterations: int = 12,
                 spacing=np.inf):
    """Secant steps on g from ``s0`` and ``s0`` less ``offset`` times its error ``e0``
    (at least 1e-9 relative, at most a quarter of ``spacing``, the distance to the
    nearest pole of g: a first step past it says nothing of the root), element-wise over
    arrays of roots; returns (s, relative error).

    ``g_and_delta(x)`` gives g and the bound of its error at x; ``admissible(c)``
    the step's point as it may be taken (e.g. projected on the jω axis) and
    whether it may be.  A root stops once its step is within rounding of its
    own uncertainty; its error is then (bound of g / slope + the last step or the Newton
    step |g/slope| where it stopped, the longer).  Where the secant wandered off (to
    another root, or nowhere: farther than 1e-3 relative, or no estimate) ``s0`` stands
    with its estimate ``e0``, but never below 10 Newton steps |g/g'| at ``s0`` (how far
    the circuit's own K says the root is; infinitely far where g is not known there).
    """
    h = np.maximum(np.minimum(np.abs(s0) * np.maximum(e0, 1e-9), spacing / 4), 1e-300)
    a, b = s0 - h * offset, s0.copy()
    ga, da = g_and_delta(a)
    gb, db = g_and_delta(b)
    with np.errstate(all="ignore"):
        g0, slope0 = gb, (gb - ga) / (b - a)
    # No secant point where g has no digit (an exact zero is known: 0·inf), network 231 of
    # seed 4: K = 1e18 (bound inf) at s0 gave a slope that "converged" 1e-9 off, error 2.2e-16
    known = (np.isfinite(da) | (ga == 0)) & (np.isfinite(db) | (gb == 0))
    active = active & np.isfinite(ga) & np.isfinite(gb) & known
    step, slope = np.full(b.shape, np.inf), np.full(b.shape, np.nan, dtype=np.result_type(b, ga))
    for _ in range(iterations):
        if not active.any():
            break
        with np.errstate(all="ignore"):
            sl = (gb - ga) / (b - a)
            c = np.where(active, b - gb / sl, b)
        c, ok = admissible(c)
        ok &= active
        gc, dc = g_and_delta(np.where(ok, c, np.nan))     # (NaN: not evaluated, not used)
        # On an exact zero of g its relative estimate says nothing (0·inf):
        # the uncertainty at the previous iterate, a step away, stands.  Elsewhere a g
        # with no digit known is no step: the secant stops there.
        dc = np.where((gc == 0) & ~np.isfinite(dc), db, dc)
        ok &= np.isfinite(gc) & np.isfinite(dc)
        step, slope = np.where(ok, np.abs(c - b), step), np.where(ok, sl, slope)
        a, ga = np.where(ok, b, a), np.where(ok, gb, ga)
        b, gb, db = np.where(ok, c, b), np.where(ok, gc, gb), np.where(ok, dc, db)
        with np.errstate(all="ignore"):
            done = step <= np.maximum(4 * _EPS * np.abs(b), db / np.abs(slope))
        active = ok & ~done
    with np.errstate(all="ignore"):
        # The last step, or the Newton step from where it stopped if longer: a secant that
        # stopped by coming back to an earlier point (a zero step) far from the root (|g|
        # large for its slope) has not converged.
        err = (db / np.abs(slope) + np.maximum(step, np.abs(gb / slope))) / np.abs(b)
        moved, newton = np.abs(b - s0) / np.abs(s0), np.abs(g0 / slope0) / np.abs(s0)
    bad = ~np.isfinite(err) | ~np.isfinite(b) | (moved > 1e-3)
    # (g not known at a start: K does not confirm a root near s0, whatever the eigen-solver said)
    newton = np.where(np.isfinite(newton) & known, 10 * newton, np.where(known, 0.0, np.inf))
    return np.where(bad, s0, b), np.where(bad, np.maximum(e0, newton), np.maximum(err, _EPS))


def secant_polish(g_and_delta, s0: np.ndarray, e0: np.ndarray, damped: bool,
                  spacing=np.inf):
    """The roots ``s0`` (eigen-solver's estimate ``e0``; ``spacing`` the distance to the
    nearest pole of g) polished by the complex secant on ``g_and_delta(s) -> (g, bound
    of g)``; returns (s, relative error).  Used for one circuit (:func:`_polish`) and for
    the roots of many designs (:mod:`mechcirc.batch`)."""

    def admissible(c):
        if not damped:
            c = 1j * c.imag                       # undamped: roots on the jω axis
        return c, np.isfinite(c)

    return secant_steps(g_and_delta, admissible, s0, e0, 1 if damped else 1j,
                        spacing=spacing)


# --------------------------------------------------------------------------
# Many designs at once (mechcirc.batch)
# --------------------------------------------------------------------------

def batched_roots(ds, omega_max: float | None = None):
    """The roots of many designs ``ds`` (a :class:`mechcirc.batch.Designs`)
    up to ``omega_max``, from stacked eigenproblems: :func:`find_resonances` step
    by step on stacks.

    The same stamps (:func:`mechcirc.nodal.stamps`), projections
    (:func:`constraint_basis`; one per design where the lever ratios vary,
    :func:`design_bases`), scaling and filters as :func:`_modes`; the
    massless directions, structural, are condensed out once for all designs and
    each pencil reduced by a batched Cholesky factorisation of its mass matrix
    (:func:`_undamped_stack`); all designs are solved by one stacked
    ``eigvalsh`` per problem (drive held: resonances; released:
    anti-resonances), and each root polished by a secant on its design's own
    K(ω) (:func:`_secant_designs`).

    Damped designs: :func:`_stacked_damped` (massless directions: :func:`_shifted_roots`).

    Returns ``(designs, pole, s, error)`` for the designs it solves
    (series–parallel, a mass matrix it can reduce, lever pivots that suit the
    design, no mode in both problems): the roots s (jω undamped), each row sorted as
    :func:`find_resonances` sorts, NaN-padded, ``pole`` true for
    anti-resonances; None when it solves none (the caller solves the others
    one by one).
    """
    check_omega_max(omega_max)
    from .errors import NotSeriesParallelError, TopologyError

    try:
        _ = ds.circuit.tree                       # series–parallel: the plan polishes
        system = ds.circuit.nodal
    except (NotSeriesParallelError, TopologyError):
        return None
    which = np.flatnonzero(ds.valid)
    if not which.size:
        return None
    n_nodes = len(system.nodes)
    # Dense, as element_patterns: without scipy when no lever needs a pivoted QR.
    *_, G_released, G_held, damped = pencil(system, dense=True)
    B = element_patterns(system)
    S = design_values(ds, system, which)
    # One basis for all when the lever ratios are the template's, else one per design.
    shared = template_levers(ds, system, which).size == which.size
    bases = [(constraint_basis(G, n_nodes, dense=True), True) if shared
             else design_bases(ds, system, G, which) for G in (G_held, G_released)]
    problems = [stacked_problem(Z, B, S, damped, omega_max) for Z, _ in bases]
    (w_h, e_h, _), (w_r, e_r, _) = problems
    loose = damped or not shared or np.logical_or(*(  # (the estimates are no bounds)
        unbounded(Z, B, S, exact_basis(G)) for (Z, _), G in zip(bases, (G_held, G_released))))
    keep = np.flatnonzero(shared_roots_free(problems, damped, loose, design_verdict(
        ds, which)) & bases[0][1] & bases[1][1])
    if not keep.size:
        return None
    pole, s, err = sorted_roots(*held_and_released(w_h[keep], w_r[keep], e_h[keep], e_r[keep]))
    if damped:                        # already polished (on the matrices)
        return _resolved(which[keep], pole, s, err)
    # Undamped: polished on each design's K (the plan is there: the tree is, above).
    w, err = _secant_designs(ds.plan(which[keep]), s, pole, err)
    if omega_max is not None:
        w = np.where(w <= omega_max, w, np.nan)
    return (which[keep], *sorted_roots(pole, 1j * w, np.maximum(err, _EPS)))


def _resolved(which, pole, s, err) -> tuple:
    """:func:`batched_roots`' damped designs without those whose roots Newton on the float64
    matrices leaves over :data:`MAX_STACKED_ERROR` (a slow overdamped root, κ·eps 3.6e-4:
    1e-5 off), which go to :func:`find_resonances` (polished on K in double-double)."""
    fine = ~(err > MAX_STACKED_ERROR).any(axis=1)
    return which[fine], pole[fine], s[fine], err[fine]


def template_levers(ds, system, which: np.ndarray) -> np.ndarray:
    """The designs of ``which`` whose lever ratios are the template's ``system``'s (its
    lever stamps and constraint basis hold for them alone)."""
    lev = {lv.name: i for i, lv in enumerate(ds.circuit.levers)}
    for lv in system.levers:
        which = which[ds.ratios[lev[lv.name], which] == lv.ratio]
    return which


def design_values(ds, system, which: np.ndarray) -> np.ndarray:
    """The value·η of ``system``'s elements in the designs ``which`` of ``ds``, (D', E)."""
    row = {e.name: i for i, e in enumerate(ds.circuit.elements)}
    el = np.array([row[e.name] for e in system.elements], dtype=np.int64)
    return (ds.values[el][:, which] * ds.eta[el][:, which]).T


def design_lever_values(ds, system, which: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The value of each of ``system``'s lever stamps in designs ``which`` of ``ds``, (D',
    stamps): ±ratio on a lever's primary side with the design's ratio, else the system's
    own (±1, and a held drive's constraint, which follows the levers'); and each lever's
    |ratio|, (D', levers)."""
    index = {name: i for i, name in enumerate(system.nodes)}
    row = {lv.name: i for i, lv in enumerate(ds.circuit.levers)}
    ratios = ds.ratios[[row[lv.name] for lv in system.levers]][:, which].T     # (D', L)
    values = np.repeat(np.asarray(system.stamps["lever"][2], dtype=float)[None], which.size, 0)
    pos = {lv.name: k for k, lv in enumerate(system.levers)}
    for t, (_, _, _, sign, lever, ratio) in enumerate(nodal.stamps((), system.levers, index)):
        if ratio:
            values[:, t] = sign * ratios[:, pos[lever.name]]
    return values, np.abs(ratios)


def design_verdict(ds, which: np.ndarray):
    """``verdict(k, s_held, s_released)``: :func:`_pair_verdict` on the circuit of design
    ``which[k]`` of ``ds`` (built once for all its pairs)."""
    systems: dict = {}

    def verdict(k, h, r):
        if k not in systems:
            systems[k] = ds.design(int(which[k])).nodal
        return _pair_verdict(systems[k], h, r)

    return verdict


def unbounded(Z: np.ndarray, B: dict, S: np.ndarray, exact: bool) -> np.ndarray:
    """Which designs' undamped roots on the basis ``Z`` (n, k) are polished on K, their
    eigenvalue estimates no bounds, as :func:`_undamped_roots` and :func:`_modes` decide
    for one: all but those of a diagonal mass matrix with mass in every direction, on a
    basis ``exact`` (:func:`exact_basis`).  ``B`` the element patterns, ``S`` the
    designs' values (D, E)."""
    P = Z.T @ B["mass"] @ Z
    k = P.shape[1]
    diagonal = not np.any(P * (1 - np.eye(k)))
    mass = S @ P[:, np.arange(k), np.arange(k)] if k else np.ones((S.shape[0], 1))
    return ~(exact & diagonal & (mass > 1e-13 * mass.max(axis=1, initial=0.0)[:, None])
             .all(axis=1))


def shared_roots_free(problems, damped: bool, loose=True, verdict=None) -> np.ndarray:
    """The designs solved in both stacked problems ((roots, errors, ok) each: held,
    released) with no mode in both (it cancels in K, :func:`_cancel`: left to the single
    path), nor, where ``loose`` (by design: estimates that are no bounds), a held and a
    released root within :data:`UNBOUNDED_PAIR` — unless each such pair is alone and
    ``verdict(design, s_held, s_released)`` (:func:`_pair_verdict` on the design's own
    circuit) says it is a pair of K, as :func:`_cancel` keeps it; undamped roots may
    be ω or jω alike."""
    (w_h, e_h, ok_h), (w_r, e_r, ok_r) = problems
    # Damped roots are compared with the eigen-solver's estimates
    # (eps·1e2·|s|max/|s|), as find_resonances compares them before polishing.
    with np.errstate(all="ignore"):
        if damped:
            e_h, e_r = (np.maximum(e, 1e2 * _EPS * np.nanmax(
                np.abs(x), axis=1, initial=1.0)[:, None] / np.abs(x))
                for e, x in ((e_h, w_h), (e_r, w_r)))
        d = np.abs(w_r[:, None, :] - w_h[:, :, None]) / np.abs(w_h[:, :, None])
        same = d < 1e3 * (e_h[:, :, None] + e_r[:, None, :])
        near = np.asarray(loose, bool).reshape(-1, 1, 1) & (d < UNBOUNDED_PAIR) & ~same
    free = ok_h & ok_r & ~same.any(axis=(1, 2))
    ask = free & near.any(axis=(1, 2))
    free &= ~ask
    for k in np.flatnonzero(ask) if verdict is not None else ():
        s_h, s_r = ((x[k] if np.iscomplexobj(x) else 1j * x[k]) for x in (w_h, w_r))
        roots = (s_h[np.isfinite(s_h)], s_r[np.isfinite(s_r)])     # (NaN: empty slots)
        free[k] = all(_alone(s_h[i], s_r[j], *roots) and verdict(k, s_h[i], s_r[j]) is True
                      for i, j in zip(*np.nonzero(near[k])))
    return free


def element_patterns(system) -> dict[str, np.ndarray]:
    """Each element's stamp pattern B_e over the node rows, by kind, shape (E, n, n).

    M = Σ_e (value·η)_e B_e (the entries :func:`mechcirc.nodal.stamps` gives
    and :func:`mechcirc.nodal.assemble` sums); projected, Zᵀ M Z = Σ_e s_e Zᵀ B_e Z.
    """
    n_nodes = len(system.nodes)
    index = {n: i for i, n in enumerate(system.nodes)}   # a node not in it: the reference
    E, pos = len(system.elements), {e.name: k for k, e in enumerate(system.elements)}
    B = {x: np.zeros((E, n_nodes, n_nodes)) for x in ("mass", "spring", "damper")}
    for kind, r, c, sign, source, _ in nodal.stamps(system.elements, (), index):
        if kind in B:
            B[kind][pos[source.name], r, c] += sign
    return B


def stacked_problem(Z, B, S, damped: bool, omega_max):
    """The roots of one stacked eigenproblem (constraint basis ``Z``, one for all designs
    (n, k) or one per design (D, n, k), :func:`design_bases`; patterns ``B``, element
    values ``S`` per design): :func:`_stacked_damped` or :func:`_stacked_modes`."""
    D = S.shape[0]
    if not Z.shape[-1]:                     # nothing left to move: no roots, solved
        return np.zeros((D, 0), complex if damped else float), np.zeros((D, 0)), \
            np.ones(D, dtype=bool)
    if damped:
        Mr, Dr, Kr = (_projected(Z, B[x], S) for x in ("mass", "damper", "spring"))
        return _stacked_damped(Mr, Dr, Kr, omega_max)
    # The massless directions are those of the pattern: with every value > 0,
    # null(Σ m_e B_e) = ∩ null(B_e) in every design.  Ordered last, they are
    # condensed out statically (_undamped_stack), as _undamped does per design.
    mu, V = np.linalg.eigh(np.swapaxes(Z, -1, -2) @ B["mass"].sum(axis=0) @ Z)
    massless = mu <= 1e-10 * np.maximum(mu.max(axis=-1, keepdims=True), 1e-300)
    order = np.argsort(massless, axis=-1, kind="stable")        # the massless last
    Z = Z @ np.take_along_axis(V, order[..., None, :], axis=-1)
    n0 = massless.sum(axis=-1)
    Mr, Kr = (_projected(Z, B[x], S) for x in ("mass", "spring"))
    w, e, ok = _stacked_modes(Mr, Kr, int(np.max(n0)), omega_max)
    return w, e, ok & (n0 == np.max(n0))          # per-design bases: the same count


def _projected(Z, B: np.ndarray, S: np.ndarray) -> np.ndarray:
    """Zᵀ (Σ_e S[:, e] B_e) Z of every design, (D, k, k): the patterns projected once for
    a shared basis Z (n, k), or each design's matrix projected on its own Z (D, n, k)."""
    if Z.ndim == 2:
        return _weighted_sum(S, Z.T @ B @ Z)
    return np.swapaxes(Z, 1, 2) @ _weighted_sum(S, B) @ Z


def design_bases(ds, system, G: np.ndarray, which: np.ndarray) -> tuple:
    """Constraint bases Z_d (D', n, k) of designs ``which`` whose lever ratios differ:
    ``G``'s lever rows (the first ``len(system.levers)``, :func:`pencil`) stamped with
    each design's ratios, and every design's unknowns eliminated at the pivots the
    template's pivoted QR chooses (:func:`_pivots`, as :func:`constraint_basis`),
    v_p = −G_p⁺ G_f v_f, its columns then made orthonormal.
    Returns ``(Z, ok)``: ``ok`` false where those pivots are ill-conditioned for the
    design (G_p's singular values more than 1e8 apart) or its constraints have a rank
    the template's have not, which the single path takes."""
    n, L = G.shape[1], len(system.levers)
    Gd = np.repeat(G[None], which.size, axis=0)
    Gd[:, :L] = 0.0
    values, _ = design_lever_values(ds, system, which)
    for t, (r, c) in enumerate(zip(*system.stamps["lever"][:2])):
        if n <= r < n + L:                          # a lever constraint row's entry
            Gd[:, r - n, c] += values[:, t]
    pivots, free = _pivots(G)
    rank = pivots.size
    Gp, Gf = Gd[:, :, pivots], Gd[:, :, free]
    sv = np.linalg.svd(Gp, compute_uv=False)
    ok = sv[:, rank - 1] > 1e-8 * sv[:, 0] if rank else np.ones(which.size, dtype=bool)
    Z = np.zeros((which.size, n, free.size))
    Z[:, free, np.arange(free.size)] = 1.0
    Z[:, pivots, :] = -np.linalg.pinv(Gp, rcond=_EPS) @ Gf
    # Orthonormal columns (the same span): the template's pivots can scale a design's
    # basis badly (a ratio of 0.0075 where the template's is 1: entries of 556), and the
    # massless directions are judged on ZᵀMZ (stacked_problem), whose spread that
    # scaling widens by its square (7e-11 there: a direction with mass taken as massless,
    # roots 3e-5 off and one lost, with estimates of 1e-15).
    Z = np.linalg.qr(Z)[0]
    # A design whose constraints have a rank the template's have not (two levers that
    # coincide at the template's ratios, r₁r₂ = 1, and not at the design's): its basis
    # misses one; the single path takes it.
    ok &= np.abs(Gd @ Z).max(axis=(1, 2), initial=0.0) <= 1e-8 * np.abs(Gd).max(
        axis=(1, 2), initial=0.0)
    return Z, ok


def held_and_released(s_h, s_r, err_h, err_r) -> tuple:
    """``(pole, s, err)``: designs' roots with the drive held (resonances) then released
    (anti-resonances, ``pole`` true), side by side in each row."""
    pole = np.zeros((s_h.shape[0], s_h.shape[1] + s_r.shape[1]), dtype=bool)
    pole[:, s_h.shape[1]:] = True
    return pole, np.concatenate([s_h, s_r], axis=1), np.concatenate([err_h, err_r], axis=1)


def tie_order(pole, mag) -> np.ndarray:
    """The order of each row of roots sorted by ω (``mag``) that puts an anti-resonance
    (``pole``) before a resonance whose ω it equals to ``TIE_RTOL``: one rounding of a
    shared ω, so that two computations of it (batched and single) sort alike."""
    idx = np.broadcast_to(np.arange(pole.shape[1]), pole.shape).copy()
    pole, mag = pole.copy(), mag.copy()
    with np.errstate(invalid="ignore"):     # (empty slots: NaN, or inf − inf)
        for _ in range(pole.shape[1]):      # swaps of one pass never overlap
            rows, j = np.nonzero(~pole[:, :-1] & pole[:, 1:] &
                                 (mag[:, 1:] - mag[:, :-1] <= TIE_RTOL * mag[:, 1:]))
            if not rows.size:
                break
            for a in (idx, pole, mag):
                a[rows, j], a[rows, j + 1] = a[rows, j + 1], a[rows, j].copy()
    return idx


def sorted_roots(pole, s, err) -> tuple:
    """``(pole, s, err)`` of designs' roots (s complex or ω; NaN: an empty slot, beyond
    omega_max or rigid), each row sorted as :func:`find_resonances` sorts (by |s|, and
    on a tie by kind: the anti-resonance first), the empty slots last (their err NaN)
    and cut off at the widest row."""
    mag = np.abs(s)
    live = np.isfinite(mag)
    order = np.lexsort((~pole, np.where(live, mag, np.inf)), axis=-1)
    order = np.take_along_axis(order, tie_order(np.take_along_axis(pole, order, 1),
                                                np.take_along_axis(mag, order, 1)), 1)
    width = int(live.sum(axis=1).max(initial=0))
    pole, s, err, live = (np.take_along_axis(x, order, 1)[:, :width]
                          for x in (pole, s, err, live))
    return pole, s, np.where(live, err, np.nan)


def _weighted_sum(S: np.ndarray, P: np.ndarray) -> np.ndarray:
    """Σ_e S[:, e] · P[e], shape (D, k, k): one small product per design (a stacked
    matmul), so that a design's matrix does not depend on the other designs of
    the batch (one large matrix product may block and sum differently)."""
    E, k = P.shape[0], P.shape[1]
    return (S[:, None, :] @ P.reshape(E, k * k)).reshape(S.shape[0], k, k)


def _scaled_stack(M, K):
    """Stacked mass and stiffness matrices scaled to unit largest entry per design,
    the reference frequency √(max|K| / max|M|) of each, and which designs are within
    float64's range (a positive, finite w_ref and scaled matrices; the others' matrices
    replaced by I): ``(scale_m, w_ref, Ms, Ks, ok)``."""
    with np.errstate(all="ignore"):
        scale_m, scale_k = (np.where(top > 0, top, 1.0)
                            for top in (np.abs(X).max(axis=(1, 2)) for X in (M, K)))
        w_ref = np.sqrt(scale_k) / np.sqrt(scale_m)
        Ms, Ks = M / scale_m[:, None, None], K / scale_k[:, None, None]
    ok = np.isfinite(w_ref) & (w_ref > 0) & np.isfinite(Ms).all(axis=(1, 2)) & \
        np.isfinite(Ks).all(axis=(1, 2))
    if not ok.all():
        Ms, Ks = (np.where(ok[:, None, None], X, np.eye(M.shape[1])) for X in (Ms, Ks))
    return scale_m, w_ref, Ms, Ks, ok


def _stacked_modes(M: np.ndarray, K: np.ndarray, n0: int, omega_max):
    """Undamped roots ω of stacks of projected pencils (K, M): :func:`_modes`'s
    scaling and filters on stacks, the pencil reduced by a Cholesky factor of M.

    Returns ``(ω, error, ok)``: ω and its eigenvalue estimate (eps·λ_max/λ·:func:`_rounding_factor`) of shape
    (D, k), NaN where no root; ``ok`` false for the designs this cannot solve (a mass
    matrix that is singular to within 1e-13 of its largest eigenvalue, where
    :func:`_undamped` condenses, or values beyond float64's range).
    """
    scale_m, w_ref, Ms, Ks, ok = _scaled_stack(M, K)
    lam, regular = _undamped_stack(Ms, Ks, n0)
    ok &= regular
    lam = np.where(np.isfinite(lam), lam, -np.inf)
    top = np.maximum(1.0, lam.max(axis=1, initial=0.0))
    live = (lam > 1e-11 * top[:, None]) & ok[:, None]
    lam = np.where(live, lam, 1.0)
    with np.errstate(all="ignore"):
        w = np.where(live, w_ref[:, None] * np.sqrt(lam), np.nan)
        err = np.where(live, _EPS * (lam.max(axis=1, initial=1.0)[:, None] / lam)
                       * _rounding_factor(M.shape[1]), np.nan)
    if omega_max is not None:
        beyond = w > omega_max * (1 + 1e-6)
        w[beyond] = err[beyond] = np.nan
    return w, err, ok


def _stacked_damped(M: np.ndarray, Dm: np.ndarray, K: np.ndarray, omega_max):
    """Damped roots s of stacks of projected problems (s² M + s D + K) v = 0, polished.

    :func:`_modes`'s scaling, filters and estimates on stacks: the companion
    matrix [[0, I], [−M⁻¹K, −M⁻¹D]] of every design whose mass matrix is safely
    definite (the criterion of :func:`_undamped_stack`), of the reversed problem
    at a shift for the others (:func:`_shifted_roots`; designs it cannot take are
    not ``ok``), one stacked ``eigvals`` call (where :func:`_damped` runs QZ on
    the pencil), and each root polished by Newton's method on det P(s),
    s ← s − 1/tr(P(s)⁻¹ P'(s)), P(s) = s²M + sD + K, batched.  The error: the
    last Newton step, at least :func:`_modes`'s estimates (eps·1e2·
    |s|max/|s|, nearly coalescing roots) and 4·eps·κ (:func:`_condition`):
    P(s) is formed in float64, so Newton
    cannot make a root more accurate than that (find_resonances polishes on K
    in double-double and reports less).  Returns ``(s, error, ok)``, NaN where
    no root (s with Im s ≥ 0, |s| > 0).
    """
    k = M.shape[1]
    scale_m, w_ref, Ms, Ks, ok = _scaled_stack(M, K)
    with np.errstate(all="ignore"):
        Ds = Dm / (scale_m * w_ref)[:, None, None]
    ok &= np.isfinite(Ds).all(axis=(1, 2))
    eye = np.eye(k)
    Ms, Ds = np.where(ok[:, None, None], Ms, eye), np.where(ok[:, None, None], Ds, 0.0)
    Ks = np.where(ok[:, None, None], Ks, eye)
    # M⁻¹ = L⁻ᵀ L⁻¹ by Cholesky where M is safely definite (``definite``).
    definite = ok.copy()
    _, Linv = _stacked_cholesky_inverse(Ms, definite)
    sig = np.linalg.eigvals(_companion(Linv, Ds, Ks, ok)).astype(complex)   # s / w_ref
    finite = np.ones(sig.shape, dtype=bool)
    shifted = np.flatnonzero(ok & ~definite)
    if shifted.size:
        sig[shifted], finite[shifted], ok[shifted] = _shifted_roots(
            Ms[shifted], Ds[shifted], Ks[shifted])
    mag = np.abs(sig)
    slow = _slow_roots(np.where(finite & ok[:, None], mag, np.inf), Ds, Ks)
    live = ((mag > 1e-6) | slow) & (sig.imag >= -1e-12 * mag) & finite & ok[:, None]
    # Coalescing roots (ζ → 1): _modes's estimate from the gaps.
    with np.errstate(all="ignore"):
        gap = np.abs(sig[:, :, None] - sig[:, None, :])
        gap[:, np.arange(2 * k), np.arange(2 * k)] = np.inf
        near = np.minimum(np.sqrt(_EPS), _EPS / (gap.min(axis=2) / mag))
    sig, step, kappa = _newton_det(np.where(live, sig, 1.0 + 0j), live, Ms, Ds, Ks)
    ok[np.nonzero(live)[0][~np.isfinite(kappa)]] = False     # beyond float64: one by one
    mag = np.abs(sig)
    with np.errstate(all="ignore"):
        # Newton on det P in float64 cannot beat the rounding of P(s) itself, about
        # the eigen-solver's own estimate (_modes's eps·1e2·|s|max/|s|):
        # measured 1.5e-13 on a slow overdamped root (tests/test_batch.py), or
        # 4·eps times the root's condition number where that is larger (a massless
        # direction's root: 6e-14 measured, 2.2e-14 by the first estimate).
        top = np.where(live, mag, 0.0).max(axis=1, initial=1.0)[:, None]
        err = np.maximum(np.maximum(step / mag, 1e2 * _EPS * top / mag), 10 * near)
        err[live] = np.maximum(err[live], 4 * _EPS * kappa)
    s, err = np.where(live, sig * w_ref[:, None], np.nan), np.where(live, err, np.nan)
    s = np.where(np.abs(s.imag) <= err * np.abs(s), s.real + 0j, s)
    if omega_max is not None:
        beyond = ~(np.abs(s) <= omega_max)
        s[beyond] = err[beyond] = np.nan
    return s, err, ok


def _companion(Linv: np.ndarray, Ds: np.ndarray, Ks: np.ndarray, ok: np.ndarray) -> np.ndarray:
    """The companion matrices [[0, I], [−M⁻¹K, −M⁻¹D]] of a stack, M⁻¹ = L⁻ᵀ L⁻¹; ``ok``
    (updated in place) loses a design whose matrix leaves float64 (zeros in its place)."""
    k = Ks.shape[1]
    with np.errstate(all="ignore"):
        Minv = np.swapaxes(Linv, 1, 2) @ Linv
        A = np.zeros((Ks.shape[0], 2 * k, 2 * k))
        A[:, :k, k:] = np.eye(k)
        A[:, k:, :k] = -(Minv @ Ks)
        A[:, k:, k:] = -(Minv @ Ds)
    bad = ~np.isfinite(A).all(axis=(1, 2))
    ok &= ~bad
    A[bad] = 0.0
    return A


def _shifted_roots(Ms: np.ndarray, Ds: np.ndarray, Ks: np.ndarray) -> tuple:
    """Roots s of (s² M + s D + K) v = 0 for a stack whose mass matrices are singular
    (massless directions; the single path runs QZ, :func:`_damped`), by the reversed
    problem at the shift σ = 1 (scaled units): s = σ + 1/μ with
    μ² P(σ) + μ (2σM + D) + M = 0, P(σ) = σ²M + σD + K.  A passive network has no
    root with Re s > 0, so P(σ) is definite and the companion of the μ problem is
    formed as for a regular M.  μ ≈ 0 is an infinite root (a massless direction).

    Returns ``(s, finite, ok)``: ``ok`` false for a design whose P(σ) is not safely
    definite or with a μ neither clearly zero (|μ| ≤ 1e-10 of the largest) nor clearly
    finite (≥ 1e-6 of it: |s| up to about 1e6 w_ref); the single path takes those.
    """
    P, Dp = Ms + Ds + Ks, 2 * Ms + Ds
    ok = np.ones(Ms.shape[0], dtype=bool)
    _, Linv = _stacked_cholesky_inverse(P, ok)
    mu = np.linalg.eigvals(_companion(Linv, Dp, Ms, ok))
    with np.errstate(all="ignore"):
        size = np.abs(mu) / np.abs(mu).max(axis=1, initial=0.0)[:, None]
    finite = size >= 1e-6
    ok &= ~((size > 1e-10) & ~finite).any(axis=1)
    with np.errstate(all="ignore"):
        return np.where(finite, 1.0 + 1.0 / mu, 1e300), finite, ok


def _stacked_cholesky_inverse(Ms: np.ndarray, ok: np.ndarray) -> tuple:
    """``(Ms, L⁻¹)`` with Ms = L Lᵀ for a stack of symmetric matrices; ``ok`` (updated in
    place) loses the designs whose matrix is not safely definite (replaced by I in Ms):
    Cholesky fails, or its least eigenvalue 1/‖L⁻¹‖²_F is below 1e-13 ‖M‖_F."""
    try:
        chol = np.linalg.cholesky(Ms)
    except np.linalg.LinAlgError:                  # one of them is not definite: which?
        for d in range(Ms.shape[0]):
            try:
                np.linalg.cholesky(Ms[d])
            except np.linalg.LinAlgError:
                ok[d] = False
        Ms = np.where(ok[:, None, None], Ms, np.eye(Ms.shape[1]))
        chol = np.linalg.cholesky(Ms)
    Linv = _lower_inverse(chol)
    with np.errstate(all="ignore"):
        lam_min = 1.0 / np.sum(Linv * Linv, axis=(1, 2))
    ok &= lam_min > 1e-13 * np.sqrt(np.sum(Ms * Ms, axis=(1, 2)))
    return Ms, Linv


def _newton_det(sig, live, Ms, Ds, Ks, steps: int = 3) -> tuple:
    """Newton on det P(s), s ← s − 1/tr(P(s)⁻¹ P'(s)), for the ``live`` roots ``sig`` of
    each design; returns the roots, the size of the last step and their condition
    numbers (:func:`_condition`, flat over the live roots)."""
    d, r = np.nonzero(live)
    x, step = sig[d, r], np.zeros(d.size)
    M, D, K = Ms[d], Ds[d], Ks[d]
    k = M.shape[1]
    # One right-hand side more: P(s)⁻¹ b, an inverse-iteration step towards P's null
    # vector at the last iterate (a step from the root: its vector to that order).
    b = np.broadcast_to((1.0 + np.arange(k) / k)[:, None], (d.size, k, 1))
    for _ in range(steps):
        z = x[:, None, None]
        P, rhs = z ** 2 * M + z * D + K, np.concatenate([2 * z * M + D, b], axis=2)
        with np.errstate(all="ignore"):
            try:
                sol = np.linalg.solve(P, rhs)
            except np.linalg.LinAlgError:
                # A zero pivot: that s is a root to working precision (a chain's
                # last pivot can cancel exactly); the others go on.
                exact = np.linalg.det(P) == 0
                sol = np.linalg.solve(np.where(exact[:, None, None], np.eye(k), P), rhs)
                sol[exact] = np.nan
            delta = 1.0 / np.trace(sol[..., :k], axis1=-2, axis2=-1)
        null = sol[..., k]
        good = np.isfinite(delta)
        x, step = np.where(good, x - delta, x), np.where(good, np.abs(delta), 0.0)
    out, size = sig.copy(), np.zeros(sig.shape)
    out[d, r], size[d, r] = x, step
    return out, size, _condition(x, null, M, D, K)


def _condition(s, x, M, D, K) -> np.ndarray:
    """The normwise relative condition number of roots s of P(s) = s²M + sD + K
    (Tisseur, 2000): κ = (|s|²‖M‖ + |s|‖D‖ + ‖K‖)‖x‖² / (|s| |xᵀ P'(s) x|), x the null
    vector of P(s) (M, D and K are symmetric, so the left one is x̄; rows not finite:
    from the singular value decomposition), Frobenius norms (≥ the 2-norms); NaN where
    P(s) leaves float64."""
    z = s[:, None, None]
    with np.errstate(all="ignore"):
        P = z ** 2 * M + z * D + K
    exact = np.flatnonzero(~np.isfinite(x).all(axis=1) & np.isfinite(P).all(axis=(1, 2)))
    if exact.size:                                  # P(s) exactly singular: its SVD's
        x[exact] = np.linalg.svd(P[exact])[2][:, -1, :].conj()
    with np.errstate(all="ignore"):
        dP = np.einsum("ri,rij,rj->r", x, 2 * z * M + D, x)
        norm = [np.sqrt(np.sum(np.abs(X) ** 2, axis=(1, 2))) for X in (M, D, K)]
        mag = np.abs(s)
        return (mag ** 2 * norm[0] + mag * norm[1] + norm[2]) * np.sum(np.abs(x) ** 2, axis=1) \
            / (mag * np.abs(dP))


def _lower_inverse(L: np.ndarray) -> np.ndarray:
    """L⁻¹ of a stack (D, k, k) of lower-triangular matrices with nonzero diagonals, by
    forward substitution a row at a time over all D at once (a general inverse,
    ``numpy.linalg.inv``, factors each again: 2–4× slower for these small k)."""
    D, k = L.shape[0], L.shape[1]
    X = np.zeros_like(L)
    with np.errstate(all="ignore"):
        d = 1.0 / np.diagonal(L, axis1=1, axis2=2)
        for i in range(k):
            r = -(L[:, i, None, :i] @ X[:, :i, :])[:, 0] if i else np.zeros((D, k))
            r[:, i] += 1.0
            X[:, i, :] = r * d[:, i, None]
    return X


def _undamped_stack(M: np.ndarray, K: np.ndarray, n0: int):
    """:func:`_undamped` on stacks (D, k, k) whose last ``n0`` directions are massless:
    λ of K v = λ M v, shape (D, k − n0); ``regular`` false where this cannot solve.

    The massless directions are condensed out statically (K_c = K_rr − K_nrᵀ K_nn⁻¹
    K_nr) and the pencil (K_c, M_rr) reduced to L⁻¹ K_c L⁻ᵀ by the Cholesky factor L of
    M_rr, provided M_rr is safely definite: its smallest eigenvalue, ≥ 1/‖L⁻¹‖²_F, above
    1e-13 of its largest, ≤ ‖M‖_F (else :func:`_undamped` would condense more
    directions, and the single path takes the design).  One stacked ``eigvalsh``.
    """
    D, k = M.shape[0], M.shape[1]
    r, regular = k - n0, np.ones(D, dtype=bool)
    Mrr, Kc = M[:, :r, :r], K[:, :r, :r]
    if n0:
        Knr, Knn = K[:, r:, :r], K[:, r:, r:]
        try:
            if n0 == 1 and not Knn.all():
                raise np.linalg.LinAlgError
            # One massless direction: the 1×1 solve is a division (the same IEEE
            # result, without LAPACK's set-up per design).
            X = Knr / Knn if n0 == 1 else np.linalg.solve(Knn, Knr)
        except np.linalg.LinAlgError:              # a massless part without stiffness
            return np.full((D, r), np.nan), np.zeros(D, dtype=bool)
        Kc = Kc - np.swapaxes(Knr, 1, 2) @ X
    _, Linv = _stacked_cholesky_inverse(Mrr, regular)
    regular &= np.isfinite(Kc).all(axis=(1, 2)) & np.isfinite(Linv).all(axis=(1, 2))
    if not regular.all():
        Kc, Linv = (np.where(regular[:, None, None], X, 0.0) for X in (Kc, Linv))
    A = Linv @ Kc @ np.swapaxes(Linv, 1, 2)
    A += np.swapaxes(A, 1, 2)
    A *= 0.5
    return np.where(regular[:, None], np.linalg.eigvalsh(A), np.nan), regular


def _secant_designs(p, w0: np.ndarray, pole: np.ndarray, e0: np.ndarray):
    """:func:`secant_polish` for undamped roots of many designs on their own K(ω) = jX(ω).

    ``p`` is the plan of the D designs (:meth:`mechcirc.reduction.Plan.with_values`);
    ``w0`` (D, R) the eigen-solver's roots (NaN: none), ``pole`` whether each is
    a zero of 1/K (anti-resonance: g = −1/X) or of K (resonance: g = X), ``e0``
    their estimates.  g and the bound of its error come from one evaluation of
    every design's plan at its own points.  Returns ``(ω, relative error)``.
    """
    from ._tree_eval import through_reciprocal
    from .reduction import evaluate_designs

    have = np.isfinite(w0)
    w_safe = np.where(have, w0, 1.0)

    def g_and_delta(w):
        K, rho = evaluate_designs(p, np.where(np.isfinite(w), w, 1.0), error=True)
        with np.errstate(all="ignore"):
            X = K.imag
            g = np.where(pole, -1.0 / X, X)
            # g = −1/X: the tree's reciprocal rule, and the division's rounding (4u)
            rho = np.where(pole, through_reciprocal(rho) + 4 * _EPS / 2, rho)
            dg = 4 * np.maximum(rho * np.abs(g), _EPS * np.abs(g))
        return g, dg

    spacing = row_spacing(w0, pole)
    w, err = secant_steps(g_and_delta, lambda c: (c, np.isfinite(c) & (c > 0)), w_safe,
                          np.nan_to_num(e0, nan=0.0), 1, have, spacing=spacing)
    # A start within rounding of the root has no digit of g, and the secant no step: the
    # root is bracketed where g is known on both sides, with opposite signs, 1e-15 … 1e-9
    # off (no pole of g between: a quarter of the spacing at most)
    lost = have & ~np.isfinite(err)
    for rel in np.logspace(-15, -9, 13):
        if not lost.any():
            break
        (g1, d1), (g2, d2) = (g_and_delta(w_safe * (1 + x)) for x in (-rel, rel))
        sure = lost & (np.abs(g1) > d1) & (np.abs(g2) > d2) & (g1 * g2 < 0) & (
            4 * rel * w_safe < spacing)
        w, err, lost = np.where(sure, w_safe, w), np.where(sure, rel, err), lost & ~sure
    return np.where(have, w, np.nan), np.where(have, err, np.nan)
