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

from .circuit import Circuit, Drive, Element, Lever  # noqa: E402
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
