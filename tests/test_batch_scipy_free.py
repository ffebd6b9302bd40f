"""A batch of designs finds its resonances without importing scipy (no levers to pivot).

The stacked eigenproblems are numpy (``eigvalsh``/``eigvals``); the only scipy
the single path needs for a lever-free network is its sparse matrices, which the
batch does not use.  Checked in a fresh process with the numpy kernels (numba
itself imports scipy), for an undamped and a damped network.  The roots
themselves are checked against the single path and mpmath in test_batch.py.
"""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]

UNDAMPED = (".param m1=1 m2=0.5 k1=1e4 k2=3e4\ndrive V a 0 velocity=1\nmass ma a 0 m1\n"
            "spring ka a b k1\nmass mb b 0 m2\nspring kb b 0 k2\n")
DAMPED = UNDAMPED + "damper cb b 0 3\n"


@pytest.fixture(scope="module")
def batched():
    """``{case: {"single", "count", "loaded"}}`` of both networks, run one after the other
    in one fresh process, the top-level modules loaded read after each: modules only
    accumulate, so each case's list holds all it imported (one process instead of two,
    each importing numpy and mechcirc: 0.2 s of CPU here, more under ``--no-compile``)."""
    code = (
        "import sys, json, numpy as np, mechcirc\n"
        "from mechcirc import _jit\n"
        "_jit.COMPILED = False\n"
        "out = {}\n"
        f"for case, text in {{'undamped': {UNDAMPED!r}, 'damped': {DAMPED!r}}}.items():\n"
        "    ds = mechcirc.designs(text, {'k1': np.array([1e4, 2e4, 5e4])})\n"
        "    r = ds.resonances()\n"
        "    out[case] = {'single': r.single.tolist(), 'count': r.count.tolist(),\n"
        "                 'loaded': sorted({m.split('.')[0] for m in sys.modules})}\n"
        "print(json.dumps(out))\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True, cwd=ROOT, timeout=600)
    return json.loads(out.stdout)


@pytest.mark.parametrize("case", ["undamped", "damped"])
def test_batched_resonances_load_no_scipy(batched, case):
    got = batched[case]
    assert got["single"] == [] and got["count"] == [3, 3, 3]       # all three batched
    assert not set(got["loaded"]) & {"scipy", "numba"}, got["loaded"]
