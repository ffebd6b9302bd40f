"""Parameter studies: a grid or a random sample over a netlist's ``.param`` values.

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

    # ... or a random sample (uniform, or log-uniform with log = true)
    # [random]
    # n = 1000
    # seed = 1
    # [random.params]
    # eta1 = {min = 0.6, max = 1.0}

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
(empty where there are fewer), for a sley simulation the minimum and maximum
over the tabulated revolution of ``eps2P eps4P eps4T`` [1/s²] and ``M2V``
[N·m] (both-sides drive: also ``eps5P M5V``), e.g. ``eps4P_min``.

Execution: all local cores (``concurrent.futures.ProcessPoolExecutor``) by
default, or an existing Dask cluster (``scheduler="tcp://host:8786"``;
``dask.distributed`` is imported only then).  Points go out in batches;
finished rows are journalled (each with a checksum) to ``OUTPUT.partial.csv``
as they arrive, so an interrupted study keeps them, and ``resume=True`` runs
only the points the journal lacks or holds incomplete.  At the end the output
(CSV, or ``.parquet`` with pyarrow) is written whole in index order
(atomically) and the journal removed; until then an existing output is
left as it was.  Local and
cluster runs give identical tables: each point is computed the same way,
whatever runs it.
"""

from __future__ import annotations

import csv
import itertools
import math
import os
import random
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable, Iterable

from .errors import MechcircError, NetlistError
from .limits import (MAX_POINTS_PER_REVOLUTION, MAX_REVOLUTIONS, MAX_STUDY_POINTS,
                     MAX_STUDY_SWEEP_POINTS, MAX_STUDY_WORK)
from .sources import (Table, brief, finite_number, load_toml, locate_path, number_error,
                      unknown_key)

__all__ = ["StudySpec", "load_spec", "parse_spec", "study_points", "run_point", "run_batch",
           "run_study", "StudyResult", "read_rows", "journal_path"]

_SWEEP_COLUMNS = ["K_abs_min", "omega_at_K_min", "K_abs_max", "omega_at_K_max", "Q0_abs_max",
                  "omega_at_Q0_max", "n_flagged"]
_SLEY_QUANTITIES = {"one-side": ["eps2P", "eps4P", "eps4T", "M2V"],
                    "both-sides": ["eps2P", "eps4P", "eps4T", "M2V", "eps5P", "M5V"]}


@dataclass(frozen=True)
class StudySpec:
    """A parsed study: the netlist text, the analysis and the points' parameter values."""

    netlist_text: str
    netlist_source: str
    analysis: str
    params: tuple[str, ...]
    points: tuple[tuple[float, ...], ...]
    omega: tuple[float, float, int, bool] | None = None
    n_resonances: int = 3
    omega_max: float | None = None
    spec_source: str = "<spec>"
    #: ``analysis = "simulate"``: (drive, variant, revolutions, points_per_revolution).
    sley: tuple | None = None

    @property
    def columns(self) -> list[str]:
        """The table's columns, in order."""
        head = ["index", *self.params, "status", "error"]
        if self.analysis == "sweep":
            return head + _SWEEP_COLUMNS
        if self.analysis == "simulate":
            return head + [f"{q}_{end}" for q in _SLEY_QUANTITIES[self.sley[0]]
                           for end in ("min", "max")]
        n = self.n_resonances
        return head + [f"resonance_{i}" for i in range(1, n + 1)] + \
            [f"antiresonance_{i}" for i in range(1, n + 1)]


class _SpecError(Exception):
    """A fault in a study description, with the TOML key path it belongs to."""

    def __init__(self, message: str, path: tuple):
        super().__init__(message)
        self.message, self.path = message, tuple(str(p) for p in path)


def _fail(path, message: str):
    raise _SpecError(message, tuple(path))


def _omega(path, value, what) -> float:
    from .units import parse_omega

    if isinstance(value, bool):
        _fail(path, f"{what} must be a number [rad/s] or a string such as '50Hz'")
    if isinstance(value, (int, float)):
        if not finite_number(value):
            _fail(path, f"{what} must be a finite number [rad/s], got {brief(value)}")
        return float(value)
    if isinstance(value, str):
        try:
            w = parse_omega(value)
        except ValueError as exc:
            _fail(path, f"{what}: {exc}")
        if not math.isfinite(w):
            _fail(path, f"{what} must be finite, got {brief(value)}")
        return w
    _fail(path, f"{what} must be a number [rad/s] or a string such as '50Hz', "
                f"got {brief(value)}")


def _number(path, value, what) -> float:
    bad = number_error(value, what)
    if bad:
        _fail(path, bad[0])
    return float(value)


def _integer(path, value, what, lo, hi) -> int:
    if isinstance(value, bool) or not isinstance(value, int) or not lo <= value <= hi:
        _fail(path, f"{what} must be an integer from {lo} to {hi:,}, got {brief(value)}")
    return value


def _axis_length(name, value) -> int:
    """How many values the axis ``grid.NAME`` has, checked before any is made."""
    path = ("grid", name)
    if isinstance(value, list):
        if not value:
            _fail(path, f"grid.{name} is an empty list")
        return len(value)
    if isinstance(value, dict):
        extra = set(value) - {"min", "max", "num", "log"}
        if extra or not {"min", "max", "num"} <= set(value):
            _fail(path, f"grid.{name} needs min, max and num (and optionally log), got "
                        f"{', '.join(sorted(map(str, value)))}")
        return _integer((*path, "num"), value["num"], f"grid.{name}.num", 1, MAX_POINTS)
    _fail(path, f"grid.{name} must be a list of values or {{min, max, num}}, "
                f"got {brief(value)}")


def _axis(name, value) -> list[float]:
    path = ("grid", name)
    if isinstance(value, list):
        return [_number(path, v, f"grid.{name}") for v in value]
    lo = _number((*path, "min"), value["min"], f"grid.{name}.min")
    hi = _number((*path, "max"), value["max"], f"grid.{name}.max")
    num = value["num"]
    import numpy as np

    if value.get("log", False):
        if lo <= 0 or hi <= 0:
            _fail((*path, "log"), f"grid.{name}: log spacing needs min and max > 0")
        return [float(x) for x in np.geomspace(lo, hi, num)]
    return [float(x) for x in np.linspace(lo, hi, num)]


#: The largest number of points (rows) a study may have; each row holds ~1 kB
#: while the study runs (docs/reliability.md).
MAX_POINTS = MAX_STUDY_POINTS


def parse_spec(data: dict, *, source: str = "<spec>", base: Path | None = None,
               text: str | None = None) -> StudySpec:
    """Check a study description (the TOML file's content) and build its points.

    ``text`` is the TOML text ``data`` was read from; with it, errors carry
    the line and column of the key at fault.

    Raises
    ------
    NetlistError
        With ``text``: at file:line:col, naming the key and what would be right.
    MechcircError
        Without ``text``: the same message after the source's name.
    """
    try:
        return _parse_spec(data, source, base or Path("."))
    except _SpecError as exc:
        if text is None:
            raise MechcircError(f"{source}: {exc.message}") from None
        line, col = locate_path(text, exc.path) if exc.path else (0, 0)
        raise NetlistError(exc.message, source, line, col) from None


#: The tables of a study file, declared once (see :class:`mechcirc.sources.Table`);
#: ``[grid]`` and ``[random.params]`` map the parameters' names.
TABLES = {
    None: Table(None, {"analysis": "\"sweep\", \"resonances\" or \"simulate\"",
                       "grid": "[grid]: NAME = [values] or {min, max, num[, log]}",
                       "netlist": "the netlist's path, relative to the spec file",
                       "omega": "[omega]: the sweep (analysis = \"sweep\")",
                       "omega_max": "highest resonance sought [rad/s]",
                       "random": "[random]: n, seed, params",
                       "resonances": "how many of each kind to tabulate",
                       "sley": "[sley]: the preset (analysis = \"simulate\")"}),
    "omega": Table("omega", {"min": "[rad/s] or \"5Hz\"", "max": "[rad/s] or \"1500Hz\"",
                             "points": "default 200", "log": "geometric spacing"}),
    "random": Table("random", {"n": "number of points", "seed": "default 0",
                               "params": "[random.params]: NAME = {min, max[, log]}"}),
    "sley": Table("sley", {"drive": "\"one-side\" or \"both-sides\"", "variant": "1 to 7",
                           "revolutions": "default 5", "points_per_revolution": "default 7200"}),
}


def _check_keys(table: str | None, entry: dict) -> None:
    """Refuse a key ``TABLES[table]`` does not declare, at its key path."""
    found = unknown_key(TABLES[table], entry)
    if found is not None:
        key, message = found
        _fail((key,) if table is None else (table, key),
              f"{message} (expected {TABLES[table].expected})")


def _parse_spec(data: dict, source: str, base: Path) -> StudySpec:
    _check_keys(None, data)
    analysis = data.get("analysis", "sweep")
    if analysis not in ("sweep", "resonances", "simulate"):
        _fail(("analysis",), f"analysis must be 'sweep', 'resonances' or 'simulate', "
                             f"got {brief(analysis)}")
    text, path = ("", "") if analysis == "simulate" else _read_netlist(data, base)
    if ("grid" in data) == ("random" in data):
        _fail(("grid",) if "grid" in data else (), "needs exactly one of a [grid] table or a "
                                                   "[random] table")
    names, points = _grid(data["grid"]) if "grid" in data else _random(data["random"])
    omega = _sweep_omega(data.get("omega"), len(points)) if analysis == "sweep" else None
    n_res = _integer(("resonances",), data.get("resonances", 3), "resonances", 1, 100)
    omega_max = _omega(("omega_max",), data["omega_max"], "omega_max") \
        if "omega_max" in data else None
    sley = None
    if analysis == "simulate":
        sley = _sley_settings(data.get("sley", {}), names)
    else:
        _check_params(text, path, names, "grid" if "grid" in data else "random")
    return StudySpec(text, str(path), analysis, names, points, omega, n_res, omega_max, source,
                     sley)


def _read_netlist(data: dict, base: Path) -> tuple[str, Path]:
    """The text of ``netlist = "PATH"`` (relative to the spec file) and its path."""
    if "netlist" not in data or not isinstance(data["netlist"], str):
        _fail(("netlist",), "needs netlist = \"PATH\" (relative to the spec file)")
    path = Path(os.path.normpath(base / data["netlist"]))
    try:
        path = path.relative_to(Path.cwd())
    except ValueError:
        pass
    from .sources import read_source

    try:
        return read_source(path, "a .mcir netlist"), path
    except NetlistError as exc:
        _fail(("netlist",), f"netlist {str(path)!r}: {exc.message}")


def _grid(grid) -> tuple[tuple[str, ...], tuple[tuple[float, ...], ...]]:
    """[grid]: the parameters' names and every combination of their values."""
    if not isinstance(grid, dict) or not grid:
        _fail(("grid",), "[grid] must name at least one parameter")
    names = tuple(grid)
    # Count first: an axis of num = 1e9 is refused before it is built.
    count = math.prod(_axis_length(n, grid[n]) for n in names)
    if count > MAX_POINTS:
        _fail(("grid",), f"the grid has {count:,} points, the limit is {MAX_POINTS:,}")
    axes = [_axis(n, grid[n]) for n in names]
    return names, tuple(itertools.product(*axes))


def _random(rnd) -> tuple[tuple[str, ...], tuple[tuple[float, ...], ...]]:
    """[random]: the parameters' names and n points drawn (seeded) from their ranges."""
    if not isinstance(rnd, dict):
        _fail(("random",), "[random] must be a table (n, seed, params)")
    _check_keys("random", rnd)
    n = _integer(("random", "n"), rnd.get("n"), "random.n", 1, MAX_POINTS)
    seed = rnd.get("seed", 0)
    if isinstance(seed, bool) or not isinstance(seed, (int, str)):
        _fail(("random", "seed"), f"random.seed must be an integer, got {brief(seed)}")
    ranges = rnd.get("params")
    if not isinstance(ranges, dict) or not ranges:
        _fail(("random", "params"), "[random.params] must give {min, max} for at least one "
                                    "parameter")
    names = tuple(ranges)
    bounds = [_random_range(name, ranges[name]) for name in names]
    rng = random.Random(seed)
    return names, tuple(tuple(math.exp(rng.uniform(math.log(lo), math.log(hi))) if log
                              else rng.uniform(lo, hi) for lo, hi, log in bounds)
                        for _ in range(n))


def _random_range(name, r) -> tuple[float, float, bool]:
    """random.params.NAME = {min, max[, log]} as (min, max, log)."""
    where = ("random", "params", name)
    if not isinstance(r, dict) or not {"min", "max"} <= set(r) or \
            set(r) - {"min", "max", "log"}:
        _fail(where, f"random.params.{name} must be {{min, max[, log]}}")
    lo = _number((*where, "min"), r["min"], f"random.params.{name}.min")
    hi = _number((*where, "max"), r["max"], f"random.params.{name}.max")
    if not lo <= hi or (r.get("log") and lo <= 0):
        _fail(where, f"random.params.{name}: need min <= max (and > 0 with log)")
    return lo, hi, bool(r.get("log", False))


def _sweep_omega(o, n_points: int) -> tuple[float, float, int, bool]:
    """[omega] of a sweep study: (min, max, points, log), within the work limit."""
    if not isinstance(o, dict) or not {"min", "max"} <= set(o):
        _fail(("omega",), "analysis 'sweep' needs an [omega] table with min and max "
                          "(and points, log)")
    _check_keys("omega", o)
    lo = _omega(("omega", "min"), o["min"], "omega.min")
    hi = _omega(("omega", "max"), o["max"], "omega.max")
    npts = _integer(("omega", "points"), o.get("points", 200), "omega.points", 1,
                    MAX_STUDY_SWEEP_POINTS)
    log = bool(o.get("log", False))
    if not (0 <= lo < hi) or (log and lo <= 0):
        _fail(("omega", "min"), f"need 0 <= omega.min < omega.max (and > 0 with log), "
                                f"got {lo}, {hi}")
    if n_points * npts > MAX_STUDY_WORK:
        _fail(("omega", "points"), f"{n_points:,} points × {npts:,} frequencies is "
                                   f"{n_points * npts:,} evaluations, the limit is "
                                   f"{MAX_STUDY_WORK:,}")
    return lo, hi, npts, log


def _check_params(text: str, path, names, table: str) -> None:
    """Every varied name is a ``.param`` of the netlist (checked once, not per point)."""
    from .netlist import parse

    base_circuit = parse(text, source=str(path))
    missing = [n for n in names if n not in base_circuit.params]
    if missing:
        _fail((table,), f"{', '.join(missing)} is not a .param of {path} (its parameters: "
                        f"{', '.join(base_circuit.params) or 'none'})")


def _sley_settings(table, names) -> tuple:
    if not isinstance(table, dict):
        _fail(("sley",), "[sley] must be a table (drive, variant, revolutions, "
                         "points_per_revolution)")
    _check_keys("sley", table)
    drive = table.get("drive", "one-side")
    if not isinstance(drive, str) or drive not in _SLEY_QUANTITIES:
        _fail(("sley", "drive"), f"sley.drive must be 'one-side' or 'both-sides', "
                                 f"got {brief(drive)}")
    settings = []
    for key, default, lo, hi in (("variant", 3, 1, 7),
                                 ("revolutions", 5, 1, MAX_REVOLUTIONS),
                                 ("points_per_revolution", 7200, 16, MAX_POINTS_PER_REVOLUTION)):
        settings.append(_integer(("sley", key), table.get(key, default), f"sley.{key}", lo, hi))
    from dataclasses import fields

    from .sley import SleyParameters

    known = {f.name for f in fields(SleyParameters)} - {"drive", "label", "branch",
                                                        "beat_sign"}
    bad = [n for n in names if n not in known]
    if bad:
        _fail(("grid",), f"{', '.join(bad)} is not a sley parameter (expected some of "
                         f"{', '.join(sorted(known))})")
    return (drive, *settings)


def load_spec(path: str | os.PathLike) -> StudySpec:
    """Read a study TOML file (see the module docstring).

    Raises
    ------
    NetlistError
        The file is missing, not UTF-8, not valid TOML, or has a fault, with
        its line and column.
    """
    from .sources import read_source

    source = os.fspath(path)
    text = read_source(path, "a study .toml")
    data = load_toml(text, source)
    return parse_spec(data, source=source, base=Path(source).resolve().parent, text=text)


def study_points(spec: StudySpec) -> list[tuple[int, dict[str, float]]]:
    """``(index, {param: value})`` for every point, in order."""
    return [(i, dict(zip(spec.params, p))) for i, p in enumerate(spec.points)]


def run_point(spec: StudySpec, index: int, values: dict[str, float]) -> dict:
    """One row of the table (errors caught and recorded, never raised): a batch of one."""
    return run_batch(spec, [(index, values)])[0]


def run_batch(spec: StudySpec, batch: list[tuple[int, dict[str, float]]]) -> list[dict]:
    """Rows of a batch of points (what each worker runs; errors recorded, never raised).

    A netlist's points are one :func:`mechcirc.batch.designs` batch: the
    netlist parsed once, K on the D × W grid in one pass, the resonances from
    stacked eigenproblems; a point the batch cannot take is computed on its
    own, and a point that fails is a row with its error.  Each row is the
    same whatever the batch it is in.
    """
    import warnings

    import numpy as np

    rows = [{"index": i, **v, "status": "ok", "error": ""} for i, v in batch]
    if spec.analysis == "simulate":
        return [_simulate_row(spec, row, v) for row, (_, v) in zip(rows, batch)]
    try:
        from .batch import designs

        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            ds = designs(spec.netlist_text, {n: [v[n] for _, v in batch] for n in spec.params},
                         source=spec.netlist_source)
            if spec.analysis == "sweep":
                lo, hi, n, log = spec.omega
                omega = np.geomspace(lo, hi, n) if log else np.linspace(lo, hi, n)
                s = ds.sweep(omega)
                flagged = np.count_nonzero(s.flags, axis=1)
                ex = ds.extremes(omega, ds.resonances(omega_max=hi * (1 + 1e-9)))
                failed = {**ex.failed, **s.failed}
                for d, row in enumerate(rows):
                    # Exact extremes over the band: 0 and inf at a zero or pole of K
                    # in it, named by its ω (issue 21 §4), not the grid's values.
                    row.update(K_abs_min=float(ex.K_min[d]), omega_at_K_min=float(
                        ex.omega_at_K_min[d]), K_abs_max=float(ex.K_max[d]),
                        omega_at_K_max=float(ex.omega_at_K_max[d]),
                        Q0_abs_max=float(ex.Q0_max[d]),
                        omega_at_Q0_max=float(ex.omega_at_Q0_max[d]),
                        n_flagged=int(flagged[d]))
            else:
                res = ds.resonances(omega_max=spec.omega_max)
                failed = res.failed
                for d, row in enumerate(rows):
                    for kind in ("resonance", "antiresonance"):
                        ws = res.omega[d, :res.count[d]][res.kind[d, :res.count[d]] == kind]
                        for i in range(spec.n_resonances):
                            row[f"{kind}_{i + 1}"] = float(ws[i]) if i < ws.size else math.nan
    except Exception as exc:  # noqa: BLE001 - a study records every failure
        if len(batch) > 1:          # find the point at fault: each on its own
            return [run_batch(spec, [point])[0] for point in batch]
        message = f"{type(exc).__name__}: {exc}".replace("\n", " ")
        return [{**row, "status": "error", "error": message} for row in rows]
    for d, message in failed.items():
        rows[d] = {"index": rows[d]["index"], **batch[d][1], "status": "error",
                   "error": _failure(ds, d, message)}
    return rows


def _failure(ds, d: int, message: str) -> str:
    """The row's error: the single path's exception, named as run_point names it."""
    try:
        ds.design(d)
    except Exception as exc:  # noqa: BLE001
        return f"{type(exc).__name__}: {exc}".replace("\n", " ")
    return message.replace("\n", " ")


def _simulate_row(spec: StudySpec, row: dict, values: dict) -> dict:
    """One row of a sley study (errors caught and recorded, never raised)."""
    import warnings

    try:
        from .sley import simulate

        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            drive, variant, revolutions, ppr = spec.sley
            result = simulate(drive, variant, revolutions=revolutions,
                              points_per_revolution=ppr, **values)
            for q in _SLEY_QUANTITIES[drive]:
                lo, hi = result.extrema[q]
                row[f"{q}_min"], row[f"{q}_max"] = float(lo), float(hi)
    except Exception as exc:  # noqa: BLE001 - a study records every failure
        row["status"] = "error"
        row["error"] = f"{type(exc).__name__}: {exc}".replace("\n", " ")
    return row


@dataclass
class StudyResult:
    """The rows of a study in index order, and how it ran."""

    columns: list[str]
    rows: list[dict]
    executor: str
    workers: int
    skipped: int = 0
    failed: int = field(default=0)


def _format(value) -> str:
    if isinstance(value, float):
        return repr(value) if math.isfinite(value) else ("nan" if math.isnan(value) else
                                                         ("inf" if value > 0 else "-inf"))
    return str(value)


#: The journal's last column: a CRC-32 of the row's other fields, so that a row cut
#: short by an interruption (even inside a number: 10.0 for 1046.098) is recognised.
_CHECK = "crc32"


def _crc(fields: list[str]) -> str:
    import zlib

    return f"{zlib.crc32(chr(31).join(fields).encode('utf-8')):08x}"


def _row(columns: list[str], rec: list[str]) -> dict | None:
    """The row of a CSV record, or None if a field does not have its column's syntax."""
    row = {}
    try:
        for name, text in zip(columns, rec, strict=True):
            if name == "status":
                if text not in ("ok", "error"):
                    return None
                row[name] = text
            elif name == "error":
                row[name] = text
            elif name in ("index", "n_flagged"):
                row[name] = int(text) if text else ""
                if name == "index" and (row[name] == "" or row[name] < 0):
                    return None
            else:
                row[name] = float(text) if text else ""
    except ValueError:
        return None
    return row


def read_rows(path: str | os.PathLike, columns: list[str]) -> list[dict]:
    """The complete rows of a study's table or journal with these ``columns`` (for ``resume``).

    A journal (written while a study runs) ends each row with a CRC-32 of its
    fields; a finished table has none.  Rows that are cut short, fail their
    check, or do not parse are left out (their points run again), and so is
    a second row for the same point.

    Raises
    ------
    MechcircError
        The file holds another study's columns, or is not UTF-8 text.
    """
    source = os.fspath(path)
    try:
        with open(path, newline="", encoding="utf-8") as fh:
            reader = csv.reader(fh)
            header = next(reader, None)
            if header is None:
                return []
            journal = header == [*columns, _CHECK]
            if header != columns and not journal:
                raise MechcircError(f"{source}: its columns ({', '.join(header)}) are not "
                                    "this study's; cannot resume (use another -o)")
            rows, seen = [], set()
            width = len(header)
            for rec in reader:
                if len(rec) != width:
                    continue        # cut short by an interruption: run that point again
                if journal and (rec[-1] != _crc(rec[:-1])):
                    continue        # cut inside its last field, or damaged
                row = _row(columns, rec[:len(columns)])
                if row is None or row["index"] in seen:
                    continue
                seen.add(row["index"])
                rows.append(row)
            return rows
    except UnicodeDecodeError:
        raise MechcircError(f"{source}: not a study's table (not UTF-8 text); cannot resume "
                            "(use another -o)") from None
    except csv.Error as exc:
        raise MechcircError(f"{source}: not a study's table ({exc}); cannot resume") from None


def _batches(points, size):
    for start in range(0, len(points), size):
        yield points[start:start + size]


def run_study(spec: StudySpec, *, output: str | os.PathLike | None = None,
              scheduler: str | None = None, workers: int | None = None, resume: bool = False,
              batch_size: int | None = None, connect_timeout: float = 10.0,
              on_rows: Callable[[int], None] | None = None) -> StudyResult:
    """Run every point of ``spec``; return the rows (and write them to ``output``).

    Parameters
    ----------
    output : path, optional
        CSV file (or ``.parquet``, needs pyarrow), written whole and
        atomically at the end in index order; an existing file is kept until
        then.  Meanwhile rows are journalled, each with a checksum, to
        ``OUTPUT.partial.csv`` (:func:`journal_path`), removed at the end.
    scheduler : str, optional
        Address of a Dask scheduler (``tcp://host:8786``); by default the
        local cores run the study.
    workers : int, optional
        Local processes (default: all cores); 1 runs in this process.
    resume : bool
        Keep the verified rows of the journal (or of a finished ``output``)
        and run only the missing points.
    batch_size : int, optional
        Points per task (default: about 8 tasks per worker, at most 500).
    connect_timeout : float
        Seconds to wait for the Dask scheduler before giving up.
    on_rows : callable, optional
        Called with the number of rows each time a batch finishes (progress).
    """
    columns = spec.columns
    todo = study_points(spec)
    parquet = bool(output) and str(output).lower().endswith(".parquet")
    if parquet:
        _require_pyarrow()
    # Rows are journalled as they finish to a CSV beside the output, each with
    # a checksum; the output itself is written whole at the end (atomically),
    # so an existing file stays as it was until the new table is complete.
    journal = journal_path(output) if output else None
    done = _resumed_rows(spec, output, journal, parquet) if resume and output else []
    have = {r["index"] for r in done}
    todo = [(i, v) for i, v in todo if i not in have]
    sink = _open_journal(journal, columns, done) if output else None
    writer = csv.writer(sink) if sink is not None else None
    rows = list(done)

    def take(batch_rows: Iterable[dict]) -> None:
        batch_rows = list(batch_rows)
        rows.extend(batch_rows)
        if sink is not None:
            for r in batch_rows:
                fields = [_format(r.get(c, "")) for c in columns]
                writer.writerow([*fields, _crc(fields)])
            sink.flush()
        if on_rows is not None:
            on_rows(len(batch_rows))

    try:
        if scheduler:
            executor, n_workers = "dask", _run_dask(spec, todo, scheduler, batch_size, take,
                                                    connect_timeout)
        else:
            executor, n_workers = _run_local(spec, todo, workers or os.cpu_count() or 1,
                                             batch_size, take)
    finally:
        if sink is not None:
            sink.close()
    rows.sort(key=lambda r: r["index"])
    if output:
        _write_output(output, parquet, columns, rows)
        os.unlink(journal)
    failed = sum(r["status"] != "ok" for r in rows)
    return StudyResult(columns, rows, executor, n_workers, len(done), failed)


def _resumed_rows(spec: StudySpec, output, journal: str, parquet: bool) -> list[dict]:
    """The verified rows of the journal, or of a finished output, that are points of ``spec``."""
    columns = spec.columns
    done: list[dict] = []
    if Path(journal).exists():
        done = read_rows(journal, columns)
    elif Path(output).exists():
        done = _read_parquet(output, columns) if parquet else read_rows(output, columns)
    n = len(spec.points)
    return [r for r in done if r["index"] < n]


def _open_journal(journal: str, columns: list[str], done: list[dict]):
    """A fresh journal holding the verified rows, open for appending.

    A resumed journal is rewritten, not appended to: its last line may lack
    its terminator.
    """
    from .outputs import atomic_open

    with atomic_open(journal, "w", newline="", encoding="utf-8") as fh:
        w = csv.writer(fh)
        w.writerow([*columns, _CHECK])
        for r in done:
            fields = [_format(r.get(c, "")) for c in columns]
            w.writerow([*fields, _crc(fields)])
    return open(journal, "a", newline="", encoding="utf-8")


def _write_output(output, parquet: bool, columns: list[str], rows: list[dict]) -> None:
    """The whole table, in index order, written atomically (CSV or Parquet)."""
    if parquet:
        _write_parquet(output, columns, rows)
        return
    from .outputs import atomic_open

    with atomic_open(output, "w", newline="", encoding="utf-8") as fh:
        w = csv.writer(fh)
        w.writerow(columns)
        for r in rows:
            w.writerow([_format(r.get(c, "")) for c in columns])


def journal_path(output: str | os.PathLike) -> str:
    """Where a study writing ``output`` journals its rows while it runs: ``OUTPUT.partial.csv``."""
    return f"{os.fspath(output)}.partial.csv"


def _require_pyarrow():
    try:
        import pyarrow  # noqa: F401
    except ImportError:
        raise MechcircError("Parquet output needs pyarrow (pip install pyarrow); "
                            "or write CSV (-o results.csv)") from None


def _write_parquet(path, columns: list[str], rows: list[dict]) -> None:
    """The table as Parquet (atomically); empty result cells are nulls."""
    import pyarrow as pa
    import pyarrow.parquet as pq

    from .outputs import atomic_path

    data = {c: [None if r.get(c, "") == "" else r.get(c) for r in rows] for c in columns}
    types = {c: pa.string() if c in ("status", "error") else
             pa.int64() if c in ("index", "n_flagged") else pa.float64() for c in columns}
    table = pa.table({c: pa.array(data[c], type=types[c]) for c in columns})
    with atomic_path(path) as tmp:
        pq.write_table(table, tmp)


def _read_parquet(path, columns: list[str]) -> list[dict]:
    import pyarrow.parquet as pq

    table = pq.read_table(path)
    if table.column_names != columns:
        raise MechcircError(f"{os.fspath(path)}: its columns ({', '.join(table.column_names)}) "
                            "are not this study's; cannot resume (use another -o)")
    return [{c: ("" if v is None else v) for c, v in row.items()} for row in table.to_pylist()]


def _for_workers(spec: StudySpec) -> StudySpec:
    """The spec without its point list: each batch carries its own points, and the
    spec is pickled once per batch (a million points would otherwise travel with
    every batch)."""
    from dataclasses import replace

    return replace(spec, points=())


def _size(n_points: int, n_workers: int, batch_size: int | None) -> int:
    if batch_size:
        return max(1, int(batch_size))
    return max(1, min(500, math.ceil(n_points / (8 * max(1, n_workers)))))


def _run_local(spec, todo, n_workers, batch_size, take) -> tuple[str, int]:
    size = _size(len(todo), n_workers, batch_size)
    if n_workers <= 1 or len(todo) <= size:
        # One batch or one worker: starting processes would cost more than it saves.
        for batch in _batches(todo, size):
            take(run_batch(spec, batch))
        return "inline", 1
    from concurrent.futures import ProcessPoolExecutor, as_completed

    with ProcessPoolExecutor(max_workers=n_workers, initializer=_die_with_parent,
                             initargs=(os.getpid(),)) as pool:
        light = _for_workers(spec)
        futures = [pool.submit(run_batch, light, batch) for batch in _batches(todo, size)]
        try:
            for fut in as_completed(futures):
                take(fut.result())
        except BaseException:
            for fut in futures:
                fut.cancel()
            raise
    return "local", n_workers


def _die_with_parent(parent: int) -> None:
    """Worker initializer: end this worker when the study's process ends, however it ends.

    After SIGKILL of the parent, workers would otherwise be re-parented to
    init and wait on the pipe for minutes.  On Linux the kernel delivers
    SIGKILL to the worker when its parent dies (``prctl(PR_SET_PDEATHSIG)``);
    elsewhere a daemon thread polls the parent's pid once a second.
    """
    import signal
    import sys
    import threading

    if sys.platform.startswith("linux"):
        try:
            import ctypes

            libc = ctypes.CDLL(None, use_errno=True)
            PR_SET_PDEATHSIG = 1
            if libc.prctl(PR_SET_PDEATHSIG, int(signal.SIGKILL), 0, 0, 0) == 0:
                if os.getppid() != parent:      # the parent died before prctl took hold
                    os._exit(1)
                return
        except (OSError, AttributeError):
            pass

    def watch():
        import time

        while os.getppid() == parent:
            time.sleep(1.0)
        os._exit(1)

    threading.Thread(target=watch, name="mechcirc-parent-watch", daemon=True).start()


def _run_dask(spec, todo, scheduler, batch_size, take, connect_timeout) -> int:
    try:
        from distributed import Client, as_completed
    except ImportError:
        raise MechcircError("--scheduler needs Dask: pip install 'mechcirc[study]'") from None
    try:
        client = Client(scheduler, timeout=f"{connect_timeout}s")
    except (OSError, TimeoutError) as exc:
        raise MechcircError(f"cannot reach the Dask scheduler at {scheduler}: {exc}") from None
    try:
        n_workers = max(1, sum(w.get("nthreads", 1) for w in
                               client.scheduler_info()["workers"].values()))
        size = _size(len(todo), n_workers, batch_size)
        spec_future = client.scatter(_for_workers(spec), broadcast=True)
        futures = [client.submit(run_batch, spec_future, batch, pure=False)
                   for batch in _batches(todo, size)]
        for fut in as_completed(futures):
            take(fut.result())
        return n_workers
    finally:
        client.close()
