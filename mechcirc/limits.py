"""The bounds on work and memory that mechcirc enforces, in one place.

Each limit is refused *before* the work starts, with the limit named in the
message (:func:`check_count`).  docs/reliability.md gives the time and peak
memory measured at each limit.  The file-size bound of every input is
:data:`mechcirc.sources.MAX_INPUT_BYTES`; the netlist's statement and line
bounds are in :mod:`mechcirc.netlist`.
"""

from __future__ import annotations

from .errors import InputError

__all__ = ["MAX_SWEEP_POINTS", "MAX_PLOT_POINTS", "MAX_JSON_POINTS", "MAX_NODAL_POINTS",
           "MAX_ADAPTIVE_NODAL_POINTS", "MAX_STUDY_POINTS", "MAX_STUDY_SWEEP_POINTS",
           "MAX_STUDY_WORK", "MAX_REVOLUTIONS", "MAX_SCIPY_REVOLUTIONS",
           "MAX_POINTS_PER_REVOLUTION", "MAX_CYCLE_POINTS", "MAX_FORMULA_ELEMENTS",
           "FORMULA_SECONDS", "check_count"]

#: Frequency points of one sweep (results alone: about 70 bytes a point).
MAX_SWEEP_POINTS = 10_000_000
#: Points a plot draws (matplotlib needs ~300 bytes a point; a screen shows ~2,000).
MAX_PLOT_POINTS = 1_000_000
#: Points a ``--json`` document may hold (JSON text is ~200 bytes a point).
MAX_JSON_POINTS = 1_000_000
#: Points of a sweep by nodal analysis (a matrix per point while solving).
MAX_NODAL_POINTS = 1_000_000
#: Points of an adaptive sweep by nodal analysis (its refinement re-solves every midpoint).
MAX_ADAPTIVE_NODAL_POINTS = 2_000
#: Points (rows) of a parameter study.
MAX_STUDY_POINTS = 1_000_000
#: Frequency points of the sweep at each study point.
MAX_STUDY_SWEEP_POINTS = 100_000
#: Study points × sweep points (the whole study's frequency evaluations).
MAX_STUDY_WORK = 1_000_000_000
#: Revolutions a time-domain simulation integrates (compiled RK4).
MAX_REVOLUTIONS = 1_000
#: Revolutions with the scipy integrators (Python right-hand side, ~0.15 s each).
MAX_SCIPY_REVOLUTIONS = 100
#: Output points per revolution of a simulation.
MAX_POINTS_PER_REVOLUTION = 1_000_000
#: Crank angles of a scene's cycle map (~10 ms each).
MAX_CYCLE_POINTS = 3_600
#: Elements of a network that is not series–parallel for a symbolic formula.
MAX_FORMULA_ELEMENTS = 8
#: Seconds a symbolic formula may take before it is abandoned.
FORMULA_SECONDS = 20.0


def check_count(value, what: str, limit: int, *, least: int = 1, why: str = "") -> int:
    """``value`` as an int in ``least..limit``, or :class:`InputError` naming the limit."""
    if isinstance(value, bool) or not isinstance(value, int):
        try:
            as_float = float(value)
        except (TypeError, ValueError, OverflowError):
            raise InputError(f"{what} must be an integer, got {value!r}") from None
        if not as_float.is_integer():
            raise InputError(f"{what} must be an integer, got {value!r}")
        value = int(as_float)
    if value < least:
        raise InputError(f"{what} must be at least {least}, got {value}")
    if value > limit:
        shown = f"{value:,}" if value < 10**30 else f"about 1e{len(str(value)) - 1}"
        raise InputError(f"{what} is {shown}, the limit is {limit:,}" + (f" ({why})" if why
                                                                           else ""))
    return value
