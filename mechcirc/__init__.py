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
   FLAG_OK, FLAG_SINGULAR, FLAG_NEAR_SINGULAR -- the values of Sweep.flags
   peak, Peak       -- the exact maximum of |Q0| between grid points
   adaptive_sweep   -- a grid refined around resonances and bends of |K|, |Q0|
   find_resonances  -- exact resonances (K = 0) and antiresonances (K = ∞)
   designs          -- D designs of one netlist (.param arrays): K, resonances, extremes at once
   Resonance        -- one of them: kind, omega, omega_d, zeta, error
   simplify         -- model reduction over a band, with the measured error
   parse_band       -- "W1:W2" -> the band (W1, W2) [rad/s] of simplify

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
   NotSeriesParallelError, GeometryError, SolverError, BandError,
   MechcircWarning, UnloadedElementWarning, UnitMixWarning
   (every class is in mechcirc.errors, under MechcircError or MechcircWarning)

The analysis methods of ``Circuit`` and ``Sweep.to_skrf`` are one-line
delegates written in their classes, importing their module when called.

The implementation modules of ``sweep`` and ``simplify`` are private
(``mechcirc._sweep``, ``mechcirc._simplify``), so that no module shadows a
function of this index.  Every public name (and every submodule,
``mechcirc.nodal`` say) is loaded on first use (a module ``__getattr__``), so
``import mechcirc`` reads no numpy.
"""

import importlib as _importlib
import importlib.util as _importlib_util

from .errors import (BandError, GeometryError, MechcircError, MechcircWarning, NetlistError,
                     NotSeriesParallelError, SolverError, TopologyError, UnitMixWarning,
                     UnloadedElementWarning)

__version__ = "0.1.0"

#: Public names loaded on first use: name -> its module, in the order of __all__.
_LAZY = {name: module for module, names in (
    ("netlist", ("parse", "load")), ("circuit", ("Circuit", "Element", "Lever", "Drive")),
    ("_sweep", ("Sweep", "sweep", "FLAG_OK", "FLAG_SINGULAR", "FLAG_NEAR_SINGULAR", "peak",
                "Peak")),
    ("adaptive", ("adaptive_sweep",)), ("resonances", ("find_resonances", "Resonance")),
    ("_simplify", ("simplify", "parse_band")), ("batch", ("designs",))) for name in names}

__all__ = [*_LAZY, "MechcircError", "NetlistError", "TopologyError", "NotSeriesParallelError",
           "GeometryError", "SolverError", "BandError", "MechcircWarning",
           "UnloadedElementWarning", "UnitMixWarning"]


def __getattr__(name):
    """A public name or a submodule, imported on first use (PEP 562)."""
    if name in _LAZY:
        value = getattr(_importlib.import_module(f"{__name__}.{_LAZY[name]}"), name)
    elif not name.startswith("__") and _importlib_util.find_spec(f"{__name__}.{name}"):
        value = _importlib.import_module(f"{__name__}.{name}")       # a submodule
    else:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    globals()[name] = value
    return value


def __dir__():
    return sorted(set(globals()) | set(_LAZY))
