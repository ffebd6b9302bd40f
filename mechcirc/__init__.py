"""mechcirc: dynamic analysis of mechanisms with mechanical circuits.

The method (K = v/Q, the element laws, series and parallel, levers) is in
``docs/theory.md``; a first session in ``docs/tutorial.md``.

Netlists and circuits
=====================

.. autosummary::

   parse            -- netlist text -> Circuit
   load             -- netlist file (.mcir) -> Circuit
   Circuit          -- elements, levers and one drive (plain data), with
                       .tree .unloaded .nodal .sweep() .resonances() .two_port() .formula()
   Element, Lever, Drive

Frequency domain
================

   sweep            -- K(ω) = v/Q [m/(N·s)], Q0 = V0/K [N] over ω: a Sweep
   Sweep            -- the result: .omega .K .Q0 .v0 .flags .error .force() .velocity() .plot()
                       .to_skrf()
   adaptive_sweep   -- a grid refined around resonances and bends of |K|, |Q0|
   find_resonances  -- exact resonances (K = 0) and antiresonances (K = ∞)
   designs          -- D designs of one netlist (.param arrays): K, resonances, extremes at once
   Resonance        -- one of them: kind, omega, omega_d, zeta, error
   simplify         -- model reduction over a band, with the measured error

Sub-packages and modules (imported on use)
==========================================

   mechcirc.plotting     -- plot_sweep, plot_forces, plot_comparison, plot_study (ax=/fig=)
   mechcirc.forces       -- element_forces: the force table at one ω
   mechcirc.units        -- parse_quantity: the one unit grammar (docs/units.md)
   mechcirc.kinematics   -- four-bar, beat-up synthesis, frame loading, planar linkages
   mechcirc.scene        -- linkage + masses + elastic links -> circuit at any crank angle
   mechcirc.sley         -- time-domain beat-up model (Mrázek)
   mechcirc.study        -- parameter studies (local cores or Dask)
   mechcirc.interop      -- scikit-rf / Touchstone, SymPy formulas

Errors and warnings
===================

   MechcircError, NetlistError (file:line:col), TopologyError,
   NotSeriesParallelError, GeometryError, SolverError,
   MechcircWarning, UnloadedElementWarning, SingularPointWarning, UnitMixWarning

The analysis methods of ``Circuit`` and ``Sweep.to_skrf`` are defined in the
top layer (``mechcirc._methods``, which says why) and attached on import, so
that ``circuit.py`` imports nothing above it; ``help(mechcirc.Circuit)`` lists them.

``mechcirc.sweep`` and ``mechcirc.simplify`` are the functions; their modules
stay importable as ``importlib.import_module("mechcirc.sweep")`` and by
``from mechcirc.sweep import ...``.  ``find_resonances``, ``adaptive_sweep``
and ``simplify`` are loaded on first use, so ``import mechcirc`` stays fast.
"""

def _starting_the_command_line() -> bool:
    """This process is ``mechcirc ...`` or ``python -m mechcirc ...`` (not a library user)."""
    import os
    import sys

    argv = getattr(sys, "orig_argv", sys.argv)
    if any(a == "-m" and b == "mechcirc" for a, b in zip(argv, argv[1:])):
        return True
    return bool(sys.argv) and os.path.basename(sys.argv[0]) in ("mechcirc", "mechcirc.exe")


if _starting_the_command_line():
    # Ctrl-C while the command line is still starting (before its own handler
    # is in place) ends it quietly, as after start-up: no traceback.
    # cli.main() restores Python's default handler.
    import signal as _signal

    def _interrupted_while_starting(signum, frame):
        import os
        import sys

        sys.stderr.write("mechcirc: interrupted\n")
        os._exit(130)

    _signal.signal(_signal.SIGINT, _interrupted_while_starting)

import importlib as _importlib  # noqa: E402
import types as _types
import sys as _sys

from .circuit import Circuit, Drive, Element, Lever
from .errors import (GeometryError, MechcircError, MechcircWarning, NetlistError,
                     NotSeriesParallelError, SingularPointWarning, SolverError, TopologyError,
                     UnitMixWarning, UnloadedElementWarning)
from .netlist import load, parse
from .sweep import Sweep
from .sweep import sweep
from . import _methods  # noqa: F401  (attaches Circuit.sweep, .tree, …; see there)

__all__ = [
    "parse", "load", "Circuit", "Element", "Lever", "Drive", "Sweep", "sweep",
    "adaptive_sweep", "find_resonances", "Resonance", "simplify", "designs",
    "MechcircError", "NetlistError", "TopologyError", "NotSeriesParallelError",
    "GeometryError", "SolverError", "MechcircWarning", "UnloadedElementWarning",
    "SingularPointWarning", "UnitMixWarning",
]

__version__ = "0.1.0"

#: Public names loaded on first use: name -> (module, attribute).
_LAZY = {"find_resonances": ("resonances", "find_resonances"),
         "Resonance": ("resonances", "Resonance"),
         "adaptive_sweep": ("adaptive", "adaptive_sweep"),
         "simplify": ("simplify", "simplify"),
         "designs": ("batch", "designs")}
#: Names that are both a function here and a submodule: the package attribute
#: is the function, whatever order the submodule is imported in.
_FUNCTIONS_OVER_MODULES = ("sweep", "simplify")


class _Package(_types.ModuleType):
    def __getattr__(self, name):
        if name in _LAZY:
            module, attr = _LAZY[name]
            value = getattr(_importlib.import_module(f"{__name__}.{module}"), attr)
            _types.ModuleType.__setattr__(self, name, value)
            return value
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")

    def __setattr__(self, name, value):
        # The import system binds a submodule on its parent when it is first
        # loaded; keep the function bound under that name instead.
        if name in _FUNCTIONS_OVER_MODULES and isinstance(value, _types.ModuleType):
            if name == "simplify":      # the function is not loaded yet: load it now
                _types.ModuleType.__setattr__(self, name, value.simplify)
            return
        _types.ModuleType.__setattr__(self, name, value)

    def __dir__(self):
        return sorted(set(super().__dir__()) | set(_LAZY))


_sys.modules[__name__].__class__ = _Package
