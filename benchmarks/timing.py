"""The benchmarks' timers, written once: the median (or the least) of ``repeat`` timed
calls, in CPU time (process time: the machine is shared, and wall time counts the moments
another process has the core) or in wall time, with the last call's result.

Not a benchmark itself; the scripts beside it import it (run them from the repository
root, ``python benchmarks/bench_x.py``: their folder is then first on ``sys.path``).
"""

from __future__ import annotations

import time

import numpy as np


def cpu(fn, repeat: int = 1, *, best: bool = False):
    """(median CPU seconds of ``repeat`` calls of ``fn()``, or the least with ``best``;
    the last call's result)."""
    times, out = samples(fn, repeat, time.process_time)
    return float(min(times) if best else np.median(times)), out


def wall(fn, repeat: int = 1, *, best: bool = False):
    """(median wall seconds of ``repeat`` calls of ``fn()``, or the least with ``best``;
    the last call's result)."""
    times, out = samples(fn, repeat, time.perf_counter)
    return float(min(times) if best else np.median(times)), out


def samples(fn, repeat: int = 1, clock=time.process_time):
    """(the ``clock`` seconds of each of ``repeat`` calls of ``fn()``, the last call's result)."""
    times, out = [], None
    for _ in range(repeat):
        t0 = clock()
        out = fn()
        times.append(clock() - t0)
    return times, out
