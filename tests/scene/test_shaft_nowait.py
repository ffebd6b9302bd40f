"""The shaft's compiled loop follows the no-wait rule of mechcirc._jit: with numba's cache
cold the Python copy of the kernels runs and one background warm-up is asked for; cached,
the compiled module; the warm-up statement itself runs (numba's JIT off, as plain Python)."""

from pathlib import Path

import pytest

from mechcirc import _jit
from mechcirc.scene import _motion_kernels, shaft

ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture
def started(monkeypatch):
    pytest.importorskip("numba")
    calls = []
    monkeypatch.setattr(_jit, "COMPILED", None)
    monkeypatch.setattr(_jit, "warm_in_background", calls.append)
    return calls


def test_a_cold_cache_runs_the_python_copy_and_asks_for_the_warm_up(started, monkeypatch):
    monkeypatch.setattr(_jit, "in_cache", lambda *d: False)
    k = shaft._shaft_kernels()
    assert k is not _motion_kernels and not k.HAVE_NUMBA
    assert started == [shaft._WARM_STATEMENT]


def test_a_cached_kernel_is_taken_compiled(started, monkeypatch):
    monkeypatch.setattr(_jit, "in_cache", lambda *d: True)
    assert shaft._shaft_kernels() is _motion_kernels and started == []


def test_the_warm_up_statement_runs(warm_up_run):
    # With numba's JIT off (plain Python), with the other warm-up statements in one
    # process (tests/conftest.py, warm_up_run): it runs without error and prints nothing.
    pytest.importorskip("numba")
    done = warm_up_run[shaft._WARM_STATEMENT]
    assert done["error"] is None and done["stdout"] == "", done
