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
(empty where there are fewer), for a sley simulation the minimum and maximum
over the tabulated revolution of ``eps2P eps4P eps4T`` [rad/s²] and ``M2V``
[N·m] (both-sides drive: also ``eps5P M5V``), e.g. ``eps4P_min``.

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

from __future__ import annotations

import contextlib
import csv
import hashlib
import io
import itertools
import json
import math
import os
import random
import re
import signal
import sys
import threading
import warnings
import zlib
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Callable, NoReturn, TextIO

import numpy as np

from .circuit import ELEMENT_UNITS, Drive, Element, units_of
from .errors import MechcircError, NetlistError
from .limits import (MAX_POINTS_PER_REVOLUTION, MAX_REVOLUTIONS, MAX_STUDY_POINTS,
                     MAX_STUDY_SWEEP_POINTS, MAX_STUDY_WORK)
from .sources import (Table, brief, csv_rows, data_frame, did_you_mean, finite_number,
                      load_toml, locate_path, number_error, read_bytes, read_source,
                      split_lines, summary_repr, unknown_key)
from .netlist import SYNTAX, expressions_of, parse
from .outputs import OutputSet, atomic_open, atomic_path
from .units import looks_like_unit, parse_omega

__all__ = ["StudySpec", "load_spec", "parse_spec", "run_batch",
           "run_study", "StudyResult", "read_rows", "journal_path", "sidecar_path",
           "provenance", "column_units", "SAMPLE_METHODS"]

_SWEEP_COLUMNS = ["K_abs_min", "omega_at_K_min", "K_abs_max", "omega_at_K_max", "Q0_abs_max",
                  "omega_at_Q0_max", "n_flagged"]
_SLEY_QUANTITIES = {"one-side": ["eps2P", "eps4P", "eps4T", "M2V"],
                    "both-sides": ["eps2P", "eps4P", "eps4T", "M2V", "eps5P", "M5V"]}


@dataclass(frozen=True)
class StudySpec:
    """A parsed study: the netlist text, the analysis and the points' parameter values."""

    __repr__ = summary_repr

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
    sley: tuple[str, int, int, int] | None = None
    #: The resolved spec as canonical JSON (sorted keys, defaults filled in, the
    #: netlist and a sample file by their SHA-256): what ``resume`` compares.
    canonical: str = "{}"
    #: The spec file's text as written (provenance; empty when built from a dict).
    spec_text: str = ""
    #: The unit of each parameter, in the order of ``params`` (see :func:`column_units`).
    param_units: tuple[str | None, ...] = ()

    @property
    def sha256(self) -> str:
        """SHA-256 of :attr:`canonical`: two specs with the same hash run the same points."""
        return _sha256(self.canonical)

    @property
    def columns(self) -> list[str]:
        """The table's columns, in order."""
        head = ["index", *self.params, "status", "error"]
        if self.analysis == "sweep":
            return head + _SWEEP_COLUMNS
        if self.analysis == "simulate":
            return head + [f"{q}_{end}" for q in _SLEY_QUANTITIES[_setting(self, "sley")[0]]
                           for end in ("min", "max")]
        return head + [f"{kind}_{i}" for kind in ("resonance", "antiresonance")
                       for i in range(1, self.n_resonances + 1)]


#: Units of the result columns [SI]; a parameter's unit is in ``StudySpec.param_units``.
_UNITS = {"index": "1", "status": "", "error": "", "K_abs_min": "m/(N·s)",
          "K_abs_max": "m/(N·s)", "Q0_abs_max": "N", "omega_at_Q0_max": "rad/s",
          "omega_at_K_min": "rad/s", "omega_at_K_max": "rad/s",
          "n_flagged": "1", "resonance": "rad/s", "antiresonance": "rad/s",
          "eps2P": "rad/s²", "eps4P": "rad/s²", "eps4T": "rad/s²", "eps5P": "rad/s²",
          "M2V": "N·m", "M5V": "N·m"}
#: The SI unit of each unit role of a sley parameter (:data:`mechcirc.sley.models.UNIT_ROLES`).
_ROLE_UNITS = {"rotary inertia": "kg·m²", "rotary spring": "N·m/rad", "rotary damper": "kg·m²/s",
               "length": "m", "angle": "rad", "omega": "rad/s", "moment": "N·m"}


def column_units(spec: StudySpec) -> dict[str, str | None]:
    """The unit of every column of ``spec``'s table (``"1"``: a count or a pure number;
    ``""``: text; None: a ``.param`` whose unit the netlist does not fix).  K and Q0
    are in the drive's units: rad/(N·m·s) and N·m for a rotary drive.

    Parameters
    ----------
    spec : StudySpec

    Returns
    -------
    dict[str, str or None]
    """
    units = dict(zip(spec.params, spec.param_units or (None,) * len(spec.params)))
    if spec.analysis == "sweep" and spec.netlist_text:
        try:
            u = units_of(parse(spec.netlist_text, source=spec.netlist_source).drive)
        except MechcircError:       # its points say why, row by row
            u = units_of(None)
        units |= {"K_abs_min": u["K"], "K_abs_max": u["K"], "Q0_abs_max": u["Q"]}
    return {c: units[c] if c in units else _UNITS.get(c, _UNITS.get(c.rsplit("_", 1)[0]))
            for c in spec.columns}


class _SpecError(Exception):
    """A fault in a study description, with the TOML key path it belongs to."""

    def __init__(self, message: str, path: tuple):
        super().__init__(message)
        self.message, self.path = message, tuple(str(p) for p in path)


def _fail(path, message: str) -> NoReturn:
    raise _SpecError(message, tuple(path))


def _omega(path, value, what) -> float:
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
    if bad := number_error(value, what):
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
            hint = did_you_mean(min(map(str, extra)), ("min", "max", "num", "log")) \
                if extra else ""
            _fail(path, f"grid.{name} needs min, max and num (and optionally log), got "
                        f"{', '.join(sorted(map(str, value)))}{hint}")
        return _integer((*path, "num"), value["num"], f"grid.{name}.num", 1, MAX_POINTS)
    _fail(path, f"grid.{name} must be a list of values or {{min, max, num}}, "
                f"got {brief(value)}")


def _axis(name, value) -> list[float]:
    path = ("grid", name)
    if isinstance(value, list):
        return [_number(path, v, f"grid.{name}") for v in value]
    lo, hi = (_number((*path, end), value[end], f"grid.{name}.{end}") for end in ("min", "max"))
    if (log := value.get("log", False)) and (lo <= 0 or hi <= 0):
        _fail((*path, "log"), f"grid.{name}: log spacing needs min and max > 0")
    return _spaced(lo, hi, value["num"], log).tolist()


#: The largest number of points (rows) a study may have; each row holds ~1 kB
#: while the study runs (docs/reliability.md).
MAX_POINTS = MAX_STUDY_POINTS


def parse_spec(data: dict, *, source: str = "<spec>", base: Path | None = None,
               text: str | None = None) -> StudySpec:
    """Check a study description (the TOML file's content) and build its points.

    ``text`` is the TOML text ``data`` was read from; with it, errors carry
    the line and column of the key at fault.

    Parameters
    ----------
    data : dict
    source : str
        File name, for errors.
    base : Path, optional
        The folder relative paths start from (default: the current one).
    text : str, optional

    Returns
    -------
    StudySpec
        Checked, with its canonical form and hash.

    Raises
    ------
    NetlistError
        With ``text``: at file:line:col, naming the key and what would be right.
    MechcircError
        Without ``text``: the same message after the source's name.
    """
    try:
        return replace(_parse_spec(data, source, base or Path(".")), spec_text=text or "")
    except _SpecError as exc:
        if text is None:
            raise MechcircError(f"{source}: {exc.message}") from None
        line, col = locate_path(text, exc.path) if exc.path else (0, 0)
        raise NetlistError(exc.message, source, line, col) from None


#: The tables of a study file, declared once (see :class:`mechcirc.sources.Table`);
#: ``[grid]``, ``[random.params]`` and ``[sample.params]`` map the parameters' names.
TABLES = {
    None: Table(None, {"analysis": "\"sweep\", \"resonances\" or \"simulate\"",
                       "grid": "[grid]: NAME = [values] or {min, max, num[, log]}",
                       "netlist": "the netlist's path, relative to the spec file",
                       "omega": "[omega]: the sweep (analysis = \"sweep\")",
                       "omega_max": "highest resonance sought [rad/s]",
                       "random": "[random]: n, seed, params",
                       "resonances": "how many of each kind to tabulate",
                       "sample": "[sample]: method, n, seed, params; or file",
                       "sley": "[sley]: the preset (analysis = \"simulate\")"}),
    "omega": Table("omega", {"min": "[rad/s] or \"5Hz\"", "max": "[rad/s] or \"1500Hz\"",
                             "points": "default 200", "log": "geometric spacing"}),
    "random": Table("random", {"n": "number of points", "seed": "default 0",
                               "params": "[random.params]: NAME = {min, max[, log]}"}),
    "sample": Table("sample", {"method": "\"random\", \"latin-hypercube\" or \"sobol\"",
                               "n": "number of points", "seed": "default 0",
                               "params": "[sample.params]: NAME = {min, max[, log]}",
                               "file": "a CSV (or Parquet) file of parameter columns"}),
    "sley": Table("sley", {"drive": "\"one-side\" or \"both-sides\"", "variant": "1 to 7",
                           "revolutions": "default 5", "points_per_revolution": "default 7200"}),
}

#: The version of what a row holds, part of the canonical spec: raise it whenever
#: :func:`run_batch` computes a column differently, so that ``resume`` refuses to
#: mix rows of the old computation with the new.
ROWS_VERSION = 2     # 2: true extremes of |K| over the band with their ω (batched core)

#: ``[sample] method``: how the n points fill the box of ``[sample.params]``.
SAMPLE_METHODS = ("random", "latin-hypercube", "sobol")
_ANALYSES = ("sweep", "resonances", "simulate")


def _check_keys(table: str | None, entry: dict) -> None:
    """Refuse a key ``TABLES[table]`` does not declare, at its key path."""
    if (found := unknown_key(TABLES[table], entry)) is not None:
        key, message = found
        _fail((key,) if table is None else (table, key),
              f"{message} (expected {TABLES[table].expected})")


def _parse_spec(data: dict, source: str, base: Path) -> StudySpec:
    _check_keys(None, data)
    analysis = data.get("analysis", "sweep")
    if analysis not in _ANALYSES:
        _fail(("analysis",), f"analysis must be 'sweep', 'resonances' or 'simulate', "
                             f"got {brief(analysis)}{did_you_mean(analysis, _ANALYSES)}")
    text, path = ("", "") if analysis == "simulate" else _read_netlist(data, base)
    kinds = [k for k in ("grid", "random", "sample") if k in data]
    if len(kinds) != 1:
        _fail((kinds[1],) if kinds else (), "needs exactly one of a [grid], a [random] or a "
                                             "[sample] table")
    kind = kinds[0]
    roles = {} if analysis == "simulate" else _param_roles(text, path)
    if kind == "grid":
        names, points, canon = _grid(data["grid"])
    elif kind == "sample" and isinstance(data["sample"], dict) and "file" in data["sample"]:
        names, points, canon = _sample_file(data["sample"], base, analysis, roles)
    else:
        names, points, canon = _sample(data[kind], kind)
    omega = _sweep_omega(data.get("omega"), len(points)) if analysis == "sweep" else None
    n_res = _integer(("resonances",), data.get("resonances", 3), "resonances", 1, 100)
    omega_max = _omega(("omega_max",), data["omega_max"], "omega_max") \
        if "omega_max" in data else None
    sley: tuple[str, int, int, int] | None = None
    if analysis == "simulate":
        sley = _sley_settings(data.get("sley", {}), names, kind)
        units = tuple(map(_sley_units().get, names))
    else:
        if missing := [n for n in names if n not in roles]:     # each a .param, checked once
            _fail((kind,), f"{', '.join(missing)} is not a .param of {path}"
                           f"{did_you_mean(missing[0], roles)} (its parameters: "
                           f"{', '.join(roles) or 'none'})")
        units = tuple(roles[n][0] for n in names)
    canon = {"analysis": analysis, "sample": canon, "rows": ROWS_VERSION}
    if omega is not None:                       # analysis == "sweep"
        canon["omega"] = dict(zip(("min", "max", "points", "log"), omega))
    elif sley is None:                          # analysis == "resonances"
        canon.update(resonances=n_res, omega_max=omega_max)
    else:
        canon["sley"] = dict(zip(("drive", "variant", "revolutions", "points_per_revolution"),
                                 sley))
    if text:
        canon["netlist_sha256"] = _sha256(text)
    return StudySpec(text, str(path), analysis, names, points, omega, n_res, omega_max, source,
                     sley, canonical=_canonical(canon), param_units=units)


def _sha256(text: str | bytes) -> str:
    return hashlib.sha256(text.encode("utf-8") if isinstance(text, str) else text).hexdigest()


def _canonical(data) -> str:
    """One line of JSON, keys sorted, floats as ``repr``: equal specs give equal text."""
    return json.dumps(data, sort_keys=True, separators=(",", ":"), ensure_ascii=True,
                      allow_nan=False)


def _read_netlist(data: dict, base: Path) -> tuple[str, Path]:
    """The text of ``netlist = "PATH"`` (relative to the spec file) and its path.

    A file whose first statement does not begin with a netlist keyword is
    refused without quoting it: it is not a netlist (``/etc/shadow``), and
    its content is nobody's business.
    """
    if "netlist" not in data or not isinstance(data["netlist"], str):
        _fail(("netlist",), "needs netlist = \"PATH\" (relative to the spec file)")
    path = _spec_relative(base, data["netlist"])

    try:
        text = read_source(path, "a .mcir netlist")
    except NetlistError as exc:
        _fail(("netlist",), f"netlist {str(path)!r}: {exc.message}")
    for lineno, line in enumerate(split_lines(text), 1):
        words = re.split(r"[#;]", line, maxsplit=1)[0].split()
        if words:
            if words[0].lower() not in SYNTAX and not words[0].startswith("*"):
                _fail(("netlist",), f"netlist {str(path)!r} is not a netlist: its first "
                                    f"statement (line {lineno}) does not begin with one of "
                                    f"{', '.join(SYNTAX)}")
            break
    return text, path


def _spec_relative(base: Path, name: str) -> Path:
    """The file ``name`` of a spec in the folder ``base``, relative to the current
    folder when it lies below it (as errors and provenance show it)."""
    path = Path(os.path.normpath(base / name))
    with contextlib.suppress(ValueError):       # not below the current folder
        return path.relative_to(Path.cwd())
    return path


def _grid(grid) -> tuple[tuple[str, ...], tuple[tuple[float, ...], ...], dict]:
    """[grid]: the parameters' names, every combination of their values, and the
    grid as the canonical spec records it."""
    if not isinstance(grid, dict) or not grid:
        _fail(("grid",), "[grid] must name at least one parameter")
    names = tuple(grid)
    # Count first: an axis of num = 1e9 is refused before it is built.
    count = math.prod(_axis_length(n, grid[n]) for n in names)
    if count > MAX_POINTS:
        _fail(("grid",), f"the grid has {count:,} points, the limit is {MAX_POINTS:,}")
    axes = [_axis(n, grid[n]) for n in names]
    canon = {"method": "grid", "order": list(names), "axes": {
        n: axis if isinstance(grid[n], list) else
        {"min": axis[0], "max": axis[-1], "num": len(axis), "log": bool(grid[n].get("log"))}
        for n, axis in zip(names, axes)}}
    return names, tuple(itertools.product(*axes)), canon


def _sample(table, kind: str) -> tuple[tuple[str, ...], tuple[tuple[float, ...], ...], dict]:
    """[random], or [sample] with a method: n points drawn (seeded) from the
    parameters' ranges (uniform, or log-uniform with log = true)."""
    if not isinstance(table, dict):
        _fail((kind,), f"[{kind}] must be a table (n, seed, params)")
    _check_keys(kind, table)
    method = table.get("method", "random")
    if method not in SAMPLE_METHODS:
        _fail((kind, "method"), f"{kind}.method must be one of {', '.join(SAMPLE_METHODS)}, "
                                f"got {brief(method)}{did_you_mean(method, SAMPLE_METHODS)}")
    n = _integer((kind, "n"), table.get("n"), f"{kind}.n", 1, MAX_POINTS)
    seed = table.get("seed", 0)
    if method == "random":          # Python's generator, as since the first [random] studies
        if isinstance(seed, bool) or not isinstance(seed, (int, str)):
            _fail((kind, "seed"), f"{kind}.seed must be an integer, got {brief(seed)}")
    else:
        seed = _integer((kind, "seed"), seed, f"{kind}.seed", 0, 2**63 - 1)
    if not isinstance(ranges := table.get("params"), dict) or not ranges:
        _fail((kind, "params"), f"[{kind}.params] must give {{min, max}} for at least one "
                                "parameter")
    names = tuple(ranges)
    bounds = [_random_range(kind, name, ranges[name]) for name in names]
    canon = {"method": method, "n": n, "seed": seed, "order": list(names),
             "params": {name: {"min": lo, "max": hi, "log": log}
                        for name, (lo, hi, log) in zip(names, bounds)}}
    if method == "random":
        rng = random.Random(seed)
        return names, tuple(tuple(math.exp(rng.uniform(math.log(lo), math.log(hi))) if log
                                  else rng.uniform(lo, hi) for lo, hi, log in bounds)
                            for _ in range(n)), canon

    from scipy.stats import qmc

    # Sobol: n not a power of 2 loses balance (the docs say so)
    with warnings.catch_warnings(action="ignore"):
        engine = (qmc.LatinHypercube if method == "latin-hypercube" else qmc.Sobol)(
            d=len(names), seed=seed)
        unit = engine.random(n)
    cols = [np.exp(np.log(lo) + u * (np.log(hi) - np.log(lo))) if log else lo + u * (hi - lo)
            for u, (lo, hi, log) in zip(unit.T, bounds)]
    return names, tuple(tuple(float(x) for x in row) for row in zip(*cols)), canon


def _random_range(kind, name, r) -> tuple[float, float, bool]:
    """KIND.params.NAME = {min, max[, log]} as (min, max, log)."""
    where = (kind, "params", name)
    extra = sorted(map(str, set(r) - {"min", "max", "log"})) if isinstance(r, dict) else []
    if extra or not isinstance(r, dict) or not {"min", "max"} <= set(r):
        _fail(where, f"{kind}.params.{name} must be {{min, max[, log]}}"
                     + (f": unknown key {extra[0]!r}"
                        f"{did_you_mean(extra[0], ('min', 'max', 'log'))}" if extra else ""))
    lo, hi = (_number((*where, end), r[end], f"{kind}.params.{name}.{end}")
              for end in ("min", "max"))
    if not lo <= hi or (r.get("log") and lo <= 0):
        _fail(where, f"{kind}.params.{name}: need min <= max (and > 0 with log)")
    return lo, hi, bool(r.get("log", False))


def _sample_file(table: dict, base: Path, analysis: str, roles: dict):
    """[sample] file = "PATH": the user's own points, one row each, a column per parameter.

    Every cell is checked before anything runs; a fault is a :class:`NetlistError`
    at the file's row (line) and column.
    """
    path = _sample_path(table, base)
    source = str(path)
    try:
        header, records = (_parquet_records if source.lower().endswith(".parquet")
                           else _csv_records)(path)
    except NetlistError as exc:
        _fail(("sample", "file"), f"sample file {source!r}: {exc.message}")
    known, what = (set(_sley_units()), "a sley parameter") if analysis == "simulate" else \
        (set(roles), "a .param of the netlist")
    names = _sample_header(header, source, known, what)
    if not records:
        raise NetlistError("has a header but no rows of values", source, 0, 0,
                           "one row per point")
    if len(records) > MAX_POINTS:
        raise NetlistError(f"has {len(records):,} rows, the limit is {MAX_POINTS:,}", source)
    points = tuple(_sample_row(cells, names, source, line, roles) for line, cells in records)
    canon = {"method": "file", "columns": list(names),
             "file_sha256": _sha256(read_bytes(path, "a sample"))}
    return names, points, canon


def _sample_path(table: dict, base: Path) -> Path:
    """The path of ``[sample] file`` (relative to the spec file), a .csv or .parquet."""
    if extra := sorted(set(table) - {"file"}):
        _fail(("sample", extra[0]), f"[sample] with file takes no {extra[0]!r} (the file "
                                    "holds the points)")
    if not isinstance(table["file"], str):
        _fail(("sample", "file"), "sample.file must be a path (relative to the spec file)")
    path = _spec_relative(base, table["file"])
    if not str(path).lower().endswith((".csv", ".parquet")):
        _fail(("sample", "file"), f"sample.file must name a .csv or .parquet file, got "
                                  f"{brief(table['file'])}")
    return path


def _sample_header(header: list, source: str, known: set[str], what: str) -> tuple[str, ...]:
    """The parameters a sample file's header names: each named once, each ``known``."""
    for j, (name, col) in enumerate(header):
        if not name:
            raise NetlistError(f"column {j + 1} has no name", source, 1, col,
                               "a header row naming each column's parameter")
        # Quoted only if it could be a name: not the first line of some other file.
        shown = brief(name) if re.fullmatch(r"[A-Za-z_]\w{0,39}", name) else \
            f"{j + 1} (not a parameter name)"
        if name in [h for h, _ in header[:j]]:
            raise NetlistError(f"column {shown} appears twice", source, 1, col)
        if name not in known:
            raise NetlistError(f"column {shown} is not {what}"
                               f"{did_you_mean(name, sorted(known))}", source, 1, col,
                               f"some of {', '.join(sorted(known)) or 'none'}")
    return tuple(h for h, _ in header)


def _sample_row(cells: list, names: tuple[str, ...], source: str, line: int,
                roles: dict) -> tuple[float, ...]:
    """The values of a sample file's row (``cells``: (text, column) each), every cell a
    finite number, and > 0 where its parameter must be (``roles``)."""
    if len(cells) != len(names):
        missing = f" (no value for {', '.join(names[len(cells):])})" \
            if len(cells) < len(names) else ""
        raise NetlistError(f"{len(cells)} values, the header names {len(names)} "
                           f"columns{missing}", source, line, cells[-1][1] if cells else 1)
    row = []
    for (text, col), name in zip(cells, names):
        try:
            value = float(text) if isinstance(text, str) else text
        except ValueError:
            value = None
        if value is None or isinstance(value, bool) or not math.isfinite(value):
            unit = roles.get(name, (None,))[0]
            raise NetlistError(f"column {name}: {brief(text)} is not a finite number",
                               source, line, col, f"a number [{unit}]" if unit else
                               "a number")
        reason = roles.get(name, ("", None))[1]
        if reason and not value > 0:
            raise NetlistError(f"column {name}: {value:g} is not allowed: {name} is "
                               f"{reason}, which must be > 0", source, line, col,
                               "a positive number")
        row.append(value)
    return tuple(row)


def _csv_records(path):
    """(header, records) of a CSV sample file: [(name, col)], [(line, [(text, col)])]."""
    text = read_source(path, "a parameter-column CSV")
    records = [(lineno, [(f.strip(), c) for f, c in zip(cells, cols)])
               for lineno, cells, cols, _ in csv_rows(text, os.fspath(path), comments=False)]
    if not records:
        raise NetlistError("is empty", os.fspath(path), 0, 0,
                           "a header row naming the parameters, then a row per point")
    return [(t, c) for t, c in records[0][1]], records[1:]


def _parquet_records(path):
    """The same as :func:`_csv_records` for a Parquet file: its rows counted from 1 as
    lines 2.. (line 1 being the header), its columns numbered from 1."""
    try:
        import pyarrow.parquet as pq
    except ImportError:
        raise NetlistError("reading Parquet needs pyarrow (pip install pyarrow); or give a "
                           "CSV file", os.fspath(path)) from None
    data = read_bytes(path, "a Parquet")
    try:
        table = pq.read_table(io.BytesIO(data))
    except Exception as exc:  # noqa: BLE001 - pyarrow's errors have no common base
        raise NetlistError(f"not a Parquet file ({type(exc).__name__})", os.fspath(path)) \
            from None
    header = [(name, j + 1) for j, name in enumerate(table.column_names)]
    columns = [table.column(j).to_pylist() for j in range(table.num_columns)]
    records = [(i + 2, [("" if v is None else v if isinstance(v, (int, float)) else str(v),
                         j + 1) for j, v in enumerate(values)])
               for i, values in enumerate(zip(*columns))]
    return header, records


def _sweep_omega(o, n_points: int) -> tuple[float, float, int, bool]:
    """[omega] of a sweep study: (min, max, points, log), within the work limit."""
    if not isinstance(o, dict) or not {"min", "max"} <= set(o):
        _fail(("omega",), "analysis 'sweep' needs an [omega] table with min and max "
                          "(and points, log)")
    _check_keys("omega", o)
    lo, hi = (_omega(("omega", end), o[end], f"omega.{end}") for end in ("min", "max"))
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


def _param_roles(text: str, path) -> dict[str, tuple[str | None, str | None]]:
    """Each ``.param`` of the netlist: its unit, and why it must be > 0 (or None).

    A parameter that is itself (not inside an expression) the value, ``eta``
    or ``ratio`` of an element, or a drive's amplitude, has the unit written
    after it on that line (``mass m1 a 0 m g``: ``g``), else that field's SI
    unit, and (value, ``eta``, ``ratio``) must be > 0.  Any other's unit is None:
    the netlist does not fix it (a parameter inside expressions).  Parsed once,
    not per point.
    """
    circuit = parse(text, source=str(path))
    owners: dict[str, Element | Drive] = {e.name: e for e in circuit.elements}
    if circuit.drive is not None:
        owners[circuit.drive.name] = circuit.drive
    lines = split_lines(text)
    defaults = {"eta": "1", "ratio": "1", "velocity": "m/s", "force": "N"}
    uses: dict[str, set] = {}
    reasons: dict[str, str] = {}
    for (owner, role), (expr, _factor) in (expressions_of(circuit) or {}).items():
        if owner == "param" or expr.kind != "name":
            continue
        unit = None
        if role in ("value", "velocity", "force") and owner in owners:
            el = owners[owner]
            words = re.split(r"[#;]", lines[el.line - 1], maxsplit=1)[0].split() \
                if 0 < el.line <= len(lines) else []
            at = 4 if role == "value" else next(
                (i for i, w in enumerate(words) if w.startswith(role + "=")), len(words))
            after = words[at + 1] if at + 1 < len(words) else ""
            unit = after if "=" not in after and looks_like_unit(after) else \
                ELEMENT_UNITS.get(el.kind, defaults.get(role))
        elif role in ("eta", "ratio"):
            unit = "1"
        uses.setdefault(expr.value, set()).add(unit)
        if role in ("value", "eta", "ratio"):
            what = f"the {owners[owner].kind}" if role == "value" else f"the {role}"
            reasons.setdefault(expr.value, f"{what} of {owner!r}")
    return {name: (next(iter(uses[name])) if len(uses.get(name, ())) == 1 else None,
                   reasons.get(name)) for name in circuit.params}


def _sley_units() -> dict[str, str]:
    """The unit of each :class:`~mechcirc.sley.SleyParameters` field a study may vary, from
    its role in :data:`mechcirc.sley.models.UNIT_ROLES`."""
    from .sley.models import UNIT_ROLES

    return {n: _ROLE_UNITS[r] for n, r in UNIT_ROLES.items() if n not in ("branch", "beat_sign")}


def _sley_settings(table, names, kind: str) -> tuple[str, int, int, int]:
    if not isinstance(table, dict):
        _fail(("sley",), "[sley] must be a table (drive, variant, revolutions, "
                         "points_per_revolution)")
    _check_keys("sley", table)
    drive = table.get("drive", "one-side")
    if not isinstance(drive, str) or drive not in _SLEY_QUANTITIES:
        _fail(("sley", "drive"), f"sley.drive must be 'one-side' or 'both-sides', "
                                 f"got {brief(drive)}")
    variant, revolutions, ppr = [
        _integer(("sley", key), table.get(key, default), f"sley.{key}", lo, hi)
        for key, default, lo, hi in (("variant", 3, 1, 7), ("revolutions", 5, 1, MAX_REVOLUTIONS),
                                     ("points_per_revolution", 7200, 16,
                                      MAX_POINTS_PER_REVOLUTION))]
    known = _sley_units()
    if bad := [n for n in names if n not in known]:
        _fail((kind,), f"{', '.join(bad)} is not a sley parameter{did_you_mean(bad[0], known)}"
                       f" (expected some of {', '.join(sorted(known))})")
    return drive, variant, revolutions, ppr


def load_spec(path: str | os.PathLike) -> StudySpec:
    """Read a study TOML file (see the module docstring).

    Parameters
    ----------
    path : str or PathLike

    Returns
    -------
    StudySpec
        As :func:`parse_spec` returns it for the file's text.

    Raises
    ------
    NetlistError
        The file is missing, not UTF-8, not valid TOML, or has a fault, with
        its line and column.
    """
    source = os.fspath(path)
    text = read_source(path, "a study .toml")
    data = load_toml(text, source)
    return parse_spec(data, source=source, base=Path(source).resolve().parent, text=text)




def run_batch(spec: StudySpec, batch: list[tuple[int, dict[str, float]]],
              curves: bool = False):
    """Rows of a batch of points (what each worker runs; errors recorded, never raised).

    With ``curves`` (a sweep), ``(rows, K)``: also K [m/(N·s)] of every point on
    the study's ω grid, shape (points, W), NaN in the rows of failed points.

    A netlist's points are one :func:`mechcirc.batch.designs` batch: the
    netlist parsed once, K on the D × W grid in one pass, the resonances from
    stacked eigenproblems; a point the batch cannot take is computed on its
    own, and a point that fails is a row with its error.  Each row is the
    same whatever the batch it is in.

    Parameters
    ----------
    spec : StudySpec
    batch : list of (int, dict[str, float])
        ``(index, values)`` of each point.
    curves : bool

    Returns
    -------
    list of dict or tuple of (list of dict, ndarray)
    """
    rows = [{"index": i, **v, "status": "ok", "error": ""} for i, v in batch]
    if spec.analysis == "simulate":
        return [_simulate_row(spec, row, v) for row, (_, v) in zip(rows, batch)]
    try:
        ds, K, failed = _design_rows(spec, rows, batch)
    except Exception as exc:  # noqa: BLE001 - a study records every failure
        if len(batch) > 1:          # find the point at fault: each on its own
            alone = [run_batch(spec, [point], curves) for point in batch]
            if not curves:
                return [r[0] for r in alone]
            return [r[0][0] for r in alone], np.concatenate([r[1] for r in alone])
        message = f"{type(exc).__name__}: {exc}".replace("\n", " ")
        rows, K, failed = [{**row, "status": "error", "error": message} for row in rows], None, {}
    for d, message in failed.items():
        rows[d] = {"index": rows[d]["index"], **batch[d][1], "status": "error",
                   "error": _failure(ds, d, message)}
    if not curves:
        return rows
    K = np.full((len(rows), _omega_grid(spec).size), np.nan + 0j) if K is None else np.array(K)
    K[[r["status"] != "ok" for r in rows]] = np.nan
    return rows, K


def _design_rows(spec: StudySpec, rows: list[dict], batch: list[tuple[int, dict[str, float]]]):
    """Fill ``rows`` (a sweep's extremes, or the resonances) from one
    :func:`mechcirc.batch.designs` batch of the points; the designs, K on the ω
    grid (a sweep, else None) and the points the batch could not take
    (``{row: message}``)."""
    from .batch import designs

    with warnings.catch_warnings(action="ignore"):
        ds = designs(spec.netlist_text, {n: [v[n] for _, v in batch] for n in spec.params},
                     source=spec.netlist_source)
        if spec.analysis != "sweep":
            res = ds.resonances(omega_max=spec.omega_max)
            for d, row in enumerate(rows):
                for kind in ("resonance", "antiresonance"):
                    ws = res.omega[d, :res.count[d]][res.kind[d, :res.count[d]] == kind]
                    for i in range(spec.n_resonances):
                        row[f"{kind}_{i + 1}"] = float(ws[i]) if i < ws.size else math.nan
            return ds, None, res.failed
        omega = _omega_grid(spec)
        s = ds.sweep(omega)
        flagged = np.count_nonzero(s.flags, axis=1)
        ex = ds.extremes(omega, ds.resonances(omega_max=_setting(spec, "omega")[1] * (1 + 1e-9)), s)
    # Exact extremes over the band: 0 and inf at a zero or pole of K in it, named by
    # its ω, not the grid's values; in the order of _SWEEP_COLUMNS.
    found = (ex.K_min, ex.omega_at_K_min, ex.K_max, ex.omega_at_K_max, ex.Q0_max,
             ex.omega_at_Q0_max)
    for d, row in enumerate(rows):
        row.update(zip(_SWEEP_COLUMNS, [*(float(x[d]) for x in found), int(flagged[d])]))
    return ds, s.K, {**ex.failed, **s.failed}


def _setting(spec: StudySpec, name: str):
    """``spec.omega`` (min, max, points, log) of a sweep study's ω grid, or ``spec.sley``
    (drive, variant, revolutions, points_per_revolution) of a sley study; an error if
    the analysis has none."""
    if (value := getattr(spec, name)) is None:
        what = "omega grid" if name == "omega" else "[sley] preset"
        raise MechcircError(f"{spec.spec_source}: analysis {spec.analysis!r} has no {what}")
    return value


def _omega_grid(spec: StudySpec):
    """The ω grid of a sweep study [rad/s]: ``spec.omega``'s points, geometric with log."""
    return _spaced(*_setting(spec, "omega"))


def _spaced(lo: float, hi: float, n: int, log: bool):
    """``n`` points from ``lo`` to ``hi``, geometric with ``log`` (a grid axis, the ω grid)."""
    return (np.geomspace if log else np.linspace)(lo, hi, n)


def _failure(ds, d: int, message: str) -> str:
    """The row's error: the single path's exception, named as the single path names it."""
    try:
        ds.design(d)
    except Exception as exc:  # noqa: BLE001
        return f"{type(exc).__name__}: {exc}".replace("\n", " ")
    return message.replace("\n", " ")


def _simulate_row(spec: StudySpec, row: dict, values: dict) -> dict:
    """One row of a sley study (errors caught and recorded, never raised)."""
    try:
        from .sley import simulate

        with warnings.catch_warnings(action="ignore"):
            drive, variant, revolutions, ppr = _setting(spec, "sley")
            result = simulate(drive, variant, revolutions=revolutions,
                              points_per_revolution=ppr, **values)
            for q in _SLEY_QUANTITIES[drive]:
                lo, hi = result.extrema[q]
                row[f"{q}_min"], row[f"{q}_max"] = float(lo), float(hi)
    except Exception as exc:  # noqa: BLE001 - a study records every failure
        row.update(status="error", error=f"{type(exc).__name__}: {exc}".replace("\n", " "))
    return row


@dataclass
class StudyResult:
    """The rows of a study in index order, and how it ran.

    ``rows`` holds every row, or with ``run_study(keep_rows=False)`` only the
    failed ones (the table is in the output file); ``count`` is the number of
    rows of the table either way.  ``units`` maps each column to its unit
    (:func:`column_units`).
    """

    __repr__ = summary_repr

    columns: list[str]
    rows: list[dict]
    executor: str
    workers: int
    skipped: int = 0
    failed: int = field(default=0)
    count: int = -1
    units: dict = field(default_factory=dict, repr=False)

    def __post_init__(self):
        if self.count < 0:
            self.count = len(self.rows)

    def to_dataframe(self):
        """:attr:`rows` as a ``pandas.DataFrame`` in :attr:`columns`; ``attrs["units"]`` the
        unit of each column ("" where it has none)."""
        return data_frame(self.rows, {c: self.units.get(c) or "" for c in self.columns})


def _journal_record(row: dict, columns: list[str]) -> list[str]:
    """A row's cells as the journal writes them, its CRC-32 last: one line each, no line
    breaks; a float as its shortest round-trip text (``str``: ``repr``, and nan, inf, -inf)."""
    fields = [str(row.get(c, "")).replace("\r", " ").replace("\n", " ") for c in columns]
    return [*fields, _crc(fields)]


#: The journal's last column: a CRC-32 of the row's other fields, so that a row cut
#: short by an interruption (even inside a number: 10.0 for 1046.098) is recognised.
_CHECK = "crc32"


def _crc(fields: list[str]) -> str:
    return f"{zlib.crc32(chr(31).join(fields).encode('utf-8')):08x}"


def _cell_type(column: str) -> type:
    """The type of a column's cells: text (status, error), int (index, n_flagged), else float."""
    return str if column in ("status", "error") else int if column in ("index", "n_flagged") \
        else float


def _row(columns: list[str], rec: list[str]) -> dict | None:
    """The row of a CSV record, or None if a field does not have its column's syntax."""
    row: dict[str, str | int | float] = {}
    try:
        for name, text in zip(columns, rec, strict=True):
            if (name == "status" and text not in ("ok", "error")) or \
                    (name == "index" and (not text or int(text) < 0)):
                return None
            kind = _cell_type(name)
            row[name] = kind(text) if text or kind is str else ""
    except ValueError:
        return None
    return row


def read_rows(path: str | os.PathLike, columns: list[str]) -> list[dict]:
    """The complete rows of a study's table or journal with these ``columns`` (for ``resume``).

    A journal (written while a study runs) starts with a line recording the
    spec and ends each row with a CRC-32 of its fields; a finished table has
    neither.  Rows that are cut short, fail their
    check, or do not parse are left out (their points run again), and so is
    a second row for the same point.

    Parameters
    ----------
    path : str or PathLike
    columns : list of str

    Returns
    -------
    list of dict

    Raises
    ------
    MechcircError
        The file holds another study's columns, or is not UTF-8 text.
    """
    source = os.fspath(path)
    try:
        with open(path, newline="", encoding="utf-8") as fh:
            if not fh.readline(len(_SPEC_LINE)).startswith(_SPEC_LINE):
                fh.seek(0)          # no spec line (a finished table)
            else:
                fh.readline()       # the rest of the spec line
            reader = csv.reader(fh)
            header = next(reader, None)
            if header is None:
                return []
            journal = header == [*columns, _CHECK]
            if header != columns and not journal:
                raise MechcircError(f"{source}: its columns ({', '.join(header)}) are not "
                                    "this study's; cannot resume (use another -o)")
            rows: dict[int, dict] = {}          # each point's first complete row
            for rec in reader:
                # Cut short by an interruption, cut inside its last field, or damaged:
                # that point runs again.
                if len(rec) != len(header) or (journal and rec[-1] != _crc(rec[:-1])):
                    continue
                if (row := _row(columns, rec[:len(columns)])) is not None:
                    rows.setdefault(row["index"], row)
            return list(rows.values())
    except UnicodeDecodeError:
        raise MechcircError(f"{source}: not a study's table (not UTF-8 text); cannot resume "
                            "(use another -o)") from None
    except csv.Error as exc:
        raise MechcircError(f"{source}: not a study's table ({exc}); cannot resume") from None


def _todo(spec: StudySpec, have: set, size: int):
    """The points not in ``have``, in batches of ``size``, made as they are taken (a
    million points are not held at once): each ``(indices, values)``, two arrays, so
    that a task travels to a worker as a few kilobytes of numbers, not dicts."""
    todo = ((i, p) for i, p in enumerate(spec.points) if i not in have)
    while batch := list(itertools.islice(todo, size)):
        index, values = zip(*batch)
        yield np.array(index, dtype=np.int64), np.array(values, dtype=float)


@dataclass
class _TaskOut:
    """What a task sends back: its rows already written as journal lines (made on
    the worker, so the study's own process only appends text), the failed rows,
    and all rows only when they are asked for."""

    text: str
    n: int
    bad: list
    rows: list | None
    K: object = None


def _run_task(spec: StudySpec, points, curves: bool, keep: bool, lines: bool) -> _TaskOut:
    """One task on a worker: :func:`run_batch` of ``points`` (``(indices, values)``
    from :func:`_todo`), its journal lines made here."""
    index, values = points
    batch = [(int(i), dict(zip(spec.params, v))) for i, v in zip(index.tolist(),
                                                                  values.tolist())]
    rows, K = run_batch(spec, batch, curves) if curves else (run_batch(spec, batch), None)
    text = _csv_text(_journal_record(r, spec.columns) for r in rows) if lines else ""
    bad = [r for r in rows if r["status"] != "ok"]
    return _TaskOut(text, len(rows), bad, rows if keep or curves else None, K)


def _csv_text(records) -> str:
    """CSV lines of ``records`` (lists of cells) as the csv module writes them."""
    buf = io.StringIO()
    csv.writer(buf).writerows(records)
    return buf.getvalue()


def run_study(spec: StudySpec, *, output: str | os.PathLike | None = None,
              scheduler: str | None = None, workers: int | None = None, resume: bool = False,
              batch_size: int | None = None, connect_timeout: float = 10.0, keep_rows: bool = True,
              on_rows: Callable[[int], None] | None = None,
              curves: str | os.PathLike | None = None) -> StudyResult:
    """Run every point of ``spec``; return the rows (and write them to ``output``).

    Parameters
    ----------
    spec : StudySpec
        From :func:`load_spec` or :func:`parse_spec`.
    output : path, optional
        CSV (or ``.parquet``, needs pyarrow) written atomically at the end (an existing file is kept
        until then) from the journal, in index order and in chunks, with the spec and column units
        (Parquet metadata or sidecar ``OUTPUT.meta.json``).  Rows are journalled with checksums to
        ``OUTPUT.partial.csv`` (:func:`journal_path`), removed at the end.
    scheduler : str, optional
        Dask scheduler address (``tcp://host:8786``); by default the local cores run the study.
    workers : int, optional
        Local processes (default: all cores); 1 runs in this process.
    resume : bool
        Keep the verified rows of the journal (or of a finished ``output``) and run only the
        missing points; refused when they were made from another spec.
    batch_size : int, optional
        Points per task (default: sized from memory, :func:`task_size`).
    connect_timeout : float
        Seconds to wait for the Dask scheduler, then for its first worker, before giving up.
    keep_rows : bool
        Return every row (default); False keeps only the failed ones in memory (with ``output``,
        for studies too large to hold: the table is the file).
    on_rows : callable, optional
        Called with the number of rows each time a batch finishes (progress).
    curves : path, optional
        Also write K(ω) of every point (a sweep) to this Parquet file (needs pyarrow), long
        format: a row per point and ω, columns ``design`` (the table's ``index``), ``omega``
        [rad/s], ``K_re``, ``K_im`` [m/(N·s), or rad/(N·m·s) for a rotary drive]; units in the
        fields' metadata, the spec (:func:`provenance`) in the file's.  One row group per task,
        in the order tasks finish; failed points have none.  Not with ``resume``.

    Returns
    -------
    StudyResult
        Columns, rows (or the failed ones), executor, workers, counts.

    Raises
    ------
    MechcircError
        Another study holds ``output`` (its ``OUTPUT.lock``); ``resume`` finds rows of another spec;
        the scheduler cannot be reached or has no worker (nothing is written).
    """
    parquet = _check_run(spec, output, scheduler, connect_timeout, resume, curves)
    with _lock(output) if output else contextlib.nullcontext(), \
            _curve_writer(curves, spec) as write_curves:
        journal = journal_path(output) if output else None
        done = _resumed_rows(spec, output, journal, parquet) if resume and journal else []
        take = _Take(spec, journal, done, keep_rows or not output, write_curves, on_rows)
        run = _execute(spec, done, (scheduler, connect_timeout), workers, batch_size, take)
        if journal:
            _publish(output, parquet, spec, journal, take, done)
    return take.result(*run)


def _publish(output, parquet: bool, spec: StudySpec, journal: str, take, done: list) -> None:
    """Write ``output`` whole (atomically) from the journal, then remove the journal."""
    # Rows are journalled as they finish to a CSV beside the output, each with
    # a checksum; the output itself is written whole at the end, so an
    # existing file stays as it was until the new table is complete.
    if take.sink is None:           # nothing ran: the journal holds the kept rows
        _open_journal(journal, spec, done).close()
    _write_output(output, parquet, spec, journal)
    with contextlib.suppress(FileNotFoundError):
        os.unlink(journal)


def _check_run(spec: StudySpec, output, scheduler, connect_timeout, resume: bool,
               curves) -> bool:
    """Refuse :func:`run_study` settings that cannot work, before anything is written;
    whether the output is Parquet."""
    if parquet := bool(output) and str(output).lower().endswith(".parquet"):
        _require_pyarrow()
    if scheduler and not (isinstance(connect_timeout, (int, float)) and
                          0 < connect_timeout <= 3600):
        raise MechcircError(f"connect_timeout must be from 0 to 3600 s, got "
                            f"{brief(connect_timeout)}")
    if curves is not None:
        if spec.analysis != "sweep":
            raise MechcircError(f"curves of K(omega) need analysis = \"sweep\" (an omega grid); "
                                f"this study is {spec.analysis!r}")
        if resume:
            raise MechcircError("curves cannot be resumed (the points kept would have "
                                "none): run the study again without --resume")
        _require_pyarrow()
    return parquet


class _Take:
    """Takes each finished task in the study's process: its curves written, its
    rows counted and kept (all, or the failed ones), its journal lines appended
    to the journal (opened with the kept rows when the first task finishes), and
    progress reported."""

    def __init__(self, spec: StudySpec, journal: str | None, done: list[dict],
                 keep_rows: bool, write_curves: Callable | None,
                 on_rows: Callable[[int], None] | None):
        self.spec, self.journal, self.done = spec, journal, done
        self.keep_rows, self.write_curves, self.on_rows = keep_rows, write_curves, on_rows
        self.rows = list(done) if keep_rows else [r for r in done if r["status"] != "ok"]
        self.count, self.failed = len(done), sum(r["status"] != "ok" for r in done)
        self.sink: TextIO | None = None

    @property
    def task(self) -> tuple:
        """What each task returns besides its failed rows: (curves, all rows, journal text)."""
        return (self.write_curves is not None, self.keep_rows, bool(self.journal))

    def __call__(self, out: _TaskOut) -> None:
        if self.write_curves is not None:
            self.write_curves(out.rows, out.K)
        self.count += out.n
        self.failed += len(out.bad)
        self.rows.extend((out.rows or []) if self.keep_rows else out.bad)
        if self.journal:
            if self.sink is None:
                self.sink = _open_journal(self.journal, self.spec, self.done)
            self.sink.write(out.text)
            self.sink.flush()
        if self.on_rows is not None:
            self.on_rows(out.n)

    def close(self) -> None:
        if self.sink is not None:
            self.sink.close()

    def result(self, executor: str, n_workers: int) -> StudyResult:
        self.rows.sort(key=lambda r: r["index"])
        return StudyResult(self.spec.columns, self.rows, executor, n_workers, len(self.done),
                           self.failed, self.count, column_units(self.spec))


def _execute(spec: StudySpec, done: list, dask: tuple, workers: int | None,
             batch_size: int | None, take: _Take) -> tuple[str, int]:
    """Run the points not in ``done`` on the Dask scheduler ``dask`` = (address,
    timeout) if given, else on the local cores, then close ``take``; the
    executor's name and its number of workers."""
    have = {r["index"] for r in done}
    n_todo = len(spec.points) - len(have)
    # Connect before the journal is touched: a failed start leaves no file.
    client = _dask_client(*dask) if dask[0] else None
    try:
        if client is not None:
            return "dask", _run_dask(spec, have, n_todo, client, batch_size, take)
        return _run_local(spec, have, n_todo, workers or os.cpu_count() or 1, batch_size, take)
    finally:
        take.close()


@contextlib.contextmanager
def _curve_writer(path, spec: StudySpec):
    """``write(rows, K)`` appending a task's K(ω) curves to the Parquet file ``path``
    (long format, see :func:`run_study`), which appears only if the block ends
    cleanly; None without ``path``."""
    if path is None:
        yield None
        return

    import pyarrow as pa
    import pyarrow.parquet as pq

    omega = _omega_grid(spec)
    record = provenance(spec)
    k_unit = record["units"]["K_abs_min"]
    record["curves"] = ("long format: one row per design and omega; design is the "
                        "table's index; K = K_re + j K_im")
    schema = pa.schema([pa.field("design", pa.int64()),
                        *(pa.field(name, pa.float64(), metadata={"unit": unit}) for name, unit in
                          (("omega", "rad/s"), ("K_re", k_unit), ("K_im", k_unit)))],
                       metadata={"mechcirc": json.dumps(record, ensure_ascii=False)})
    with atomic_path(path) as tmp, pq.ParquetWriter(tmp, schema) as writer:
        def write(rows, K):
            ok = np.array([r["status"] == "ok" for r in rows], dtype=bool)
            if not ok.any():
                return
            index = np.array([r["index"] for r in rows], dtype=np.int64)[ok]
            K = np.asarray(K)[ok]
            writer.write_table(pa.table({
                "design": np.repeat(index, omega.size), "omega": np.tile(omega, index.size),
                "K_re": K.real.ravel(), "K_im": K.imag.ravel()}, schema=schema))

        yield write


#: First line of a journal: this tag, the spec's SHA-256 and its canonical JSON.
_SPEC_LINE = "#mechcirc-study-spec"


def _resumed_rows(spec: StudySpec, output, journal: str, parquet: bool) -> list[dict]:
    """The verified rows of the journal, or of a finished output, that are points of ``spec``.

    The file's recorded spec must be ``spec``'s (else an error naming what
    changed); a row whose parameter values are not its point's is run again.
    """
    if Path(journal).exists():
        _same_spec(journal, _journal_spec(journal), spec)
        done = read_rows(journal, spec.columns)
    elif Path(output).exists() and parquet:
        recorded, table = _read_parquet(output)
        _same_spec(os.fspath(output), recorded, spec)
        if table.column_names != spec.columns:
            raise MechcircError(f"{os.fspath(output)}: its columns "
                                f"({', '.join(table.column_names)}) are not this study's; "
                                "cannot resume (use another -o)")
        done = [{c: ("" if v is None else v) for c, v in row.items()}
                for row in table.to_pylist()]
    elif Path(output).exists():
        _same_spec(os.fspath(output), _sidecar_spec(output), spec)
        done = read_rows(output, spec.columns)
    else:
        return []
    n, k = len(spec.points), len(spec.params)
    return [r for r in done if r["index"] < n and
            tuple(r[p] for p in spec.params) == spec.points[r["index"]][:k]]


def _same_spec(where: str, recorded: str | None, spec: StudySpec) -> None:
    """Refuse to resume from ``where`` unless it records ``spec`` (its canonical text)."""
    if recorded is None:
        raise MechcircError(f"{where}: records no study spec (written by another program or "
                            "an older mechcirc), so its rows cannot be checked against this "
                            "study; cannot resume (run without --resume to start over, or use "
                            "another -o)")
    if recorded == spec.canonical:
        return
    try:
        changes = _changes(json.loads(recorded), json.loads(spec.canonical))
    except (ValueError, AttributeError):
        changes = []
    changes = changes or ["its spec record differs"]
    raise MechcircError(f"{where} was made from another spec: {'; '.join(changes[:4])}"
                        f"{'; …' if len(changes) > 4 else ''}; cannot resume (run without "
                        "--resume to start over, or use another -o)")


def _changes(old: dict, new: dict, prefix: str = "") -> list[str]:
    """What differs between two canonical specs, key by key (``sample.axes.eta1 was …``);
    of two samples made by different methods, only the method."""
    out = []
    if old.get("method") != new.get("method"):
        return [f"{prefix}method was {_show(old.get('method'))}, now {_show(new.get('method'))}"]
    for key in sorted(set(old) | set(new)):
        name = prefix + key
        if key not in new:
            out.append(f"{name} was {_show(old[key])}, now absent")
        elif key not in old:
            out.append(f"{name} is new ({_show(new[key])})")
        elif isinstance(old[key], dict) and isinstance(new[key], dict):
            out += _changes(old[key], new[key], name + ".")
        elif old[key] != new[key]:
            out.append(f"{name} was {_show(old[key])}, now {_show(new[key])}")
    return out


def _show(value) -> str:
    # a SHA-256 (the file's content changed) by its first 12 digits
    return value[:12] + "…" if isinstance(value, str) and re.fullmatch(r"[0-9a-f]{64}", value) \
        else brief(value)


def _journal_spec(journal: str) -> str | None:
    """The canonical spec a journal was started with (its first line), or None."""
    try:
        with open(journal, encoding="utf-8") as fh:
            first = fh.readline().rstrip("\n")
    except (UnicodeDecodeError, OSError):
        return None
    tag, _, rest = first.partition(" ")
    digest, _, canonical = rest.partition(" ")
    return canonical if tag == _SPEC_LINE and digest == "sha256=" + _sha256(canonical) else None


def _open_journal(journal: str, spec: StudySpec, done: list[dict]) -> TextIO:
    """A fresh journal holding the spec and the verified rows, open for appending.

    A resumed journal is rewritten, not appended to: its last line may lack
    its terminator.
    """
    columns = spec.columns
    with atomic_open(journal, "w", newline="", encoding="utf-8") as fh:
        fh.write(f"{_SPEC_LINE} sha256={spec.sha256} {spec.canonical}\n")
        w = csv.writer(fh)
        w.writerow([*columns, _CHECK])
        w.writerows(_journal_record(r, columns) for r in done)
    return open(journal, "a", newline="", encoding="utf-8")


def provenance(spec: StudySpec) -> dict:
    """What an output records about the study that made it (JSON-ready).

    ``spec`` (the canonical spec, as a dict) and ``spec_sha256`` (its hash,
    what ``--resume`` compares), ``spec_text`` (the spec file as written),
    ``spec_file``, ``netlist``, ``units`` (every column's unit) and the
    ``mechcirc`` version.

    Parameters
    ----------
    spec : StudySpec

    Returns
    -------
    dict
    """
    from . import __version__

    return {"mechcirc": __version__, "spec_sha256": spec.sha256,
            "spec": json.loads(spec.canonical), "spec_file": spec.spec_source,
            "spec_text": spec.spec_text, "netlist": spec.netlist_source or None,
            "units": column_units(spec)}


def sidecar_path(output: str | os.PathLike) -> str:
    """The provenance file of a CSV table: ``OUTPUT.meta.json`` (see :func:`provenance`).

    Parameters
    ----------
    output : str or PathLike
        The study's CSV table.

    Returns
    -------
    str
        The sidecar's path, beside the table.
    """
    return f"{os.fspath(output)}.meta.json"


def _sidecar_spec(output) -> str | None:
    try:
        with open(sidecar_path(output), encoding="utf-8") as fh:
            return _canonical(json.load(fh)["spec"])
    except (OSError, ValueError, KeyError, TypeError):
        return None


def _write_output(output, parquet: bool, spec: StudySpec, journal: str) -> None:
    """The whole table, in index order, with its provenance: Parquet with it in the
    file's metadata, or CSV with the sidecar ``OUTPUT.meta.json``, the two
    replaced together (sidecar first) or not at all.  The rows come from the
    journal a chunk at a time (:func:`_journal_in_order`), as the CSV lines they
    already are there."""
    columns, record = spec.columns, provenance(spec)
    chunks = _journal_in_order(journal, len(columns))
    with OutputSet() as out:
        if parquet:
            _write_parquet(out.path(output), columns, chunks, record)
            return
        with open(out.path(sidecar_path(output)), "w", encoding="utf-8") as fh:
            json.dump(record, fh, indent=1, ensure_ascii=False)
            fh.write("\n")
        with open(out.path(output), "wb") as fh:
            fh.write(_csv_text([columns]).encode("utf-8"))
            fh.writelines(b"".join(lines) for lines in chunks)
            fh.flush()
            os.fsync(fh.fileno())


def _verified(line: bytes, width: int) -> bytes | None:
    """A journal line's CSV row (its cells, without the checksum, ending in CRLF as
    the csv module writes it), or None if the checksum does not match."""
    body, _, crc = line.rstrip(b"\r\n").rpartition(b",")
    if b'"' in body:                     # quoted cells: split them as csv does
        rec = next(csv.reader([line.decode("utf-8")]))
        ok = len(rec) == width + 1 and rec[-1] == _crc(rec[:-1])
    else:                                   # the cells are the text between commas
        ok = (body.count(b",") == width - 1 and
              crc == b"%08x" % zlib.crc32(body.replace(b",", b"\x1f")))
    return body + b"\r\n" if ok else None


def _journal_in_order(journal: str, width: int, chunk: int = 65536):
    """The rows of a finished journal in index order, as CSV lines (bytes, the
    checksum dropped), ``chunk`` rows at a time; a second row of one point is left out.

    Only the index and the byte offset of each row are held (16 bytes a row):
    the rows are read back in order (by seeking, unless the journal is already in
    order), so writing a million rows takes no more memory than a chunk of them.
    Each row is one line (:func:`_journal_record`), and is checked against its CRC again.
    """
    from array import array

    index, offset = array("q"), array("q")
    with open(journal, "rb") as fh:
        fh.readline()                           # the spec
        fh.readline()                           # the header
        pos = fh.tell()
        for line in fh:
            index.append(int(line[:line.index(b",")]))
            offset.append(pos)
            pos += len(line)
        idx, offs = np.asarray(index), np.asarray(offset)     # int64 views, empty or not
        _, first = np.unique(idx, return_index=True)   # each point's first row, by index
        offs = offs[first]
        in_order = bool(np.all(np.diff(offs) > 0))
        for start in range(0, offs.size, chunk):
            lines = []
            for off in offs[start:start + chunk].tolist():
                if not in_order or fh.tell() != off:
                    fh.seek(off)
                row = _verified(fh.readline(), width)
                if row is None:
                    raise MechcircError(f"{journal}: the row at byte {off} changed on disk "
                                        "while the study ran; run it again with --resume")
                lines.append(row)
            yield lines


def journal_path(output: str | os.PathLike) -> str:
    """Where a study writing ``output`` journals its rows while it runs: ``OUTPUT.partial.csv``.

    Parameters
    ----------
    output : str or PathLike
        The study's table (CSV or Parquet).

    Returns
    -------
    str
        The journal's path; it is removed once ``output`` is written.
    """
    return f"{os.fspath(output)}.partial.csv"


def _require_pyarrow():
    try:
        import pyarrow  # noqa: F401
    except ImportError:
        raise MechcircError("Parquet output needs pyarrow (pip install pyarrow); "
                            "or write CSV (-o results.csv)") from None


def _write_parquet(path, columns: list[str], chunks, record: dict) -> None:
    """The table as Parquet from chunks of rows (CSV lines as in the journal), one
    row group a chunk, parsed by pyarrow; empty cells are nulls.  The file's
    key-value metadata ``mechcirc`` holds ``record`` (JSON), and each field its
    ``unit``."""
    import pyarrow as pa
    import pyarrow.csv as pcsv
    import pyarrow.parquet as pq

    arrow = {str: pa.string(), int: pa.int64(), float: pa.float64()}
    types = {c: arrow[_cell_type(c)] for c in columns}
    units = record["units"]
    schema = pa.schema([pa.field(c, types[c], metadata=None if units[c] is None else
                                 {"unit": units[c]}) for c in columns],
                       metadata={"mechcirc": json.dumps(record, ensure_ascii=False)})
    read = pcsv.ReadOptions(column_names=columns)
    convert = pcsv.ConvertOptions(column_types=types, null_values=[""],
                                  strings_can_be_null=True)
    with pq.ParquetWriter(path, schema) as writer:
        for lines in chunks:
            table = pcsv.read_csv(pa.BufferReader(b"".join(lines)), read_options=read,
                                  convert_options=convert)
            writer.write_table(table.cast(schema))


def _read_parquet(path):
    """The recorded canonical spec (or None) and the table of a study's Parquet file."""
    import pyarrow.parquet as pq

    try:
        table = pq.read_table(path)
    except Exception as exc:  # noqa: BLE001 - pyarrow's errors have no common base
        raise MechcircError(f"{os.fspath(path)}: not a Parquet table ({type(exc).__name__}); "
                            "cannot resume (use another -o)") from None
    try:
        recorded = _canonical(json.loads(table.schema.metadata[b"mechcirc"])["spec"])
    except (TypeError, KeyError, ValueError):
        recorded = None
    return recorded, table


@contextlib.contextmanager
def _lock(output):
    """Hold ``OUTPUT.lock`` while a study writes ``output`` (a context manager).

    ``fcntl.flock`` on the lock file: the kernel releases it when its holder
    ends, however it ends, so a lock file left by a killed study (its pid no
    longer running) is simply taken over.  The file names the holder's pid for
    the message a second writer gets.  Without ``fcntl`` (Windows) the file is
    created with ``O_EXCL`` and one left by a killed study must be deleted by hand.
    """
    import socket

    path = f"{os.fspath(output)}.lock"

    def held(holder: str, hint: str = ""):
        return MechcircError(f"{os.fspath(output)} is being written by another study "
                             f"({holder or 'pid unknown'}, per {path}); wait for it to end, "
                             f"or write another -o{hint}")

    try:
        import fcntl
    except ImportError:
        fcntl = None
    while True:
        try:
            fd = os.open(path, os.O_RDWR | os.O_CREAT | (0 if fcntl else os.O_EXCL), 0o644)
        except FileExistsError:
            raise held(_holder(path), f" (if it is no longer running, delete {path})") from None
        except OSError as exc:
            raise MechcircError(f"{os.fspath(output)}: cannot create the lock file {path}: "
                                f"{exc.strerror}") from None
        if fcntl is None:
            break
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            os.close(fd)
            raise held(_holder(path)) from None
        with contextlib.suppress(FileNotFoundError):   # the holder may have removed it
            if os.path.samestat(os.fstat(fd), os.stat(path)):
                break
        os.close(fd)
    _LOCK_FDS.add(fd)
    try:
        os.ftruncate(fd, 0)
        os.write(fd, f"pid {os.getpid()} on {socket.gethostname()}\n".encode())
        yield
    finally:
        with contextlib.suppress(OSError):
            os.unlink(path)         # before the lock goes: see the samestat check
        _LOCK_FDS.discard(fd)
        os.close(fd)


#: Descriptors of the output locks this process holds: a forked worker closes its
#: copies (:func:`_die_with_parent`), so that the lock ends with the study's process.
_LOCK_FDS: set[int] = set()


def _holder(path: str) -> str:
    try:
        with open(path, encoding="utf-8", errors="replace") as fh:
            return fh.read(200).strip()
    except OSError:
        return ""


#: Memory a task may fill with its arrays (bytes): the batch's K, error bound,
#: Q0 and flags on the designs × ω grid and its stacked nodal matrices.
TASK_BYTES = 64 * 2 ** 20
#: Bytes a design takes in a task: for its resonances and extremes, and per ω point
#: (tracemalloc's peak over designs + sweep + flags + resonances + extremes of
#: stb_heald.mcir: 12.3 kB and 37 B measured; see docs/performance.md).
_BYTES_PER_DESIGN, _BYTES_PER_POINT = 13_000, 40


def task_size(spec: StudySpec, n_points: int, n_workers: int,
              batch_size: int | None = None) -> int:
    """Points per task: ``batch_size`` if given, else as many as fit in
    :data:`TASK_BYTES` (the designs' arrays), but at least four tasks per worker
    (so that the workers share the end of the study) and at most ``n_points``.
    A sley simulation is one point at a time: at most 500 per task."""
    if batch_size:
        return max(1, int(batch_size))
    share = math.ceil(n_points / (4 * max(1, n_workers)))
    if spec.analysis == "simulate":
        return max(1, min(500, share))
    width = spec.omega[2] if spec.analysis == "sweep" and spec.omega else 0
    fit = TASK_BYTES // (_BYTES_PER_DESIGN + _BYTES_PER_POINT * width)
    return max(1, min(fit, share))


def _run_local(spec, have, n_todo, n_workers, batch_size, take) -> tuple[str, int]:
    size = task_size(spec, n_todo, n_workers, batch_size)
    if n_workers <= 1 or n_todo <= size:
        # One batch or one worker: starting processes would cost more than it saves.
        for batch in _todo(spec, have, size):
            take(_run_task(spec, batch, *take.task))
        return "inline", 1
    from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait

    with ProcessPoolExecutor(max_workers=n_workers, initializer=_die_with_parent,
                             initargs=(os.getpid(),)) as pool:
        # The spec without its point list: each batch carries its own points, and the
        # spec is pickled once per batch (a million points would otherwise travel with
        # every batch).
        light = replace(spec, points=())
        batches = _todo(spec, have, size)
        pending: set = set()
        try:
            # A few tasks per worker in flight, the next made as one finishes: the
            # points of a large study are never all in memory as tasks.
            pending.update(pool.submit(_run_task, light, batch, *take.task)
                           for batch in itertools.islice(batches, 2 * n_workers))
            while pending:
                finished, pending = wait(pending, return_when=FIRST_COMPLETED)
                for fut in finished:
                    take(fut.result())
                    if (batch := next(batches, None)) is not None:
                        pending.add(pool.submit(_run_task, light, batch, *take.task))
        except BaseException:
            for fut in pending:
                fut.cancel()
            raise
    return "local", n_workers


def _die_with_parent(parent: int) -> None:
    """Worker initializer: end this worker when the study's process ends, however it ends.

    After SIGKILL of the parent, workers would otherwise be re-parented to
    init and wait on the pipe for minutes.  On Linux the kernel delivers
    SIGKILL to the worker when its parent dies (``prctl(PR_SET_PDEATHSIG)``);
    elsewhere a daemon thread polls the parent's pid once a second.  A forked
    worker also closes its copies of the output lock's descriptor (a flock
    belongs to every copy: the lock would outlive a killed study in its workers).
    """
    for fd in _LOCK_FDS:
        with contextlib.suppress(OSError):
            os.close(fd)
    _LOCK_FDS.clear()

    if sys.platform.startswith("linux"):
        with contextlib.suppress(OSError, AttributeError):     # no libc or prctl: poll
            import ctypes

            libc = ctypes.CDLL(None, use_errno=True)
            PR_SET_PDEATHSIG = 1
            if libc.prctl(PR_SET_PDEATHSIG, int(signal.SIGKILL), 0, 0, 0) == 0:
                if os.getppid() != parent:      # the parent died before prctl took hold
                    os._exit(1)
                return

    def watch():
        import time

        while os.getppid() == parent:
            time.sleep(1.0)
        os._exit(1)

    threading.Thread(target=watch, name="mechcirc-parent-watch", daemon=True).start()


def _dask_client(scheduler: str, timeout: float):
    """A client of the scheduler at ``scheduler`` once it has a worker, else a user error
    within about ``timeout`` seconds (for the connection, then for the first worker)."""
    try:
        from distributed import Client
    except ImportError:
        raise MechcircError("--scheduler needs Dask: pip install 'mechcirc[study]'") from None
    try:
        client = Client(scheduler, timeout=f"{timeout}s")
    except (OSError, TimeoutError, ValueError) as exc:
        raise MechcircError(f"cannot reach the Dask scheduler at {brief(scheduler)}: "
                            f"{exc}") from None
    try:
        client.wait_for_workers(1, timeout=timeout)
    except (OSError, TimeoutError):
        client.close()
        raise MechcircError(f"the Dask scheduler at {scheduler} has no workers (none joined "
                            f"within {timeout:g} s); start one with 'dask worker {scheduler}' "
                            "or raise --connect-timeout") from None
    except BaseException:
        client.close()
        raise
    return client


def _run_dask(spec, have, n_todo, client, batch_size, take) -> int:
    from distributed import as_completed

    try:
        n_workers = max(1, sum(w.get("nthreads", 1) for w in
                               client.scheduler_info()["workers"].values()))
        size = task_size(spec, n_todo, n_workers, batch_size)
        try:
            spec_future = client.scatter(replace(spec, points=()), broadcast=True)   # as local
        except TimeoutError:
            raise MechcircError("the Dask cluster's workers left before the study "
                                "started") from None
        # A few tasks per worker thread in flight, the next submitted as one finishes.
        batches = _todo(spec, have, size)
        futures = as_completed([client.submit(_run_task, spec_future, batch, *take.task,
                                              pure=False)
                                for batch in itertools.islice(batches, 4 * n_workers)])
        for fut in futures:
            take(fut.result())
            if (batch := next(batches, None)) is not None:
                futures.add(client.submit(_run_task, spec_future, batch, *take.task, pure=False))
        return n_workers
    finally:
        client.close()
