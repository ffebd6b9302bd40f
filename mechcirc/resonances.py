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
``scipy.linalg.eigvalsh`` (error bound eps·λ_max/λ, Weyl).  Damped networks:
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
the drive (it cancels in K) and is not reported.  Zero-frequency (rigid-body)
modes are not reported.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal

import numpy as np
import scipy.linalg as la

from .circuit import Circuit
from .errors import InputError, NetlistError, SolverError

__all__ = ["Resonance", "find_resonances", "MAX_UNKNOWNS", "MAX_UNKNOWNS_DAMPED"]

#: Largest eigenproblem solved (unknowns left after the constraints).  The
#: dense solve costs O(n³): about 12 s at 2000 unknowns undamped, and the
#: damped 2n linearisation about 10 s at 500 (measured, docs/reliability.md).
#: Larger networks are refused at once instead of running for hours.
MAX_UNKNOWNS = 2000
#: The same for networks with dampers (QZ on a 2n × 2n pencil).
MAX_UNKNOWNS_DAMPED = 500
#: The most eigenvalues the band solver asks ARPACK for (roots and their mirror images).
MAX_BAND_ROOTS = 192


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
    if omega_max is not None and not omega_max > 0:     # NaN would report nothing, silently
        raise InputError(f"omega_max must be > 0 rad/s or None, got {omega_max!r}")
    for e in circuit.elements:
        if not math.isfinite(e.value * e.eta):
            raise NetlistError(f"{e.kind} {e.name!r}: value × eta = {e.value:g} × {e.eta:g} "
                               "overflows float64", circuit.source, e.line, e.col,
                               "a product below 1.8e308")
    system = circuit.nodal
    if system.unloaded:
        import warnings

        from .errors import UnloadedElementWarning

        d = circuit.drive
        warnings.warn(
            f"{len(system.unloaded)} element(s) lie on no path between the drive's nodes "
            f"{d.n1!r} and {d.n2!r} and carry no force: {', '.join(system.unloaded)}",
            UnloadedElementWarning, stacklevel=2)
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
    released = _modes(M, D, Ks, G_levers, damped, omega_max)
    held = _modes(M, D, Ks, np.vstack([G_levers, drive_row]), damped, omega_max)
    held, released = _cancel(held, released)
    roots = [("resonance", s, e, f) for s, e, f in held] + \
        [("antiresonance", s, e, f) for s, e, f in released]
    if omega_max is not None:
        # A little beyond the band: polishing may move a root across its edge.
        roots = [t for t in roots if abs(t[1]) <= omega_max * (1 + 1e-6)]
    out = _polish(system, roots, damped) if roots else []
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
    rows, cols = np.nonzero(elim)
    r = np.concatenate([free, pivots[rows]])
    c = np.concatenate([np.arange(free.size), cols])
    v = np.concatenate([np.ones(free.size), elim[rows, cols]])
    Z = sp.csr_matrix((v, (r, c)), shape=(n, free.size))
    return Z


def _modes(M, D, Ks, G, damped: bool, omega_max=None) -> np.ndarray:
    """:func:`_modes_unchecked`, with LAPACK's failures reported as :class:`SolverError`."""
    try:
        return _modes_unchecked(M, D, Ks, G, damped, omega_max)
    except np.linalg.LinAlgError as exc:
        # Seen only for values spanning most of float64's range (1e-320 … 1e220).
        raise SolverError(f"resonances: the eigenvalue solver failed ({exc}); element "
                          "values span too many orders of magnitude", status="lapack") from None


def _modes_unchecked(M, D, Ks, G, damped: bool, omega_max=None) -> np.ndarray:
    """Eigenvalues s (Im s ≥ 0, |s| > 0) of the constrained network, with their error estimates.

    ``M``, ``D``, ``Ks`` are sparse; returns an array of shape (k, 2): column
    0 the complex s, column 1 the estimated relative error of |s|.  Networks
    above the dense limits are solved in the band |s| ≤ ``omega_max`` by
    shift-invert Arnoldi (:func:`_band_modes`); without a band they are refused.
    """
    Z = _project(G, M.shape[0])
    limit = MAX_UNKNOWNS_DAMPED if damped else MAX_UNKNOWNS
    if Z.shape[1] > limit:
        if omega_max is not None and math.isfinite(omega_max) and omega_max > 0:
            with np.errstate(all="ignore"):
                Mr, Dr, Kr = ((Z.T @ X @ Z).tocsc() for X in (M, D, Ks))
            return _band_modes(Mr, Dr, Kr, float(omega_max))
        raise SolverError(
            f"resonances: {Z.shape[1]} unknowns, the limit is {limit} for "
            f"{'damped' if damped else 'undamped'} networks (a dense O(n³) eigenproblem) "
            "unless a band omega_max is given; give omega_max, sweep K(ω) instead, or "
            "reduce the network", status="size")
    with np.errstate(all="ignore"):
        Mr, Dr, Kr = ((Z.T @ X @ Z).toarray() for X in (M, D, Ks))
    if Mr.shape[0] == 0:
        return np.zeros((0, 3), dtype=complex)
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
        lam, direct = _undamped(Mr / scale_m, Kr / scale_k)      # λ = (ω / w_ref)²
        lam = lam[lam > 1e-11 * max(1.0, lam.max(initial=0.0))]
        s = 1j * w_ref * np.sqrt(lam)
        err = eps * (lam.max(initial=1.0) / lam) * 4
        # Weyl's bound holds for the scaled matrix, not through a static
        # condensation or an eigen-decomposition of M (their rounding is
        # amplified by the condition of the condensed block): not a bound
        # then, and these roots are always polished on K (column 2).
        must = np.full(s.size, 0.0 if direct else 1.0)
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
    if damped:
        must = np.ones(s.size)
    return np.column_stack([s, err, must]) if s.size else np.zeros((0, 3), dtype=complex)


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
    keep = (np.abs(s_all) > 1e-6 * omega_max) & (np.abs(s_all) <= omega_max * (1 + 1e-6)) \
        & (s_all.imag >= -1e-9 * np.abs(s_all))
    s = s_all[keep]
    s = np.where(np.abs(s.imag) <= 1e-9 * np.abs(s), s.real + 0j, s)
    err = np.full(s.size, 1e-8)
    must = np.ones(s.size)
    return np.column_stack([s, err, must]) if s.size else np.zeros((0, 3), dtype=complex)


def _band_modes_undamped(M, K, omega_max: float, v0: np.ndarray) -> np.ndarray | None:
    """The undamped band: roots s = jω, ω ≤ ``omega_max``, of K v = ω² M v, or None.

    The roots in the band are counted first (:func:`count_undamped_roots`), so
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
    w = np.sqrt(np.sort(lam[lam > 0]))
    w = w[(w > 1e-6 * omega_max) & (w <= omega_max * (1 + 1e-6))]
    s = 1j * w
    return np.column_stack([s, np.full(s.size, 1e-8), np.ones(s.size)]) if s.size \
        else np.zeros((0, 3), dtype=complex)


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
    if not np.all(np.isfinite(d)) or np.any(d == 0):
        return None
    return int(np.count_nonzero(d < 0))


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
    if lo is None or hi is None:
        return None
    return lo, hi


def count_undamped_roots(M, K, omega_max: float) -> int | None:
    """How many natural frequencies 1e-6·omega_max < ω < omega_max the pencil (K, M) has.

    See :func:`_inertia_counts`; None when the count cannot be had.
    """
    counts = _inertia_counts(M, K, omega_max)
    return None if counts is None else counts[1] - counts[0]


def _undamped(M: np.ndarray, K: np.ndarray) -> np.ndarray:
    """λ with K v = λ M v, M positive semi-definite; massless directions condensed out.

    Returns ``(λ, direct)``: ``direct`` when M was diagonal and every
    direction had mass (no condensation), where eps·λ_max/λ bounds the error.

    A diagonal M (every mass to the frame, the usual mobility-analogy layout)
    is handled without an eigen-decomposition of M.
    """
    if not np.any(M - np.diag(np.diag(M))):
        mu = np.diag(M)
        V = None
    else:
        mu, V = la.eigh(M)
    massive = mu > 1e-13 * max(mu.max(initial=0.0), 1e-300)
    direct = V is None and bool(massive.all())
    if not massive.any():
        return np.zeros(0), direct  # no inertia: no oscillation
    if V is None:
        Krr = K[np.ix_(massive, massive)]
        Knn = K[np.ix_(~massive, ~massive)]
        Knr = K[np.ix_(~massive, massive)]
    else:
        R, N = V[:, massive], V[:, ~massive]
        Krr, Knn, Knr = R.T @ K @ R, N.T @ K @ N, N.T @ K @ R
    Kc = Krr - Knr.T @ la.lstsq(Knn, Knr)[0] if Knn.size else Krr
    if Kc.shape[0] == 0:
        return np.zeros(0), direct
    # Symmetric scaling by the masses gives a standard symmetric eigenproblem.
    d = 1.0 / np.sqrt(mu[massive])
    A = Kc * d[:, None] * d[None, :]
    return la.eigvalsh((A + A.T) / 2), direct


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
    for i, (s, err, _) in enumerate(held):
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


def _make(kind: str, s: complex, err: float) -> Resonance:
    s = complex(s)
    wn = abs(s)
    return Resonance(kind, float(wn), float(abs(s.imag)),
                     float(-s.real / wn) + 0.0 if wn else 0.0, float(err))


#: Roots whose eigen-solver bound is below this are not polished on K (undamped).
_POLISH_BELOW = 1e-13


def _polish(system, roots: list, damped: bool) -> list[Resonance]:
    """Each root polished on the circuit's own K(s) by a complex secant iteration.

    K(s) comes from the nodal matrices at complex frequency, A(s) = D + C +
    sM + Kₛ/s (``nodal.combine`` at ω = −js); a resonance is a zero of K, an
    anti-resonance a zero of 1/K.  The error of the polished root is
    |δg| / |g'(s)| with δg the absolute error of g = K (or 1/K) at the root
    (K is refined in double-double; δK its estimate, at least eps·|K|,
    times a safety factor of 4), plus the last secant step.  Undamped roots whose eigenvalue bound (Weyl:
    eps·λ_max/λ) is already below :data:`_POLISH_BELOW` keep it; a root the
    secant does not confirm (it leaves for another root) keeps its
    eigen-solver value and estimate.
    """
    eps = np.finfo(float).eps
    kinds = [k for k, _, _, _ in roots]
    s0 = np.array([complex(s) for _, s, _, _ in roots])
    e0 = np.array([float(np.real(e)) for _, _, e, _ in roots])
    must = np.array([float(np.real(f)) > 0 for _, _, _, f in roots])
    todo = np.flatnonzero((e0 > _POLISH_BELOW) | must) if not damped else np.arange(s0.size)
    s_new, e_new = s0.copy(), e0.copy()
    if todo.size:
        pole = np.array([kinds[i] == "antiresonance" for i in todo])
        s, err = _secant(system, s0[todo], pole, e0[todo], damped)
        s_new[todo], e_new[todo] = s, err
    if not damped:
        s_new = 1j * np.abs(s_new.imag)
    else:
        s_new = np.where(np.abs(s_new.imag) <= e_new * np.abs(s_new), s_new.real + 0j, s_new)
    return [_make(k, s, max(e, eps)) for k, s, e in zip(kinds, s_new, e_new)]


def _g_and_delta(system, s: np.ndarray, pole: np.ndarray):
    """g(s) (K, or 1/K at anti-resonances) and its absolute rounding uncertainty."""
    from . import nodal

    eps = np.finfo(float).eps
    g = np.full(s.shape, np.nan, dtype=complex)
    dg = np.full(s.shape, np.inf)
    for want, sys_ in ((~pole, system), (pole, _held(system))):
        if want.any():
            # Anti-resonances on the held system: 1/K = −q there, and A is
            # singular at the root while the held matrix is not.
            K, dK = nodal.evaluate_complex(sys_, s[want])
            sign = -1.0 if sys_ is not system else 1.0
            g[want] = sign * K
            # The refined value is good to about eps relative at best (its
            # rounding to float64), whatever the estimate of the solve says.
            dg[want] = 4 * np.maximum(dK, eps * np.abs(K))
    return g, dg


_HELD: dict = {}


def _held(system):
    """nodal.held(system), built once per system."""
    from . import nodal

    key = id(system)
    if key not in _HELD or _HELD[key][0] is not system:
        _HELD.clear()
        _HELD[key] = (system, nodal.held(system))
    return _HELD[key][1]


def _secant(system, s0: np.ndarray, pole: np.ndarray, e0: np.ndarray, damped: bool):
    """Complex secant iteration from the eigen-solver's roots; returns (s, relative error)."""
    eps = np.finfo(float).eps
    h = np.maximum(np.abs(s0) * np.maximum(e0, 1e-9), 1e-300)
    a, b = s0 - h * (1 if damped else 1j), s0.copy()
    ga, _ = _g_and_delta(system, a, pole)
    gb, db = _g_and_delta(system, b, pole)
    with np.errstate(all="ignore"):
        g0, slope0 = gb, (gb - ga) / (b - a)
    active = np.isfinite(ga) & np.isfinite(gb)
    step = np.full(s0.size, np.inf)
    slope = np.full(s0.size, np.nan, dtype=complex)
    for _ in range(12):
        if not active.any():
            break
        with np.errstate(all="ignore"):
            sl = (gb - ga) / (b - a)
            c = np.where(active, b - gb / sl, b)
        if not damped:
            c = 1j * c.imag                       # undamped: roots on the jω axis
        ok = active & np.isfinite(c)
        gc, dc = _g_and_delta(system, np.where(ok, c, b), pole)
        ok &= np.isfinite(gc)
        # On an exact zero of g its relative estimate says nothing (0·inf):
        # the uncertainty at the previous iterate, a step away, stands.
        dc = np.where(np.isfinite(dc), dc, db)
        step = np.where(ok, np.abs(c - b), step)
        slope = np.where(ok, sl, slope)
        a, ga = np.where(ok, b, a), np.where(ok, gb, ga)
        b, gb, db = np.where(ok, c, b), np.where(ok, gc, gb), np.where(ok, dc, db)
        # Stop once a step is within rounding of the root's own uncertainty.
        with np.errstate(all="ignore"):
            done = step <= np.maximum(4 * eps * np.abs(b), db / np.abs(slope))
        active = ok & ~done
    with np.errstate(all="ignore"):
        err = (db / np.abs(slope) + step) / np.abs(b)
    # Keep the eigen-solver's root where the secant wandered off (to another root,
    # or nowhere): farther than 1e-3 relative, or no estimate.
    moved = np.abs(b - s0) / np.abs(s0)
    bad = ~np.isfinite(err) | ~np.isfinite(b) | (moved > 1e-3)
    s = np.where(bad, s0, b)
    # Unconfirmed: the eigen-solver's estimate, but never below the Newton
    # step |g/g'| at its root (how far the circuit's own K says the root is).
    with np.errstate(all="ignore"):
        newton = np.abs(g0 / slope0) / np.abs(s0)
    newton = np.where(np.isfinite(newton), 10 * newton, 0.0)
    err = np.where(bad, np.maximum(e0, newton), np.maximum(err, eps))
    return s, err
