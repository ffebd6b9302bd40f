"""Speed of parameter studies (issue 6 §6): 10,000 points of ``netlists/stb_heald.mcir``.

A random sample of the lever ratios eta1, eta2, eta3, each point a 200-point
log sweep (10 … 10⁴ rad/s) summarised to one row, run

(a) in one process (``workers=1``),
(b) on all local cores (``ProcessPoolExecutor``),
(c) on a Dask ``LocalCluster`` with one single-threaded worker process per core,
    if ``dask.distributed`` is installed (cluster start-up timed separately),

and the three tables compared (they must be identical).  Wall times with
``time.perf_counter``; the script prints, it asserts nothing.  Run from the
repository root::

    python benchmarks/bench_study.py             # 10,000 points
    python benchmarks/bench_study.py --points 2000
"""

from __future__ import annotations

import argparse
import os
import platform
import time
from pathlib import Path

from mechcirc.study import parse_spec, run_study

NETLIST = Path(__file__).resolve().parents[1] / "netlists" / "stb_heald.mcir"


def spec(n):
    return parse_spec({
        "netlist": str(NETLIST), "analysis": "sweep",
        "omega": {"min": 10, "max": 1e4, "points": 200, "log": True},
        "random": {"n": n, "seed": 6, "params": {
            "eta1": {"min": 0.6, "max": 1.0}, "eta2": {"min": 1.0, "max": 1.5},
            "eta3": {"min": 0.7, "max": 1.1}}}}, source="bench")


def table(result):
    return [[r.get(c) for c in result.columns] for r in result.rows]


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--points", type=int, default=10_000)
    args = ap.parse_args()
    s = spec(args.points)
    cores = os.cpu_count() or 1
    print(f"{platform.processor() or platform.machine()}, {cores} cores, Python "
          f"{platform.python_version()}; {args.points} points x 200 omega each")
    t0 = time.perf_counter()
    one = run_study(s, workers=1)
    t_one = time.perf_counter() - t0
    print(f"(a) one process        {t_one:7.2f} s  {args.points / t_one:8.0f} points/s")
    t0 = time.perf_counter()
    local = run_study(s, workers=cores)
    t_local = time.perf_counter() - t0
    print(f"(b) {local.workers} local processes  {t_local:7.2f} s  "
          f"{args.points / t_local:8.0f} points/s  speed-up {t_one / t_local:.2f}x  "
          f"identical: {table(local) == table(one)}")
    try:
        from distributed import LocalCluster
    except ImportError:
        print("(c) dask.distributed not installed: skipped")
        return
    t0 = time.perf_counter()
    with LocalCluster(n_workers=cores, threads_per_worker=1, processes=True,
                      dashboard_address=None) as cluster:
        t_start = time.perf_counter() - t0
        t0 = time.perf_counter()
        dask = run_study(s, scheduler=cluster.scheduler_address)
        t_dask = time.perf_counter() - t0
    print(f"(c) Dask LocalCluster   {t_dask:7.2f} s  {args.points / t_dask:8.0f} points/s  "
          f"speed-up {t_one / t_dask:.2f}x  identical: {table(dask) == table(one)}  "
          f"(cluster start {t_start:.2f} s, not included)")
    print(f"failed points: {one.failed}")


if __name__ == "__main__":
    main()
