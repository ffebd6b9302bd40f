"""Two or more checkouts' compiled plan kernels in one process, alternated: K and K + bound.

``bench_bound_cost.py --compare`` runs each checkout in a process of its own, and
its ratios move by several per cent from run to run.  For a change to
``mechcirc/_sp_kernel.py`` this loads each checkout's kernel source as a module
of its own (numba's disk cache off, so two sources of the same file name do not
mix: each is compiled here, a few seconds), builds the plans once with this
checkout's ``mechcirc`` (the kernels must take the same plan arrays), and times
the kernels alternated call by call: CPU medians, K alone, K with its bound and
their ratio, on the 45- and 999-element ladders at 401 ω (``bench_work_precision``)
and ``netlists/stb_heald.mcir`` at 400.  K alone differs by a few per cent between
two compilations of the same source (where the code lands); a kernel copied with
pieces taken out (timing only) shows what each piece costs.  It asserts nothing.
Run from the repository root::

    python benchmarks/bench_bound_ab.py /path/to/main /path/to/branch
    python benchmarks/bench_bound_ab.py . /tmp/variant --points 4001 --cases 999
"""

from __future__ import annotations

import argparse
import importlib.util
import os
import re
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(ROOT), str(ROOT / "benchmarks")]

import mechcirc  # noqa: E402
from bench_work_precision import ladder, ladder_netlist  # noqa: E402
from mechcirc import _jit, _tree_eval  # noqa: E402


def _uncached(force_python: bool = False, nrt: bool = True):
    """:func:`mechcirc._jit.decorators` with numba's disk cache off."""
    from numba import njit

    flags: dict = {} if nrt else {"_nrt": False}
    return (True, njit(cache=False, error_model="numpy", **flags),
            njit(cache=False, error_model="numpy", inline="always"))


def load_kernel(checkout: Path):
    """``evaluate_plan`` of ``checkout``'s ``mechcirc/_sp_kernel.py``, compiled afresh."""
    name = "mechcirc._ab_" + re.sub(r"\W", "_", str(checkout))
    spec = importlib.util.spec_from_file_location(name, checkout / "mechcirc" / "_sp_kernel.py")
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module
    saved = _jit.decorators
    _jit.decorators = _uncached
    try:
        spec.loader.exec_module(module)
    finally:
        _jit.decorators = saved
    return module.evaluate_plan


def case(name: str, points: int):
    """(plan, ω as one row) of a benchmark case."""
    if name == "stb_heald":
        c = mechcirc.load(ROOT / "netlists" / "stb_heald.mcir")
        omega = np.linspace(10.0, 1000.0, points)
    else:
        c = mechcirc.parse(ladder_netlist(*ladder(int(name))))
        omega = np.geomspace(2 * np.pi * 0.1, 2 * np.pi * 1e3, points)
    return _tree_eval.plan(c.tree), np.atleast_2d(omega)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("checkouts", nargs="+", type=Path)
    ap.add_argument("--points", type=int, default=401)
    ap.add_argument("--repeat", type=int, default=200, help="calls each (a quarter at 999)")
    ap.add_argument("--cases", default="45,999,stb_heald")
    args = ap.parse_args()
    kernels = [load_kernel(c.resolve()) for c in args.checkouts]
    print(f"load average {os.getloadavg()[0]:.1f}; CPU ms, medians, kernels alternated")
    for name in args.cases.split(","):
        p, omega = case(name, args.points)
        K = np.empty(omega.shape, dtype=complex)
        rho, none = np.empty(omega.shape), np.empty((1, 0))
        for k in kernels:                      # compiled at the first call
            k(omega, *p.arrays(), True, K, rho)
            k(omega, *p.arrays(), False, K, none)
        times = np.zeros((len(kernels), 2, max(5, args.repeat // (4 if name == "999" else 1))))
        for r in range(times.shape[2]):
            for i, k in enumerate(kernels):
                t = time.process_time()
                k(omega, *p.arrays(), False, K, none)
                times[i, 0, r] = time.process_time() - t
                t = time.process_time()
                k(omega, *p.arrays(), True, K, rho)
                times[i, 1, r] = time.process_time() - t
        medians = np.median(times, axis=2) * 1e3
        for c, (k_alone, k_bound) in zip(args.checkouts, medians):
            ratio = k_bound / k_alone
            print(f"{name:>9} {str(c):<30} K {k_alone:.4f}  K+bound {k_bound:.4f}  ({ratio:.3f}x K)")
    print(f"load average after: {os.getloadavg()[0]:.1f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
