"""The benchmarks' timers, written once: the median of ``repeat`` timed calls, in CPU time
(process time: the machine is shared, and wall time counts the moments another process
has the core) or in wall time, with the last call's result.

Not a benchmark itself; the scripts beside it import it (run them from the repository
root, ``python benchmarks/bench_x.py``: their folder is then first on ``sys.path``).
"""

from __future__ import annotations

import time

import numpy as np


def cpu(fn, repeat: int = 1):
    """(median CPU seconds of ``repeat`` calls of ``fn()``, the last call's result)."""
    return _median(fn, repeat, time.process_time)


def wall(fn, repeat: int = 1):
    """(median wall seconds of ``repeat`` calls of ``fn()``, the last call's result)."""
    return _median(fn, repeat, time.perf_counter)


def _median(fn, repeat: int, clock):
    times, out = [], None
    for _ in range(repeat):
        t0 = clock()
        out = fn()
        times.append(clock() - t0)
    return float(np.median(times)), out
