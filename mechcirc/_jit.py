"""Optional compilation with numba, decided in one place for every kernel module.

:data:`COMPILED` is the one switch between a compiled kernel and the numpy code
it replaces: None (default) lets each caller decide (numba installed, enough
work to repay loading it), True always runs the kernel (as plain Python without
numba), False never (the numpy paths; tests compare the two).

The kernels (sley, scene motion, transients, contact laws) are plain Python
functions written in the subset numba compiles.  With the ``fast`` extra
installed they are compiled on first use (cached on disk); without it they run
as Python.  A kernel module asks for its decorators with
``HAVE_NUMBA, jit, jit_inline = decorators(force_python)``; tests load a fresh
copy of a kernel module with ``force_python`` set to compare both backends.
numba is imported here only when a kernel module is imported, never by
``import mechcirc``.

By default (``COMPILED`` None) a caller never waits for numba to compile:
it takes a kernel only when numba's disk cache holds it (:func:`in_cache`;
loading takes about 1 s, compiling 4–11 s of CPU), and otherwise runs its
numpy path while a detached Python process compiles the kernel into the
cache (:func:`warm_in_background`), for the next call or the next process.
A run far longer as Python than compiling (a scene's crosscheck:
``scene.simulation.kernels_for(long=True)``) takes the compiled kernels anyway.
A kernel counts as found there when the functions it calls are too, compiled on
this machine with their data files present (else its first call would compile
them in the process); they are loaded from the cache before it, as an
in-process compile has them.
The environment variable ``MECHCIRC_NO_WARM=1`` turns that rule off: no
detached process, and a kernel is compiled in-process on its first use, as
numba does by default (a cluster, or a run that would rather wait once than
run the slower path); the test suite sets it, for its subprocesses too.

While numba compiles (any function, in this process, once a kernel module is
loaded), Python's cyclic garbage collector runs less often (:data:`GC_THRESHOLD_COMPILING`
instead of its first threshold of 700 new objects, restored after the outermost compile):
numba's compiler makes and copies millions of small objects, and at the default the
collector took about 1.5 s of a 16 s cold compile of the scene kernels, for 23 MB
more at the compile's peak (docs/performance.md, "seventeenth session").
"""

from __future__ import annotations

import contextlib
import gc
import os
import sys
from pathlib import Path

__all__ = ["decorators", "internal", "COMPILED", "use", "in_cache", "warm_in_background"]

#: None: each caller decides; True: always the kernel; False: never (see above).
COMPILED: bool | None = None

#: The collector's first threshold (new container objects between two young collections)
#: while numba compiles; Python's default is 700.
GC_THRESHOLD_COMPILING = 10_000


def _identity(fn):
    return fn


def decorators(force_python: bool = False, nrt: bool = True):
    """``(have_numba, jit, jit_inline)`` for a kernel module.

    ``nrt=False``: for a kernel that allocates nothing and only reads and writes the
    arrays it is given (a right-hand side called millions of times): compiled without
    numba's reference counting, which otherwise costs an atomic increment and decrement
    of every array argument on every call (half the time of the scene's right-hand side).
    """
    if not force_python:
        try:
            from numba import njit
        except ImportError:          # the "fast" extra is not installed
            pass
        else:
            _collect_less_while_compiling()
            flags: dict = {} if nrt else {"_nrt": False}
            jit = njit(cache=True, error_model="numpy", **flags)     # (njit's decorators)
            jit_inline = njit(cache=True, error_model="numpy", inline="always")
            return True, jit, jit_inline
    return False, _identity, _identity


def internal(force_python: bool = False, nrt: bool = True):
    """The decorator of a helper that only kernels call (never a kernel's entry from Python).

    numba compiles it for each kernel that calls it (``numba.extending.register_jitable``:
    an overload of the plain function) without the CPython wrapper and the C-callable one
    a kernel of its own has, whose code each compiled caller links, optimises and emits
    again; called from Python it is the plain function.  The kernels that call it hold it
    in their own cache entries.  ``nrt=False`` as for :func:`decorators`.
    """
    if not decorators(force_python)[0]:         # without numba: the plain function
        return _identity
    from numba.extending import register_jitable

    return register_jitable(error_model="numpy", **({} if nrt else {"_nrt": False}))


_GC_RULE: list = []


def _collect_less_while_compiling() -> None:
    """Have numba's compile events (once per process) raise the collector's first threshold
    to :data:`GC_THRESHOLD_COMPILING` for the outermost compile, then put it back."""
    if _GC_RULE:
        return
    from numba.core import event

    class Rule(event.Listener):
        depth = 0
        saved = (700, 10, 10)

        def on_start(self, ev):
            if self.depth == 0:
                self.saved = gc.get_threshold()
                gc.set_threshold(max(self.saved[0], GC_THRESHOLD_COMPILING), *self.saved[1:])
            self.depth += 1

        def on_end(self, ev):
            self.depth -= 1
            if self.depth == 0:
                gc.set_threshold(*self.saved)

    _GC_RULE.append(Rule())
    event.register("numba:compile", _GC_RULE[0])


def load(name: str, **flags):
    """A fresh copy of the module ``name`` run with ``flags`` set in its globals.

    A kernel module reads its flags (``_FORCE_PYTHON``, ``_COMPILE``) before
    it decorates its functions: a copy loaded with them set is the same text
    compiled, or run as Python, beside the module as normally imported.
    """
    import importlib.util

    spec = importlib.util.find_spec(name)
    if spec is None or spec.loader is None:
        raise ImportError(f"no module {name!r} to load")
    module = importlib.util.module_from_spec(spec)
    module.__dict__.update(flags)
    spec.loader.exec_module(module)
    return module


def use(statement: str, *dispatchers) -> bool:
    """Whether a caller runs these compiled kernels (numba installed) rather than its other path.

    True where :data:`COMPILED` is True, False where it is False; where it is None
    (default), whether numba's disk cache holds them (:func:`in_cache`), and where it
    does not, ``statement`` compiles them in a detached process (:func:`warm_in_background`).
    Where they are used and cached, their callees are loaded first (:func:`in_cache`).
    """
    if COMPILED is False:
        return False
    if in_cache(*dispatchers) or COMPILED:
        return True
    warm_in_background(statement)
    return False


def in_cache(*dispatchers) -> bool:
    """Whether numba's disk cache holds each of these compiled functions for its current source.

    Parameters
    ----------
    *dispatchers : numba Dispatcher
        Functions decorated with ``njit(cache=True)``; nothing is compiled.  Those
        found there have the functions they call loaded first.

    Returns
    -------
    bool
        True if every one, and every function it calls, is in the cache for this
        machine with its data file (or already in the process); True also where
        the cache cannot be asked (numba's private layout changed) or
        ``MECHCIRC_NO_WARM`` is set: the caller then loads, or compiles, as it
        would without the check.
    """
    try:
        for d in dispatchers:
            if d not in _IN_CACHE:      # index reads (~0.1 ms each) once per process
                todo = [(c, _held(c)) for c in [*_callees(d), d]
                        if not (c.overloads or _inlined(c))]
                if not all(sigs for _, sigs in todo):
                    return os.environ.get("MECHCIRC_NO_WARM", "") not in ("", "0")
                # A cached kernel's object code holds its own copies of the functions it
                # calls (weak symbols), used unless the process already holds them: loaded
                # alone it ran them from there, up to 1.4x slower than compiled in the
                # process (docs/performance.md, "a kernel loaded from the cache").  So its
                # callees are loaded first, each after its own.
                for c, sigs in todo:
                    for sig in sigs if c is not d else ():
                        c.compile(sig)
                _IN_CACHE.add(d)
        return True
    except Exception:
        return True


def _callees(caller) -> list:
    """The compiled functions ``caller`` calls, directly or not, each after its own callees."""
    found: list = []
    for d in map(caller.py_func.__globals__.get, caller.py_func.__code__.co_names):
        if isinstance(d, type(caller)) and d not in found:
            found += [c for c in _callees(d) if c not in found] + [d]
    return found


def _inlined(d) -> bool:
    """Whether ``d`` is only copied into its callers (``inline="always"``): never cached alone."""
    return d.targetoptions.get("inline") == "always"


def _held(d) -> list:
    """The signatures numba's cache holds for ``d`` compiled on this machine, data file present.

    An index entry whose data file is gone (or another machine's entry) would have
    ``d`` compiled in the process on its first call: the wait :func:`use` avoids.
    """
    index, codegen = d._cache._cache_file, d.targetctx.codegen()
    return [key[0] for key, name in index._load_index().items()
            if key == d._cache._index_key(key[0], codegen)
            and os.path.exists(index._data_path(name))]


#: The dispatchers :func:`in_cache` has found in the cache (their source cannot change
#: while this process runs, so they stay there).
_IN_CACHE: set = set()


_WARMING: set = set()


def warm_in_background(statement: str) -> None:
    """Run ``statement`` in a detached Python process of its own, once per statement and process.

    Parameters
    ----------
    statement : str
        Python code (a constant of the caller, never user text) that compiles
        kernels into numba's disk cache; its output is discarded and nobody
        waits for it.
    """
    import site
    import subprocess

    if (statement in _WARMING or getattr(sys, "frozen", False) or not sys.executable
            or os.environ.get("MECHCIRC_NO_WARM", "") not in ("", "0")):
        return              # (a frozen application's executable is not a Python)
    _WARMING.add(statement)

    env = dict(os.environ)
    # The child imports this copy of mechcirc: a checkout goes first on its path
    # (an installed copy is found as it is; its site directory is not put
    # ahead of the standard library).
    here = str(Path(__file__).resolve().parents[1])
    sites = {str(Path(d).resolve()) for d in [*site.getsitepackages(), site.getusersitepackages()]}
    if here not in sites:
        env["PYTHONPATH"] = os.pathsep.join(p for p in (here, env.get("PYTHONPATH")) if p)
    with contextlib.suppress(OSError):      # no process to spare: the numpy path goes on
        subprocess.Popen([sys.executable, "-c", statement], env=env,
                         stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL,
                         stderr=subprocess.DEVNULL, start_new_session=True)
