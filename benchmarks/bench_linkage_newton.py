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

The same for the closed-form dyads (``--dyads-only``: these two sections alone):

4. ``Linkage.motion(θ)`` of every shipped dyad linkage by the numpy ``_DyadSolver``
   (``COMPILED = False``), by ``dyads_path`` run as Python and compiled (RRR dyads
   only; with sliders the numpy form is the only one), 37/361/3,601 positions, and
   the largest differences compiled against numpy;
5. whole commands with numba and its cache filled, the dyads by numpy or by
   ``dyads_path``, and what compiling ``dyads_path`` costs a fresh cache.

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
import time
from pathlib import Path

import numpy as np

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


def cpu_median(fn, repeat):
    times = []
    for _ in range(repeat):
        c0 = time.process_time()
        fn()
        times.append(time.process_time() - c0)
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
                    row[backend] = cpu_median(lambda lk=lk, th=th: lk.motion(th, method="newton"),
                                              repeat)
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


# ------------------------------------------------------------------ the dyads' twin
#: Child process for the dyads: argv[1] "numpy" (the numpy ``_DyadSolver`` for every
#: linkage), "compiled" (``dyads_path`` for RRR-only linkages, from numba's cache) or
#: "cold" ("compiled" on an empty cache: compiled in the process), the rest a command.
DYAD_CHILD = r"""
import sys, contextlib, io
from mechcirc import _jit
_jit.warm_in_background = lambda statement: None
from mechcirc.kinematics import linkage_solver as L
variant, argv = sys.argv[1], sys.argv[2:]
real = L._compiled
L._compiled = lambda kernel: (variant != "numpy") if kernel == "dyads_path" else real(kernel)
from mechcirc.cli import main
with contextlib.redirect_stdout(io.StringIO()):
    rc = main(argv)
sys.exit(rc)
"""


def dyad_linkages():
    from mechcirc.kinematics import load_linkage
    from mechcirc.scene import load_scene

    def scene(path):
        return load_scene(ROOT / path).linkage

    return {
        "heald_scene (5 RRR)": scene("examples/heald_scene.toml"),
        "sley_scene (RRR)": scene("docs/examples/sley_scene.toml"),
        "mrazek_one_side (RRR)": scene("examples/mrazek_one_side.toml"),
        "mrazek_both_sides (2 RRR)": scene("examples/mrazek_both_sides.toml"),
        "rocker_drive (RRR)": scene("docs/examples/rocker_drive.toml"),
        "quick_return (RPR, RRP)": load_linkage(ROOT / "examples" / "quick_return.toml"),
        "slider_crank_scene (RRP)": scene("examples/slider_crank_scene.toml"),
    }


def dyad_table(sizes, repeat):
    """Section 4: ``Linkage.motion`` by the dyads, three backends, in this process."""
    import mechcirc.kinematics as kin
    from mechcirc import _jit
    from mechcirc.kinematics import _linkage_kernels as compiled_module
    from mechcirc.kinematics.linkage_solver import plan

    python_module = _jit.load("mechcirc.kinematics._linkage_kernels", _FORCE_PYTHON=True)

    def use(backend):
        _jit.COMPILED = backend != "numpy"
        K = python_module if backend == "python" else compiled_module
        kin._linkage_kernels = sys.modules["mechcirc.kinematics._linkage_kernels"] = K

    print("\n4. Linkage.motion(θ) by the dyads, one turn, CPU median [ms]: numpy _DyadSolver, "
          "dyads_path as Python, compiled (RRR only: with sliders the numpy form runs)")
    print(f"{'linkage':26s} {'N':>5s} {'numpy':>8s} {'Python':>8s} {'compiled':>8s} "
          f"{'Py/numpy':>8s} {'np/comp':>7s} {'|Δq|/size':>9s} {'|Δq̇|/max':>9s} {'|Δq̈|/max':>9s}")
    try:
        for name, lk in dyad_linkages().items():
            rrr = all(d.kind == "RRR" for d in plan(lk).dyads)
            for N in sizes:
                th = np.linspace(0.0, 2 * math.pi, N)
                row, out = {}, {}
                for backend in ("numpy", "python", "compiled") if rrr else ("numpy",):
                    use(backend)
                    lk.motion(th[:3])
                    row[backend] = cpu_median(lambda lk=lk, th=th: lk.motion(th), repeat)
                    out[backend] = lk.motion(th)
                if not rrr:
                    print(f"{name:26s} {N:5d} {row['numpy'] * 1e3:8.2f} {'-':>8s} {'-':>8s}",
                          flush=True)
                    continue
                a, b = out["compiled"], out["numpy"]
                d = [np.max(np.abs(a.q - b.q)) / lk.length_scale()] + \
                    [np.max(np.abs(x - y)) / np.max(np.abs(y))
                     for x, y in ((a.qdot, b.qdot), (a.qddot, b.qddot))]
                print(f"{name:26s} {N:5d} {row['numpy'] * 1e3:8.2f} {row['python'] * 1e3:8.1f} "
                      f"{row['compiled'] * 1e3:8.2f} {row['python'] / row['numpy']:8.1f} "
                      f"{row['numpy'] / row['compiled']:7.1f} " +
                      " ".join(f"{x:9.1e}" for x in d), flush=True)
    finally:
        _jit.COMPILED = None
        kin._linkage_kernels = sys.modules["mechcirc.kinematics._linkage_kernels"] = \
            compiled_module


DYAD_COMMANDS = [
    ["scene", "examples/heald_scene.toml", "--theta", "40"],
    ["scene", "examples/heald_scene.toml", "--cycle"],
    ["scene", "docs/examples/sley_scene.toml", "--cycle"],
    ["simulate", "examples/heald_scene.toml"],
    ["simulate", "docs/examples/sley_scene.toml"],
    ["simulate", "examples/mrazek_both_sides.toml"],
]


def dyad_commands(repeat, quick):
    """Section 5: whole commands with numba, the dyads by numpy or by ``dyads_path``."""
    def cpu(variant, argv, fresh=False):
        env = dict(os.environ, PYTHONPATH=os.pathsep.join(
            p for p in (str(ROOT), os.environ.get("PYTHONPATH")) if p))
        env.pop("MECHCIRC_NO_WARM", None)
        times = []
        for _ in range(repeat):
            with tempfile.TemporaryDirectory(prefix="dy36-cache-") as cache:
                if fresh:
                    env["NUMBA_CACHE_DIR"] = cache
                p = subprocess.Popen([sys.executable, "-c", DYAD_CHILD, variant, *argv],
                                     cwd=ROOT, env=env, stdout=subprocess.DEVNULL,
                                     stderr=subprocess.DEVNULL)
                _, status, ru = os.wait4(p.pid, 0)
                if os.waitstatus_to_exitcode(status) != 0:
                    raise SystemExit(f"{variant} {' '.join(argv)} failed")
            times.append(ru.ru_utime + ru.ru_stime)
        return float(np.median(times))

    cpu("compiled", DYAD_COMMANDS[0])       # dyads_path into numba's cache, if not there
    print("\n5. with numba (kernels in its cache): command CPU [s], median of", repeat)
    print(f"{'command':48s} {'numpy':>7s} {'compiled':>8s} {'numpy-comp':>10s}")
    for argv in DYAD_COMMANDS[:2] if quick else DYAD_COMMANDS:
        a, b = cpu("numpy", argv), cpu("compiled", argv)
        print(f"{' '.join(argv):48s} {a:7.2f} {b:8.2f} {a - b:+10.2f}", flush=True)
    argv = DYAD_COMMANDS[0]
    a, b = cpu("numpy", argv, fresh=True), cpu("cold", argv, fresh=True)
    print(f"compiling dyads_path (and what it calls) on an empty cache, in the command "
          f"'{' '.join(argv)}': {b:.2f} s CPU against {a:.2f} s with numpy: +{b - a:.2f} s")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--quick", action="store_true", help="fewer sizes and commands")
    ap.add_argument("--long", action="store_true",
                    help="also the cam-jump scene's simulate without numba (minutes)")
    ap.add_argument("--dyads-only", action="store_true", help="sections 4 and 5 only")
    args = ap.parse_args()
    print(f"load average at start: {os.getloadavg()[0]:.2f} (2 shared cores); python "
          f"{sys.version.split()[0]}, numpy {np.__version__}")
    sizes = (37, 361) if args.quick else (37, 361, 3601)
    if not args.dyads_only:
        solve_table(sizes, args.repeat)
        command_table(args.repeat, args.quick, args.long)
    dyad_table(sizes, args.repeat)
    dyad_commands(args.repeat, args.quick)
    print(f"\nload average at end: {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()
