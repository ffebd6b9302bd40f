"""Parameter studies: a grid, a sample or a file of designs over a netlist's ``.param`` values.

A study is described by a TOML file (``mechcirc study SPEC.toml``)::

    netlist = "../netlists/stb_heald.mcir"   # relative to this file
    analysis = "sweep"                       # or "resonances"

    [omega]                  # the sweep at each point (analysis = "sweep")
    min = 10                 # rad/s; or a string with a unit: "5Hz", "300rpm"
    max = "1500Hz"
    points = 400
    log = true

    [grid]                   # every combination (full factorial) ...
    eta1 = [0.7, 0.8, 0.9]                    # listed values
    eta2 = {min = 1.0, max = 1.5, num = 6}    # evenly spaced (log = true: geometric)

    # ... or a sample of n points in a box (uniform, or log-uniform with log = true)
    # [sample]
    # method = "sobol"        # "random" (default), "latin-hypercube" or "sobol"
    # n = 1024
    # seed = 1
    # [sample.params]
    # eta1 = {min = 0.6, max = 1.0}
    # ([random] with n, seed, params is method = "random")

    # ... or your own points: a CSV (or Parquet) file, a header row naming the
    # parameters, a row per point; every cell checked (file:line:col errors)
    # [sample]
    # file = "designs.csv"

    # analysis = "resonances": how many of each kind to tabulate, and up to where
    # resonances = 3
    # omega_max = 5000

A study of the sley model (:mod:`mechcirc.sley`) varies a preset's
:class:`~mechcirc.sley.SleyParameters` fields instead, and needs no netlist::

    analysis = "simulate"
    [sley]
    drive = "one-side"       # Table 1; "both-sides" for Table 2
    variant = 3
    revolutions = 3
    points_per_revolution = 720
    [grid]
    C2 = {min = 2e4, max = 8e4, num = 4}     # N·m/rad
    omega = [90.0, 100.0, 110.0]            # rad/s

The points of a task are one batch of designs (:func:`mechcirc.batch.designs`):
the netlist is parsed once and its ``.param`` expressions evaluated over the
points' values, so parameters defined from them follow, as with
:func:`mechcirc.parse` ``params=``.  Values are SI.  A point that fails (a negative
mass, a singular network) is a row with ``status = "error"`` and the message,
never dropped.

Columns: ``index``, the parameters, ``status``, ``error``, then for a sweep
``K_abs_min omega_at_K_min K_abs_max omega_at_K_max Q0_abs_max omega_at_Q0_max
n_flagged`` [m/(N·s), rad/s, m/(N·s), rad/s, N, rad/s, 1]: the true extremes over
the band (:meth:`mechcirc.batch.Designs.extremes`), not grid samples — ``0``
or ``inf`` with the ω of the first zero or pole of K when the band holds an
undamped one — and the number of flagged grid points; for resonances
``resonance_1..N`` and ``antiresonance_1..N`` [rad/s]
(NaN where there are fewer; an error row leaves every result empty), for a
sley simulation the minimum and maximum over the tabulated revolution of
``eps2P eps4P eps4T`` [rad/s²] and ``M2V`` [N·m] (both-sides drive: also
``eps5P M5V``), e.g. ``eps4P_min``.

Execution: all local cores (``concurrent.futures.ProcessPoolExecutor``) by
default, or an existing Dask cluster (``scheduler="tcp://host:8786"``;
``dask.distributed`` is imported only then).  Points go out in batches;
finished rows are journalled (each with a checksum) to ``OUTPUT.partial.csv``
as they arrive, so an interrupted study keeps them, and ``resume=True`` runs
only the points the journal lacks or holds incomplete, refusing a journal
(or finished output) made from another spec.  At the end the output (CSV, or
``.parquet`` with pyarrow) is written whole in index order (atomically) and
the journal removed; until then an existing output is left as it was.
``OUTPUT.lock`` keeps a second study from writing the same output.  Local and
cluster runs give identical tables: each point is computed the same way,
whatever runs it.

Provenance: :attr:`StudySpec.canonical` is the resolved spec as canonical JSON
(the netlist and a sample file by their SHA-256) and :attr:`StudySpec.sha256`
its hash; the journal's first line, a Parquet output's metadata and a CSV
output's sidecar ``OUTPUT.meta.json`` (:func:`provenance`) record them, with
the spec's text and the unit of every column (:func:`column_units`).
"""

from .executors import StudyResult, run_study
from .journal import journal_path, provenance, read_rows, sidecar_path
from .rows import run_batch
from .spec import SAMPLE_METHODS, StudySpec, column_units, load_spec, parse_spec

__all__ = ["StudySpec", "load_spec", "parse_spec", "run_batch",
           "run_study", "StudyResult", "read_rows", "journal_path", "sidecar_path",
           "provenance", "column_units", "SAMPLE_METHODS"]
