"""Benchmark: the linkage Newton's twin — batched numpy ``Newton`` against ``newton_path`` (issue 24).

Issue 24 asks for one source per numeric kernel, decided by measurement.  The
linkage Newton continuation has two: the batched numpy class
``linkage_solver.Newton`` (what runs without numba, and on a fresh numba install
until the kernel is in numba's cache) and ``_linkage_kernels.newton_path`` (one
scalar loop, compiled with numba, plain Python without it).  Deleting the numpy
one would route a user without numba through ``newton_path`` run as Python.
This script measures, in one run, what that would cost:

1. the solve alone (in this process, CPU medians): ``Linkage.motion(θ,
   method="newton")`` by the numpy ``Newton`` (``mechcirc._jit.COMPILED = False``),
   by ``newton_path`` run as Python (the same source loaded with ``_FORCE_PYTHON``)
   and by ``newton_path`` compiled (numba), on every linkage the package ships
   that Newton solves (``examples/fnf_sixbar.toml``, the cam-jump scene's linkage)
   and on the heald, sley and quick-return linkages (dyads, solved by Newton when
   asked), at 37, 361 and 3,601 positions over one turn; with the largest
   difference of q (Python loop against numpy, relative to the linkage's size) and
   of q̇ (relative to its largest);
2. a user without numba (numba made unimportable in a child process): the CPU
   of whole commands that solve a Newton linkage, as they are (numpy ``Newton``)
   and with ``newton_path`` as Python in its place;
3. a fresh numba install's first command (an empty ``NUMBA_CACHE_DIR``): as it is
   (the numpy ``Newton`` runs; the detached warm-up is switched off here so that
   only the command's own CPU is counted), with the kernel compiled in the
   process instead, and with the kernel run as Python.

The result, and the decision it led to (the numpy ``Newton`` stays): docs/performance.md,
"The numpy Newton beside newton_path".

The same was measured for the closed-form dyads (28 Nov, sections 4–5 of this script
at commit 486231a: ``git show 486231a:benchmarks/bench_linkage_newton.py``, run with
``--dyads-only``): the numpy ``_DyadSolver`` against ``dyads_path`` as Python and
compiled, and whole commands with numba cached.  The compiled loop made no command
faster and was removed with those sections (docs/performance.md, "The dyads: one
source").

Each child's CPU is its user + system time (``os.wait4``), medians of
``--repeat`` runs (default 3).  The machine is shared: read the ratios.

Run:  python benchmarks/bench_linkage_newton.py [--repeat 3] [--quick] [--long]
"""

from __future__ import annotations

import argparse
import math
import os
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np
from timing import cpu

ROOT = Path(__file__).resolve().parents[1]

#: Child process: argv[1] the variant, the rest a mechcirc command line.
#: "numpy": as shipped; "python": newton_path as plain Python in place of the numpy
#: Newton; "compile": newton_path compiled in the process (numba, on its first call).
#: NO_NUMBA=1 makes numba unimportable (a plain install).
CHILD = r"""
import os, sys, contextlib, io
if os.environ.get("NO_NUMBA") == "1":
    sys.modules["numba"] = None
from mechcirc import _jit
_jit.warm_in_background = lambda statement: None      # nothing detached: the command's CPU only
variant, argv = sys.argv[1], sys.argv[2:]
if variant != "numpy":
    import mechcirc.kinematics as kin
    from mechcirc.kinematics import linkage_solver as L
    if variant == "python":
        K = _jit.load("mechcirc.kinematics._linkage_kernels", _FORCE_PYTHON=True)
        kin._linkage_kernels = sys.modules["mechcirc.kinematics._linkage_kernels"] = K
    real = L._compiled
    L._compiled = lambda kernel: True if kernel == "newton_path" else real(kernel)
from mechcirc.cli import main
with contextlib.redirect_stdout(io.StringIO()):
    rc = main(argv)
sys.exit(rc)
"""


def child_cpu(variant, argv, env_extra, repeat):
    """Median CPU [s] (user + system) of the command ``argv`` in a child process."""
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(
        p for p in (str(ROOT), os.environ.get("PYTHONPATH")) if p), **env_extra)
    env.pop("MECHCIRC_NO_WARM", None)
    times = []
    for _ in range(repeat):
        cache = None
        if env_extra.get("NUMBA_CACHE_DIR") == "fresh":
            cache = tempfile.TemporaryDirectory(prefix="nw32-cache-")
            env["NUMBA_CACHE_DIR"] = cache.name
        with tempfile.TemporaryFile() as err:
            p = subprocess.Popen([sys.executable, "-c", CHILD, variant, *argv], cwd=ROOT,
                                 env=env, stdout=subprocess.DEVNULL, stderr=err)
            _, status, ru = os.wait4(p.pid, 0)
            if os.waitstatus_to_exitcode(status) != 0:
                err.seek(0)
                raise SystemExit(f"{variant} {' '.join(argv)} failed:\n{err.read().decode()}")
        times.append(ru.ru_utime + ru.ru_stime)
        if cache is not None:
            cache.cleanup()
    return float(np.median(times))


def linkages():
    from mechcirc.kinematics import load_linkage
    from mechcirc.scene import load_scene

    return {
        "fnf_sixbar (Newton)": load_linkage(ROOT / "examples" / "fnf_sixbar.toml"),
        "cam_jump_scene (Newton)": load_scene(ROOT / "examples" / "cam_jump_scene.toml").linkage,
        "heald_scene (dyads)": load_scene(ROOT / "examples" / "heald_scene.toml").linkage,
        "sley_scene (dyads)": load_scene(ROOT / "docs" / "examples" / "sley_scene.toml").linkage,
        "quick_return (dyads)": load_linkage(ROOT / "examples" / "quick_return.toml"),
    }


def solve_table(sizes, repeat):
    """Section 1: the solve alone, three backends, in this process."""
    import mechcirc.kinematics as kin
    from mechcirc import _jit
    from mechcirc.kinematics import _linkage_kernels as compiled_module

    python_module = _jit.load("mechcirc.kinematics._linkage_kernels", _FORCE_PYTHON=True)

    def use(backend):
        _jit.COMPILED = backend != "numpy"
        K = python_module if backend == "python" else compiled_module
        kin._linkage_kernels = sys.modules["mechcirc.kinematics._linkage_kernels"] = K

    print("\n1. Linkage.motion(θ, method='newton'), one turn, CPU median [ms] "
          f"(numba {'loaded' if compiled_module.HAVE_NUMBA else 'NOT installed'})")
    print(f"{'linkage':26s} {'N':>5s} {'numpy':>9s} {'Python':>9s} {'compiled':>9s} "
          f"{'Py/numpy':>8s} {'Py/pos µs':>9s} {'|Δq|/size':>9s} {'|Δq̇|/max':>9s}")
    try:
        for name, lk in linkages().items():
            for N in sizes:
                th = np.linspace(0.0, 2 * math.pi, N)
                row, out = {}, {}
                for backend in ("numpy", "python", "compiled"):
                    use(backend)
                    lk.motion(th[:3], method="newton")      # imports, compile or cache load
                    row[backend] = cpu(lambda lk=lk, th=th: lk.motion(th, method="newton"),
                                       repeat)[0]
                    out[backend] = lk.motion(th, method="newton")
                a, b = out["python"], out["numpy"]
                dq = np.max(np.abs(a.q - b.q)) / lk.length_scale()
                dqd = np.max(np.abs(a.qdot - b.qdot)) / np.max(np.abs(b.qdot))
                print(f"{name:26s} {N:5d} {row['numpy'] * 1e3:9.2f} {row['python'] * 1e3:9.1f} "
                      f"{row['compiled'] * 1e3:9.2f} {row['python'] / row['numpy']:8.1f} "
                      f"{row['python'] / N * 1e6:9.0f} {dq:9.1e} {dqd:9.1e}", flush=True)
    finally:
        _jit.COMPILED = None
        kin._linkage_kernels = sys.modules["mechcirc.kinematics._linkage_kernels"] = \
            compiled_module


COMMANDS = [
    ["linkage", "examples/fnf_sixbar.toml", "--theta", "30"],
    ["linkage", "examples/fnf_sixbar.toml", "--theta", "30", "--plot", "{tmp}/six.png"],
    ["scene", "examples/fnf_sixbar_scene.toml", "--theta", "40"],
    ["scene", "examples/cam_jump_scene.toml", "--theta", "40"],
    ["scene", "examples/fnf_sixbar_scene.toml", "--cycle"],
    ["scene", "examples/cam_jump_scene.toml", "--cycle"],
    ["simulate", "examples/fnf_sixbar_scene.toml"],
]
#: ``--long``: once each (78 s of CPU as Python without numba: its RK4, not the linkage).
LONG = [["simulate", "examples/cam_jump_scene.toml"]]


def command_table(repeat, quick, long):
    """Sections 2 and 3: whole commands in child processes."""
    with tempfile.TemporaryDirectory(prefix="nw32-out-") as tmp:
        cmds = [[a.format(tmp=tmp) for a in c] for c in COMMANDS]
        print("\n2. a user without numba: command CPU [s], median of", repeat)
        print(f"{'command':58s} {'numpy':>7s} {'Python':>7s} {'extra':>7s} {'ratio':>6s}")
        for argv in (cmds[:3] if quick else cmds) + (LONG if long else []):
            rep = 1 if argv in LONG else repeat
            a = child_cpu("numpy", argv, {"NO_NUMBA": "1"}, rep)
            b = child_cpu("python", argv, {"NO_NUMBA": "1"}, rep)
            print(f"{' '.join(argv).replace(tmp, '…'):58s} {a:7.2f} {b:7.2f} {b - a:+7.2f} "
                  f"{b / a:6.2f}", flush=True)
        print("\n3. a fresh numba install's first command (empty NUMBA_CACHE_DIR): CPU [s], "
              "median of", repeat)
        print(f"{'command':58s} {'numpy':>7s} {'compile':>7s} {'Python':>7s}")
        for argv in (cmds[0], cmds[3]) if quick else (cmds[0], cmds[2], cmds[3], cmds[-1]):
            got = [child_cpu(v, argv, {"NUMBA_CACHE_DIR": "fresh"}, repeat)
                   for v in ("numpy", "compile", "python")]
            print(f"{' '.join(argv):58s} " + " ".join(f"{g:7.2f}" for g in got), flush=True)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--quick", action="store_true", help="fewer sizes and commands")
    ap.add_argument("--long", action="store_true",
                    help="also the cam-jump scene's simulate without numba (minutes)")
    args = ap.parse_args()
    print(f"load average at start: {os.getloadavg()[0]:.2f} (2 shared cores); python "
          f"{sys.version.split()[0]}, numpy {np.__version__}")
    solve_table((37, 361) if args.quick else (37, 361, 3601), args.repeat)
    command_table(args.repeat, args.quick, args.long)
    print(f"\nload average at end: {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()
