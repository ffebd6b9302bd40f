"""Rank the per-test CPU written by the suite with ``MECHCIRC_TEST_CPU=PATH``.

``python tests/cpu_report.py PATH [N]`` reads every ``PATH.<worker>`` file
(tests/conftest.py writes them) and prints the total CPU of the tests (the
worker processes and the subprocesses they waited for), the CPU of tests
that spawned subprocesses, the numba compilation and the tests that paid for
it, and the N (default 20) most expensive tests.
"""

import glob
import sys


def main(path, top=20):
    rows = []
    base = glob.escape(path)
    names = sorted(glob.glob(f"{base}.gw*") + glob.glob(f"{base}.main*"))
    for name in (n for n in names if not n.endswith(".jit")):
        with open(name, encoding="utf-8") as fh:
            for line in fh:
                node, own, kids, *jit = line.rstrip("\n").split("\t")
                rows.append((float(own) + float(kids), float(own), float(kids), node,
                             float(jit[0]) if jit else 0.0))
    rows.sort(reverse=True)
    total = sum(r[0] for r in rows)
    spawning = [r for r in rows if r[2] > 0.05]
    print(f"{len(rows)} tests, {total:.1f} s CPU "
          f"({sum(r[1] for r in rows):.1f} s in the workers, "
          f"{sum(r[2] for r in rows):.1f} s in subprocesses)")
    print(f"{len(spawning)} tests spawned subprocesses using "
          f"{sum(r[2] for r in spawning):.1f} s CPU")
    compiling = sorted((r for r in rows if r[4] > 0.05), key=lambda r: -r[4])
    print(f"{len(compiling)} tests compiled numba kernels (or loaded them from its cache) "
          f"using {sum(r[4] for r in compiling):.1f} s of the workers' CPU; the first {top}:")
    for r in compiling[:top]:
        print(f"{r[4]:8.2f} of {r[0]:7.2f}  {r[3]}")
    print(f"top {top} (total = worker + subprocesses, seconds):")
    for cpu, own, kids, node, _ in rows[:top]:
        print(f"{cpu:8.2f} = {own:7.2f} + {kids:7.2f}  {node}")
    kernels([n for n in names if n.endswith(".jit")], top)


def kernels(names, top):
    """Print the compiled kernels by CPU, and any compiled by more than one process.

    ``PATH.<worker>.jit`` (tests/conftest.py) has one line per numba compile
    call: test, kernel, signature, compiled / loaded / had, CPU, depth.  The
    outermost calls (depth 1) hold the CPU of their callees.

    Parameters
    ----------
    names : list of str
        The ``.jit`` files.
    top : int
        How many of the costliest compilations to list.
    """
    if not names:
        return
    outer, where = [], {}
    for name in names:
        worker = name.rsplit(".", 2)[-2]
        with open(name, encoding="utf-8") as fh:
            for line in fh:
                node, kernel, sig, what, cpu, depth = line.rstrip("\n").split("\t")
                if what == "compiled" and not kernel.startswith("numba."):
                    where.setdefault((kernel, sig), []).append(worker)
                if depth == "1" and what != "had":
                    outer.append((float(cpu), what, kernel, worker, node))
    outer.sort(reverse=True)
    for what in ("compiled", "loaded"):
        some = [r for r in outer if r[1] == what]
        print(f"{what}: {len(some)} outermost kernels, {sum(r[0] for r in some):.1f} s CPU")
    print(f"the {top} costliest (seconds, kernel, worker, test):")
    for cpu, what, kernel, worker, node in outer[:top]:
        print(f"{cpu:8.2f} {what:8s} {kernel}  {worker}  {node}")
    twice = {k: w for k, w in where.items() if len(w) > 1}
    print(f"{len(twice)} kernel signatures compiled more than once (numba's own "
          f"helpers, recompiled for each caller, not counted; by the workers "
          f"{sorted({x for w in twice.values() for x in w})})")
    for (kernel, sig), workers in sorted(twice.items())[:top]:
        print(f"  {kernel} {sig[:60]} x{len(workers)}: {', '.join(workers)}")


if __name__ == "__main__":
    main(sys.argv[1], int(sys.argv[2]) if len(sys.argv) > 2 else 20)
