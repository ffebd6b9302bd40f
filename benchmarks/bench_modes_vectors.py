"""Eigenvectors of the 30×30 grid: dense ``eigh`` against the banded LAPACK routes, same run.

``modes()`` needs every eigenvector of A = M^-1/2 K M^-1/2 (held and released
problem).  ``resonances()`` gets the eigenvalues from A reordered by reverse
Cuthill–McKee (band 30 for 899 rows) with ``scipy.linalg.eigvals_banded``.
This script times, CPU seconds, median of ``--repeat``, the calls alternating
within each repetition, on the grid's held problem:

* ``numpy.linalg.eigh`` (LAPACK syevd, what ``modes()`` uses);
* ``scipy.linalg.eigh(driver="evd")`` (the same routine through SciPy);
* ``scipy.linalg.eig_banded`` on the band, all vectors (sbevd);
* ``scipy.linalg.eig_banded(select="i")`` (sbevx: bisection + inverse iteration);
* the same for the lowest n/10 roots only (a band ``omega_max``);
* ``scipy.linalg.eigvals_banded`` (the values alone, what ``resonances()`` pays);
* LAPACK ``dsytrd`` alone (the reduction to tridiagonal inside ``eigh``);
* inverse iteration on the band, the route that knows the eigenvalues: one
  shifted banded LU and solve (``dgbtrf`` + ``dgbtrs``, bandwidth b each side)
  per root, timed on ``--solves`` roots and scaled to all n (one step each, no
  reorthogonalisation of the grid's equal roots: a lower bound of that route);

and prints each against ``eigh`` with the accuracy of the vectors (residual
max |A x − λx|/λ_max and max |XᵀX − I|, i.e. M-orthonormality of the
mode shapes after the mass scaling).  The band is formed here the way
``mechcirc.resonances`` forms it (reverse Cuthill–McKee of A's pattern).

Run from the repository root: ``OPENBLAS_NUM_THREADS=1 python benchmarks/bench_modes_vectors.py``.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

import mechcirc  # noqa: E402
from bench_nodal_speed import grid  # noqa: E402
from mechcirc.resonances import constraint_basis, pencil  # noqa: E402


def scaled_held(n: int) -> np.ndarray:
    """A = M^-1/2 K M^-1/2 of the n×n grid's held problem (M diagonal there)."""
    M, _, K, _, G_held, _ = pencil(mechcirc.parse(grid(n)).nodal)
    Z = constraint_basis(G_held, M.shape[0])
    Mr, Kr = ((Z.T @ X @ Z).toarray() for X in (M, K))
    d = 1.0 / np.sqrt(np.diag(Mr))
    A = Kr * d[:, None] * d[None, :]
    return (A + A.T) / 2


def band(A: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(lower band storage, the reordered dense matrix) after reverse Cuthill–McKee."""
    import scipy.sparse as sp
    from scipy.sparse.csgraph import reverse_cuthill_mckee

    S = sp.csr_matrix(A)
    p = reverse_cuthill_mckee(S, symmetric_mode=True)
    P = S[p][:, p].tocoo()
    b = int((P.row - P.col).max(initial=0))
    low = P.row >= P.col
    ab = np.zeros((b + 1, A.shape[0]))
    ab[(P.row - P.col)[low], P.col[low]] = P.data[low]
    return ab, P.toarray()


def band_solver(Ap: np.ndarray, b: int, count: int):
    """A call doing ``count`` steps of inverse iteration on the band of ``Ap``, each at
    its own shift (an eigenvalue moved by 1e-10): LAPACK dgbtrf + dgbtrs in general
    band storage (the storage and the shifts made here, outside the timing)."""
    from scipy.linalg import eigvalsh, lapack

    n = Ap.shape[0]
    G = np.zeros((3 * b + 1, n), order="F")
    for d in range(-b, b + 1):                  # A[i, j] at row 2b + i − j, column j
        G[2 * b - d, max(d, 0):n + min(d, 0)] = np.diagonal(Ap, d)
    rhs = np.random.default_rng(1).standard_normal(n)
    shifts = eigvalsh(Ap)[np.linspace(0, n - 1, count).astype(int)] * (1 + 1e-10)

    def solves() -> None:
        for lam in shifts:
            shifted = G.copy(order="F")
            shifted[2 * b] -= lam
            lu, piv, _ = lapack.dgbtrf(shifted, b, b, overwrite_ab=1)
            lapack.dgbtrs(lu, b, b, rhs, piv)
    return solves


def main() -> None:
    from scipy.linalg import eig_banded, eigh, eigvals_banded, lapack

    ap = argparse.ArgumentParser()
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--solves", type=int, default=40)
    args = ap.parse_args()
    A = scaled_held(30)
    ab, Ap = band(A)
    n = A.shape[0]
    solves = band_solver(Ap, ab.shape[0] - 1, args.solves)
    calls = {
        "numpy eigh (syevd)": (A, lambda: np.linalg.eigh(A)),
        "scipy eigh evd": (A, lambda: eigh(A, driver="evd", check_finite=False)),
        "eig_banded all (sbevd)": (Ap, lambda: eig_banded(ab, lower=True, check_finite=False)),
        "eig_banded select=i (sbevx)": (Ap, lambda: eig_banded(
            ab, lower=True, select="i", select_range=(0, n - 1), check_finite=False)),
        "sbevx, lowest n/10 only": (Ap, lambda: eig_banded(
            ab, lower=True, select="i", select_range=(0, n // 10 - 1), check_finite=False)),
        "eigvals_banded (values only)": (Ap, lambda: (eigvals_banded(
            ab, lower=True, check_finite=False), None)),
        "dsytrd (eigh's reduction)": (A, lambda: (lapack.dsytrd(A, lower=1), None)),
        "band inverse iteration, all n": (Ap, lambda: (solves(), None)),
    }
    times: dict[str, list[float]] = {k: [] for k in calls}
    out: dict = {}
    for _ in range(args.repeat):
        for name, (_, fn) in calls.items():
            t0 = time.process_time()
            out[name] = fn()
            times[name].append(time.process_time() - t0)
    times["band inverse iteration, all n"] = [t * n / args.solves
                                              for t in times["band inverse iteration, all n"]]
    base = statistics.median(times["numpy eigh (syevd)"])
    print(f"30×30 grid, held problem: {n} rows, band {ab.shape[0] - 1}")
    for name, (B, _) in calls.items():
        t = statistics.median(times[name])
        w, X = out[name]
        acc = ""
        if X is not None:
            res = np.abs(B @ X - X * w).max() / np.abs(w).max()
            orth = np.abs(X.T @ X - np.eye(X.shape[1])).max()
            acc = f"; residual {res:.1e}, |XᵀX − I| {orth:.1e}"
        print(f"{name:30s} {t * 1e3:7.1f} ms CPU ({t / base:.2f}× eigh){acc}")


if __name__ == "__main__":
    main()
