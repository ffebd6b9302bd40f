"""Nodal ladders end to end against libngspice, 45 … 99,999 elements (both mechcirc paths).

For the ladders of ``bench_sp_sweep.py --e2e`` (springs k ∈ [1e4, 2e4] N/m
in series, masses m ∈ [0.2, 1.2] kg to the frame, a damper 1e-3 N·s/m at the
end) of 45, 99, 999, 9,999 and 99,999 elements, at the 401 frequencies of
``.ac dec 100 0.1 1k``, it times in the same run (CPU medians):

* ``mechcirc.parse(text).sweep(ω, method="nodal")`` (refined: the default)
  and with ``refine=False``, each on the numpy path (``_jit.COMPILED =
  False``: what ``pip install .`` gives, and what a fresh process runs
  while numba compiles) and on the compiled path (numba's kernels loaded
  before timing: a warm cache);
* libngspice through ctypes on the analogous electrical ladder (circuit
  load, ``run``, reading V(a)), as ``bench_sp_sweep.py --e2e`` does;

and prints the ratios to libngspice.  Accuracy, against the ladder's
continued fraction in mpmath (40 digits) at ngspice's own frequencies, is
printed for the sizes up to ``--mp-max`` elements: the largest relative
error of K of each mechcirc variant and of ngspice.

With ``--breakdown`` it prints instead where one default sweep's CPU time
goes on each path (medians of ``--repeats``): parsing, assembly, the
pattern and the regularity check, the factorisations, the solves with their
factors, the double-double residuals, the error estimates, the first-step
bounds (their numpy part) and the sensitivities, each timed around its function
and counted once: a timed phase called inside another (the pattern inside the
regularity check; past 60 unknowns its trial factor and solves) is in its own row
only.  The rest of the total is the Python between them.

Run from the repository root::

    python benchmarks/bench_nodal_ngspice.py [--sizes 45,99,999,9999,99999] [--repeats 5]
    python benchmarks/bench_nodal_ngspice.py --breakdown [--sizes 45,99,999]
    python benchmarks/bench_nodal_ngspice.py --bound-ab [--sizes 45,99] [--repeats 21]

It prints; it asserts nothing.
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

from bench_sp_sweep import NgSpice, ladder_netlist, ladder_numbers, spice_lines  # noqa: E402

import mechcirc  # noqa: E402
from mechcirc import _jit, nodal  # noqa: E402
from timing import cpu


def mp_ladder(ks, ms, r, omega):
    """K(ω) of the ladder as its continued fraction in mpmath (40 digits)."""
    import mpmath

    out = np.empty(omega.size, dtype=complex)
    with mpmath.workdps(40):
        ks = [mpmath.mpf(float(k)) for k in ks]
        ms = [mpmath.mpf(float(m)) for m in ms]
        for i, w in enumerate(omega):
            jw = mpmath.mpc(0, mpmath.mpf(float(w)))
            K = 1 / mpmath.mpf(r)                       # the damper's mobility
            for k, m in zip(ks[::-1], ms[::-1]):
                K = jw / k + 1 / (jw * m + 1 / K)
            out[i] = complex(K)
    return out


class Spice(NgSpice):
    """:class:`NgSpice` that also keeps the run's frequencies [rad/s] (``last_omega``)."""

    def ac(self, lines):
        ct = self.ctypes
        arr = (ct.c_char_p * (len(lines) + 1))(*[x.encode() for x in lines], None)
        self.lib.ngSpice_Circ(arr)
        self.lib.ngSpice_Command(b"run")
        out = []
        for name in (b"a", b"frequency"):
            v = self.lib.ngGet_Vec_Info(name).contents
            raw = np.ctypeslib.as_array(ct.cast(v.v_compdata, ct.POINTER(ct.c_double)),
                                        shape=(2 * v.v_length,))
            out.append(raw[0::2] + 1j * raw[1::2])
        self.last_omega = 2 * np.pi * out[1].real
        self.lib.ngSpice_Command(b"destroy all")
        self.lib.ngSpice_Command(b"remcirc")
        return out[0]


def breakdown(sizes, omega, repeats) -> None:
    """Print where a default sweep's CPU time goes, by phase, on both paths."""
    import functools

    from mechcirc import _nodal_equations, _nodal_residual, _nodal_solvers

    spent: dict[str, float] = {}
    inner: list[float] = []         # per running timed call: the time of the timed calls in it

    def timed(owner, name, label, wrap_result=None):
        fn = getattr(owner, name)

        @functools.wraps(fn)
        def run(*a, **k):
            inner.append(0.0)
            t0 = time.process_time()
            out = fn(*a, **k)
            took = time.process_time() - t0
            spent[label] = spent.get(label, 0.0) + took - inner.pop()
            if inner:
                inner[-1] += took
            return wrap_result(out) if wrap_result else out
        setattr(owner, name, run)

    def solves(out):                            # time the solves with the factors too
        good, fn = out
        box = type("Solves", (), {"solve": staticmethod(fn)})
        timed(box, "solve", "solves")
        return good, box.solve

    timed(mechcirc, "parse", "parse")
    timed(_nodal_equations, "assemble", "assemble")
    nodal.assemble = _nodal_equations.assemble
    timed(_nodal_residual.Pattern, "__init__", "pattern")
    timed(nodal, "require_nonsingular", "regularity check")
    for cls in (_nodal_solvers.SparseSolver, _nodal_solvers.DenseSolver):
        timed(cls, "factor", "factor", solves)
    timed(_nodal_residual.Pattern, "residual", "dd residual")
    passes = {"first": 0, "later": 0}
    timed_residual = _nodal_residual.Pattern.residual

    def counted(self, omega, xh, xl, *a, **k):     # ω per pass: first step, later steps
        passes["first" if xl is None else "later"] += len(omega)
        return timed_residual(self, omega, xh, xl, *a, **k)
    _nodal_residual.Pattern.residual = counted
    timed(nodal, "_estimate", "estimate")
    timed(nodal, "first_step_bound", "first-step bound")
    timed(_nodal_residual.Pattern, "sensitivities", "sensitivities")
    for n in sizes:
        text = ladder_netlist(*ladder_numbers(n))
        for compiled in (False, True):
            _jit.COMPILED = compiled
            if compiled and nodal.kernels(10 ** 9) is None:
                continue
            mechcirc.parse(text).sweep(omega, method="nodal")
            runs = []
            for _ in range(repeats):
                spent.clear()
                passes.update(first=0, later=0)
                t0 = time.process_time()
                mechcirc.parse(text).sweep(omega, method="nodal")
                spent["total"] = time.process_time() - t0
                runs.append(dict(spent))
            keys = ["total"] + [k for k in runs[0] if k != "total"]
            first, later = passes["first"], passes["later"]       # (the last sweep's)
            # What does not scale with the points: the same call at one ω.
            one = cpu(lambda t=text: mechcirc.parse(t).sweep(omega[200:201], method="nodal"),
                      repeats)[0]
            print(f"{n:,} elements, {'compiled' if compiled else 'numpy'} (ms): " + ", ".join(
                f"{k} {np.median([r.get(k, 0.0) for r in runs]) * 1e3:.2f}" for k in keys)
                + f"; residual ω: {first} first step, {later} later"
                + f"; the same call at 1 ω: {one * 1e3:.2f}", flush=True)
    _jit.COMPILED = None


def bound_ab(sizes, omega, repeats) -> None:
    """The default sweep with and without the solver's first-step bound
    (``nodal.first_step_bound``: no second pass where it is below 16 eps),
    alternated in this process, on both paths (CPU medians)."""
    from mechcirc import _nodal_solvers

    keep = _nodal_solvers._BoundSolve.__init__

    def without(self, solve, bound):
        self.solve, self.bound = solve, None
    for n in sizes:
        text = ladder_netlist(*ladder_numbers(n))
        for compiled in (False, True):
            _jit.COMPILED = compiled
            mechcirc.parse(text).sweep(omega[:3], method="nodal")
            t: dict = {keep: [], without: []}
            for _ in range(repeats):
                for init in t:
                    _nodal_solvers._BoundSolve.__init__ = init
                    c = time.process_time()
                    mechcirc.parse(text).sweep(omega, method="nodal")
                    t[init].append(time.process_time() - c)
            _nodal_solvers._BoundSolve.__init__ = keep
            a, b = (float(np.median(v)) * 1e3 for v in t.values())
            print(f"{n:,} elements, {'compiled' if compiled else 'numpy'}: with the bound "
                  f"{a:.1f} ms, without {b:.1f} ms, ratio {a / b:.3f}", flush=True)
    _jit.COMPILED = None


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", default="45,99,999,9999,99999")
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--no-spice", action="store_true", help="mechcirc only")
    ap.add_argument("--breakdown", action="store_true",
                    help="where a default sweep's time goes, by phase (no libngspice)")
    ap.add_argument("--bound-ab", action="store_true",
                    help="the default sweep with and without the first-step bound, alternated")
    ap.add_argument("--mp-max", type=int, default=999,
                    help="largest ladder checked against mpmath")
    args = ap.parse_args()
    sizes = [int(s) for s in args.sizes.split(",")]
    omega = 2 * np.pi * np.geomspace(0.1, 1e3, 401)
    if args.breakdown:
        breakdown(sizes, omega, args.repeats)
        return 0
    if args.bound_ab:
        bound_ab(sizes, omega, args.repeats)
        return 0
    try:
        if args.no_spice:
            raise OSError("--no-spice")
        spice = Spice()
    except OSError as exc:
        spice = None
        print(f"# libngspice not available ({exc}): mechcirc only")
    print(f"# {os.cpu_count()} cores, load {os.getloadavg()[0]:.1f}; numpy {np.__version__}; "
          f"401 points; CPU medians of {args.repeats} (1 at 99,999 elements)")
    cols = ["numpy refined", "numpy plain", "compiled refined", "compiled plain"]
    print("| elements | " + " | ".join(f"{c} ms" for c in cols) + " | libngspice ms | "
          + " | ".join(f"{c} / ngspice" for c in cols) + " |")
    print("|---:" * (2 * len(cols) + 2) + "|")
    errors = []
    for n in sizes:
        ks, ms = ladder_numbers(n)
        text = ladder_netlist(ks, ms)
        rep = args.repeats if n < 50_000 else 1
        times, results = {}, {}
        for col in cols:
            compiled = col.startswith("compiled")
            refine = col.endswith("refined")
            _jit.COMPILED = compiled
            if compiled and nodal.kernels(10 ** 9) is None:
                times[col] = np.nan
                continue
            mechcirc.parse(text).sweep(omega[:3], method="nodal", refine=refine)   # load kernels
            times[col], s = cpu(lambda r=refine, t=text: mechcirc.parse(t).sweep(
                omega, method="nodal", refine=r), rep)
            results[col] = s.K
            print(f"# {n:,} elements, {col}: {times[col] * 1e3:.1f} ms", file=sys.stderr,
                  flush=True)                 # what a long run has measured so far
        _jit.COMPILED = None
        if spice is not None:
            lines = spice_lines(ks, ms)
            t_s, K_sp = cpu(lambda x=lines: spice.ac(x), rep)
            w_sp = spice.last_omega
        else:
            t_s, K_sp, w_sp = np.nan, None, None
        print(f"| {n:,} | " + " | ".join(f"{times[c] * 1e3:.1f}" for c in cols)
              + f" | {t_s * 1e3:.1f} | " + " | ".join(f"{times[c] / t_s:.2f}" for c in cols)
              + " |", flush=True)
        if n <= args.mp_max:
            ref = mp_ladder(ks, ms, 1e-3, omega)
            row = {c: float(np.max(np.abs(K / ref - 1))) for c, K in results.items()}
            if K_sp is not None:
                ref_sp = mp_ladder(ks, ms, 1e-3, w_sp)
                row["libngspice"] = float(np.nanmax(np.abs(K_sp / ref_sp - 1)))
                row["ngspice NaN"] = int(np.sum(~np.isfinite(K_sp)))
            errors.append((n, row))
    if errors:
        print("\nlargest relative error of K against mpmath (40 digits):")
        for n, row in errors:
            print(f"  {n:,} elements: " + ", ".join(
                f"{k} {v:.1e}" if isinstance(v, float) else f"{k} {v}" for k, v in row.items()))
    print(f"# load {os.getloadavg()[0]:.1f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
