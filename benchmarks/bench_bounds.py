"""Bounded work (issue 8, §2): time and peak memory of the large cases.

Each case runs in its own process under ``/usr/bin/time -v`` (peak resident
set size of the whole process, numpy buffers included); inside, tracemalloc
reports the peak of Python-level allocations (numpy's included, since numpy
reports its buffers to tracemalloc).

    python benchmarks/bench_bounds.py              # every case, a table
    python benchmarks/bench_bounds.py --case sweep_1e7

Cases
-----
sweep_1e7            Circuit.sweep of netlists/stb_heald.mcir at 10⁷ points, then flags
                     (K, Q0, v0, error, flags all held), chunked (CHUNK_POINTS = 2¹⁸).
sweep_1e7_unchunked  The same with chunking switched off, for comparison.
netlist_1e6          Parse, reduce and sweep (100 points) a 10⁶-element ladder.
cli_sweep_1e7        mechcirc sweep --points 10000000 -o K.csv (the CLI's CSV writer).
hostile_quick        9**9**9, 101 nested parentheses, 10⁶ nested parentheses, a
                     5000-digit literal and a 10 MB line: the time to refuse each.
"""

from __future__ import annotations

import argparse
import json
import os
import re
import subprocess
import sys
import tempfile
import time
import tracemalloc
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
STB = ROOT / "netlists" / "stb_heald.mcir"


def ladder(n_elements: int) -> str:
    """A ladder of n elements: series masses along the line, springs to the frame."""
    lines = ["drive V n0 0 velocity=0.1"]
    for i in range(n_elements // 2):
        lines.append(f"mass m{i} n{i} n{i + 1} {1 + i % 5}")
        lines.append(f"spring k{i} n{i + 1} 0 {1000 + i % 7}")
    return "\n".join(lines) + "\n"


def case_sweep_1e7(chunked: bool = True) -> dict:
    import numpy as np

    import mechcirc
    import importlib
    sweep_module = importlib.import_module("mechcirc._sweep")

    if not chunked:
        sweep_module.CHUNK_POINTS = 10**9
    c = mechcirc.load(STB)
    omega = np.geomspace(1.0, 1e4, 10**7)
    tracemalloc.start()
    t0 = time.perf_counter()
    s = c.sweep(omega)
    t_K = time.perf_counter() - t0
    flags = s.flags
    t_all = time.perf_counter() - t0
    _, peak = tracemalloc.get_traced_memory()
    return {"points": omega.size, "seconds_K": round(t_K, 2), "seconds_with_flags": round(t_all, 2),
            "flagged": int(np.count_nonzero(flags)), "tracemalloc_peak_MB": round(peak / 1e6)}


def case_netlist_1e6() -> dict:
    import warnings

    import numpy as np

    import mechcirc

    text = ladder(10**6)
    tracemalloc.start()
    t0 = time.perf_counter()
    c = mechcirc.parse(text)
    t_parse = time.perf_counter() - t0
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        tree = c.tree
    t_reduce = time.perf_counter() - t0 - t_parse
    t1 = time.perf_counter()
    s = c.sweep(np.geomspace(1.0, 1e3, 100))
    flags = s.flags
    t_sweep = time.perf_counter() - t1
    _, peak = tracemalloc.get_traced_memory()
    return {"elements": len(c.elements), "text_MB": round(len(text) / 1e6, 1),
            "seconds_parse": round(t_parse, 1), "seconds_reduce": round(t_reduce, 1),
            "seconds_sweep_100": round(t_sweep, 1), "flagged": int(np.count_nonzero(flags)),
            "tracemalloc_peak_MB": round(peak / 1e6), "tree_type": type(tree).__name__}


def case_cli_sweep_1e7() -> dict:
    from mechcirc.cli import main

    with tempfile.TemporaryDirectory() as tmp:
        t0 = time.perf_counter()
        status = main(["sweep", str(STB), "--omega-min", "1", "--omega-max", "1e4",
                       "--points", "10000000", "--log", "-o", os.path.join(tmp, "K.csv")])
        size = os.path.getsize(os.path.join(tmp, "K.csv"))
    return {"status": status, "seconds": round(time.perf_counter() - t0, 1),
            "csv_MB": round(size / 1e6)}


def case_hostile_quick() -> dict:
    import mechcirc
    from mechcirc.errors import NetlistError
    from mechcirc.expressions import parse_expression

    cases = {
        "9**9**9": "drive V a 0 velocity=1\nmass m a 0 {9**9**9}\n",
        "101 nested parentheses": "drive V a 0 velocity=1\nmass m a 0 {" + "(" * 101 + "1"
                                  + ")" * 101 + "}\n",
        "5000-digit literal": "drive V a 0 velocity=1\nmass m a 0 " + "1" * 5000 + "\n",
        "10 MB line": "drive V a 0 velocity=1\nmass m a 0 " + "1" * (10 * 2**20) + "\n",
    }
    out = {}
    for name, text in cases.items():
        t0 = time.perf_counter()
        try:
            mechcirc.parse(text)
            message = "accepted"
        except NetlistError as exc:
            message = exc.message
        out[name] = {"ms": round(1e3 * (time.perf_counter() - t0), 2), "error": message}
    t0 = time.perf_counter()
    try:
        parse_expression("(" * 10**6 + "1" + ")" * 10**6)
    except NetlistError as exc:
        out["10^6 nested parentheses"] = {"ms": round(1e3 * (time.perf_counter() - t0), 2),
                                          "error": exc.message}
    return out


CASES = {"sweep_1e7": case_sweep_1e7,
         "sweep_1e7_unchunked": lambda: case_sweep_1e7(chunked=False),
         "netlist_1e6": case_netlist_1e6, "cli_sweep_1e7": case_cli_sweep_1e7,
         "hostile_quick": case_hostile_quick}


def measure(name: str) -> dict:
    """Run one case in a child process under /usr/bin/time -v."""
    proc = subprocess.run(["/usr/bin/time", "-v", sys.executable, __file__, "--case", name,
                           "--child"], capture_output=True, text=True)
    m = re.search(r"Maximum resident set size \(kbytes\): (\d+)", proc.stderr)
    wall = re.search(r"Elapsed \(wall clock\) time \(h:mm:ss or m:ss\): ([\d:.]+)", proc.stderr)
    result = json.loads(proc.stdout.strip().splitlines()[-1]) if proc.returncode == 0 else {
        "failed": proc.stderr[-2000:]}
    result["peak_RSS_MB"] = round(int(m.group(1)) / 1024) if m else None
    result["wall"] = wall.group(1) if wall else None
    return result


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--case", choices=list(CASES))
    ap.add_argument("--child", action="store_true", help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.child:
        print(json.dumps(CASES[args.case]()))
        return 0
    for name in [args.case] if args.case else list(CASES):
        print(f"{name}: {json.dumps(measure(name))}", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
