"""CPU time of single CLI commands, start-up included, against their goals.

Each command runs in a fresh Python process (``python -m mechcirc ...``, the
way a user runs it); its CPU time (user + system, from ``resource.getrusage``
of the finished child) is taken over ``--repeat`` runs (default 7, at least
5) and the median, lowest and highest are printed with the goal.  In the same
run, interleaved with the commands, five floors are timed the same way: the
bare interpreter (``python -c pass``), ``python -c "import numpy"`` — what
any command of a numpy program pays before it does anything — the same with
``OPENBLAS_NUM_THREADS=1``, as the command line starts numpy unless the user
chose a BLAS thread count (OpenBLAS then starts no pool of threads), and numpy
with matplotlib's ``Figure`` and Agg canvas (imported, one canvas made), what
any command that draws a PNG pays (also with one thread).  Each command is
printed with its ratio to its floor and what it costs beyond it (medians); the
sweep, with and without a PNG, also with what it costs beyond the one-thread
floor.  The BLAS thread variables
(``OPENBLAS_NUM_THREADS``, ``GOTO_NUM_THREADS``, ``OMP_NUM_THREADS``) are
removed from the environment of every timed process, so each runs as in a
user's default environment.

Bytecode is written once, by an untimed first run of each command, to a
cache directory of the run (``PYTHONPYCACHEPREFIX``; an installed package
has its bytecode, and a checkout run with ``PYTHONDONTWRITEBYTECODE`` would
compile every module at each start).  Outputs go to a temporary directory.  It
asserts nothing.  Run from the repository root::

    python benchmarks/bench_startup.py
    python benchmarks/bench_startup.py --repeat 11
    python benchmarks/bench_startup.py --compare /path/to/other/checkout
    python benchmarks/bench_startup.py --instructions --compare /path/to/other/checkout

``--compare DIR`` times the same commands with ``PYTHONPATH=DIR`` (another
checkout, e.g. before a change) interleaved with this one.

``--instructions`` counts instead of timing (valgrind's callgrind, the
instructions a whole process executes, ``Ir``; ``PYTHONHASHSEED=0``): the PNG
command and its one-thread floor, once each.  A count repeats to about 0.01 %
where CPU time on a loaded machine moves by several per cent, so a change of
a per cent shows; it weighs every instruction alike (a cache miss, a branch
mispredicted or a C loop are not time), so it shows what changed, not the
time it saves.  A run takes minutes.
"""

from __future__ import annotations

import argparse
import os
import platform
import re
import resource
import shutil
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
NETLIST = "netlists/stb_heald.mcir"
SWEEP = ["sweep", NETLIST, "--omega-min", "10", "--omega-max", "10000", "--points", "400",
         "--log"]


PASS, NUMPY, MPL = ("python -c pass (floor)", "python -c 'import numpy' (floor)",
                    "python -c 'import numpy, matplotlib Figure, Agg' (floor)")
NUMPY1 = "OPENBLAS_NUM_THREADS=1 python -c 'import numpy' (floor)"
MPL1 = "OPENBLAS_NUM_THREADS=1 python -c 'import numpy, matplotlib Figure, Agg' (floor)"
#: What OpenBLAS reads for its thread count: taken out of every timed process's environment.
BLAS_THREADS = ("OPENBLAS_NUM_THREADS", "GOTO_NUM_THREADS", "OMP_NUM_THREADS")
#: numpy, matplotlib.figure and the Agg canvas, as the PNG command loads them
MPL_CODE = ("import numpy; from matplotlib.figure import Figure; "
            "from matplotlib.backends.backend_agg import FigureCanvasAgg; "
            "FigureCanvasAgg(Figure())")


def cases(tmp: Path) -> list[tuple[str, list[str], float | None, tuple[str, ...], dict]]:
    """``(label, argv after python, goal in s CPU or None for a floor, its floors' labels,
    extra environment)``; the first floor is the one the ratio is taken to."""
    m = ["-m", "mechcirc"]
    return [
        (PASS, ["-c", "pass"], None, (), {}),
        (NUMPY, ["-c", "import numpy"], None, (), {}),
        (NUMPY1, ["-c", "import numpy"], None, (), {"OPENBLAS_NUM_THREADS": "1"}),
        (MPL, ["-c", MPL_CODE], None, (), {}),
        (MPL1, ["-c", MPL_CODE], None, (), {"OPENBLAS_NUM_THREADS": "1"}),
        ("mechcirc --help", m + ["--help"], 0.15, (PASS,), {}),
        ("mechcirc sweep stb_heald, 400 points, CSV", m + SWEEP + ["-o", str(tmp / "x.csv")],
         0.3, (NUMPY, NUMPY1), {}),
        ("  ... with a PNG", m + SWEEP + ["-o", str(tmp / "x.csv"), "--plot",
                                          str(tmp / "sweep.png")], 1.0, (MPL, MPL1), {}),
    ]


def cpu_of(argv: list[str], env: dict) -> float:
    """CPU seconds (user + system) of one child process running ``argv``."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    # Run in the checkout itself: ``python -m`` puts the working directory first
    # on sys.path, before PYTHONPATH.
    done = subprocess.run([sys.executable, *argv], cwd=env["PYTHONPATH"], env=env,
                          stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if done.returncode != 0:
        raise SystemExit(f"{' '.join(argv)} failed ({done.returncode}): {done.stderr[-500:]}")
    return (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


def instructions_of(argv: list[str], env: dict) -> int:
    """Instructions (callgrind's ``Ir``) one child process running ``argv`` executes."""
    with tempfile.TemporaryDirectory() as out:
        done = subprocess.run(
            ["valgrind", "--tool=callgrind", f"--callgrind-out-file={out}/callgrind.out",
             sys.executable, *argv], cwd=env["PYTHONPATH"], env=dict(env, PYTHONHASHSEED="0"),
            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    found = re.search(r"Collected : (\d+)", done.stderr)
    if done.returncode != 0 or found is None:
        raise SystemExit(f"valgrind {' '.join(argv)} failed ({done.returncode}): "
                         f"{done.stderr[-500:]}")
    return int(found.group(1))


def count_png(envs: dict, tmp: Path) -> None:
    """``--instructions``: the PNG command (in each tree) and its one-thread floor, counted."""
    todo = [(label + tag, argv, floors, dict(envs[tag], **extra))
            for label, argv, goal, floors, extra in cases(tmp)
            if label == MPL1 or "PNG" in label for tag in envs if goal is not None or not tag]
    for _label, argv, _, env in todo:       # bytecode written, not counted
        cpu_of(argv, env)
    counts = {label: instructions_of(argv, env) for label, argv, _, env in todo}
    width = max(len(label) for label in counts)
    for label, _, floors, _ in todo:
        beyond = f"  {counts[label] - counts[MPL1]:+,} beyond its one-thread floor" if floors else ""
        print(f"{label:<{width}}  {counts[label]:>14,} instructions{beyond}")


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=7, help="fresh processes per command (>= 5)")
    ap.add_argument("--compare", metavar="DIR", help="another checkout, timed alongside")
    ap.add_argument("--instructions", action="store_true",
                    help="count the PNG command's instructions (valgrind) instead of timing")
    args = ap.parse_args()
    repeat = max(5, args.repeat)
    trees = [("", ROOT)] + ([(" [compare]", Path(args.compare).resolve())] if args.compare
                            else [])
    # Bytecode goes to a cache directory of this run (PYTHONPYCACHEPREFIX), not into
    # the checkouts; the untimed warm-up run of each command writes it.
    cache = tempfile.mkdtemp(prefix="bench_startup_pycache_")
    envs = {}
    for tag, tree in trees:
        env = dict(os.environ, PYTHONPATH=str(tree), MPLBACKEND="Agg",
                   PYTHONPYCACHEPREFIX=cache)
        env.pop("PYTHONDONTWRITEBYTECODE", None)
        for name in BLAS_THREADS:
            env.pop(name, None)
        envs[tag] = env
    if args.instructions:
        if shutil.which("valgrind") is None:
            raise SystemExit("--instructions needs valgrind (apt-get install valgrind)")
        print(f"python {platform.python_version()}; instructions of one process each "
              "(valgrind --tool=callgrind)")
        with tempfile.TemporaryDirectory() as tmp:
            count_png(envs, Path(tmp))
        shutil.rmtree(cache, ignore_errors=True)
        return 0
    import matplotlib
    import numpy
    import scipy

    print(f"python {platform.python_version()}, numpy {numpy.__version__}, scipy "
          f"{scipy.__version__}, matplotlib {matplotlib.__version__}; "
          f"load average {os.getloadavg()[0]:.1f}; median of {repeat} fresh processes, CPU s")
    with tempfile.TemporaryDirectory() as tmp:
        todo = [(label + tag, argv, goal, floors, dict(envs[tag], **extra))
                for label, argv, goal, floors, extra in cases(Path(tmp))
                for tag in envs if goal is not None or not tag]
        times: dict[str, list[float]] = {label: [] for label, *_ in todo}
        for _label, argv, _, _, env in todo:    # warm the OS file cache, not timed
            cpu_of(argv, env)
        for _ in range(repeat):                 # interleaved: load changes hit all alike
            for label, argv, _, _, env in todo:
                times[label].append(cpu_of(argv, env))
    width = max(len(label) for label in times)
    median = {label: statistics.median(t) for label, t in times.items()}
    for label, _, goal, floors, _ in todo:
        t = times[label]
        med = median[label]
        verdict = "" if goal is None else \
            f"  goal <= {goal:.2f} s: {'met' if med <= goal else 'NOT met'} ({med / goal:.2f}x)"
        print(f"{label:<{width}}  median {med:.3f} s (min {min(t):.3f}, max {max(t):.3f}){verdict}")
        if floors:
            floor, *others = floors
            print(f"{'':<{width}}  {med / median[floor]:.2f}x its floor "
                  f"({floor.replace(' (floor)', '')}), "
                  f"{med - median[floor]:+.3f} s beyond it"
                  + "".join(f"; {med - median[o]:+.3f} s beyond {o.replace(' (floor)', '')}"
                            for o in others))
    print(f"load average after: {os.getloadavg()[0]:.1f}")
    shutil.rmtree(cache, ignore_errors=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
