"""Why the nodal path keeps a numpy form beside its compiled kernels (issue 24's decision).

The nodal kernels (``mechcirc._nodal_kernels``: the double-double residual, the
banded LU, its solve and its first-step bound) are written as loops in the
subset numba compiles.  Written once, they would serve without numba too, run as
plain Python: what ``pip install .`` without the ``fast`` extra would get, and
what a fresh process would run while numba compiles in the background (the
no-wait rule of ``mechcirc._jit``; a cold compile of these kernels takes about
4 s of CPU, over the 1 s a first sweep may wait).  This script times, in one
process, a default (refined) ``sweep(method="nodal")`` of the ladders of
``bench_nodal_ngspice.py`` at 401 ω on

* the numpy path (``_jit.COMPILED = False``: vectorised over ω), and
* the same kernels run as Python (``_jit.load(..., _FORCE_PYTHON=True)``),

and prints the ratio.  It asserts nothing.

Run from the repository root::

    python benchmarks/bench_nodal_one_source.py [--sizes 45,99,999] [--repeats 3]
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

from bench_sp_sweep import ladder_netlist, ladder_numbers  # noqa: E402

import mechcirc  # noqa: E402
from mechcirc import _jit, nodal  # noqa: E402


def sweep_cpu(text: str, omega, repeats: int) -> float:
    """Best CPU time [s] of parse + default nodal sweep."""
    best = np.inf
    for _ in range(repeats):
        t0 = time.process_time()
        mechcirc.parse(text).sweep(omega, method="nodal")
        best = min(best, time.process_time() - t0)
    return best


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", default="45,99,999")
    ap.add_argument("--repeats", type=int, default=3)
    args = ap.parse_args()
    omega = np.geomspace(0.1, 1e3, 401)
    python_kernels = _jit.load("mechcirc._nodal_kernels", _FORCE_PYTHON=True)
    print(f"# 2 cores, load {os.getloadavg()[0]:.1f}; numpy {np.__version__}; 401 ω; "
          f"best CPU of {args.repeats} (numpy) and of 1 (Python kernels)")
    for n in (int(s) for s in args.sizes.split(",")):
        text = ladder_netlist(*ladder_numbers(n))
        _jit.COMPILED = False
        nodal._KERNELS.clear()
        t_numpy = sweep_cpu(text, omega, args.repeats)
        _jit.COMPILED = True
        nodal._KERNELS[:] = [python_kernels]
        t_python = sweep_cpu(text, omega, 1)
        print(f"{n} elements: numpy path {t_numpy * 1e3:.1f} ms, the kernels as Python "
              f"{t_python * 1e3:.0f} ms ({t_python / t_numpy:.0f}x)")
    _jit.COMPILED = None
    nodal._KERNELS.clear()


if __name__ == "__main__":
    main()
