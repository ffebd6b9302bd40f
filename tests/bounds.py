"""Bounds on work in the tests: CPU time of this process, never the wall clock.

A loaded machine stretches wall-clock time, not the CPU time a computation
needs, so "finishes at once" is checked as CPU seconds with a wide margin over
the measured cost (and far below what the unbounded work would take).
Subprocesses get :data:`SUBPROCESS_TIMEOUT`, which is only there so that a hung
child cannot hang the suite: no test checks how long a child takes.
"""

from __future__ import annotations

import contextlib
import time

#: Seconds a child process may run before the test gives up on it (a hang, not slowness).
SUBPROCESS_TIMEOUT = 1800


@contextlib.contextmanager
def cpu_seconds_below(seconds: float):
    """Fail if the block used ``seconds`` or more of this process's CPU time."""
    t0 = time.process_time()
    yield
    used = time.process_time() - t0
    assert used < seconds, f"{used:.3g} s of CPU time, the bound is {seconds} s"
