"""The time-domain kernels (scene motion, linkage solver, transients) are not waited for.

With ``mechcirc._jit.COMPILED`` None a caller takes a kernel only when numba's
disk cache holds it; otherwise it runs the Python (or numpy) path, whose numbers
are those of ``COMPILED = False`` to the bit, and starts one background warm-up.
The cache and the warm-up are replaced here as in tests/test_startup.py; the
warm-up statements themselves are run with numba's JIT off.
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import mechcirc
from mechcirc import _jit
from mechcirc.kinematics import linkage_solver, parse_linkage
from mechcirc.scene import load_scene, simulate_scene
from mechcirc.scene import simulation as scene_sim
from mechcirc.transient import propagate as transient_sim
from mechcirc.transient.simulate import transient

ROOT = Path(__file__).resolve().parents[1]
FOURBAR = """
[points]
A = [0.0, 0.0]
B = [29.0, 0.0]
C = [150.0, 160.0]
D = [189.0, 0.0]
[ground]
points = ["A", "D"]
[links]
crank = ["A", "B"]
coupler = ["B", "C"]
rocker = ["D", "C"]
[[cranks]]
link = "crank"
omega = 100.0
"""
BACKLASH = "mass m a 0 1\nspring k a 0 1e4 backlash=0.02\n.ic a v=0.5\n"
LINEAR = "mass m a b 1\nspring k b 0 1e4\ndamper c a 0 3\ndrive V a 0 velocity=1\n"


@pytest.fixture
def cache(monkeypatch):
    """``cache(held)``: numba's cache holds every kernel (True) or none; returns the
    list of warm-up statements started (recorded, none run)."""
    pytest.importorskip("numba")
    started = []
    monkeypatch.setattr(_jit, "COMPILED", None)
    monkeypatch.setattr(_jit, "warm_in_background", started.append)

    def set_cache(held):
        monkeypatch.setattr(_jit, "in_cache", lambda *dispatchers: held)
        return started

    return set_cache


def _with_compiled(flag, fn):
    saved = _jit.COMPILED
    _jit.COMPILED = flag
    try:
        return fn()
    finally:
        _jit.COMPILED = saved


def _scene_run():
    scene = load_scene(ROOT / "examples" / "cam_follower_scene.toml")
    return simulate_scene(scene, revolutions=1, error_estimate=False, points=32,
                          steps_per_period=25)


def test_a_cold_scene_kernel_runs_python(cache):
    started = cache(False)
    r = _scene_run()
    assert r.backend == "python" and scene_sim.COLD_NOTE in r.notes
    ref = _with_compiled(False, _scene_run)
    assert ref.backend == "python" and scene_sim.COLD_NOTE not in ref.notes
    assert r.values.keys() == ref.values.keys() and len(r.values) > 3
    for name in r.values:
        assert np.asarray(r.values[name]).tobytes() == np.asarray(ref.values[name]).tobytes()
    # The scene's warm-up asked for; the linkage solver's too unless this process
    # already holds its compiled kernels (the scene's rigid motion asks for them, and
    # which earlier test loaded them depends on the order the suite runs in).
    assert scene_sim._WARM_STATEMENT in started
    assert set(started) <= {scene_sim._WARM_STATEMENT, linkage_solver._WARM_STATEMENT}


def test_a_cached_scene_kernel_is_compiled(cache):
    from mechcirc.scene import _motion_kernels

    started = cache(True)
    assert scene_sim.kernels_for("rk4") == (_motion_kernels, "numba")
    assert scene_sim.kernels_for("DOP853") == (_motion_kernels, "numba")
    assert scene_sim.kernels_for("rk4-python")[1] == "python"
    assert started == []
    cache(False)
    assert _with_compiled(True, lambda: scene_sim.kernels_for("rk4")) == (_motion_kernels, "numba")
    assert started == []                    # forced: compiled here, nothing started


def test_a_long_scene_run_takes_the_compiled_kernels_cold(cache, monkeypatch):
    """A crosscheck's records (650,000 RK4 steps for the heald scene) ran as Python with a
    cold cache: 268 s of CPU against 18 s compiling first.  ``long=True`` takes the compiled
    kernels, cold or not, and starts no warm-up; ``COMPILED = False`` still gives Python;
    the crosscheck asks for it."""
    import math

    from mechcirc.scene import _motion_kernels
    from mechcirc.scene.crosscheck import crosscheck_scene

    started = cache(False)
    assert scene_sim.kernels_for("rk4", long=True) == (_motion_kernels, "numba")
    assert scene_sim.kernels_for("rk4")[1] == "python"          # a short run: not waited for
    assert started == [scene_sim._WARM_STATEMENT]               # (by the short one only)
    assert _with_compiled(False, lambda: scene_sim.kernels_for("rk4", long=True))[1] == "python"
    asked = []

    def stop(method, **kw):                 # what the crosscheck asks for, then no run
        asked.append(kw)
        raise RuntimeError("stop")

    monkeypatch.setattr(scene_sim, "kernels_for", stop)
    cache(True)     # what runs before the stop (the rigid motion) on its usual, compiled path
    with pytest.raises(RuntimeError, match="stop"):
        crosscheck_scene(load_scene(ROOT / "examples" / "heald_scene.toml"), math.radians(40))
    assert asked == [{"long": True}]


def test_a_cold_linkage_kernel_runs_numpy(cache):
    started = cache(False)
    lk = parse_linkage(FOURBAR)
    theta = np.linspace(0.0, 2 * np.pi, 181)
    m = lk.motion(theta, method="newton")
    ref = _with_compiled(False, lambda: parse_linkage(FOURBAR).motion(theta, method="newton"))
    for field in ("q", "qdot", "qddot", "parts"):
        assert getattr(m, field).tobytes() == getattr(ref, field).tobytes()
    assert set(started) == {linkage_solver._WARM_STATEMENT}
    cache(True)
    assert linkage_solver._compiled("newton_path")
    assert set(started) == {linkage_solver._WARM_STATEMENT}


def test_a_dyad_linkage_starts_no_warm_up(cache):
    """The dyads are numpy only (no compiled twin, by measurement: docs/performance.md):
    solving them on a cold cache asks numba for nothing and starts no detached compile."""
    started = cache(False)
    parse_linkage(FOURBAR).motion(np.linspace(0.0, 2 * np.pi, 181), method="dyads")
    assert started == []


@pytest.mark.parametrize("net", [BACKLASH, LINEAR])
def test_a_cold_transient_kernel_runs_python(cache, net):
    from mechcirc.transient import _kernels

    started = cache(False)
    run = lambda: transient(mechcirc.parse(net, require_drive=False), 0.05, 1e-3)  # noqa: E731
    r = run()
    ref = _with_compiled(False, run)
    assert r.time.tobytes() == ref.time.tobytes()
    assert r.node("a")[0].tobytes() == ref.node("a")[0].tobytes()
    assert r.node("a")[1].tobytes() == ref.node("a")[1].tobytes()
    assert set(started) == {transient_sim._WARM_STATEMENT}
    assert transient_sim.kernels() is not _kernels and not transient_sim.kernels().HAVE_NUMBA
    cache(True)
    assert transient_sim.kernels() is _kernels


def test_the_time_domain_warm_up_statements_run(warm_up_run):
    # As the detached process runs each, with numba's JIT off (the same calls as
    # plain Python, nothing compiled): they import and run without error and print
    # nothing (run with the other warm-up statements: tests/conftest.py, warm_up_run).
    pytest.importorskip("numba")
    for statement in (scene_sim._WARM_STATEMENT, linkage_solver._WARM_STATEMENT,
                      transient_sim._WARM_STATEMENT):
        done = warm_up_run[statement]
        assert done["error"] is None and done["stdout"] == "", done


_CHAIN = """
from numba import njit

@njit(cache=True)
def inner(x):
    return 2.0 * x

@njit(cache=True)
def outer(x):
    return inner(x) + 1.0
"""

_LOAD = """
import json, sys
sys.path.insert(0, sys.argv[1])
from mechcirc import _jit
out = []
for name, compiled in (("chain_none", None), ("chain_true", True)):
    chain = __import__(name)
    _jit.COMPILED = compiled
    before = len(chain.inner.overloads)
    used = _jit.use("pass", chain.outer)
    stats = chain.inner.stats
    out.append([before, len(chain.inner.overloads), sum(stats.cache_hits.values()),
                sum(stats.cache_misses.values()), used, chain.outer(1.5)])
gone = __import__("chain_gone")         # its callee's data file deleted: not to be waited for
_jit.COMPILED, _jit.warm_in_background = None, out.append
out.append([_jit.use("warm", gone.outer), len(gone.inner.overloads), len(gone.outer.overloads)])
print(json.dumps(out))
"""


def test_a_cached_kernel_has_its_callees_loaded_from_the_cache_first(tmp_path):
    """A kernel found in numba's cache gets the compiled functions it calls loaded from
    the cache before it runs (as an in-process compile has them: docs/performance.md,
    "a kernel loaded from the cache"), with ``COMPILED`` None and True; nothing is
    compiled for that.  Where a callee's data file is gone from the cache, the kernel
    counts as not cached (its first call would compile that callee in the process).
    The chains are compiled into the cache here, and loaded in a fresh process (one,
    to keep the suite's CPU down)."""
    pytest.importorskip("numba")
    import importlib

    sys.path.insert(0, str(tmp_path))
    try:
        for name in ("chain_none", "chain_true", "chain_gone"):
            (tmp_path / f"{name}.py").write_text(_CHAIN, encoding="utf-8")
            importlib.import_module(name).outer(1.0)    # compiled here, into numba's cache
        # (beside the source, or under NUMBA_CACHE_DIR where that is set)
        where = Path(sys.modules["chain_gone"].inner._cache._cache_path)
    finally:
        sys.path.remove(str(tmp_path))
        for name in ("chain_none", "chain_true", "chain_gone"):
            sys.modules.pop(name, None)
    gone = list(where.glob("chain_gone.inner-*.nbc"))
    assert len(gone) == 1
    gone[0].unlink()
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    env.pop("MECHCIRC_NO_WARM", None)
    out = subprocess.run([sys.executable, "-c", _LOAD, str(tmp_path)], env=env, check=True,
                         capture_output=True, text=True, timeout=600).stdout
    assert __import__("json").loads(out) == [[0, 1, 1, 0, True, 4.0]] * 2 + ["warm", [False, 0, 0]]
