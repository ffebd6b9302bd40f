"""Work–precision: CPU time against the achieved error, each method beside its peers.

Frequency domain.  A lightly damped ladder (springs k ∈ [1e4, 2e4] N/m in
series, masses m ∈ [0.2, 1.2] kg to the frame, a damper 1e-3 N·s/m at the
end; 45 and 999 elements), K at 401 log points 0.1 Hz – 1 kHz.  Reference:
the ladder's continued fraction in mpmath at 40 digits (written here, from
the element values; nothing of mechcirc in it).  Error: the largest
|K − K_ref| / |K_ref| over the points.  Methods (no tolerance to turn: each is
one point): the series–parallel tree (numpy path, and the compiled plan
when numba is installed; with and without the error bound the flags need),
the nodal solve (with its double-double refinement, and without it:
``refine=False``), and the peers: the same continued fraction by hand in
numpy (the floor of any method) and one dense ``numpy.linalg.solve`` per ω
of the nodal matrices (45 elements only: at 999 the 401 dense matrices take
1.6 GB).

Time domain.  Two problems, each against a reference from ``solve_ivp``
DOP853 at rtol 1e-13 (atol 1e-16 × the scale) with a Python right-hand side
written here from the element values:

* linear: a 10-mass damped chain (unit masses to the frame, springs 1e4 N/m
  and dampers 2 N·s/m between neighbours), a 1 N force step at the last
  mass, 0.5 s, 501 outputs: mechcirc's exact propagation (no tolerance:
  one point);
* clearances: the same chain with a 2 mm clearance at every spring (damping
  1 N·s/m in each contact), the last mass started at 1 m/s, 0.2 s, 401
  outputs: mechcirc's integrator (Dormand–Prince 5(4), compiled when numba
  is installed, its error estimate included) at rtol 1e-3 … 1e-12.

Peers on both: scipy's RK45, DOP853, Radau, BDF and LSODA, and SUNDIALS
CVODE (Adams and BDF, through scikit-sundae when it is installed:
the ``bench`` extra) at the same rtol (atol = rtol × 1e-3 × the
solution's scale), all with the same Python right-hand side.  Error: the largest |x − x_ref|
over all masses and outputs over the largest |x_ref|.  Times are medians of
CPU time (``time.process_time``) over ``--repeat`` runs, after one warm run.

It prints a table and writes the plot (``--plot``, default
docs/performance_work_precision.png).  It asserts nothing.  Run from the
repository root::

    python benchmarks/bench_work_precision.py [--quick] [--repeat 3]
"""

from __future__ import annotations

import argparse
import os
import platform
import sys
import time
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")     # as bench_transient: no spin-waits
os.environ.setdefault("OMP_NUM_THREADS", "1")

import numpy as np  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

import mechcirc  # noqa: E402
from mechcirc import _jit, _tree_eval, nodal, reduction  # noqa: E402
from mechcirc.transient import transient  # noqa: E402

RTOLS = [10.0 ** -k for k in range(3, 13)]
SCIPY_METHODS = ("RK45", "DOP853", "Radau", "BDF", "LSODA")


def cpu(fn, repeat: int, warm: bool = True):
    """(median CPU seconds, last result) of ``repeat`` runs (after one untimed run)."""
    out = fn() if warm else None
    times = []
    for _ in range(repeat):
        t0 = time.process_time()
        out = fn()
        times.append(time.process_time() - t0)
    return float(np.median(times)), out


# ------------------------------------------------------------------ frequency domain
def ladder(n: int):
    rng = np.random.default_rng(n)
    n_sec = n // 2
    return rng.uniform(1e4, 2e4, n_sec), rng.uniform(0.2, 1.2, n_sec), 1e-3


def ladder_netlist(ks, ms, r) -> str:
    nodes = ["a"] + [f"n{i}" for i in range(1, len(ks) + 1)]
    lines = ["drive V a 0 velocity=1"]
    for i, (k, m) in enumerate(zip(ks, ms)):
        lines.append(f"spring k{i} {nodes[i]} {nodes[i + 1]} {float(k)!r}")
        lines.append(f"mass m{i} {nodes[i + 1]} 0 {float(m)!r}")
    lines.append(f"damper r {nodes[-1]} 0 {r!r}")
    return "\n".join(lines) + "\n"


def ladder_mpmath(ks, ms, r, omega, dps: int = 40) -> np.ndarray:
    """K = jω/k₁ + 1/(jωm₁ + 1/(… + 1/(jωmₙ + r))) from the end, in mpmath."""
    import mpmath

    out = np.empty(omega.size, dtype=complex)
    with mpmath.workdps(dps):
        kk = [mpmath.mpf(float(k)) for k in ks]
        mm = [mpmath.mpf(float(m)) for m in ms]
        rr = mpmath.mpf(float(r))
        for i, w in enumerate(omega):
            jw = mpmath.mpc(0, mpmath.mpf(float(w)))
            K = None
            for k, m in zip(kk[::-1], mm[::-1]):
                Y = jw * m + (rr if K is None else 1 / K)
                K = jw / k + 1 / Y
            out[i] = complex(K)
    return out


def ladder_numpy(ks, ms, r, omega) -> np.ndarray:
    """The same continued fraction by hand in numpy: the floor of any method."""
    jw = 1j * omega
    K = None
    for k, m in zip(ks[::-1], ms[::-1]):
        Y = jw * m + (r if K is None else 1.0 / K)
        K = jw * (1.0 / k) + 1.0 / Y
    return K


def frequency_domain(sizes, repeat: int) -> list[dict]:
    omega = np.geomspace(2 * np.pi * 0.1, 2 * np.pi * 1e3, 401)
    have_kernel = _tree_eval.compiled_evaluator() is not None
    rows = []
    for n in sizes:
        ks, ms, r = ladder(n)
        ref = ladder_mpmath(ks, ms, r, omega)
        circuit = mechcirc.parse(ladder_netlist(ks, ms, r))
        tree, system = circuit.tree, circuit.nodal

        def dense_solve(system=system):
            A = nodal.dense_matrices(system, omega)
            x = np.linalg.solve(A, np.broadcast_to(system.injection(), A.shape[:2])[..., None])
            return system.difference(x[..., 0])

        def compiled(flag: bool, error: bool, tree=tree):
            def run():
                _jit.COMPILED = flag
                try:
                    out = reduction.evaluate(tree, omega, error=error)
                finally:
                    _jit.COMPILED = None
                return out[0] if error else out
            return run

        methods = [("floor: continued fraction by hand (numpy)", "peer",
                    lambda ks=ks, ms=ms, r=r: ladder_numpy(ks, ms, r, omega))]
        if n <= 100:        # 401 dense (n/2)² matrices: 1.6 GB and minutes at 999 elements
            methods.append(("numpy.linalg.solve per ω (dense LU)", "peer", dense_solve))
        methods += [("sp tree, numpy path", "mechcirc", compiled(False, False)),
                   ("sp tree, numpy path + error bound", "mechcirc", compiled(False, True))]
        if have_kernel:
            methods += [("sp tree, compiled plan", "mechcirc", compiled(True, False)),
                        ("sp tree, compiled plan + error bound", "mechcirc",
                         compiled(True, True))]
        methods += [("nodal, refined (default)", "mechcirc", lambda system=system: nodal.mobility(system, omega)),
                    ("nodal, refine=False", "mechcirc",
                     lambda system=system: nodal.mobility_unrefined(system, omega))]
        for label, who, fn in methods:
            t, K = cpu(fn, repeat)
            with np.errstate(all="ignore"):
                err = float(np.max(np.abs(K - ref) / np.abs(ref)))
            rows.append({"domain": f"frequency, ladder of {n}", "method": label, "who": who,
                         "rtol": None, "cpu": t, "error": err})
            show(rows[-1])
    return rows


# ----------------------------------------------------------------------- time domain
def chain(n: int, clearance: float | None):
    """Netlist, masses, springs (i, j, c, d, clearance) with node indices (−1 = frame)."""
    lines, springs = [], []
    if clearance is None:
        lines.append(f"drive F n{n} 0 force=1")
    for i in range(1, n + 1):
        prev = "0" if i == 1 else f"n{i - 1}"
        lines.append(f"mass m{i} n{i} 0 1")
        if clearance is None:
            lines += [f"spring k{i} {prev} n{i} 1e4", f"damper c{i} {prev} n{i} 2"]
            springs.append((i - 2, i - 1, 1e4, 2.0, 0.0))
        else:
            lines.append(f"spring k{i} {prev} n{i} 1e4 backlash={clearance} damping=1")
            springs.append((i - 2, i - 1, 1e4, 1.0, clearance))
    if clearance is not None:
        lines.append(f".ic n{n} v=1")
    return "\n".join(lines) + "\n", springs


def _law(e, w, c, d, b):
    """Spring force of the clearance law (as mechcirc's ElastoBacklash, written again here)."""
    if b <= 0.0:
        return c * e + d * w
    if e > b / 2:
        fc, fd = c * (e - b / 2), d * w
        return 0.0 if fc + fd <= 0 else fc + min(fc, fd)
    if e < -b / 2:
        fc, fd = c * (e + b / 2), d * w
        return 0.0 if fc + fd >= 0 else fc + max(fc, fd)
    return 0.0


def rhs_of(n: int, springs, force_at_last: float):
    def rhs(_, y):
        x, v = y[:n], y[n:]
        a = np.zeros(n)
        a[-1] += force_at_last
        for i, j, c, d, b in springs:
            xi = x[j] - (x[i] if i >= 0 else 0.0)     # elongation n_j − n_i
            vi = v[j] - (v[i] if i >= 0 else 0.0)
            f = _law(xi, vi, c, d, b)
            a[j] -= f
            if i >= 0:
                a[i] += f
        return np.concatenate([v, a])
    return rhs


def cvode_runner(rhs, y0, t, method: str, rtol: float, atol: float):
    """A CVODE run (scikit-sundae) on the same Python right-hand side, or None if not installed."""
    try:
        from sksundae.cvode import CVODE
    except ImportError:
        return None

    def fill(tt, y, yp):
        yp[:] = rhs(tt, y)

    def run():
        return CVODE(fill, method=method, rtol=rtol, atol=atol).solve(t, y0)
    return run


def time_domain(repeat: int, quick: bool) -> list[dict]:
    from scipy.integrate import solve_ivp

    n = 10
    rows = []
    rtols = RTOLS[::3] if quick else RTOLS
    for label, clearance, t_end, outputs in (("linear chain, force step", None, 0.5, 501),
                                             ("chain with clearances", 0.002, 0.2, 401)):
        text, springs = chain(n, clearance)
        circuit = mechcirc.parse(text, require_drive=False)
        t = np.linspace(0.0, t_end, outputs)
        dt = t[1] - t[0]
        y0 = np.zeros(2 * n)
        if clearance is not None:
            y0[2 * n - 1] = 1.0
        rhs = rhs_of(n, springs, 1.0 if clearance is None else 0.0)
        ref = solve_ivp(rhs, (0, t_end), y0, method="DOP853", rtol=1e-13, atol=1e-16,
                        t_eval=t).y[:n].T
        scale = float(np.abs(ref).max())
        order = None

        def error(x):
            return float(np.abs(x - ref).max() / scale)

        domain = f"time, {label}"
        if clearance is None:
            run = (lambda: transient(circuit, t_end, dt, "step", elements=False,
                                     velocities=False))
            c, res = cpu(run, repeat)
            order = [res.nodes.index(f"n{i}") for i in range(1, n + 1)]
            rows.append({"domain": domain, "method": "mechcirc exact (FOH propagation)",
                         "who": "mechcirc", "rtol": None, "cpu": c,
                         "error": error(res.x[:, order])})
            show(rows[-1])
        else:
            for rtol in rtols:
                run = (lambda rtol=rtol: transient(circuit, t_end, dt, rtol=rtol,
                                                   elements=False, velocities=False))
                c, res = cpu(run, repeat)
                order = [res.nodes.index(f"n{i}") for i in range(1, n + 1)]
                rows.append({"domain": domain, "method": "mechcirc DP5(4) (its estimate incl.)",
                             "who": "mechcirc", "rtol": rtol, "cpu": c,
                             "error": error(res.x[:, order])})
                show(rows[-1])
        for method in SCIPY_METHODS:
            for rtol in rtols:
                def run(method=method, rtol=rtol):
                    return solve_ivp(rhs, (0, t_end), y0, method=method, rtol=rtol,
                                     atol=rtol * 1e-3 * scale, t_eval=t)
                # (nothing to compile: the slow tight runs are timed once, without a warm run)
                c, sol = cpu(run, 1, warm=False) if rtol < 1e-8 else cpu(run, repeat)
                err = error(sol.y[:n].T) if sol.success else float("nan")
                rows.append({"domain": domain, "method": f"scipy {method}", "who": "peer",
                             "rtol": rtol, "cpu": c, "error": err})
                show(rows[-1])
        for method in ("Adams", "BDF"):
            for rtol in rtols:
                run = cvode_runner(rhs, y0, t, method, rtol, rtol * 1e-3 * scale)
                if run is None:
                    break
                c, sol = cpu(run, 1, warm=False) if rtol < 1e-8 else cpu(run, repeat)
                err = error(sol.y[:, :n]) if sol.success else float("nan")
                rows.append({"domain": domain, "method": f"CVODE {method}", "who": "peer",
                             "rtol": rtol, "cpu": c, "error": err})
                show(rows[-1])
    return rows


# ------------------------------------------------------------------------------ output
def show(r: dict) -> None:
    """One row of the table, printed as soon as it is measured."""
    rt = "" if r["rtol"] is None else f"{r['rtol']:.0e}"
    print(f"{r['domain']:<34} {r['method']:<44} {rt:>7} {r['cpu']:>10.3g} {r['error']:>9.2e}",
          flush=True)


def plot(rows, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    from matplotlib.figure import Figure

    domains = list(dict.fromkeys(r["domain"] for r in rows))
    colour = {m: f"C{k % 10}" for k, m in
              enumerate(dict.fromkeys(r["method"] for r in rows))}   # one colour per method
    cols = 2
    nrows = -(-len(domains) // cols)
    fig = Figure(figsize=(6.5 * cols, 5.0 * nrows))
    axes = fig.subplots(nrows, cols, squeeze=False).ravel()
    for ax in axes[len(domains):]:
        ax.set_visible(False)
    for ax, domain in zip(axes, domains):
        sel = [r for r in rows if r["domain"] == domain]
        methods = list(dict.fromkeys(r["method"] for r in sel))
        for m in methods:
            pts = [r for r in sel if r["method"] == m and np.isfinite(r["error"])]
            if not pts:
                continue
            err = [max(r["error"], 1e-18) for r in pts]      # 0 (or denormal) drawn at 1e-18
            cpu_s = [r["cpu"] for r in pts]
            mine = pts[0]["who"] == "mechcirc"
            ax.loglog(err, cpu_s, "-o" if len(pts) > 1 else "o", ms=5 if mine else 4,
                      lw=2 if mine else 1, color=colour[m],
                      mfc=None if mine else "none", label=m)
        ax.set_xlabel("achieved error (max relative to the reference; 0 drawn at 1e-18)")
        ax.set_ylabel("CPU time [s]")
        ax.set_title(domain, fontsize="medium")
        ax.grid(True, which="major", alpha=0.3)
        ax.legend(fontsize="x-small", loc="best")
    fig.suptitle("work–precision: mechcirc (filled) beside its peers (open)")
    fig.tight_layout()
    fig.savefig(path, dpi=100)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true",
                    help="the 45-element ladder only, every third rtol")
    ap.add_argument("--repeat", type=int, default=3, help="timed runs per point (median)")
    ap.add_argument("--plot", default=str(ROOT / "docs" / "performance_work_precision.png"))
    args = ap.parse_args()
    print(f"python {platform.python_version()}, numpy {np.__version__}, numba "
          f"{'yes' if _tree_eval.compiled_evaluator() is not None else 'no'}; load average "
          f"{os.getloadavg()[0]:.1f} on {os.cpu_count()} cores; CPU medians of {args.repeat}")
    transient(mechcirc.parse(chain(10, 0.002)[0], require_drive=False), 0.01, 1e-3)
    print(f"{'domain':<34} {'method':<44} {'rtol':>7} {'CPU s':>10} {'error':>9}", flush=True)
    rows = frequency_domain([45] if args.quick else [45, 999], args.repeat)
    rows += time_domain(args.repeat, args.quick)
    plot(rows, Path(args.plot))
    print(f"plot written to {args.plot}; load average after {os.getloadavg()[0]:.1f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
