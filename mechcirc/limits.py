"""The bounds on work and memory that mechcirc enforces, in one place.

Each limit is refused *before* the work starts, with the limit named in the
message.  docs/reliability.md gives the time and peak
memory measured at each limit.  The file-size bound of every input is
:data:`mechcirc.sources.MAX_INPUT_BYTES`; the netlist's statement and line
bounds are in :mod:`mechcirc.netlist`.
"""

from __future__ import annotations

__all__ = ["MAX_SWEEP_POINTS", "MAX_PLOT_POINTS", "MAX_JSON_POINTS", "MAX_NODAL_POINTS",
           "MAX_ADAPTIVE_POINTS", "MAX_ADAPTIVE_NODAL_POINTS", "MAX_ADAPTIVE_WORK",
           "MAX_ADAPTIVE_NODAL_WORK", "MAX_STUDY_POINTS", "MAX_STUDY_SWEEP_POINTS",
           "MAX_STUDY_WORK", "MAX_REVOLUTIONS", "MAX_SCIPY_REVOLUTIONS",
           "MAX_POINTS_PER_REVOLUTION", "MAX_CYCLE_POINTS", "MAX_FORMULA_ELEMENTS",
           "FORMULA_SECONDS", "METHODS", "SCIPY_METHODS"]

#: Frequency points of one sweep (results alone: about 70 bytes a point).
MAX_SWEEP_POINTS = 10_000_000
#: Points a plot draws (matplotlib needs ~300 bytes a point; a screen shows ~2,000).
MAX_PLOT_POINTS = 1_000_000
#: Points a ``--json`` document may hold (JSON text is ~200 bytes a point).
MAX_JSON_POINTS = 1_000_000
#: Points of a sweep by nodal analysis (~0.2 ms a point on the bundled netlist: 10⁶ took over 4 min).
MAX_NODAL_POINTS = 100_000
#: Points of an adaptive sweep (``mechcirc.adaptive.adaptive_sweep``'s default budget).
MAX_ADAPTIVE_POINTS = 20_000
#: Points of an adaptive sweep by nodal analysis.
MAX_ADAPTIVE_NODAL_POINTS = 2_000
#: K evaluations × (elements + levers) of an adaptive sweep on the series–parallel tree
#: (5–50 ns each measured: a 4,000-element ladder gets 16,666 points, ≤ 10 s).
MAX_ADAPTIVE_WORK = 200_000_000
#: The same by nodal analysis (0.5–1.2 µs per element and point measured: ≤ 12 s).
MAX_ADAPTIVE_NODAL_WORK = 10_000_000
#: Points (rows) of a parameter study.  A study written to a file streams its rows
#: (about 0.2 kB a point held: the spec's values; see docs/performance.md); rows
#: returned in memory (the API's default, the CLI's --json and --plot) take about
#: 1.1 kB each.
MAX_STUDY_POINTS = 1_000_000
#: Frequency points of the sweep at each study point.
MAX_STUDY_SWEEP_POINTS = 100_000
#: Study points × sweep points (the whole study's frequency evaluations).
MAX_STUDY_WORK = 1_000_000_000
#: The integrators of a time-domain simulation (scene, sley): the fixed-step RK4 kernel
#: (numba, or pure Python), RK8, and scipy's adaptive ones, whose bound below is lower.
METHODS = ("rk4", "rk4-python", "rk8", "DOP853", "RK45", "LSODA")
SCIPY_METHODS = ("DOP853", "RK45", "LSODA")
#: Revolutions a time-domain simulation integrates (compiled RK4).
MAX_REVOLUTIONS = 1_000
#: Revolutions with the scipy integrators (Python right-hand side: 100 took 31 s here).
MAX_SCIPY_REVOLUTIONS = 100
#: Output points per revolution of a simulation.
MAX_POINTS_PER_REVOLUTION = 1_000_000
#: Crank angles of a scene's cycle map (a step of 0.25°; 10–25 ms each: 3,600 took 95 s under load).
MAX_CYCLE_POINTS = 1_440
#: Elements (and levers) of a network without a series–parallel tree whose symbolic
#: formula is attempted (its size grows with the number of spanning trees).
MAX_FORMULA_ELEMENTS = 12
#: CPU seconds (not wall clock: the same on a loaded machine) a symbolic formula may
#: use before it is abandoned (``cli._common.time_limit``).
FORMULA_SECONDS = 20.0

