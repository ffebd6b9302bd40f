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
(exact) and the symmetric definite problem Kₛ v = ω² M v is solved by
``scipy.linalg.eigh``; each root is then polished to full precision on the
circuit's own K(ω) (a bracketed root search on Im K, which is monotone in ω
for a lossless network by Foster's reactance theorem).  Damped networks: the
problem is linearised to a 2n generalised eigenproblem solved by QZ
(``scipy.linalg.eig``); s = −ζωₙ ± jωₙ√(1 − ζ²).

A mode that appears in both problems at the same frequency is not seen from
the drive (it cancels in K) and is not reported.  Zero-frequency (rigid-body)
modes are not reported.

Cost: O(n³) in the number of unknowns n; polishing costs about ten
evaluations of K at all roots at once.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal

import numpy as np
import scipy.linalg as la

from .circuit import Circuit
from .errors import NetlistError, SolverError

__all__ = ["Resonance", "find_resonances", "MAX_UNKNOWNS", "MAX_UNKNOWNS_DAMPED"]

#: Largest eigenproblem solved (unknowns left after the constraints).  The
#: dense solve costs O(n³): about 12 s at 2000 unknowns undamped, and the
#: damped 2n linearisation about 10 s at 500 (measured, docs/reliability.md).
#: Larger networks are refused at once instead of running for hours.
MAX_UNKNOWNS = 2000
#: The same for networks with dampers (QZ on a 2n × 2n pencil).
MAX_UNKNOWNS_DAMPED = 500


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
    """

    kind: Literal["resonance", "antiresonance"]
    omega: float
    omega_d: float
    zeta: float
    error: float

    @property
    def f_hz(self) -> float:
        """Natural frequency ωₙ / 2π [Hz]."""
        return self.omega / (2 * math.pi)

    @property
    def fd_hz(self) -> float:
        """Damped natural frequency ω_d / 2π [Hz]."""
        return self.omega_d / (2 * math.pi)


def find_resonances(circuit: Circuit, omega_max: float | None = None) -> list[Resonance]:
    """All resonances and anti-resonances of ``circuit`` up to ``omega_max`` [rad/s].

    Returns them sorted by ``omega``.  See the module docstring for the method.

    Examples
    --------
    >>> from mechcirc import parse
    >>> c = parse("drive V a 0 velocity=1\\nmass m a b 1\\nspring k b 0 100\\n")
    >>> [(r.kind, round(r.omega, 12)) for r in c.resonances()]
    [('resonance', 10.0)]
    """
    for e in circuit.elements:
        if not math.isfinite(e.value * e.eta):
            raise NetlistError(f"{e.kind} {e.name!r}: value × eta = {e.value:g} × {e.eta:g} "
                               "overflows float64", circuit.source, e.line, e.col,
                               "a product below 1.8e308")
    system = circuit.nodal
    n_nodes = len(system.nodes)
    # Lever constraints are the rows of C below the node block; the lever forces
    # themselves drop out once the velocities are confined to the constraints' null space.
    G_levers = system.C[n_nodes:, :n_nodes].toarray()
    M, D, Ks = (X[:n_nodes, :n_nodes] for X in (system.M, system.D, system.Ks))
    drive_row = np.zeros((1, n_nodes))
    if system.a >= 0:
        drive_row[0, system.a] = 1.0
    if system.b >= 0:
        drive_row[0, system.b] = -1.0
    damped = D.nnz > 0 and bool(np.any(D.data))
    released = _modes(M, D, Ks, G_levers, damped)
    held = _modes(M, D, Ks, np.vstack([G_levers, drive_row]), damped)
    held, released = _cancel(held, released)
    out = [_make("resonance", s) for s in held] + [_make("antiresonance", s) for s in released]
    if not damped and out:
        out = _polish(circuit, out)
    if omega_max is not None:
        out = [r for r in out if r.omega <= omega_max]
    return sorted(out, key=lambda r: (r.omega, r.kind))


def _project(G: np.ndarray, n: int):
    """A basis Z (sparse, n × (n − rank G)) of the null space of the constraint rows ``G``.

    Each constraint eliminates one unknown (pivot chosen by a column-pivoted
    QR of G), so Z is the identity with the eliminated unknowns expressed in
    the others: projections Zᵀ X Z stay sparse and cheap.
    """
    import scipy.sparse as sp

    if G.shape[0] == 0:
        return sp.identity(n, format="csr")
    _, r, perm = la.qr(G, mode="economic", pivoting=True)
    rank = int(np.sum(np.abs(np.diag(r)) > 1e-12 * np.abs(r).max()))
    pivots = np.sort(perm[:rank])
    free = np.setdiff1d(np.arange(n), pivots)
    if free.size == 0:
        return sp.csr_matrix((n, 0))
    # G_p v_p + G_f v_f = 0  ->  v_p = -G_p⁺ G_f v_f (exact for consistent constraints)
    Gp, Gf = G[:, pivots], G[:, free]
    elim = -la.lstsq(Gp, Gf)[0]
    Z = sp.lil_matrix((n, free.size))
    Z[free, np.arange(free.size)] = 1.0
    rows, cols = np.nonzero(np.abs(elim) > 0)
    for i, j in zip(rows, cols):
        Z[pivots[i], j] = elim[i, j]
    return Z.tocsr()


def _modes(M, D, Ks, G, damped: bool) -> np.ndarray:
    """:func:`_modes_unchecked`, with LAPACK's failures reported as :class:`SolverError`."""
    try:
        return _modes_unchecked(M, D, Ks, G, damped)
    except np.linalg.LinAlgError as exc:
        # Seen only for values spanning most of float64's range (1e-320 … 1e220).
        raise SolverError(f"resonances: the eigenvalue solver failed ({exc}); element "
                          "values span too many orders of magnitude", status="lapack") from None


def _modes_unchecked(M, D, Ks, G, damped: bool) -> np.ndarray:
    """Eigenvalues s (Im s ≥ 0, |s| > 0) of the constrained network, with their error estimates.

    ``M``, ``D``, ``Ks`` are sparse; returns an array of shape (k, 2): column
    0 the complex s, column 1 the estimated relative error of |s|.
    """
    Z = _project(G, M.shape[0])
    limit = MAX_UNKNOWNS_DAMPED if damped else MAX_UNKNOWNS
    if Z.shape[1] > limit:
        raise SolverError(
            f"resonances: {Z.shape[1]} unknowns, the limit is {limit} for "
            f"{'damped' if damped else 'undamped'} networks (a dense O(n³) eigenproblem); "
            "sweep K(ω) instead, or reduce the network", status="size")
    with np.errstate(all="ignore"):
        Mr, Dr, Kr = ((Z.T @ X @ Z).toarray() for X in (M, D, Ks))
    if Mr.shape[0] == 0:
        return np.zeros((0, 2), dtype=complex)
    if not (np.isfinite(Mr).all() and np.isfinite(Dr).all() and np.isfinite(Kr).all()):
        raise SolverError("resonances: the network's matrices overflow float64 (element "
                          "values or lever ratios near 1e308 combine beyond it)",
                          status="overflow")
    scale_m = np.abs(Mr).max() or 1.0
    scale_k = np.abs(Kr).max() or 1.0
    # sqrt of each: the quotient itself can leave float64 (1e-200 / 1e180).
    w_ref = math.sqrt(scale_k) / math.sqrt(scale_m)
    if not (math.isfinite(w_ref) and w_ref > 0):
        raise SolverError(f"resonances: the stiffness and mass scales ({scale_k:.3g} N/m, "
                          f"{scale_m:.3g} kg) are too far apart for float64", status="range")
    eps = np.finfo(float).eps
    if not damped:
        lam = _undamped(Mr / scale_m, Kr / scale_k)      # λ = (ω / w_ref)²
        lam = lam[lam > 1e-11 * max(1.0, lam.max(initial=0.0))]
        s = 1j * w_ref * np.sqrt(lam)
        err = eps * (lam.max(initial=1.0) / lam) * 4
    else:
        with np.errstate(all="ignore"):
            scaled = (Mr / scale_m, Dr / (scale_m * w_ref), Kr / scale_k)
        if not all(np.isfinite(X).all() for X in scaled):
            raise SolverError("resonances: the damping, mass and stiffness scales are too far "
                              "apart for float64", status="range")
        s_all = _damped(*scaled) * w_ref
        # Rigid-body (zero) roots come out of QZ split by about sqrt(eps)·w_ref.
        keep = np.flatnonzero((np.abs(s_all) > 1e-6 * w_ref)
                              & (s_all.imag >= -1e-12 * np.abs(s_all)))
        s = s_all[keep]
        mag = np.abs(s)
        err = eps * 1e2 * (mag.max(initial=1.0) / mag)
        if s.size > 1 or s_all.size > 1:
            # Coalescing roots (critical damping, ζ → 1): a root at relative
            # distance δ from another moves by about eps/δ, and a double root
            # by about sqrt(eps) — far more than the simple-root estimate.
            gap = np.abs(s[:, None] - s_all[None, :])
            gap[np.arange(s.size), keep] = np.inf
            with np.errstate(divide="ignore"):
                near = np.minimum(np.sqrt(eps), eps / (gap.min(axis=1) / mag))
            err = np.maximum(err, 10 * near)
        s = np.where(np.abs(s.imag) <= 1e-12 * np.abs(s), s.real + 0j, s)
    return np.column_stack([s, err]) if s.size else np.zeros((0, 2), dtype=complex)


def _undamped(M: np.ndarray, K: np.ndarray) -> np.ndarray:
    """λ with K v = λ M v, M positive semi-definite; massless directions condensed out.

    A diagonal M (every mass to the frame, the usual mobility-analogy layout)
    is handled without an eigen-decomposition of M.
    """
    if not np.any(M - np.diag(np.diag(M))):
        mu = np.diag(M)
        V = None
    else:
        mu, V = la.eigh(M)
    massive = mu > 1e-13 * max(mu.max(initial=0.0), 1e-300)
    if not massive.any():
        return np.zeros(0)          # no inertia: no oscillation
    if V is None:
        Krr = K[np.ix_(massive, massive)]
        Knn = K[np.ix_(~massive, ~massive)]
        Knr = K[np.ix_(~massive, massive)]
    else:
        R, N = V[:, massive], V[:, ~massive]
        Krr, Knn, Knr = R.T @ K @ R, N.T @ K @ N, N.T @ K @ R
    Kc = Krr - Knr.T @ la.lstsq(Knn, Knr)[0] if Knn.size else Krr
    if Kc.shape[0] == 0:
        return np.zeros(0)
    # Symmetric scaling by the masses gives a standard symmetric eigenproblem.
    d = 1.0 / np.sqrt(mu[massive])
    A = Kc * d[:, None] * d[None, :]
    return la.eigvalsh((A + A.T) / 2)


def _damped(M, D, K) -> np.ndarray:
    """Finite eigenvalues s of (s² M + s D + K) v = 0 by a companion linearisation."""
    n = M.shape[0]
    eye, zero = np.eye(n), np.zeros((n, n))
    A = np.block([[zero, eye], [-K, -D]])
    B = np.block([[eye, zero], [zero, M]])
    alpha, beta = la.eig(A, B, right=False, homogeneous_eigvals=True)
    finite = np.abs(beta) > 1e-12 * np.abs(alpha)
    return alpha[finite] / beta[finite]


def _cancel(held: np.ndarray, released: np.ndarray):
    """Drop modes present in both problems (they do not appear in K)."""
    keep_h = np.ones(len(held), bool)
    keep_r = np.ones(len(released), bool)
    for i, (s, err) in enumerate(held):
        if not len(released):
            break
        d = np.abs(released[:, 0] - s) / abs(s)
        d[~keep_r] = np.inf
        j = int(np.argmin(d))
        # The same sub-network's mode, computed twice, agrees to rounding; distinct
        # modes of long chains can lie within 1e-8 of each other, so use the estimates.
        if d[j] < 1e3 * (abs(err) + abs(released[j, 1])):
            keep_h[i] = keep_r[j] = False
    return held[keep_h], released[keep_r]


def _make(kind: str, row) -> Resonance:
    s, err = complex(row[0]), float(np.real(row[1]))
    wn = abs(s)
    return Resonance(kind, float(wn), float(abs(s.imag)),
                     float(-s.real / wn) if wn else 0.0, err)


def _polish(circuit: Circuit, found: list[Resonance]) -> list[Resonance]:
    """Refine undamped roots on the circuit's own K(ω) by a bracketed (Illinois) search.

    Im K rises through zero at a resonance and −1/Im K rises through zero at
    an anti-resonance (Foster); roots without a sign change in the bracket
    keep their eigenvalue estimate.
    """
    w0 = np.array([r.omega for r in found])
    pole = np.array([r.kind == "antiresonance" for r in found])
    width = np.maximum(np.array([r.error for r in found]) * 50, 1e-9)

    def f(w):
        X = circuit.sweep(w).K.imag
        with np.errstate(divide="ignore"):
            return np.where(pole, -1.0 / X, X)

    lo, hi = w0 * (1 - width), w0 * (1 + width)
    flo, fhi = f(lo), f(hi)
    ok = (flo < 0) & (fhi > 0) & np.isfinite(flo) & np.isfinite(fhi)
    side = np.zeros(w0.size)
    for _ in range(60):
        if not ok.any():
            break
        with np.errstate(all="ignore"):
            mid = np.where(ok, (lo * fhi - hi * flo) / (fhi - flo), w0)
        mid = np.where((mid > lo) & (mid < hi), mid, 0.5 * (lo + hi))
        fm = f(mid)
        left = ok & (fm < 0)
        right = ok & (fm >= 0)
        lo, flo = np.where(left, mid, lo), np.where(left, fm, flo)
        hi, fhi = np.where(right, mid, hi), np.where(right, fm, fhi)
        # Illinois: halve the stale end's value when the same end moves twice.
        fhi = np.where(left & (side < 0), fhi / 2, fhi)
        flo = np.where(right & (side > 0), flo / 2, flo)
        side = np.where(left, -1, np.where(right, 1, side))
        if np.all(~ok | (hi - lo <= 4 * np.finfo(float).eps * hi)):
            break
    with np.errstate(all="ignore"):
        f_lo, f_hi = f(lo), f(hi)
    out = []
    for r, good, a, b, fa, fb in zip(found, ok, lo, hi, f_lo, f_hi):
        if good:
            # An end on an exact zero of the computed f is the root itself (the
            # midpoint of a one-ulp bracket [10 − ulp, 10] is not).
            w = float(a if fa == 0 else b if fb == 0 else 0.5 * (a + b))
            out.append(Resonance(r.kind, w, w, 0.0, float(max((b - a) / (2 * w),
                                                               np.finfo(float).eps))))
        else:
            out.append(r)
    return out
