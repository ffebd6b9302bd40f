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

Two more measurements (issue 21's goals), on eta1…eta4 and written to Parquet:

``--memory``: the study run by the CLI in a child process (``mechcirc study
SPEC -o OUT.parquet --workers 1``), its peak resident memory read from
``resource.getrusage(RUSAGE_CHILDREN)`` (goal ≤ 1 GB at 10⁶ points).

``--cluster``: a real Dask cluster on 127.0.0.1 — ``dask scheduler`` and
``dask worker`` processes (one thread each) started by the script — the
same study on 1 and on 2 workers, alternated ``--repeats`` times (1, 2, 1, 2,
…), the throughput ratio per pair and the load average around each run
(goal ≥ 1.7× on a quiet 2-core machine)::

    python benchmarks/bench_study.py --memory --points 1000000
    python benchmarks/bench_study.py --cluster --points 1000000 --repeats 2
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


def spec_text(n):
    return (f'netlist = "{NETLIST}"\nanalysis = "sweep"\n'
            "[omega]\nmin = 10\nmax = 1e4\npoints = 200\nlog = true\n"
            f'[sample]\nmethod = "random"\nn = {n}\nseed = 21\n[sample.params]\n'
            "eta1 = {min = 0.6, max = 1.0}\neta2 = {min = 1.0, max = 1.5}\n"
            "eta3 = {min = 0.7, max = 1.1}\neta4 = {min = 0.8, max = 1.2}\n")


def memory(n):
    import resource
    import subprocess
    import sys
    import tempfile

    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "study.toml"
        path.write_text(spec_text(n))
        load = os.getloadavg()[0]
        t0 = time.perf_counter()
        subprocess.run([sys.executable, "-m", "mechcirc", "study", str(path), "-o",
                        str(Path(tmp) / "out.parquet"), "--workers", "1"], check=True)
        wall = time.perf_counter() - t0
        use = resource.getrusage(resource.RUSAGE_CHILDREN)
        import pyarrow.parquet as pq

        rows = pq.ParquetFile(Path(tmp) / "out.parquet").metadata.num_rows
    print(f"{n:,} points to Parquet ({rows:,} rows): peak RSS {use.ru_maxrss / 1024:.0f} MB "
          f"(goal ≤ 1024), CPU {use.ru_utime + use.ru_stime:.1f} s, wall {wall:.1f} s, "
          f"load {load:.1f} before, {os.getloadavg()[0]:.1f} after")


def _cpu(pid):
    """CPU seconds (user + system) used so far by process ``pid`` and its children."""
    import psutil                 # a dependency of dask.distributed

    proc = psutil.Process(pid)
    total = sum(proc.cpu_times()[:2])
    return total + sum(sum(c.cpu_times()[:2]) for c in proc.children(recursive=True))


def cluster_scaling(n, repeats):
    import socket
    import subprocess
    import sys
    import tempfile

    from mechcirc.study import load_spec

    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        port = sock.getsockname()[1]
    address = f"tcp://127.0.0.1:{port}"
    dask = [sys.executable, "-m", "distributed.cli.dask_scheduler"]
    worker = [sys.executable, "-m", "distributed.cli.dask_worker", address, "--nthreads", "1",
              "--nworkers", "1", "--no-dashboard", "--memory-limit", "0"]
    procs = []
    try:
        with tempfile.TemporaryDirectory() as tmp:
            path = Path(tmp) / "study.toml"
            path.write_text(spec_text(n))
            s = load_spec(path)
            procs.append(subprocess.Popen(dask + ["--host", "127.0.0.1", "--port", str(port),
                                                  "--no-dashboard"],
                                          stderr=subprocess.DEVNULL, cwd=tmp))
            procs.append(subprocess.Popen(worker, stderr=subprocess.DEVNULL, cwd=tmp))
            from distributed import Client

            times = {1: [], 2: []}
            for r in range(repeats):
                for k in (1, 2):
                    with Client(address) as c:
                        if len(procs) - 1 < k:
                            procs.append(subprocess.Popen(worker, stderr=subprocess.DEVNULL,
                                                          cwd=tmp))
                        while len(procs) - 1 > k:
                            procs.pop().terminate()
                        c.wait_for_workers(k, timeout=120)
                        while len(c.scheduler_info()["workers"]) != k:
                            time.sleep(0.2)
                    before = os.getloadavg()[0]
                    cpu0 = [_cpu(p.pid) for p in procs]
                    t0, c0 = time.perf_counter(), time.process_time()
                    res = run_study(s, output=Path(tmp) / f"out{k}.parquet", scheduler=address,
                                    keep_rows=False)
                    wall, client = time.perf_counter() - t0, time.process_time() - c0
                    sched, *work = [_cpu(p.pid) - c for p, c in zip(procs, cpu0)]
                    times[k].append(wall)
                    print(f"  repeat {r + 1}, {k} worker(s): {wall:7.1f} s, "
                          f"{n / wall:8.0f} points/s (workers {res.workers}, failed "
                          f"{res.failed}); load {before:.1f} before, "
                          f"{os.getloadavg()[0]:.1f} after", flush=True)
                    # CPU seconds by role, which the load does not change much: the
                    # client's and the scheduler's share bounds what 2 cores can give.
                    print(f"    CPU: client {client:.1f} s, scheduler {sched:.1f} s, workers "
                          f"{' + '.join(f'{w:.1f}' for w in work)} s", flush=True)
                print(f"  ratio of this pair: {times[1][-1] / times[2][-1]:.2f}x (goal ≥ 1.7)",
                      flush=True)
    finally:
        for p in procs[::-1]:
            p.terminate()
            p.wait(timeout=30)


def table(result):
    return [[r.get(c) for c in result.columns] for r in result.rows]


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--points", type=int, default=10_000)
    ap.add_argument("--memory", action="store_true", help="peak memory of a CLI study")
    ap.add_argument("--cluster", action="store_true", help="1 against 2 Dask workers")
    ap.add_argument("--repeats", type=int, default=2)
    args = ap.parse_args()
    cores = os.cpu_count() or 1
    print(f"{platform.processor() or platform.machine()}, {cores} cores, Python "
          f"{platform.python_version()}; {args.points} points x 200 omega each; "
          f"load {os.getloadavg()[0]:.1f}")
    if args.memory or args.cluster:
        if args.memory:
            memory(args.points)
        if args.cluster:
            cluster_scaling(args.points, args.repeats)
        return
    s = spec(args.points)
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
