"""Long fuzz run of mechcirc (issue 8, §1): ≥ 100,000 inputs, not collected by pytest.

Usage::

    python tests/fuzz/long_run.py                    # the default counts below
    python tests/fuzz/long_run.py --scale 0.01       # a quick look
    python tests/fuzz/long_run.py --json result.json

Each input is generated from its own seed (``random.Random(seed)``), so a
failure is reproduced by running the target on that seed alone.  The
property is the in-suite one (``harness.run_target``, ``harness.cli_property``):
a result or a ``MechcircError`` located inside the text, never another
exception, never more than the per-input time bound.
"""

from __future__ import annotations

import argparse
import json
import platform
import random
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from fuzz import harness as h  # noqa: E402

#: Inputs per target in a full run (103,000 in all).
COUNTS = {"expression": 40_000, "netlist": 40_000, "linkage": 20_000, "cli": 3_000}
#: Issue 16: files of every kind through their public readers (netlist, linkage,
#: scene, study, Touchstone: hostile values, non-UTF-8, pickles, binary, line
#: breakers) and parallel/series blow-ups.  ``--targets files blowup``.
COUNTS.update({"files": 100_000, "blowup": 200})
#: Issue 23: this round's commands and inputs (``harness.round_argv``): ``round`` cycles
#: through periodic (law, table), cam, resonances, sweep --sensitivity and study sample
#: files; ``round_crosscheck`` is crosscheck alone (a transient run per input).
COUNTS.update({"round": 12_000, "round_crosscheck": 300})
#: The campaign: any registered sub-command (``harness.all_argv``), its inputs drawn from
#: the file kind it reads (netlists, scenes, linkages, study specs by grid, random, Latin
#: hypercube, Sobol or file, Touchstone, drive tables) or made wrong.
COUNTS.update({"all": 20_000})


def run(target: str, n: int, first_seed: int, work: Path) -> dict:
    gen = {"expression": (h.expression_input, h.expression_property),
           "netlist": (h.netlist_input, h.netlist_property),
           "linkage": (h.toml_input, h.linkage_property)}
    counts = {"result": 0, "error": 0, "verdict": 0}   # verdict: crosscheck's exit 3
    failures = []
    files = h.cli_files(work, random.Random(first_seed)) if target == "cli" else None
    if target == "all":
        files = h.all_files(work / "all", random.Random(first_seed))
    if target.startswith("round"):
        files = h.round_files(work / "round")
        kinds = [k for k in h.ROUND_KINDS if k != "crosscheck"] if target == "round" \
            else ["crosscheck"]
    by_kind: dict = {}
    t0, c0 = time.perf_counter(), time.process_time()
    slowest = (0.0, None)
    for seed in range(first_seed, first_seed + n):
        rng = random.Random(seed)
        t1 = time.perf_counter()
        try:
            if target == "cli":
                outcome = h.cli_property(h.cli_argv(rng, work, files))
            elif target == "all":
                argv = h.all_argv(rng, work / "all", files)
                kind = argv[0]
                by_kind.setdefault(kind, {"result": 0, "error": 0, "verdict": 0, "failures": 0})
                try:
                    outcome = h.cli_property(argv)
                except h.PropertyFailure:
                    by_kind[kind]["failures"] += 1
                    raise
                by_kind[kind][outcome] += 1
                if seed % 50 == 0 and "matplotlib.pyplot" in sys.modules:
                    sys.modules["matplotlib.pyplot"].close("all")
            elif target.startswith("round"):
                kind = kinds[seed % len(kinds)]
                by_kind.setdefault(kind, {"result": 0, "error": 0, "verdict": 0, "failures": 0})
                try:
                    outcome = h.cli_property(h.round_argv(rng, kind, work / "round", files))
                except h.PropertyFailure:
                    by_kind[kind]["failures"] += 1
                    raise
                by_kind[kind][outcome] += 1
            elif target == "files":
                kind = h.FILE_KINDS[seed % len(h.FILE_KINDS)]
                outcome = h.file_property(kind, h.file_input(rng, kind), work)
            elif target == "blowup":
                outcome = h.netlist_blowup_property(h.blowup_netlist(rng, rng.choice(
                    [1000, 4000, 16000, 50000])))
                if seed % 50 == 0 and "matplotlib.pyplot" in sys.modules:
                    sys.modules["matplotlib.pyplot"].close("all")
            else:
                make, prop = gen[target]
                outcome = prop(make(rng))
            counts[outcome] += 1
        except h.PropertyFailure as exc:
            failures.append({"seed": seed, "failure": str(exc)[:500]})
            print(f"  FAILURE seed {seed}: {str(exc)[:300]}", flush=True)
        dt = time.perf_counter() - t1
        if (seed - first_seed + 1) % (50 if target == "round_crosscheck" else
                                         200 if target in ("all", "round") else 1000) == 0:
            print(f"  {target}: {seed - first_seed + 1} inputs, {counts}, {len(failures)} "
                  f"failures, {time.perf_counter() - t0:.0f} s {by_kind}", flush=True)
        if dt > slowest[0]:
            if target == "all" and dt > 5:
                print(f"  slow input: seed {seed}, {dt:.1f} s", flush=True)
            slowest = (dt, seed)
    return {"target": target, "inputs": n, "first_seed": first_seed, **counts,
            "failures": failures, "by_kind": by_kind, "seconds": round(time.perf_counter() - t0, 1),
            "cpu_seconds": round(time.process_time() - c0, 1),
            "slowest_input_s": round(slowest[0], 3), "slowest_seed": slowest[1]}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scale", type=float, default=1.0, help="multiply every count")
    ap.add_argument("--first-seed", type=int, default=1_000_000)
    ap.add_argument("--targets", nargs="*", default=["expression", "netlist", "linkage", "cli"],
                    choices=list(COUNTS))
    ap.add_argument("--json", help="write the summary here")
    args = ap.parse_args(argv)
    summary = {"python": platform.python_version(), "machine": platform.machine(),
               "started": time.strftime("%Y-%m-%d %H:%M:%S %Z"), "targets": []}
    with tempfile.TemporaryDirectory() as tmp:
        for target in args.targets:
            n = max(1, int(COUNTS[target] * args.scale))
            res = run(target, n, args.first_seed, Path(tmp))
            summary["targets"].append(res)
            print(f"{target:10s} {res['inputs']:7d} inputs  {res['result']:6d} results  "
                  f"{res['error']:6d} MechcircError  {len(res['failures'])} failures  "
                  f"{res['seconds']:7.1f} s  (slowest input {res['slowest_input_s']} s)",
                  flush=True)
            for f in res["failures"][:10]:
                print(f"    seed {f['seed']}: {f['failure']}", flush=True)
    total = sum(t["inputs"] for t in summary["targets"])
    bad = sum(len(t["failures"]) for t in summary["targets"])
    secs = sum(t["seconds"] for t in summary["targets"])
    summary.update(total_inputs=total, total_failures=bad, total_seconds=round(secs, 1))
    print(f"total      {total:7d} inputs, {bad} failures, {secs:.0f} s")
    if args.json:
        Path(args.json).write_text(json.dumps(summary, indent=2))
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
