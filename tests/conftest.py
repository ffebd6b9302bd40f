"""Shared test configuration.

Property tests (hypothesis) are derandomized by default, so a run of the suite
is reproducible: CI and a developer see the same examples.  Set
``HYPOTHESIS_PROFILE=explore`` to draw fresh random examples (and keep a
database of failures) when hunting for new cases.
"""

import contextlib
import gc
import os

import pytest
from hypothesis import settings


def _one_bytecode_cache_for_the_run():
    """Under ``PYTHONDONTWRITEBYTECODE``, compile each module once for the run, not per process.

    The flag (set in CI) keeps ``.pyc`` files out of the sources and the
    environment, and the README's ``pip install --no-compile`` writes none:
    then every interpreter a test starts compiled numpy, SciPy, matplotlib
    and mechcirc from source again (about 1.45 s of CPU for one that
    imports them and sweeps, 0.55 s with their bytecode; 30 tests start
    one).  Here this process and its children share one bytecode cache in
    a temporary folder of the run's own (``PYTHONPYCACHEPREFIX``), removed
    at exit (or by the next run, when this one was killed): nothing is
    written beside the sources or into the environment, and what every
    process imports and runs is the same.  A prefix the user chose is kept;
    without the flag nothing changes (bytecode is written as usual), nor where
    the packages were installed with their bytecode (numpy's is looked for:
    a prefix would hide it, and every module would be compiled again).
    """
    import importlib.util
    import sys

    if os.environ.get("PYTHONPYCACHEPREFIX") or not os.environ.get("PYTHONDONTWRITEBYTECODE"):
        return
    numpy = importlib.util.find_spec("numpy")
    if numpy is None or numpy.cached is None or os.path.exists(numpy.cached):
        return                                  # installed with its bytecode: read it as it is
    import atexit
    import glob
    import shutil
    import tempfile

    # In memory where there is a tmpfs: on disk the test process's 2,800 files cost about
    # 1 s of system time more (1,714 of them: 1.0-1.5 s on disk, 0.1 s in /dev/shm).
    shm = "/dev/shm"
    where = shm if os.path.isdir(shm) and os.access(shm, os.W_OK) else tempfile.gettempdir()
    for stale in glob.glob(os.path.join(where, "mechcirc-tests-pyc-*-*")):
        try:                                    # a run killed before its exit (SIGTERM, SIGKILL)
            os.kill(int(stale.split("-")[-2]), 0)
        except ProcessLookupError:
            shutil.rmtree(stale, ignore_errors=True)
        except (ValueError, OSError):           # not a number, or another user's process
            pass
    prefix = tempfile.mkdtemp(prefix=f"mechcirc-tests-pyc-{os.getpid()}-", dir=where)
    atexit.register(shutil.rmtree, prefix, ignore_errors=True)
    os.environ["PYTHONPYCACHEPREFIX"] = prefix
    del os.environ["PYTHONDONTWRITEBYTECODE"]
    sys.pycache_prefix = prefix
    sys.dont_write_bytecode = False


_one_bytecode_cache_for_the_run()

from mechcirc.cli import one_blas_thread  # noqa: E402  (after the bytecode cache is set)

# One OpenBLAS thread unless the user chose a count, as the command line asks for its own
# process (mechcirc.cli.one_blas_thread), here before anything imports numpy (pytest,
# hypothesis and mechcirc.cli do not): the tests' arrays are small, and a second OpenBLAS
# thread only spins beside the first (the resonance and mode tests took 13.9-18.2 s of CPU
# with it against 7.7 s without, one process each at load 6; more wall time too).  What
# the tests compute and check is the same; a test that needs a thread count sets the
# variables itself (tests/test_startup.py).
one_blas_thread(os.environ)

# The youngest generation collected every 20,000 net allocations instead of 700: numba's
# compiler and the tests allocate millions of short-lived objects, and each young
# collection also walks the survivors.  The whole suite in a fresh numba cache, one
# process each back to back (load about 1, 27 Nov): 148.8 s of CPU against 159.6 s with
# the default; the transient and linkage warm-ups alone (fresh cache, three runs each)
# 12.3 s against 13.7 s.  Garbage is still collected (generations 1 and 2 as before,
# relative to the young collections); what the tests compute and check is the same.
gc.set_threshold(20000, 10, 10)

settings.register_profile("ci", derandomize=True, database=None)
settings.register_profile("explore", derandomize=False)
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "ci"))


def _first_given_run_while_the_heap_is_small():
    """Run one trivial property now, before the tests fill the worker's memory.

    Hypothesis's first ``@given`` run in a process registers its random
    generator, and that calls ``gc.collect()`` and ``gc.get_referrers()``:
    both walk every object the process holds.  With 6.2 million objects
    alive (numpy, SciPy, SymPy, numba, mechcirc imported and a list of
    dicts) the first property test cost 1.27 s of CPU against 0.30 s after
    this warm-up (one process, ``time.process_time``); here, before any
    test ran, it costs milliseconds.  Nothing a test checks changes (the
    examples are seeded per test).
    """
    from hypothesis import given
    from hypothesis import strategies as st

    @settings(max_examples=1, database=None)
    @given(st.none())
    def once(_):
        pass

    once()


_first_given_run_while_the_heap_is_small()


def pytest_collection_finish(session):
    """Move every object alive after collection out of the garbage collector's scans.

    The collected process holds several hundred thousand long-lived objects
    (numpy, SciPy, SymPy, the test modules), and every full collection walked
    them: the whole suite's 23 full collections took 8.2 s of CPU; with them
    frozen, 35 (the rest of the heap grows past the trigger sooner) took
    6.6 s (``gc.callbacks``, one process each, warm numba cache, load 3).
    Objects the tests make are collected as before (``gc.collect`` included);
    a frozen object is never freed, as none of these would be before exit.
    """
    gc.freeze()


def pytest_sessionfinish(session, exitstatus):
    """Collect the run's garbage once, then freeze what is left alive, as after collection.

    At exit pytest collects twice (its unraisable-exception check, in
    cleanup and in ``pytest_unconfigure``), and each full collection walked
    every object the tests left alive: 0.95 s of CPU each after the whole
    suite (cProfile).  One collection here, while pytest's hook for
    unraisable exceptions is still in place (what a ``__del__`` raises is
    reported as before), then the two find only what was made since.
    """
    gc.collect()
    gc.freeze()
# The no-wait rule off (mechcirc._jit): no detached numba warm-up processes (they would
# load the machine outside the suite's own accounting), and the kernels compiled
# in-process on first use, under the lock below, in the CLI subprocesses too;
# tests/test_startup.py and tests/test_nowait.py patch the rule's checks to test it.
os.environ.setdefault("MECHCIRC_NO_WARM", "1")


@pytest.fixture(autouse=True)
def _cwd_is_kept():
    """Every test leaves the working directory as it found it.

    A test that changed it for good (a monkeypatch.chdir undone to the wrong
    folder once did) would run the rest of its worker from elsewhere, and
    child processes started there import whatever ``mechcirc`` that folder holds.
    """
    before = os.getcwd()
    yield
    after = os.getcwd()
    if after != before:
        os.chdir(before)
        pytest.fail(f"the test left the working directory at {after} (was {before})")


def _once_per_run(tmp_path_factory, name, compute):
    """``compute()`` (JSON data) run once for the whole run, under xdist too.

    The first caller runs it and writes the result to ``cli-once-NAME.json`` in
    the run's base temporary folder; a worker that finds another computing it
    waits (a file lock) and reads that result instead of computing it again.
    """
    import json

    shared = tmp_path_factory.getbasetemp()
    if os.environ.get("PYTEST_XDIST_WORKER"):
        shared = shared.parent                  # the folder every worker of this run sees
    path = shared / f"cli-once-{name}.json"
    with _exclusive(shared / f"cli-once-{name}.lock"):
        if path.exists():
            return json.loads(path.read_text(encoding="utf-8"))
        done = compute()
        path.write_text(json.dumps(done), encoding="utf-8")
        return done


@contextlib.contextmanager
def _crosschecks_computed_once(computed):
    """While in effect, a sley or scene cross-check computed again with equal arguments is
    a deep copy of the first one's result (``computed``: pickled arguments -> result, and
    how many times it called ``on_step``, called as often again).

    ``crosscheck`` with ``--unit Hz`` or ``rpm`` or ``--json`` computes what the
    same command in rad/s computed (tests/test_unit18_crosscheck.py runs each scene and
    the sley preset three times: 4.3 s of CPU of 6.6): the command line's parsing, unit
    conversion and printing still run for each argv; only the computation, called with
    arguments equal to an earlier call's (pickled bytes equal; an option that changed
    them computes afresh), is not repeated.
    """
    import copy
    import pickle

    from mechcirc.scene import crosscheck as scene_crosscheck
    from mechcirc.sley import crosscheck as sley_crosscheck

    def once(compute):
        takes_steps = "on_step" in (compute.__kwdefaults__ or {})

        def call(*args, **kwargs):
            on_step = kwargs.pop("on_step", None)
            try:
                key = pickle.dumps((compute.__qualname__, args, sorted(kwargs.items())))
            except Exception:                   # not picklable: computed as usual
                key = None
            if key in computed:
                result, steps = computed[key]
                for _ in range(steps if on_step else 0):
                    on_step()
                return copy.deepcopy(result)
            steps = [0]

            def step():
                steps[0] += 1
                if on_step is not None:
                    on_step()

            result = compute(*args, on_step=step, **kwargs) if takes_steps else \
                compute(*args, **kwargs)
            if key is not None:
                computed[key] = (copy.deepcopy(result), steps[0])
            return result
        return call

    saved = [(m, name, getattr(m, name)) for m, name in
             ((sley_crosscheck, "crosscheck_sley"), (scene_crosscheck, "crosscheck_scene"))]
    for module, name, compute in saved:
        setattr(module, name, once(compute))
    try:
        yield
    finally:
        for module, name, compute in saved:
            setattr(module, name, compute)


@pytest.fixture(scope="session")
def cli_once(tmp_path_factory):
    """``cli_once(argv)``: (status, stdout, stderr) of ``mechcirc ARGV`` in-process, run once.

    For long commands (a full ``crosscheck``) that several test files check
    with the same argv: the first caller runs it, the others read the same
    output.  Under xdist the workers share it through a file in the run's
    base temporary folder (a worker that finds another running the command
    waits for its result instead of running it a second time).  Only for
    commands that read shipped inputs and nothing a test patches (no
    ``monkeypatch`` in effect while it runs).  While a command runs, a sley or scene
    cross-check with the arguments of one computed before is not computed again
    (:func:`_crosschecks_computed_once`): ``--unit`` and ``--json`` print what the
    rad/s command computed.
    """
    import hashlib
    import io
    import json

    from mechcirc.cli import main

    done: dict[tuple[str, ...], tuple[int, str, str]] = {}
    computed: dict[bytes, tuple[object, int]] = {}

    def execute(key):
        out, err = io.StringIO(), io.StringIO()
        with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err), \
                _crosschecks_computed_once(computed):
            try:
                status = main(list(key))
            except SystemExit as exc:
                status = exc.code
        return status, out.getvalue(), err.getvalue()

    def run(argv):
        key = tuple(map(str, argv))
        if key not in done:
            name = hashlib.sha256(json.dumps(key).encode()).hexdigest()[:16]
            done[key] = tuple(_once_per_run(tmp_path_factory, name, lambda: execute(key)))
        return done[key]

    return run


#: The statements a kernel module hands to ``mechcirc._jit.warm_in_background`` that are
#: not a module constant (``_WARM_STATEMENT``): the nodal and the tree kernels'.
WARM_NODAL = "from mechcirc.nodal import warm_kernels; warm_kernels()"
WARM_TREE = "from mechcirc._tree_eval import warm_kernel; warm_kernel()"

#: The key of ``warm_up_run`` under which the recording below is found.
RECORDED_NODAL = "nodal.warm_kernels, its kernel calls recorded"
# Run in the warm-up process before the statements: nodal.warm_kernels with every
# function of mechcirc._nodal_kernels recorded when called (the names, in RESULT);
# the functions are put back afterwards.
_RECORD_NODAL = """
from mechcirc import _nodal_kernels as k, nodal
called = set()
def recorder(name, f):
    def call(*a):
        called.add(name)
        return f(*a)
    return call
saved = {n: f for n, f in vars(k).items()
         if isinstance(f, type(recorder)) and f.__module__ == k.__name__}
for name, f in saved.items():
    setattr(k, name, recorder(name, f))
try:
    nodal.warm_kernels()
finally:
    for name, f in saved.items():
        setattr(k, name, f)
RESULT = sorted(called)
"""

# Each statement in a namespace of its own, its output captured; then the results as JSON.
_RUN_EACH = """
import contextlib, io, json, sys, traceback
out = {}
for statement in json.loads(sys.stdin.read()):
    namespace, shown = {"__name__": "__main__"}, io.StringIO()
    try:
        with contextlib.redirect_stdout(shown):
            exec(compile(statement, "<warm-up statement>", "exec"), namespace)
        error = None
    except BaseException:
        error = traceback.format_exc()[-2000:]
    out[statement] = {"error": error, "stdout": shown.getvalue(),
                      "result": namespace.get("RESULT")}
sys.stdout.write("\\n" + json.dumps(out))
"""


@pytest.fixture(scope="session")
def warm_up_run(tmp_path_factory):
    """``{statement: {"error", "stdout", "result"}}``: every warm-up statement run as the
    detached warm-up process runs it, with numba's JIT off (the same calls as plain Python,
    nothing compiled), all in one process for the run.

    Each statement runs in a fresh namespace, in turn, after the recording of
    nodal.warm_kernels' kernel calls (``_RECORD_NODAL``, under the key
    :data:`RECORDED_NODAL`, whose ``result`` is the names called); ``error`` is its
    traceback or None, ``stdout`` what it printed.  One process instead of five: each
    imported numpy, SciPy, numba and mechcirc again (about 0.4 s of CPU with .pyc files, more under the README's ``--no-compile``),
    and the statements' own work is small (all six in one process took 1.9 s of CPU,
    one at a time 5.0 s; load 4, 27 Nov).  A statement that needs an import it does
    not make could pass here after another statement made it: each statement imports
    what it calls (``from mechcirc.X import f; f()``), as the one process the warm-up
    statements of the time-domain kernels shared before did.
    """
    import json
    import subprocess
    import sys
    from pathlib import Path

    from mechcirc.kinematics import linkage_solver
    from mechcirc.scene import shaft
    from mechcirc.scene import simulation as scene_sim
    from mechcirc.transient import propagate as transient_sim

    root = Path(__file__).resolve().parents[1]
    statements = [_RECORD_NODAL, scene_sim._WARM_STATEMENT, linkage_solver._WARM_STATEMENT,
                  transient_sim._WARM_STATEMENT, shaft._WARM_STATEMENT, WARM_NODAL, WARM_TREE]

    def compute():
        env = {**os.environ, "NUMBA_DISABLE_JIT": "1", "PYTHONPATH": str(root)}
        done = subprocess.run([sys.executable, "-c", _RUN_EACH], input=json.dumps(statements),
                              cwd=root, env=env, capture_output=True, text=True, timeout=600)
        assert done.returncode == 0, done.stderr[-2000:]
        out = json.loads(done.stdout.rsplit("\n", 1)[-1])
        out[RECORDED_NODAL] = out.pop(_RECORD_NODAL)
        return out

    return _once_per_run(tmp_path_factory, "warm-up", compute)


# The steps of ``light_imports``, in this order, ``sys.modules`` read after each.
_LIGHT_IMPORTS = """
import json, signal, sys
sys.argv = ["mechcirc", "check"]          # the process named mechcirc (the signal check)
before = [repr(signal.getsignal(s)) for s in (signal.SIGINT, signal.SIGTERM)]
out = {}
import argparse
from mechcirc.cli import kinematics_commands
kinematics_commands.register(argparse.ArgumentParser().add_subparsers())
out["register kinematics"] = sorted(sys.modules)
import mechcirc, mechcirc.netlist, mechcirc.units
from mechcirc import cli
cli.build_parser()
out["build_parser"] = sorted(sys.modules)
out["mechcirc.__file__"] = mechcirc.__file__
import numpy as np
s = mechcirc.load("netlists/stb_heald.mcir").sweep(np.linspace(10, 1000, 400))
s.flags, s.error
out["sweep with flags"] = sorted(sys.modules)
import mechcirc.sley
out["import mechcirc.sley"] = sorted(sys.modules)
import mechcirc.kinematics
out["import mechcirc.kinematics"] = sorted(sys.modules)
[getattr(mechcirc, name) for name in mechcirc.__all__]
cli.build_parser()
out["signals"] = [before, [repr(signal.getsignal(s)) for s in (signal.SIGINT, signal.SIGTERM)]]
print(json.dumps(out))
"""


@pytest.fixture(scope="session")
def light_imports(tmp_path_factory):
    """What a fresh ``python`` process has imported after each step of ``_LIGHT_IMPORTS``
    (``{step: sorted sys.modules}``), and its SIGINT and SIGTERM handlers before any
    import and after the last step (``"signals"``), one process for the run.

    The steps, in turn: register the kinematics commands on a parser; import mechcirc
    (netlist, units) and build the command line's parser; load and sweep the bundled
    netlist with its flags and error bound; import mechcirc.sley; import
    mechcirc.kinematics; every public name of mechcirc and the parser again.  Modules
    only accumulate, so each list holds all its step imported, and what earlier steps
    imported is allowed for each later test: a test checks what a step does not load,
    and every step before it checks at least as much.  Seven processes before
    (tests/test_cli.py, test_cli_ux.py, test_interop_skrf.py, test_cli_common.py,
    test_startup.py, sley/test_simulation.py, two in kinematics/test_cli_kinematics.py),
    each paying the interpreter and numpy's import: 1.1 s of CPU here, more in CI.
    """
    import json
    import subprocess
    import sys
    from pathlib import Path

    from bounds import SUBPROCESS_TIMEOUT

    def compute():
        done = subprocess.run([sys.executable, "-c", _LIGHT_IMPORTS], capture_output=True,
                              text=True, cwd=Path(__file__).resolve().parents[1],
                              timeout=SUBPROCESS_TIMEOUT)
        assert done.returncode == 0, done.stderr[-2000:]
        return json.loads(done.stdout)

    return _once_per_run(tmp_path_factory, "light-imports", compute)


@contextlib.contextmanager
def _exclusive(lock_path):
    """Hold an exclusive lock on ``lock_path`` (one xdist worker at a time; none off POSIX)."""
    try:
        import fcntl
    except ImportError:
        yield
        return
    with open(lock_path, "a") as fh:
        fcntl.flock(fh, fcntl.LOCK_EX)
        try:
            yield
        finally:
            fcntl.flock(fh, fcntl.LOCK_UN)


#: CPU seconds this process spent in numba's compiler so far (outermost compiles only).
_COMPILE_CPU = [0.0]
#: With ``MECHCIRC_TEST_CPU``: one line per ``Dispatcher.compile`` call of the current test
#: (kernel, signature, compiled / loaded / had, CPU seconds, nesting depth).
_COMPILES: list[str] = []


def _wrap_numba_compile():
    """Count numba's compile CPU; with ``-n 2``, one compilation at a time across the workers.

    The kernels are compiled with ``cache=True``; numba looks in its disk
    cache, finds nothing, and compiles.  Two workers starting the same kernel
    together both compile it (about 45 s of CPU for every kernel in a fresh
    environment).  Under xdist a file lock around ``Dispatcher.compile`` makes
    the second worker wait and then load what the first wrote to the cache
    (the method checks the cache after taking the lock).  The CPU spent in the
    outermost ``compile`` (a cache load included) is added to
    :data:`_COMPILE_CPU`, so ``MECHCIRC_TEST_CPU`` can tell which test paid for
    a kernel's compilation.  Nothing changes in what is compiled or run;
    without numba this does nothing.
    """
    import importlib.util

    if importlib.util.find_spec("numba") is None:
        return
    try:
        import fcntl
    except ImportError:                             # not on this platform: no lock
        fcntl = None
    import tempfile
    import threading
    import time

    from numba.core.dispatcher import Dispatcher

    lock_path = None
    if os.environ.get("PYTEST_XDIST_WORKER") and fcntl is not None:
        lock_path = os.path.join(tempfile.gettempdir(),
                                 f"mechcirc-numba-{os.environ.get('PYTEST_XDIST_TESTRUNUID', 'x')}"
                                 ".lock")
    held = threading.local()
    compile_ = Dispatcher.compile

    def compile_one_at_a_time(self, sig):
        depth = getattr(held, "depth", 0)
        if depth:                                   # a callee, compiled under our lock
            held.depth = depth + 1
            try:
                return logged(self, sig)
            finally:
                held.depth -= 1
        with contextlib.ExitStack() as stack:
            if lock_path is not None:
                fh = stack.enter_context(open(lock_path, "a"))
                fcntl.flock(fh, fcntl.LOCK_EX)
                stack.callback(fcntl.flock, fh, fcntl.LOCK_UN)
            t0 = time.process_time()
            held.depth = 1
            try:
                return logged(self, sig)
            finally:
                held.depth = 0
                _COMPILE_CPU[0] += time.process_time() - t0

    def compile_logged(self, sig):
        """``compile``, noting in :data:`_COMPILES` whether it compiled or loaded from the cache."""
        before = sum(self._cache_misses.values()), sum(self._cache_hits.values())
        t0 = time.process_time()
        try:
            return compile_(self, sig)
        finally:
            fn = self.py_func
            missed = sum(self._cache_misses.values()) - before[0]
            hit = sum(self._cache_hits.values()) - before[1]
            what = "compiled" if missed else "loaded" if hit else "had"
            _COMPILES.append(f"{fn.__module__}.{fn.__qualname__}\t{sig}\t{what}"
                             f"\t{time.process_time() - t0:.3f}\t{held.depth}")

    logged = compile_logged if os.environ.get("MECHCIRC_TEST_CPU") else compile_
    Dispatcher.compile = compile_one_at_a_time


_wrap_numba_compile()



def _cpu_seconds():
    """(this process, its waited-for children) user + system CPU seconds so far."""
    import resource

    me, kids = (resource.getrusage(who) for who in (resource.RUSAGE_SELF,
                                                      resource.RUSAGE_CHILDREN))
    return me.ru_utime + me.ru_stime, kids.ru_utime + kids.ru_stime


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_protocol(item, nextitem):
    """With ``MECHCIRC_TEST_CPU=PATH``: the CPU seconds of every test, appended to PATH.

    One line per test (setup, call and teardown together): node id, CPU of
    the worker process, CPU of the subprocesses it waited for (a CLI or an
    example run by ``subprocess``), and the part of the worker's CPU spent
    compiling numba kernels (or loading them from numba's cache), tab-separated.  Each xdist worker writes
    its own ``PATH.<worker>`` file.  Off (nothing measured) without the
    variable; ``python tests/cpu_report.py PATH`` sums and ranks the files.
    """
    path = os.environ.get("MECHCIRC_TEST_CPU")
    if not path:
        yield
        return
    before, compiling = _cpu_seconds(), _COMPILE_CPU[0]
    yield
    after, compiled = _cpu_seconds(), _COMPILE_CPU[0] - compiling
    worker = os.environ.get("PYTEST_XDIST_WORKER", "main")
    with open(f"{path}.{worker}", "a", encoding="utf-8") as fh:
        fh.write(f"{item.nodeid}\t{after[0] - before[0]:.3f}\t{after[1] - before[1]:.3f}"
                 f"\t{compiled:.3f}\n")
    if _COMPILES:
        with open(f"{path}.{worker}.jit", "a", encoding="utf-8") as fh:
            fh.writelines(f"{item.nodeid}\t{line}\n" for line in _COMPILES)
        _COMPILES.clear()
