"""Rank the per-test CPU written by the suite with ``MECHCIRC_TEST_CPU=PATH``.

``python tests/cpu_report.py PATH [N]`` reads every ``PATH.<worker>`` file
(tests/conftest.py writes them) and prints the total CPU of the tests (the
worker processes and the subprocesses they waited for), the CPU of tests
that spawned subprocesses, the numba compilation and the tests that paid for
it, the N (default 20) most expensive tests, and the N most expensive test files
and test functions (every parametrisation summed), numba compiling left out.
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
    groups(rows, top)
    kernels([n for n in names if n.endswith(".jit")], top)


def groups(rows, top):
    """Print the test files and test functions with the most CPU, numba compiling left out.

    A test function's parametrisations are summed (the node id up to ``[``),
    so a cheap test run many times shows beside one long test.

    Parameters
    ----------
    rows : list of tuple
        ``(total, worker, subprocesses, node id, compiling)`` of each test.
    top : int
        How many files and functions to list.
    """
    for what, key in (("files", lambda node: node.split("::")[0]),
                      ("functions", lambda node: node.split("[")[0])):
        cpu: dict[str, list] = {}
        for total, _, _, node, jit in rows:
            entry = cpu.setdefault(key(node), [0.0, 0])
            entry[0] += total - jit
            entry[1] += 1
        ranked = sorted(cpu.items(), key=lambda kv: -kv[1][0])
        print(f"top {top} test {what} without compiling (seconds, tests):")
        for name, (seconds, count) in ranked[:top]:
            print(f"{seconds:8.2f} {count:5d}  {name}")


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
