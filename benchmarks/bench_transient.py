"""Benchmark: transients, speed against error (issue 12 §5), baselines in the same run.

Linear: a 100-degree-of-freedom damped chain (unit masses to the frame,
springs 1e4 N/m and dampers 2 N·s/m between neighbours and to the frame at
the first), a force step of 1 N at the last mass, 1e5 output steps of 1 ms;
all 100 node displacements.

* ``mechcirc.transient`` (exact first-order hold; the whole call; the model
  and its eigen-decomposition are kept on the circuit, so the first call on a
  new circuit is timed as well) for the same outputs as the baselines (x of all nodes: ``velocities=False,
  elements=False``), with v as well, with every element force, and its
  propagation cores alone (modal, and the block method it falls back to);
* ``scipy.signal.lsim`` on the same state space (FOH, also exact for a step);
* ``solve_ivp`` DOP853 rtol 1e-10 (atol 1e-14), sparse-matrix Python RHS.

Error: largest |x − x_lsim| over all nodes and times (lsim and mechcirc are
two independent exact discretisations; they agree to rounding).

Clearances: the MSL backlash example (one ElastoBacklash, 1 s, 1e3 outputs)
and a 10-mass chain with a clearance at every spring (0.2 s), against
``solve_ivp`` DOP853 rtol 1e-8 with a Python RHS of the same law; peak force
error against DOP853 rtol 1e-11.  mechcirc keeps a circuit's state-space
model on the circuit, so repeated runs skip building it; the first call on a
new circuit is timed too.  Cold start (numba compilation) measured in
a fresh process with an empty cache directory.

Times are medians (wall clock, and CPU time of the process, which the other
jobs on the shared machine disturb less); the ratios of one run are what to
read.

Run:  python benchmarks/bench_transient.py [--quick]
"""

from __future__ import annotations

import os

# Every method runs with single-threaded BLAS: on this shared 2-core machine a
# multi-threaded OpenBLAS spin-waits against the other jobs and small matrix
# products become ~50x slower (measured: 100 products 200x200 took 3.5 s with
# 2 threads, 0.07 s with 1).  Set before numpy is imported.
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("OMP_NUM_THREADS", "1")

import argparse  # noqa: E402
import subprocess
import sys
import tempfile
import time

import numpy as np  # noqa: E402
import scipy.sparse as sp  # noqa: E402
from scipy.integrate import solve_ivp  # noqa: E402

import mechcirc  # noqa: E402
from mechcirc.transient import transient  # noqa: E402


def timed(fn, repeat=1):
    """(median wall time, median CPU time of this process, last result) of ``repeat`` runs [s].

    On the shared machine the wall time depends on the other jobs; the CPU
    time much less, so both are printed.
    """
    wall, cpu, out = [], [], None
    for _ in range(repeat):
        out = None
        c0, t0 = time.process_time(), time.perf_counter()
        out = fn()
        wall.append(time.perf_counter() - t0)
        cpu.append(time.process_time() - c0)
    return float(np.median(wall)), float(np.median(cpu)), out


def chain_netlist(n, k=1e4, c=2.0, m=1.0, backlash=None, damping_in_spring=False):
    lines = ["drive F n%d 0 force=1" % n]
    prev = "0"
    for i in range(1, n + 1):
        node = f"n{i}"
        lines.append(f"mass m{i} {node} 0 {m}")
        if backlash is None:
            lines.append(f"spring k{i} {prev} {node} {k}")
            lines.append(f"damper c{i} {prev} {node} {c}")
        else:
            lines.append(f"spring k{i} {prev} {node} {k} backlash={backlash} damping={c}")
        prev = node
    return "\n".join(lines) + "\n"


def chain_matrices(n, k=1e4, c=2.0):
    main = np.full(n, 2.0)
    main[-1] = 1.0
    L = sp.diags([main, -np.ones(n - 1), -np.ones(n - 1)], [0, 1, -1]).tocsr()
    return L * k, L * c


def linear(n=100, steps=100_000, dt=1e-3, repeat=3):
    """Median of ``repeat`` runs of each method, interleaved (same load for all)."""
    from scipy import signal

    circuit = mechcirc.parse(chain_netlist(n))
    t_end = steps * dt
    transient(circuit, 10 * dt, dt, "step")          # warm: numba kernel loaded/compiled
    from mechcirc.transient.model import state_space
    from mechcirc.transient.propagate import propagate_blocks, propagate_modal

    ss = state_space(circuit)
    u = np.ones(steps + 1)
    # lsim on the same physics written here: z = [x, v], M = I.
    K, C = chain_matrices(n)
    A = np.block([[np.zeros((n, n)), np.eye(n)], [-K.toarray(), -C.toarray()]])
    B = np.zeros((2 * n, 1))
    B[-1, 0] = 1.0
    Cm = np.hstack([np.eye(n), np.zeros((n, n))])
    sys_ = signal.StateSpace(A, B, Cm, np.zeros((n, 1)))
    t = np.linspace(0, t_end, steps + 1)

    def rhs(_, y):
        x, v = y[:n], y[n:]
        a = -(K @ x) - (C @ v)
        a[-1] += 1.0
        return np.concatenate([v, a])

    import dataclasses

    # The ceiling: forming the outputs alone.  Any method that returns x of all
    # n nodes at every step fills a new (steps + 1) × n array; a modal method
    # forms it as one product of its (steps + 1) × n modal signals with the n × n
    # mode shapes.  That product alone, into a new array as a result must be,
    # on random data of the same shapes (nothing of mechcirc in it); into a
    # preallocated array (its pages already mapped) for comparison:
    rng = np.random.default_rng(0)
    q_signals = rng.standard_normal((steps + 1, n))
    shapes = rng.standard_normal((n, n))
    x_out = np.empty((steps + 1, n))

    runs = {
        "x": lambda: transient(circuit, t_end, dt, "step", elements=False, velocities=False),
        "x_first": lambda: transient(dataclasses.replace(circuit), t_end, dt, "step",
                                     elements=False, velocities=False),
        "nodes": lambda: transient(circuit, t_end, dt, "step", elements=False),
        "all": lambda: transient(circuit, t_end, dt, "step"),
        "modal": lambda: propagate_modal(ss.A, ss.B, ss.initial[0], u, dt, ss.Cx,
                                          ss.g @ ss.Cv, True),
        "block": lambda: propagate_blocks(ss.A, ss.B, ss.initial[0], u, dt),
        "lsim": lambda: signal.lsim(sys_, np.ones_like(t), t, interp=True),
        "dop": lambda: solve_ivp(rhs, (0, t_end), np.zeros(2 * n), method="DOP853",
                                 rtol=1e-10, atol=1e-14, t_eval=t),
        "ceiling": lambda: np.matmul(q_signals, shapes),
        "product": lambda: np.matmul(q_signals, shapes, out=x_out),
        "write": lambda: np.empty((steps + 1, n)).fill(0.0),
    }
    times = {k: [] for k in runs}
    cpu = {k: [] for k in runs}
    out = {}
    for _ in range(repeat):
        for k, fn in runs.items():
            dt_k, c_k, res = timed(fn)
            times[k].append(dt_k)
            cpu[k].append(c_k)
            if k in ("x", "nodes", "lsim", "dop"):
                out[k] = res
            del res
    med = {k: float(np.median(v)) for k, v in times.items()}
    mcpu = {k: float(np.median(v)) for k, v in cpu.items()}
    order = [out["x"].nodes.index(f"n{i}") for i in range(1, n + 1)]
    x_lsim = out["lsim"][1]
    scale = np.abs(x_lsim).max()
    x_mc = out["x"].x[:, order]
    x_nodes = out["nodes"].x[:, order]
    x_dop = out["dop"].y[:n].T
    print(f"linear chain, {n} DOF, {steps} steps of {dt} s (force step), median of {repeat} "
          f"interleaved runs")
    print(f"  path: {out['x'].notes[-1]}")
    print(f"  mechcirc.transient, x only        {med['x']:8.3f} s   max|x - x_lsim| "
          f"{np.abs(x_mc - x_lsim).max() / scale:.1e} (rel. to max|x|)")
    print(f"  ... x only, first call on a new circuit (model, eigen-decomposition and checks "
          f"made in the call) {med['x_first']:8.3f} s")
    print(f"  mechcirc.transient, nodes only    {med['nodes']:8.3f} s   (x and v of 100 nodes) "
          f"max|x - x_lsim| {np.abs(x_nodes - x_lsim).max() / scale:.1e}")
    print(f"  mechcirc.transient, all outputs   {med['all']:8.3f} s   (x, v of 100 nodes, force "
          f"and Δv of 300 elements)")
    print(f"  propagation core: modal {med['modal']:.3f} s, block (the fallback) "
          f"{med['block']:.3f} s")
    print(f"  scipy.signal.lsim (x)             {med['lsim']:8.3f} s   (reference)")
    print(f"  solve_ivp DOP853 rtol 1e-10       {med['dop']:8.3f} s   max|x - x_lsim| "
          f"{np.abs(x_dop - x_lsim).max() / scale:.1e}")
    print(f"  ratios, same outputs (x of all nodes): lsim / mechcirc {med['lsim'] / med['x']:.1f}x; "
          f"DOP853 / mechcirc {med['dop'] / med['x']:.1f}x")
    print(f"  ratios with v as well: lsim / mechcirc {med['lsim'] / med['nodes']:.1f}x; "
          f"DOP853 / mechcirc {med['dop'] / med['nodes']:.1f}x")
    print("  CPU time of this process (medians): " + ", ".join(
        f"{k} {mcpu[k]:.3f} s" for k in ("x", "x_first", "nodes", "all", "modal", "block",
                                         "lsim", "dop", "ceiling", "product", "write")))
    print(f"  ceiling (forming the outputs alone: one ({steps + 1} x {n}) @ ({n} x {n}) product "
          f"into a new array) {med['ceiling']:.3f} s wall, {mcpu['ceiling']:.3f} s CPU; the "
          f"product into a preallocated array {mcpu['product']:.3f} s CPU; a new "
          f"{steps + 1} x {n} array filled with zeros {mcpu['write']:.3f} s CPU")
    goal_x = mcpu["lsim"] / mcpu["x"]
    near = mcpu["x"] / mcpu["ceiling"]
    # The ceiling clause stands in for 20x only where 20x is out of reach: lsim / ceiling < 20.
    reach = mcpu["lsim"] / mcpu["ceiling"]
    clause = ("met" if near <= 1.5 else "not met") if reach < 20 else "does not apply"
    print(f"  goal: lsim / mechcirc >= 20x ({goal_x:.1f}x: {'met' if goal_x >= 20 else 'not met'})"
          f" or mechcirc within 1.5x of the ceiling when lsim / ceiling < 20 "
          f"(lsim / ceiling {reach:.1f}x; mechcirc / ceiling {near:.2f}x: {clause}), CPU times")
    print(f"  ratios in CPU time, x of all nodes: lsim / mechcirc "
          f"{mcpu['lsim'] / mcpu['x']:.1f}x; DOP853 / mechcirc {mcpu['dop'] / mcpu['x']:.1f}x; "
          f"first call on a new circuit: "
          f"lsim / mechcirc {mcpu['lsim'] / mcpu['x_first']:.1f}x "
          f"(wall {med['lsim'] / med['x_first']:.1f}x)")


def _law(e, w, c, d, b):
    if b <= 1e-10:
        return c * e + d * w
    if e > b / 2:
        fc, fd = c * (e - b / 2), d * w
        return 0.0 if fc + fd <= 0 else fc + min(fc, fd)
    if e < -b / 2:
        fc, fd = c * (e + b / 2), d * w
        return 0.0 if fc + fd >= 0 else fc + max(fc, fd)
    return 0.0


def clearance_case(label, circuit, masses, springs, x0, t_end, dt):
    """springs: list of (i, j, c, d, b) with node indices (−1 = frame)."""
    n = len(masses)
    m = np.array(masses)

    def rhs(_, y):
        x, v = y[:n], y[n:]
        a = np.zeros(n)
        for i, j, c, d, b in springs:
            xi = x[i] if i >= 0 else 0.0
            xj = x[j] if j >= 0 else 0.0
            vi = v[i] if i >= 0 else 0.0
            vj = v[j] if j >= 0 else 0.0
            f = _law(xi - xj, vi - vj, c, d, b)
            if i >= 0:
                a[i] -= f
            if j >= 0:
                a[j] += f
        return np.concatenate([v, a / m])

    t = np.linspace(0, t_end, int(round(t_end / dt)) + 1)
    y0 = np.concatenate([x0, np.zeros(n)])

    def forces(Y):
        out = []
        for i, j, c, d, b in springs:
            xi = Y[i] if i >= 0 else 0 * Y[0]
            xj = Y[j] if j >= 0 else 0 * Y[0]
            vi = Y[n + i] if i >= 0 else 0 * Y[0]
            vj = Y[n + j] if j >= 0 else 0 * Y[0]
            out.append([_law(a, b_, c, d, b) for a, b_ in zip(xi - xj, vi - vj)])
        return np.array(out)

    t_ref, _, ref = timed(lambda: solve_ivp(rhs, (0, t_end), y0, method="DOP853", rtol=1e-11,
                                            atol=1e-14, t_eval=t))
    t_dop, c_dop, dop = timed(lambda: solve_ivp(rhs, (0, t_end), y0, method="DOP853",
                                                rtol=1e-8, atol=1e-12, t_eval=t), repeat=5)
    f_ref = forces(ref.y)
    f_dop = forces(dop.y)
    peak = np.abs(f_ref).max()
    e_dop = abs(np.abs(f_dop).max() - peak) / peak
    print(f"{label}: {t.size} outputs")
    print(f"  solve_ivp DOP853 rtol 1e-8, Python RHS {t_dop:8.3f} s  peak-force err {e_dop:.1e}, "
          f"max|ΔF|/peak {np.abs(f_dop - f_ref).max() / peak:.1e}"
          f"   (reference DOP853 rtol 1e-11: {t_ref:.2f} s); CPU {c_dop:.3f} s")
    names = [e.name for e in circuit.elements if e.kind == "spring"]
    transient(circuit, t_end, dt)                 # warm (compiled)
    for rtol in (1e-10, 1e-7):
        t_mc, c_mc, res = timed(lambda: transient(circuit, t_end, dt, rtol=rtol), repeat=31)
        f_mc = np.array([res.element_force(nm) + (res.element_force(nm + "_damping")
                                                  if nm + "_damping" in res.elements else 0)
                         for nm in names])
        e_mc = abs(np.abs(f_mc).max() - peak) / peak
        e_mc_all = np.abs(f_mc - f_ref).max() / peak
        print(f"  mechcirc rtol {rtol:g} (numba, incl. the pilot and the reference run of the error estimate) "
              f"{t_mc:8.4f} s  peak-force err {e_mc:.1e}, max|ΔF|/peak {e_mc_all:.1e}  "
              f"ratio {t_dop / t_mc:.0f}x (CPU {c_mc:.4f} s: {c_dop / c_mc:.0f}x)")
        _first_call(lambda c: transient(c, t_end, dt, rtol=rtol), circuit, t_dop, c_dop)


def _first_call(run, circuit, t_dop, c_dop):
    """The same run on a new copy of the circuit: the state-space model is built again."""
    import dataclasses

    t_1, c_1, _ = timed(lambda: run(dataclasses.replace(circuit)), repeat=15)
    print(f"    first call on a new circuit (model built in the call) {t_1:8.4f} s  "
          f"ratio {t_dop / t_1:.0f}x (CPU {c_1:.4f} s: {c_dop / c_1:.0f}x)")


def clearances(quick=False):
    import math

    c = mechcirc.load(os.path.join(os.path.dirname(__file__), "..", "examples",
                                   "msl_backlash.mcir"))
    clearance_case("MSL backlash example (2 inertias, 1 s)", c, [5.0, 5.0],
                   [(0, -1, 20e3, 50.0, math.radians(45)), (1, -1, 20e3, 50.0, 0.0)],
                   np.array([math.pi / 2, math.pi / 2]), 1.0, 1e-3)
    n = 10
    text = "\n".join([f"mass m{i} n{i} 0 1" for i in range(1, n + 1)] +
                     [f"spring k{i} {'0' if i == 1 else f'n{i-1}'} n{i} 1e4 backlash=0.002 "
                      f"damping=1" for i in range(1, n + 1)] +
                     [f".ic n{n} v=1"]) + "\n"
    chain = mechcirc.parse(text, require_drive=False)
    springs = [((i - 2) if i > 1 else -1, i - 1, 1e4, 1.0, 0.002) for i in range(1, n + 1)]
    _chain_with_velocity(chain, springs, n)


def _chain_with_velocity(chain, springs, n, t_end=0.2, dt=1e-4):
    # like clearance_case but with v0 = 1 at the last mass
    m = np.ones(n)

    def rhs(_, y):
        x, v = y[:n], y[n:]
        a = np.zeros(n)
        for i, j, c, d, b in springs:
            xi = x[i] if i >= 0 else 0.0
            xj = x[j] if j >= 0 else 0.0
            vi = v[i] if i >= 0 else 0.0
            vj = v[j] if j >= 0 else 0.0
            f = _law(xi - xj, vi - vj, c, d, b)
            if i >= 0:
                a[i] -= f
            if j >= 0:
                a[j] += f
        return np.concatenate([v, a / m])

    t = np.linspace(0, t_end, int(round(t_end / dt)) + 1)
    y0 = np.zeros(2 * n)
    y0[2 * n - 1] = 1.0
    t_ref, _, ref = timed(lambda: solve_ivp(rhs, (0, t_end), y0, method="DOP853", rtol=1e-11,
                                            atol=1e-14, t_eval=t))
    t_dop, c_dop, dop = timed(lambda: solve_ivp(rhs, (0, t_end), y0, method="DOP853",
                                                rtol=1e-8, atol=1e-12, t_eval=t), repeat=5)

    def forces(Y):
        out = []
        for i, j, c, d, b in springs:
            xi = Y[i] if i >= 0 else 0 * Y[0]
            xj = Y[j] if j >= 0 else 0 * Y[0]
            vi = Y[n + i] if i >= 0 else 0 * Y[0]
            vj = Y[n + j] if j >= 0 else 0 * Y[0]
            out.append([_law(a, b_, c, d, b) for a, b_ in zip(xi - xj, vi - vj)])
        return np.array(out)

    f_ref, f_dop = forces(ref.y), forces(dop.y)
    peak = np.abs(f_ref).max()
    e_dop = abs(np.abs(f_dop).max() - peak) / peak
    print(f"10-mass chain, 2 mm clearance at every spring, v0 = 1 m/s at the end, "
          f"{t_end} s, {t.size} outputs")
    print(f"  solve_ivp DOP853 rtol 1e-8, Python RHS {t_dop:8.3f} s  peak-force err {e_dop:.1e}, "
          f"max|ΔF|/peak {np.abs(f_dop - f_ref).max() / peak:.1e}"
          f"   (reference DOP853 rtol 1e-11: {t_ref:.2f} s); CPU {c_dop:.3f} s")
    transient(chain, t_end, dt)
    for rtol in (1e-10, 1e-7):
        t_mc, c_mc, res = timed(lambda: transient(chain, t_end, dt, rtol=rtol), repeat=31)
        f_mc = np.array([res.element_force(f"k{i}") + res.element_force(f"k{i}_damping")
                         for i in range(1, n + 1)])
        e_mc = abs(np.abs(f_mc).max() - peak) / peak
        print(f"  mechcirc rtol {rtol:g} (numba, incl. the pilot and the reference run of the error estimate) "
              f"{t_mc:8.4f} s  peak-force err {e_mc:.1e}, "
              f"max|ΔF|/peak {np.abs(f_mc - f_ref).max() / peak:.1e}  ratio {t_dop / t_mc:.0f}x "
              f"(CPU {c_mc:.4f} s: {c_dop / c_mc:.0f}x)")
        _first_call(lambda c: transient(c, t_end, dt, rtol=rtol), chain, t_dop, c_dop)


def cold_start():
    code = ("import time,mechcirc;t=time.perf_counter();from mechcirc.transient import "
            "transient;c=mechcirc.load('examples/msl_backlash.mcir');transient(c,1.0,1e-3);"
            "print(time.perf_counter()-t)")
    root = os.path.join(os.path.dirname(__file__), "..")
    with tempfile.TemporaryDirectory() as cache:
        env = dict(os.environ, NUMBA_CACHE_DIR=cache)
        cold = float(subprocess.check_output([sys.executable, "-c", code], cwd=root, env=env))
        warm = float(subprocess.check_output([sys.executable, "-c", code], cwd=root, env=env))
    print(f"cold start (MSL example, fresh process): empty numba cache {cold:.2f} s, "
          f"with the on-disk cache {warm:.2f} s")


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="1e4 linear steps instead of 1e5")
    ap.add_argument("--repeat", type=int, default=3, help="linear runs per method (median)")
    ap.add_argument("--only", choices=("linear", "clearances", "cold"), help="one part only")
    args = ap.parse_args()
    print(f"load average {os.getloadavg()[0]:.2f} on {os.cpu_count()} cores; "
          f"OPENBLAS_NUM_THREADS={os.environ.get('OPENBLAS_NUM_THREADS')}")
    if args.only in (None, "linear"):
        linear(steps=10_000 if args.quick else 100_000, repeat=args.repeat)
    if args.only in (None, "clearances"):
        clearances()
    if args.only in (None, "cold"):
        cold_start()


if __name__ == "__main__":
    main()
