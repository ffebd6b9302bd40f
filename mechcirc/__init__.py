"""mechcirc: dynamic analysis of mechanisms with mechanical circuits.

The method (K = v/Q, the element laws, series and parallel, levers) is in
``docs/theory.md``; a first session in ``docs/tutorial.md``.

Netlists and circuits
=====================

.. autosummary::

   parse            -- netlist text -> Circuit
   load             -- netlist file (.mcir) -> Circuit
   Circuit          -- elements, levers and one drive (plain data), with
                       .tree .unloaded .nodal .sweep() .resonances() .modes() .periodic()
                       .speed_map() .two_port() .formula()
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
   MechcircWarning, UnloadedElementWarning, UnitMixWarning
   (every class is in mechcirc.errors, under MechcircError or MechcircWarning)

The analysis methods of ``Circuit`` and ``Sweep.to_skrf`` are one-line
delegates written in their classes, importing their module when called.

``mechcirc.sweep`` and ``mechcirc.simplify`` are the functions; their modules
stay importable as ``importlib.import_module("mechcirc.sweep")`` and by
``from mechcirc.sweep import ...``.  Every public name (and every submodule,
``mechcirc.nodal`` say) is loaded on first use, so ``import mechcirc`` reads
no numpy and the command line is in charge of Ctrl-C from its first line.
"""

import importlib as _importlib
import importlib.util as _importlib_util
import sys as _sys
import types as _types

from .errors import (GeometryError, MechcircError, MechcircWarning, NetlistError,
                     NotSeriesParallelError, SolverError, TopologyError, UnitMixWarning,
                     UnloadedElementWarning)

__all__ = [
    "parse", "load", "Circuit", "Element", "Lever", "Drive", "Sweep", "sweep",
    "adaptive_sweep", "find_resonances", "Resonance", "simplify", "designs",
    "MechcircError", "NetlistError", "TopologyError", "NotSeriesParallelError",
    "GeometryError", "SolverError", "MechcircWarning", "UnloadedElementWarning",
    "UnitMixWarning",
]

__version__ = "0.1.0"

#: Public names loaded on first use: name -> (module, attribute).
_LAZY = {"parse": ("netlist", "parse"), "load": ("netlist", "load"),
         "Circuit": ("circuit", "Circuit"), "Element": ("circuit", "Element"),
         "Lever": ("circuit", "Lever"), "Drive": ("circuit", "Drive"),
         "Sweep": ("sweep", "Sweep"), "sweep": ("sweep", "sweep"),
         "find_resonances": ("resonances", "find_resonances"),
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
        elif not name.startswith("__") and _importlib_util.find_spec(f"{__name__}.{name}"):
            value = _importlib.import_module(f"{__name__}.{name}")       # a submodule
        else:
            raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
        _types.ModuleType.__setattr__(self, name, value)
        return value

    def __setattr__(self, name, value):
        # The import system binds a submodule on its parent when it is first
        # loaded; bind the function of that name instead.
        if name in _FUNCTIONS_OVER_MODULES and isinstance(value, _types.ModuleType):
            value = getattr(value, name)
        _types.ModuleType.__setattr__(self, name, value)

    def __dir__(self):
        return sorted(set(super().__dir__()) | set(_LAZY))


_sys.modules[__name__].__class__ = _Package
