"""Nodal sweeps at sparse-solver speed (issue 14 §3): mechcirc against ``splu`` per ω and ngspice.

For each network, in the same run and interleaved (median of ``--repeat``
runs each), prints the CPU time of

* the floor: A(ω) = D + C + j(ωM − Kₛ/ω) built with scipy.sparse
  arithmetic and factorised by ``scipy.sparse.linalg.splu`` at every ω,
  one solve, no refinement, no error estimate;
* ngspice (``ngspice -b``, CPU time of the child process) on the
  electrical analogue (mobility analogy: mass → capacitor to ground,
  spring k → inductor 1/k, damper c → resistor 1/c; the ladder is driven
  by a voltage source, K = −1/I(V1); the grid by a current source, K =
  V(node)), one AC sweep over the same points (``.ac dec``), results
  written with ``wrdata``; skipped with a note when ngspice is not installed;
* mechcirc's factorisation and one solve per ω, nothing else (what the
  refinement's cost is measured against);
* ``nodal.solve(system, ω, refine=False)``: mechcirc's plain solve (with
  its one-correction error estimate);
* ``nodal.mobility_and_error(system, ω)``: the default, refined in
  double-double with the error estimate (what ``Circuit.sweep(method=
  "nodal")`` does);

and the ratios, and the largest relative difference of K between mechcirc
and the floor and ngspice (ngspice writes 9 significant digits).  Networks:
random ladders of 9,999 (and, with ``--big``, 99,999) elements forced
through nodal analysis, the 30×30 spring–mass grid and (``--big``) a
100×100 grid; ngspice on the 100×100 grid is run on ``--big-points``
points only (it takes minutes) and its time scaled to the sweep's points.

Run from the repository root: ``python benchmarks/bench_nodal_speed.py [--big]``.
"""

from __future__ import annotations

import argparse
import importlib.util
import os
import resource
import shutil
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

import mechcirc
import mechcirc._nodal_solvers as solvers
import mechcirc.nodal as nodal
from mechcirc import _jit

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
from reference.networks import grid_text  # noqa: E402
from timing import cpu


grid = grid_text       # the tests' grid (tests/reference/networks.py)


def ladder(n_el: int, seed: int = 0) -> str:
    """Springs k in [1e4, 2e4] N/m in series, masses m in [0.2, 1.2] kg to the frame."""
    rng = np.random.default_rng(seed)
    lines = ["drive V n0 0 velocity=1"]
    for i in range(n_el):
        node = i // 2
        if i % 2 == 0:
            lines.append(f"spring k{i} n{node} n{node + 1} {rng.uniform(1e4, 2e4)!r}")
        else:
            lines.append(f"mass m{i} n{node + 1} 0 {rng.uniform(0.2, 1.2)!r}")
    return "\n".join(lines)


def spice_ladder(n_el: int, seed: int = 0) -> str:
    """The ladder of :func:`ladder` as an ngspice netlist (voltage drive)."""
    rng = np.random.default_rng(seed)
    lines = ["* ladder", "V1 n0 0 DC 0 AC 1"]
    for i in range(n_el):
        node = i // 2
        if i % 2 == 0:
            lines.append(f"L{i} n{node} n{node + 1} {1 / rng.uniform(1e4, 2e4)!r}")
        else:
            lines.append(f"C{i} n{node + 1} 0 {float(rng.uniform(0.2, 1.2))!r}")
    return "\n".join(lines)


def spice_grid(n: int, k: float = 1e4, m: float = 1.0) -> str:
    """The grid of :func:`grid` as an ngspice netlist (current drive: K = V(g0_0))."""
    lines = ["* grid", "I1 0 g0_0 DC 0 AC 1"]
    for i in range(n):
        for j in range(n):
            g = f"g{i}_{j}"
            lines += [f"Cm{i}_{j} {g} 0 {m}", f"Lf{i}_{j} {g} 0 {1 / k!r}"]
            if i + 1 < n:
                lines.append(f"Lh{i}_{j} {g} g{i + 1}_{j} {1 / k!r}")
            if j + 1 < n:
                lines.append(f"Lv{i}_{j} {g} g{i}_{j + 1} {1 / k!r}")
    return "\n".join(lines)


def ngspice(netlist: str, probe: str, w0: float, w1: float, per_decade: int):
    """(CPU s of ``ngspice -b``, its K and frequencies) for ``.ac dec per_decade``."""
    with tempfile.TemporaryDirectory() as tmp:
        out = os.path.join(tmp, "out.txt")
        cir = os.path.join(tmp, "net.cir")
        with open(cir, "w") as f:
            # noopac: no DC operating point before the AC sweep (the circuit is
            # linear; the grid's loops of inductors make the DC point singular).
            f.write(netlist + f"\n.options noopac\n.ac dec {per_decade} {float(w0 / (2 * np.pi))!r} "
                    f"{float(w1 / (2 * np.pi))!r}\n"
                    f".control\nrun\nwrdata {out} {probe}\n.endc\n.end\n")
        before = resource.getrusage(resource.RUSAGE_CHILDREN)
        # ngspice-39 exits with status 1 after a batch run with a .control
        # block even when it succeeded: judge by the output file.
        proc = subprocess.run(["ngspice", "-b", cir], capture_output=True, text=True)
        after = resource.getrusage(resource.RUSAGE_CHILDREN)
        if not os.path.exists(out):
            raise RuntimeError(f"ngspice failed:\n{proc.stdout[-2000:]}{proc.stderr[-2000:]}")
        data = np.loadtxt(out)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return cpu, data[:, 1] + 1j * data[:, 2], 2 * np.pi * data[:, 0]


def baseline(system, omega):
    from scipy.sparse.linalg import splu

    base = (system.D + system.C).tocsc()
    M, Ks = system.M.tocsc(), system.Ks.tocsc()
    b = system.injection().astype(complex)
    out = np.empty(omega.size, dtype=complex)
    for i, w in enumerate(omega):
        out[i] = system.difference(splu((base + 1j * (w * M - Ks / w)).tocsc()).solve(b))
    return out


def bare(system, omega):
    """mechcirc's factorisation and one solve per ω, no residual, no estimate (what refinement adds to)."""
    solver = solvers.solver(system)
    rhs = system.injection().astype(complex)
    out = np.full(omega.size, np.nan, dtype=complex)
    for start in range(0, omega.size, 8):
        sel = np.arange(start, min(start + 8, omega.size))
        good, solve = solver.factor(omega[sel])
        x = solve(np.broadcast_to(rhs, (int(good.sum()), rhs.size)))
        out[sel[good]] = system.difference(x)
    return out


def run(name, text, spice, omega, repeat, *, spice_points=None, floor=True):
    """Time the floor, ngspice and mechcirc on one network; print the table row."""
    system = mechcirc.parse(text).nodal
    nodal.mobility_and_error(system, omega[:3])         # warm: compile / load kernels
    runs = {"mechcirc LU + solve": lambda: bare(system, omega),
            "mechcirc plain": lambda: nodal.solve(system, omega, refine=False,
                                                  keep_x=False).K,
            "mechcirc refined": lambda: nodal.mobility_and_error(system, omega)[0]}
    if floor:
        # With spice_points (the 100×100 grid) the floor too is timed on that
        # many points of the same range and scaled to the sweep's points.
        few = np.geomspace(omega[0], omega[-1], spice_points) if spice_points else omega
        runs = {"splu per ω": lambda: (baseline(system, few), omega.size / few.size),
                **runs}
    have_ng = shutil.which("ngspice") is not None
    decades = np.log10(omega[-1] / omega[0])
    if have_ng and spice is not None:
        netlist, probe, sign = spice
        pts = spice_points or omega.size
        per_dec = int(round((pts - 1) / decades))

        def ng():
            cpu, K, w = ngspice(netlist, probe, omega[0], omega[-1], per_dec)
            return cpu * omega.size / K.size, (sign(K), w)
        runs["ngspice -b"] = ng
    times = {k: [] for k in runs}
    results = {}
    for _ in range(repeat):                     # interleaved
        for k, fn in runs.items():
            t, out = cpu(fn)
            if k == "ngspice -b":
                t, out = out[0], out[1]
            elif k == "splu per ω":
                out, scale = out
                t *= scale
            times[k].append(t)
            results[k] = out
    med = {k: statistics.median(v) for k, v in times.items()}
    print(f"{name}: {system.size} unknowns, {omega.size} points (CPU s, median of {repeat})")
    for k in runs:
        note = ""
        if k == "ngspice -b" and spice_points:
            note = f"  (run at {results[k][0].size} points, scaled)"
        if k == "splu per ω" and spice_points:
            note = f"  (run at {results[k].size} points, scaled)"
        ratio = " ".join(f"{med[k] / med[b]:.2f}× {b}" for b in ("splu per ω", "ngspice -b")
                         if b in med and b != k)
        print(f"    {k:18s} {med[k]:8.3f} s   {ratio}{note}")
    K = results["mechcirc refined"]
    fin = np.isfinite(K)
    if not fin.all():
        print(f"    mechcirc: {np.sum(~fin)} point(s) on a pole of K (+∞·j, flagged), "
              "left out of the comparisons")
    if floor:
        Kf = K if not spice_points else nodal.mobility_and_error(
            system, np.geomspace(omega[0], omega[-1], spice_points))[0]
        both = np.isfinite(Kf)
        with np.errstate(all="ignore"):
            d = np.abs(Kf[both] / results["splu per ω"][both] - 1)
        print(f"    max |K/K_splu - 1| = {np.max(d):.1e} (the floor is not refined)")
    if "ngspice -b" in results:
        Kn, wn = results["ngspice -b"]
        Km = nodal.mobility_and_error(system, wn)[0] if spice_points else K
        if Km.size == Kn.size:
            both = np.isfinite(Kn) & np.isfinite(Km)
            with np.errstate(all="ignore"):
                print(f"    max |K/K_ngspice - 1| = {np.max(np.abs(Km[both] / Kn[both] - 1)):.1e} "
                      f"(ngspice's points, 9 digits written; ngspice NaN at "
                      f"{np.sum(~np.isfinite(Kn))})")
    elif spice is not None:
        print("    ngspice not installed: skipped")
    print(f"    refined / (LU + solve) {med['mechcirc refined'] / med['mechcirc LU + solve']:.2f} "
          f"(goal <= 1.5), refined / plain "
          f"{med['mechcirc refined'] / med['mechcirc plain']:.2f}; solver: {solvers.solver(system).kind}, "
          f"band {solvers.solver(system).kl}; numba kernels: {nodal.kernels(10 ** 9) is not None}")


def versions() -> str:
    import scipy

    ng = "not installed"
    if shutil.which("ngspice"):
        out = subprocess.run(["ngspice", "-v"], capture_output=True, text=True).stdout
        ng = next((ln.split(":")[0].strip(" *") for ln in out.splitlines()
                   if "ngspice-" in ln), "?")
    return (f"numpy {np.__version__}, scipy {scipy.__version__}, ngspice: {ng}; "
            f"load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores")


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--big", action="store_true", help="99,999-element ladder, 100×100 grid")
    ap.add_argument("--points", type=int, default=1001)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--big-points", type=int, default=41,
                    help="points of the ngspice run on the 100×100 grid")
    ap.add_argument("--only", default="", help="comma-separated: ladder,grid,ladder99,grid100")
    args = ap.parse_args()
    if importlib.util.find_spec("numba"):
        # The compiled path, compiled in this process if numba's cache lacks it (with
        # COMPILED None a cold cache gives the numpy path while a detached process
        # compiles: a first run then timed the numpy path as "numba kernels: True").
        _jit.COMPILED = True
    print(versions())
    only = set(filter(None, args.only.split(",")))
    want = (lambda k: k in only) if only else (lambda k: k in ("ladder", "grid") or args.big)
    omega = np.geomspace(0.6, 6e3, args.points)
    gomega = np.geomspace(10, 1e3, args.points)

    def lad(n):
        return (spice_ladder(n), "i(V1)", lambda i: np.divide(-1, i, where=i != 0,
                                                               out=np.full_like(i, np.nan)))

    def grd(n):
        return (spice_grid(n), "v(g0_0)", lambda v: v)
    if want("ladder"):
        run("ladder 9,999 elements", ladder(9999), lad(9999), omega, args.repeat)
    if want("grid"):
        run("30×30 grid", grid(30), grd(30), gomega, args.repeat)
    if want("ladder99"):
        run("ladder 99,999 elements", ladder(99999), lad(99999), omega, 1)
    if want("grid100"):
        run("100×100 grid", grid(100), grd(100), gomega, 1, spice_points=args.big_points)
    print(versions())


if __name__ == "__main__":
    main()
