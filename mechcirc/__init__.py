"""mechcirc: dynamic analysis of mechanisms with mechanical circuits.

Main entry points
-----------------
parse(text, source)   netlist text -> Circuit
load(path)            netlist file -> Circuit
Circuit.sweep(omega)  K(ω) = v/Q [m/(N·s)], Q0 = V0/K [N], per-element Q and v
Circuit.tree          the series–parallel reduction tree

Sub-packages (imported on use): ``mechcirc.kinematics`` (four-bar, synthesis,
planar linkages), ``mechcirc.sley`` (time-domain beat-up model).
"""

from .circuit import Circuit, Drive, Element, Lever
from .errors import (GeometryError, MechcircError, MechcircWarning, NetlistError,
                     SingularPointWarning, SolverError, TopologyError,
                     UnloadedElementWarning)
from .netlist import load, parse
from .sweep import Sweep
from . import _methods  # noqa: F401  (attaches Circuit.sweep, .tree, …; see there)

__all__ = [
    "parse", "load", "Circuit", "Element", "Lever", "Drive", "Sweep",
    "MechcircError", "NetlistError", "TopologyError", "GeometryError", "SolverError",
    "MechcircWarning", "UnloadedElementWarning", "SingularPointWarning",
]

__version__ = "0.1.0"
