"""The compiled nodal kernels per node and per ω, against a minimal banded LU (the floor).

On the ladders of ``bench_nodal_ngspice.py`` (999 and 9,999 elements: about
500 and 5,000 unknowns, half band 1) at its 401 frequencies, it times the
package's compiled kernels on the sweep's own arrays (:mod:`mechcirc._nodal_kernels`:
A(ω) formed and factorised, one solve with the factors, one residual in
double-double) and, on the same band matrices, a floor written here and
nowhere else: a complex banded LU without pivoting (the ladders' matrices are
complex symmetric with a dominant diagonal here; the check below says how far
its K is from the package's) and its solve, in two layouts —

* ``node``: one ω at a time, the nodes innermost (the package's layout:
  each column's division waits on the previous one);
* ``omega``: the real and imaginary parts as separate float64 arrays with
  ω innermost, so that each column's operations run over all ω at once
  (LLVM vectorises them; no chain of dependent divisions per ω).

Each kernel is called over the whole 401 ω at once and, for the factor and
solve, also in the sweep's own chunks (``nodal._KERNEL_CHUNK`` (ω, unknown)
pairs, at least ``nodal._KERNEL_MIN_OMEGA`` ω: 16 ω at 500 and at 5,000 unknowns;
before the seventh session 8 and 1), which is what a sweep pays.  CPU
medians of ``--repeats``, in ns per unknown per ω.

Run from the repository root::

    python benchmarks/bench_nodal_floor.py [--sizes 999,9999] [--repeats 7]

It prints; it asserts nothing.
"""

from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path

import numba
import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

from bench_sp_sweep import ladder_netlist, ladder_numbers  # noqa: E402
from timing import cpu  # noqa: E402

import mechcirc  # noqa: E402
from mechcirc import _jit, nodal  # noqa: E402
from mechcirc._nodal_residual import pattern  # noqa: E402
from mechcirc._nodal_solvers import solver  # noqa: E402


@numba.njit(cache=True)
def floor_node(ab, kl, r, x):
    """LU without pivoting and one solve, per ω, nodes innermost (band storage as the
    package's before its seventh session: ``ab[k, c, 2·kl + i − c]`` = A[i, c]); x = A⁻¹ r."""
    n_w, n = x.shape
    kv = 2 * kl
    for k in range(n_w):
        a = ab[k]
        for j in range(n):
            x[k, j] = r[k, j]
        for j in range(n):
            recip = 1.0 / a[j, kv]
            km = min(kl, n - 1 - j)
            for t in range(1, km + 1):
                a[j, kv + t] *= recip
            for c in range(j + 1, min(n, j + kl + 1)):
                u = a[c, kv + j - c]
                for t in range(1, km + 1):
                    a[c, kv + j + t - c] -= a[j, kv + t] * u
            for t in range(1, km + 1):
                x[k, j + t] -= a[j, kv + t] * x[k, j]
        for j in range(n - 1, -1, -1):
            xj = x[k, j] / a[j, kv]
            x[k, j] = xj
            for i in range(max(0, j - kl), j):
                x[k, i] -= a[j, kv + i - j] * xj


@numba.njit(cache=True, fastmath=False)
def floor_omega(dr, di, lr, li, ur, ui, br, bi):
    """Tridiagonal LU without pivoting and one solve, ω innermost, real and imaginary
    parts apart: d the diagonal, l the sub-, u the super-diagonal (shape (n, n_ω));
    b the right-hand side, overwritten by the solution.  One reciprocal per pivot."""
    n, m = dr.shape
    pr = np.empty(m)
    pi = np.empty(m)
    for j in range(n):
        for k in range(m):                      # pivot's reciprocal, then the multiplier
            s = dr[j, k] * dr[j, k] + di[j, k] * di[j, k]
            pr[k] = dr[j, k] / s
            pi[k] = -di[j, k] / s
        dr[j, :] = pr
        di[j, :] = pi
        if j + 1 < n:
            for k in range(m):
                mr = lr[j, k] * pr[k] - li[j, k] * pi[k]
                mi = lr[j, k] * pi[k] + li[j, k] * pr[k]
                lr[j, k] = mr
                li[j, k] = mi
                dr[j + 1, k] -= mr * ur[j, k] - mi * ui[j, k]
                di[j + 1, k] -= mr * ui[j, k] + mi * ur[j, k]
                br[j + 1, k] -= mr * br[j, k] - mi * bi[j, k]
                bi[j + 1, k] -= mr * bi[j, k] + mi * br[j, k]
    for j in range(n - 1, -1, -1):
        for k in range(m):
            tr = br[j, k]
            ti = bi[j, k]
            if j + 1 < n:
                tr -= ur[j, k] * br[j + 1, k] - ui[j, k] * bi[j + 1, k]
                ti -= ur[j, k] * bi[j + 1, k] + ui[j, k] * br[j + 1, k]
            br[j, k] = tr * dr[j, k] - ti * di[j, k]
            bi[j, k] = tr * di[j, k] + ti * dr[j, k]


def run(n_el, omega, repeats):
    from mechcirc import _nodal_kernels as kern

    system = mechcirc.parse(ladder_netlist(*ladder_numbers(n_el))).nodal
    pat, sol = pattern(system), solver(system)
    n, kl, nw = pat.n, sol.kl, omega.size
    assert sol.kind == "band", sol.kind
    rhs = system.injection()
    chunk = max(nodal._KERNEL_MIN_OMEGA, nodal._KERNEL_CHUNK // n)
    rows = 3 * kl + 1
    ab = np.empty((2, n, rows, nw))
    ipiv = np.empty((n, nw), np.int64)
    ok = np.ones(nw, bool)

    def factor_all():
        kern.band_assemble_factor(pat.dc, pat.m, pat.k, omega, sol.dest[0], sol.dest[1],
                                  kl, ab, ipiv, ok)

    def factor_chunks():                        # as a sweep does: fresh arrays per chunk
        for s in range(0, nw, chunk):
            w = omega[s:s + chunk]
            kern.band_assemble_factor(pat.dc, pat.m, pat.k, w, sol.dest[0], sol.dest[1],
                                      kl, np.empty((2, n, rows, w.size)),
                                      np.empty((n, w.size), np.int64), np.ones(w.size, bool))
    factor_all()
    r = np.require(np.broadcast_to(rhs, (nw, n)), complex, ("C", "W"))
    every = np.arange(nw)
    x = np.empty((nw, n), complex)

    def solve_all():
        kern.band_solve_perm(ab, kl, ipiv, every, sol.p, r, x)
    solve_all()
    res = np.empty((nw, n), complex)

    def residual():
        kern.residual(omega, x.real, x.imag, x.real, x.imag, False, rhs, pat.k_bi, pat.k_bj,
                      pat.k_bs, pat.e_i, pat.e_j, pat.e_val, pat.e_vs[0], pat.e_vs[1],
                      pat.s_col, pat.s_val, pat.s_vs[0], pat.s_vs[1], res)
    # The floor's inputs: A(ω) in the package's band storage, before factorisation.
    a0 = np.zeros((nw, n, rows), complex)
    for k, w in enumerate(omega):
        a0[k][sol.dest] = nodal.combine(pat.dc, pat.m, pat.k, w)
    abn = np.empty_like(a0)
    xn = np.empty((nw, n), complex)
    rp = np.ascontiguousarray(r[:, sol.p])

    def node():
        abn[:] = a0
        floor_node(abn, kl, rp, xn)
    node()
    t_copy = cpu(lambda: abn.__setitem__(slice(None), a0), repeats)[0]
    kv = 2 * kl
    if kl == 1:
        diag = np.ascontiguousarray(a0[:, :, kv].T)
        sub = np.ascontiguousarray(a0[:, :, kv + 1].T)        # A[c + 1, c]
        sup = np.zeros((n, nw), complex)
        sup[:-1] = a0[:, 1:, kv - 1].T                          # A[c, c + 1]
        bo = np.ascontiguousarray(rp.T)
        srcs = [np.ascontiguousarray(f(z)) for z in (diag, sub, sup, bo)
                for f in (np.real, np.imag)]
        parts = [np.empty((n, nw)) for _ in srcs]

        def omega_fn():
            for p, z in zip(parts, srcs):
                p[:] = z
            floor_omega(*parts)
        omega_fn()
        xo = (parts[6] + 1j * parts[7]).T
        t_oc = cpu(lambda: [p.__setitem__(slice(None), z) for p, z in zip(parts, srcs)], repeats)[0]
    xp = x[:, sol.p]
    err_node = np.max(np.abs(xn - xp) / np.max(np.abs(xp), axis=1, keepdims=True))
    per = 1e9 / (n * nw)
    out = {"factor (A formed + LU, 401 ω in one call)": cpu(factor_all, repeats)[0],
           f"factor in the sweep's chunks ({chunk} ω)": cpu(factor_chunks, repeats)[0],
           "solve (one, 401 ω)": cpu(solve_all, repeats)[0],
           "residual in double-double (first pass)": cpu(residual, repeats)[0],
           "floor node-innermost LU + solve (copy out)": cpu(node, repeats)[0] - t_copy}
    if kl == 1:
        out["floor ω-innermost LU + solve, re/im apart (copy out)"] = \
            cpu(omega_fn, repeats)[0] - t_oc
        err_o = np.max(np.abs(xo - xp) / np.max(np.abs(xp), axis=1, keepdims=True))
    print(f"{n_el:,} elements: {n} unknowns, half band {kl}, {nw} ω; ns per unknown per ω "
          f"(CPU medians of {repeats}, load {os.getloadavg()[0]:.1f})")
    for k, v in out.items():
        print(f"    {k:58s} {v * per:7.1f} ns  ({v * 1e3:.2f} ms)")
    print(f"    floor's x against the package's: node {err_node:.1e}"
          + (f", ω-innermost {err_o:.1e}" if kl == 1 else ""), flush=True)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", default="999,9999")
    ap.add_argument("--repeats", type=int, default=7)
    args = ap.parse_args()
    _jit.COMPILED = True
    if nodal.kernels(10 ** 9) is None:
        print("numba's nodal kernels are not available")
        return 0
    omega = 2 * np.pi * np.geomspace(0.1, 1e3, 401)
    for n in (int(s) for s in args.sizes.split(",")):
        run(n, omega, args.repeats)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
