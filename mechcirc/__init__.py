"""mechcirc: dynamic analysis of mechanisms with mechanical circuits."""

from .errors import (GeometryError, MechcircError, MechcircWarning, NetlistError,
                     SingularPointWarning, SolverError, TopologyError,
                     UnloadedElementWarning)

__version__ = "0.1.0"
