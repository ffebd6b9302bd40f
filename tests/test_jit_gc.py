"""While numba compiles, Python's cyclic garbage collector runs less often (mechcirc._jit).

Numba's compiler builds and copies millions of small objects; with the default gen-0
threshold (700) the collector runs thousands of times during a cold compile of the scene
kernels (about 1.5 s of their 16 s).  The threshold is raised for the outermost compile
only and restored after it, also when the compile fails.
"""

from __future__ import annotations

import gc

import pytest

from mechcirc import _jit

numba = pytest.importorskip("numba")
from numba.core import event  # noqa: E402


class _Seen(event.Listener):
    def __init__(self):
        self.at_start = []

    def on_start(self, ev):
        self.at_start.append(gc.get_threshold())

    def on_end(self, ev):
        pass


def test_gc_threshold_raised_while_numba_compiles_and_restored_after():
    _jit.decorators()                   # a kernel module's first call registers the rule
    saved = gc.get_threshold()          # (tests/conftest.py raises it for the whole suite)
    gc.set_threshold(700, 10, 10)       # Python's default
    before = gc.get_threshold()
    seen = _Seen()
    event.register("numba:compile", seen)
    try:
        @numba.njit
        def inner(x):
            return x + 1

        @numba.njit
        def outer(x):
            return inner(x) * 2

        assert outer(3) == 8

        @numba.njit
        def broken(x):
            return x.no_such_attribute

        with pytest.raises(numba.core.errors.TypingError):
            broken(1.0)
        after = gc.get_threshold()
    finally:
        event.unregister("numba:compile", seen)
        gc.set_threshold(*saved)
    assert after == before                          # restored after each outermost compile
    assert len(seen.at_start) == 3                  # outer, inner (nested), broken
    for threshold in seen.at_start:
        assert threshold[0] >= _jit.GC_THRESHOLD_COMPILING > before[0]
        assert threshold[1:] == before[1:]
