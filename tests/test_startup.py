"""What a single command pays before it computes: lazy imports and no compile wait.

The speed itself is measured by ``benchmarks/bench_startup.py`` and
``benchmarks/bench_bound_cost.py``; these tests check only what those
speed-ups must not change: which modules a sweep loads, and that the default
path gives the numpy path's numbers, bit for bit, while numba's cache is cold.
"""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import mechcirc
from mechcirc import _jit, _tree_eval, reduction

ROOT = Path(__file__).resolve().parents[1]
STB = ROOT / "netlists" / "stb_heald.mcir"


def test_a_sweep_with_flags_loads_no_scipy_matplotlib_or_numba():
    # load + sweep + error bound + flags: the frequency-domain core is numpy only.
    code = (
        "import sys, json, numpy as np, mechcirc\n"
        f"c = mechcirc.load({str(STB)!r})\n"
        "s = c.sweep(np.linspace(10, 1000, 400)); s.flags; s.error\n"
        "print(json.dumps(sorted({m.split('.')[0] for m in sys.modules})))\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True, cwd=ROOT, timeout=600)
    loaded = set(json.loads(out.stdout))
    assert not loaded & {"scipy", "matplotlib", "numba", "networkx", "pandas"}, loaded


@pytest.fixture
def cold_kernel(monkeypatch):
    """The default path as in a fresh process whose numba cache does not hold the kernel;
    returns the list of warm-up processes started (recorded, none run)."""
    started = []
    monkeypatch.setattr(_jit, "COMPILED", None)
    monkeypatch.setattr(_tree_eval, "_KERNEL", [])
    monkeypatch.setattr(_tree_eval, "_WARMING", [])
    monkeypatch.setattr(_tree_eval, "KERNEL_MIN_WORK", 1)      # every call is "large"
    monkeypatch.setattr(_tree_eval, "_in_cache", lambda dispatcher: False)
    monkeypatch.setattr(_tree_eval, "_start_warming", lambda: started.append(1) or "started")
    return started


def _numpy_path(tree, omega, error):
    saved = _jit.COMPILED
    _jit.COMPILED = False
    try:
        return reduction.evaluate(tree, omega, error=error)
    finally:
        _jit.COMPILED = saved


def _corpus():
    sys.path.insert(0, str(ROOT / "tests"))
    from reference import sp_corpus

    rng = np.random.default_rng(26)
    trees = [sp_corpus.random_tree(rng, int(rng.integers(1, 30)), damped=d)
             for _ in range(15) for d in (0.0, 0.3)]
    return [sp_corpus.to_circuit(t) for t in trees] + \
        [mechcirc.load(ROOT / "netlists" / n) for n in ("stb_heald.mcir", "heald_damped.mcir")]


def test_a_cold_kernel_is_not_waited_for(cold_kernel):
    pytest.importorskip("numba")
    omega = np.concatenate([[0.0, np.inf], np.geomspace(1e-2, 1e4, 50)])
    for c in _corpus():
        K, rho = reduction.evaluate(c.tree, omega, error=True)
        K0, rho0 = _numpy_path(c.tree, omega, True)
        # Not the compiled kernel (a few ulps apart), the numpy path itself, to the bit.
        assert K.tobytes() == K0.tobytes() and rho.tobytes() == rho0.tobytes()
        assert reduction.evaluate(c.tree, omega).tobytes() == K0.tobytes()
        s = c.sweep(omega[2:])
        assert s.error.tobytes() == _numpy_path(c.tree, omega[2:], True)[1].tobytes()
    assert cold_kernel == [1]                  # one warm-up process, started once
    assert _tree_eval._KERNEL == []            # and nothing compiled here


def test_a_cached_kernel_is_loaded(cold_kernel, monkeypatch):
    pytest.importorskip("numba")
    monkeypatch.setattr(_tree_eval, "_in_cache", lambda dispatcher: True)
    c = mechcirc.load(STB)
    omega = np.linspace(10, 1000, 40)
    K, rho = reduction.evaluate(c.tree, omega, error=True)
    assert _tree_eval._KERNEL and _tree_eval._KERNEL[0] is not None
    assert cold_kernel == []
    _jit.COMPILED = True
    K1, rho1 = reduction.evaluate(c.tree, omega, error=True)
    assert K.tobytes() == K1.tobytes() and rho.tobytes() == rho1.tobytes()


def test_the_cache_check_sees_numbas_index():
    numba = pytest.importorskip("numba")

    @numba.njit(cache=True)
    def never_compiled(x):      # defined here, compiled nowhere: not in any cache
        return x + 0.5

    assert _tree_eval._in_cache(never_compiled) is False
    assert _tree_eval._in_cache(object()) is True      # no cache to ask: load as before
