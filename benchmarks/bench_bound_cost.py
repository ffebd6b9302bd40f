"""What the error bound (hence the flags) costs over K, and the default path against its floor.

Series–parallel ladders of 45 and 999 elements at 401 ω (the work–precision
ladders) and ``netlists/stb_heald.mcir`` at 400 ω.  Each case runs in a fresh
Python process (numba's kernel not loaded, as in a user's first call) which
times, interleaved and as medians of CPU time:

* the floor: the same continued fraction written by hand in numpy;
* the default path (``reduction.evaluate``, ``COMPILED`` None): K alone, and
  K with its error bound (what ``Sweep.error`` and ``Sweep.flags`` compute);
  its first call (the tree's leaf sums folded once) is shown apart;
* the numpy path (``COMPILED`` False), K and K + bound;
* the default path at a single ω, K and K + bound: the part of each call's cost
  that does not depend on the number of points (numpy's per-call overhead);
* a sweep, the sweep and then its flags (``Sweep.error`` evaluates the tree
  again), and ``sweep(..., error=True)`` and its flags (one pass);
* then, once the default path has been timed (a loaded kernel serves every
  later call), the compiled plan (``COMPILED`` True), K and K + bound, when
  numba is installed (its load is not timed).

It prints the ratios bound/K and default/floor beside their goals (≤ 1.5× and
≤ 1.2×).  With ``--compile`` it also
times, each in a fresh process with an empty numba cache directory, the cold
compile of the plan evaluator and then its load from that cache (≈ 10 s of
CPU).  It asserts nothing.  Run from the repository root::

    python benchmarks/bench_bound_cost.py
    python benchmarks/bench_bound_cost.py --compile
    python benchmarks/bench_bound_cost.py --compare /path/to/other/checkout
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

CHILD = r"""
import inspect, json, sys, time
import numpy as np
sys.path.insert(0, BENCH)
import mechcirc
from mechcirc import _jit, reduction
from bench_work_precision import ladder, ladder_netlist, ladder_numpy

case, repeat = sys.argv[1], int(sys.argv[2])
if case == "stb_heald":
    c = mechcirc.load(ROOT + "/netlists/stb_heald.mcir")
    omega = np.linspace(10.0, 1000.0, 400)
    floor = None
else:
    ks, ms, r = ladder(int(case))
    c = mechcirc.parse(ladder_netlist(ks, ms, r))
    omega = np.geomspace(2 * np.pi * 0.1, 2 * np.pi * 1e3, 401)
    floor = lambda: ladder_numpy(ks, ms, r, omega)
tree = c.tree
T = time.process_time

def run(mode, error):
    def go():
        _jit.COMPILED = mode
        try:
            return reduction.evaluate(tree, omega, error=error)
        finally:
            _jit.COMPILED = None
    return go

t = T(); run(None, False)(); first = T() - t
fns = {"default K": run(None, False), "default K+bound": run(None, True)}
if floor is not None:
    fns["floor"] = floor
fns["numpy K"], fns["numpy K+bound"] = run(False, False), run(False, True)
# A Sweep, and its flags asked afterwards (the tree evaluated again), or taken from
# the sweep's own pass (sweep(..., error=True), where this version has it).
fns["sweep"] = lambda: mechcirc.sweep(c, omega)
fns["sweep, flags"] = lambda: mechcirc.sweep(c, omega).flags
if "error" in inspect.signature(mechcirc.sweep).parameters:
    fns["sweep(error), flags"] = lambda: mechcirc.sweep(c, omega, error=True).flags
# The same at a single ω: what the calls cost whatever the number of points.
one = omega[len(omega) // 2:len(omega) // 2 + 1]
for key, err in (("one K", False), ("one K+bound", True)):
    fns[key] = (lambda err: lambda: reduction.evaluate(tree, one, error=err))(err)

def timed(fns):
    times = {k: [] for k in fns}
    for _ in range(repeat):
        for k, f in fns.items():
            t = T(); f(); times[k].append(T() - t)
    return {k: float(np.median(v)) for k, v in times.items()}

out = {"first": first, **timed(fns)}
# Only now the kernel: once loaded, the default path takes it for every call.
from mechcirc._tree_eval import compiled_evaluator
if WITH_KERNEL and compiled_evaluator() is not None:      # loaded (or compiled) here
    run(True, True)()
    out.update(timed({"compiled K": run(True, False), "compiled K+bound": run(True, True)}))
print(json.dumps(out))
"""

COMPILE = r"""
import time, sys
sys.path.insert(0, ROOT)
T = time.process_time
import numpy as np
from mechcirc import _tree_eval
t = T(); _tree_eval.warm_kernel(); print(T() - t)
"""


#: Issue 26's goals: K with its bound at most this many times K alone, and the
#: default path's K at most this many times the hand-written floor.
GOAL_BOUND, GOAL_FLOOR = 1.5, 1.2


def child(code: str, args: list[str], env: dict, tree: Path = ROOT) -> str:
    """Run ``code`` in a fresh process importing the mechcirc of ``tree``; its last line."""
    src = code.replace("BENCH", repr(str(ROOT / "benchmarks"))).replace("ROOT", repr(str(tree)))
    src = src.replace("WITH_KERNEL", repr(env.get("_WITH_KERNEL") == "1"))
    done = subprocess.run([sys.executable, "-c", src, *args], cwd=tree,
                          env=dict(env, PYTHONPATH=str(tree)), capture_output=True, text=True)
    if done.returncode:
        raise SystemExit(done.stderr[-2000:])
    return done.stdout.strip().splitlines()[-1]


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=21)
    ap.add_argument("--compare", metavar="DIR",
                    help="another checkout (e.g. before a change): its cases run alongside")
    ap.add_argument("--compile", action="store_true",
                    help="also time numba's cold compile and cached load (≈ 10 s CPU)")
    args = ap.parse_args()
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    try:
        import numba  # noqa: F401
        env["_WITH_KERNEL"] = "1"
    except ImportError:
        pass
    print(f"load average {os.getloadavg()[0]:.1f}; medians of {args.repeat} calls, CPU ms, "
          "each case in a fresh process")
    trees = [("", ROOT)] + ([(" [compare]", Path(args.compare).resolve())] if args.compare
                            else [])
    for case in ("45", "999", "stb_heald"):
        repeat = args.repeat if case != "999" else max(5, args.repeat // 3)
        for tag, tree in trees:
            r = json.loads(child(CHILD, [case, str(repeat)], env, tree))
            ms = {k: v * 1e3 for k, v in r.items()}
            label = (f"ladder of {case}" if case != "stb_heald" else "stb_heald.mcir") + tag
            line = (f"{label:<25} default: K {ms['default K']:.3f}, K+bound "
                    f"{ms['default K+bound']:.3f} ({r['default K+bound'] / r['default K']:.2f}x K, "
                    f"goal <= {GOAL_BOUND}x)")
            if "floor" in r:
                line += (f"; floor {ms['floor']:.3f}, default K / floor "
                         f"{r['default K'] / r['floor']:.2f}x (goal <= {GOAL_FLOOR}x; "
                         f"first call {ms['first']:.3f})")
            print(line)
            print(f"{'':<25} at one ω: K {ms['one K']:.3f}, K+bound {ms['one K+bound']:.3f} "
                  f"({r['one K'] / r['default K']:.0%} and "
                  f"{r['one K+bound'] / r['default K+bound']:.0%} of the times at "
                  f"{'400' if case == 'stb_heald' else '401'} ω)")
            line = (f"{'':<25} sweep {ms['sweep']:.3f}, then its flags {ms['sweep, flags']:.3f} "
                    f"({r['sweep, flags'] / r['sweep']:.2f}x)")
            if "sweep(error), flags" in r:
                line += (f"; sweep(error=True) + flags {ms['sweep(error), flags']:.3f} "
                         f"({r['sweep(error), flags'] / r['sweep']:.2f}x)")
            print(line)
            if "compiled K" in r:
                print(f"{'':<25} compiled plan: K {ms['compiled K']:.3f}, K+bound "
                      f"{ms['compiled K+bound']:.3f} "
                      f"({r['compiled K+bound'] / r['compiled K']:.2f}x K, goal <= {GOAL_BOUND}x)")
    if args.compile and env.get("_WITH_KERNEL"):
        with tempfile.TemporaryDirectory() as cache:
            env_c = dict(env, NUMBA_CACHE_DIR=cache)
            cold = float(child(COMPILE, [], env_c))
            warm = float(child(COMPILE, [], env_c))
        print(f"plan evaluator: cold compile {cold:.2f} s CPU, load from numba's cache "
              f"{warm:.2f} s CPU (numba's import included in both)")
    print(f"load average after: {os.getloadavg()[0]:.1f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
