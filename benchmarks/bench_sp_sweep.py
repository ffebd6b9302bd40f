"""SP sweep against a hand-written numpy continued fraction, and end to end
against libngspice (issue 14 §1–2).

For issue 11's ladders (springs k ∈ [1e4, 2e4] N/m in series, masses m ∈
[0.2, 1.2] kg to the frame, a damper r = 1e-3 N·s/m at the end) of 15 … 1e5
elements, at 1000 log points 0.1 Hz – 1 kHz, the script times in the same run:

* ``floor``: the ladder's continued fraction written by hand in numpy, from the
  end of the ladder: Y = jωm + 1/K (c at the end), K = jω/k + 1/Y;
* ``sp``: ``mechcirc.reduction.evaluate`` on the circuit's tree (K only), by the
  compiled plan (numba, loaded before timing) and by the numpy path;
* ``sp+err``: the same with the error bound (``error=True``), which is what
  ``Sweep.flags`` needs.

Goals: sp ≤ 1.2 × floor, sp+err ≤ 1.5 × sp.

With ``--e2e`` it times, at 401 points, netlist text → ``mechcirc.parse`` →
``sweep`` → K (and the flags) on ladders of 45 / 90 / 180 / 999 elements,
against libngspice called through ctypes on the analogous electrical ladder
(mobility analogy: spring → inductor 1/k, mass → capacitor m, damper →
resistor 1/c, a 1 A AC source at the drive; ``.ac dec 100 0.1 1k`` gives the
same 401 frequencies): circuit load, ``run`` and reading V(a), as ``PySpice``
would do it.  It checks that both K agree (ngspice's default tolerances) and
skips ngspice with a note when libngspice is missing.

With ``--reduce`` it times the reduction (``circuit.tree``) of n springs in
parallel between two nodes and of a series chain of n springs, n = 4,000 …
64,000 (issue 14 §2: 16,000 in parallel took 264 s before the flattening was
made linear; goal < 0.1 s), and prints the time per element.  Times are medians of
CPU time (``time.process_time``; ``--repeats`` runs for ``--e2e``); the tree is built once (reduction is
timed elsewhere).  It prints; it asserts nothing.  Run from the repository root::

    python benchmarks/bench_sp_sweep.py [--quick] [--e2e] [--reduce]
"""

from __future__ import annotations

import argparse
import os
import platform
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))

from mechcirc.reduction import evaluate  # noqa: E402
from reference import sp_corpus  # noqa: E402
from timing import cpu


def floor_ladder(ks, ms, r, omega):
    """The continued fraction by hand (numpy, complex arrays)."""
    jw = 1j * omega
    inv_k = 1.0 / ks
    K = None
    for k_inv, m in zip(inv_k[::-1], ms[::-1]):
        Y = jw * m + (r if K is None else 1.0 / K)
        K = jw * k_inv + 1.0 / Y
    return K


def bench_reduce() -> int:
    import mechcirc

    print(f"# load {os.getloadavg()[0]:.1f}; reduction (circuit.tree) of runs of n springs")
    print(f"{'run':>9} {'n':>7} {'reduce s':>9} {'µs/elem':>8}")
    for kind in ("parallel", "series"):
        for n in (4000, 16_000, 64_000):
            if kind == "parallel":
                lines = [f"spring k{i} a 0 {1e3 + i}" for i in range(n)]
            else:
                nodes = ["a"] + [f"n{i}" for i in range(1, n)] + ["0"]
                lines = [f"spring k{i} {nodes[i]} {nodes[i + 1]} {1e3 + i}" for i in range(n)]
            c = mechcirc.parse("drive V a 0 velocity=1\n" + "\n".join(lines))
            t0 = time.process_time()
            c.tree
            t = time.process_time() - t0
            print(f"{kind:>9} {n:>7} {t:>9.3f} {t / n * 1e6:>8.1f}")
    return 0


def ladder_numbers(n: int):
    rng = np.random.default_rng(n)
    n_sec = n // 2
    return rng.uniform(1e4, 2e4, n_sec), rng.uniform(0.2, 1.2, n_sec)


def ladder_tree(ks, ms, r=1e-3):
    node = ("leaf", "damper", r)
    for k, m in zip(ks[::-1], ms[::-1]):
        node = ("s", [("leaf", "spring", float(k)), ("p", [("leaf", "mass", float(m)), node])])
    return sp_corpus.to_circuit(node).tree


def bench_floor(args) -> int:
    from mechcirc import _jit, reduction

    sizes = [15, 45, 999, 10_000] + ([] if args.quick else [100_000])
    omega = np.geomspace(2 * np.pi * 0.1, 2 * np.pi * 1e3, args.points)
    have_kernel = reduction.compiled_evaluator() is not None      # load it before timing
    print(f"# {platform.processor() or platform.machine()}, {os.cpu_count()} cores, "
          f"load {os.getloadavg()[0]:.1f}; numpy {np.__version__}; {args.points} points; "
          f"median times; compiled plan {'(numba)' if have_kernel else 'unavailable'}")
    print("| elements | floor ms | sp ms | sp+err ms | sp / floor | err / sp "
          "| numpy sp / floor | numpy err / sp | max abs(dK)/abs(K) |")
    print("|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
    for n in sizes:
        ks, ms = ladder_numbers(n)
        tree = ladder_tree(ks, ms)
        repeats = 3 if (args.quick or n >= 100_000) else 7
        K_floor = floor_ladder(ks, ms, 1e-3, omega)
        times = {}
        for path in (True, False):
            if path and not have_kernel:
                continue
            _jit.COMPILED = path
            K_sp = evaluate(tree, omega)
            diff = float(np.max(np.abs(K_sp - K_floor) / np.abs(K_floor)))
            evaluate(tree, omega, error=True)
            t_floor = cpu(lambda: floor_ladder(ks, ms, 1e-3, omega), repeats)[0]
            t_sp = cpu(lambda: evaluate(tree, omega), repeats)[0]
            t_err = cpu(lambda: evaluate(tree, omega, error=True), repeats)[0]
            times[path] = (t_floor, t_sp, t_err, diff)
        _jit.COMPILED = None
        tf, ts, te, diff = times.get(True, (np.nan,) * 4)
        nf, ns, ne, ndiff = times[False]
        print(f"| {n:,} | {tf * 1e3:.2f} | {ts * 1e3:.2f} | {te * 1e3:.2f} | {ts / tf:.2f} "
              f"| {te / ts:.2f} | {ns / nf:.2f} | {ne / ns:.2f} | {max(diff, ndiff):.1e} |",
              flush=True)
    return 0


# --------------------------------------------------------------------------
# End to end against libngspice
# --------------------------------------------------------------------------

def ladder_netlist(ks, ms, r=1e-3) -> str:
    lines = ["drive V a 0 velocity=1"]
    nodes = ["a"] + [f"n{i}" for i in range(1, len(ks) + 1)]
    for i, (k, m) in enumerate(zip(ks, ms)):
        lines.append(f"spring k{i} {nodes[i]} {nodes[i + 1]} {float(k)!r}")
        lines.append(f"mass m{i} {nodes[i + 1]} 0 {float(m)!r}")
    lines.append(f"damper r {nodes[-1]} 0 {r!r}")
    return "\n".join(lines) + "\n"


def spice_lines(ks, ms, r=1e-3) -> list[str]:
    """The analogous electrical ladder (mobility analogy): V(a) / 1 A = K."""
    lines = ["* mechcirc ladder, mobility analogy", "I1 0 a AC 1"]
    nodes = ["a"] + [f"n{i}" for i in range(1, len(ks) + 1)]
    for i, (k, m) in enumerate(zip(ks, ms)):
        lines.append(f"L{i} {nodes[i]} {nodes[i + 1]} {1.0 / float(k)!r}")
        lines.append(f"C{i} {nodes[i + 1]} 0 {float(m)!r}")
    lines.append(f"R1 {nodes[-1]} 0 {1.0 / r!r}")
    lines += [".ac dec 100 0.1 1k", ".end"]
    return lines


class NgSpice:
    """libngspice through ctypes: load a circuit, ``run``, read the complex V(a)."""

    def __init__(self):
        import ctypes

        class Cx(ctypes.Structure):
            _fields_ = [("re", ctypes.c_double), ("im", ctypes.c_double)]

        class VectorInfo(ctypes.Structure):
            _fields_ = [("v_name", ctypes.c_char_p), ("v_type", ctypes.c_int),
                        ("v_flags", ctypes.c_short),
                        ("v_realdata", ctypes.POINTER(ctypes.c_double)),
                        ("v_compdata", ctypes.POINTER(Cx)), ("v_length", ctypes.c_int)]

        self.ctypes = ctypes
        self.lib = ctypes.CDLL("libngspice.so.0")
        text = ctypes.CFUNCTYPE(ctypes.c_int, ctypes.c_char_p, ctypes.c_int, ctypes.c_void_p)
        ext = ctypes.CFUNCTYPE(ctypes.c_int, ctypes.c_int, ctypes.c_bool, ctypes.c_bool,
                               ctypes.c_int, ctypes.c_void_p)
        bg = ctypes.CFUNCTYPE(ctypes.c_int, ctypes.c_bool, ctypes.c_int, ctypes.c_void_p)
        self._callbacks = (text(lambda *a: 0), text(lambda *a: 0), ext(lambda *a: 0),
                           bg(lambda *a: 0))
        cb = self._callbacks
        self.lib.ngSpice_Init(cb[0], cb[1], cb[2], None, None, cb[3], None)
        self.lib.ngGet_Vec_Info.restype = ctypes.POINTER(VectorInfo)
        self.lib.ngSpice_Circ.argtypes = [ctypes.POINTER(ctypes.c_char_p)]
        version = self.ctypes.c_char_p.in_dll(self.lib, "ngspice_version") \
            if hasattr(self.lib, "ngspice_version") else None
        self.version = version.value.decode() if version is not None else "libngspice.so.0"

    def ac(self, lines: list[str]) -> np.ndarray:
        ct = self.ctypes
        arr = (ct.c_char_p * (len(lines) + 1))(*[x.encode() for x in lines], None)
        self.lib.ngSpice_Circ(arr)
        self.lib.ngSpice_Command(b"run")
        v = self.lib.ngGet_Vec_Info(b"a").contents
        raw = np.ctypeslib.as_array(ct.cast(v.v_compdata, ct.POINTER(ct.c_double)),
                                    shape=(2 * v.v_length,))
        K = raw[0::2] + 1j * raw[1::2]
        self.lib.ngSpice_Command(b"destroy all")
        self.lib.ngSpice_Command(b"remcirc")
        return K


def bench_e2e(args) -> int:
    import mechcirc
    from mechcirc import _jit, reduction

    omega = 2 * np.pi * np.geomspace(0.1, 1e3, 401)
    try:
        spice = NgSpice()
    except OSError as exc:
        spice = None
        print(f"# libngspice not available ({exc}): mechcirc only")
    have_kernel = reduction.compiled_evaluator() is not None      # loaded before timing
    print(f"# {platform.processor() or platform.machine()}, {os.cpu_count()} cores, "
          f"load {os.getloadavg()[0]:.1f}; python {platform.python_version()}, "
          f"numpy {np.__version__}; 401 points; median of {args.repeats}; "
          f"compiled plan {'loaded' if have_kernel else 'unavailable'}")
    print("| elements | mechcirc K ms | mechcirc K + flags ms | numpy path K + flags ms "
          "| libngspice ms | K / ngspice | K+flags / ngspice | numpy path / ngspice "
          "| max abs(dK)/abs(K) | ngspice NaN points |")
    print("|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
    for n in (45, 90, 180, 999):
        ks, ms = ladder_numbers(n)
        text = ladder_netlist(ks, ms)

        def mech_K():
            return mechcirc.parse(text).sweep(omega).K

        def mech_flags():
            s = mechcirc.parse(text).sweep(omega)
            return s.K, s.flags

        K = mech_K()
        t_k = cpu(mech_K, args.repeats)[0]
        t_f = cpu(mech_flags, args.repeats)[0]
        # The numpy path: what a fresh process gets below KERNEL_MIN_WORK.
        _jit.COMPILED = False
        t_n = cpu(mech_flags, args.repeats)[0]
        _jit.COMPILED = None
        if spice is not None:
            lines = spice_lines(ks, ms)
            K_sp = spice.ac(lines)
            # ngspice's AC solve can return NaN at a point (999 elements: one of 401).
            nan_spice = int(np.count_nonzero(~np.isfinite(K_sp)))
            diff = float(np.nanmax(np.abs(K - K_sp) / np.abs(K)))
            t_s = cpu(lambda: spice.ac(lines), args.repeats)[0]
        else:
            t_s, diff, nan_spice = np.nan, np.nan, 0
        print(f"| {2 * len(ks) + 1} | {t_k * 1e3:.2f} | {t_f * 1e3:.2f} | {t_n * 1e3:.2f} "
              f"| {t_s * 1e3:.2f} | {t_k / t_s:.2f} | {t_f / t_s:.2f} | {t_n / t_s:.2f} "
              f"| {diff:.1e} | {nan_spice} |", flush=True)
    return 0


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="up to 1e4 elements, 3 repeats")
    ap.add_argument("--points", type=int, default=1000)
    ap.add_argument("--repeats", type=int, default=9, help="for --e2e")
    ap.add_argument("--reduce", action="store_true", help="only time parallel/series runs")
    ap.add_argument("--e2e", action="store_true", help="only the end-to-end comparison")
    args = ap.parse_args()
    if args.reduce:
        return bench_reduce()
    if args.e2e:
        return bench_e2e(args)
    return bench_floor(args)


if __name__ == "__main__":
    raise SystemExit(main())
