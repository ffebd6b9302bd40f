"""The study spec: the TOML file checked, its axes, samples and sample files made
into points, each parameter's unit, and the canonical form ``resume`` compares
(the format: :mod:`mechcirc.study`)."""

import contextlib
import hashlib
import io
import itertools
import json
import math
import os
import random
import re
import warnings
from dataclasses import dataclass, replace
from pathlib import Path
from typing import NoReturn

import numpy as np

from ..circuit import ELEMENT_UNITS, Drive, Element, units_of
from ..errors import MechcircError, NetlistError
from ..limits import (MAX_POINTS_PER_REVOLUTION, MAX_REVOLUTIONS, MAX_STUDY_POINTS,
                      MAX_STUDY_SWEEP_POINTS, MAX_STUDY_WORK)
from ..netlist import SYNTAX, expressions_of, parse
from ..sources import (Table, brief, csv_rows, did_you_mean, finite_number, load_toml,
                       locate_path, number_error, read_bytes, read_source, split_lines,
                       summary_repr, unknown_key)
from ..units import looks_like_unit, parse_omega

__all__ = ["StudySpec", "load_spec", "parse_spec", "column_units", "SAMPLE_METHODS"]


SWEEP_COLUMNS = ["K_abs_min", "omega_at_K_min", "K_abs_max", "omega_at_K_max", "Q0_abs_max",
                  "omega_at_Q0_max", "n_flagged"]
SLEY_QUANTITIES = {"one-side": ["eps2P", "eps4P", "eps4T", "M2V"],
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
        return sha256(self.canonical)

    @property
    def columns(self) -> list[str]:
        """The table's columns, in order."""
        head = ["index", *self.params, "status", "error"]
        if self.analysis == "sweep":
            return head + SWEEP_COLUMNS
        if self.analysis == "simulate":
            return head + [f"{q}_{end}" for q in SLEY_QUANTITIES[setting(self, "sley")[0]]
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
    if isinstance(value, str):
        try:
            w = parse_omega(value)
        except ValueError as exc:
            _fail(path, f"{what}: {exc}")
        if not math.isfinite(w):
            _fail(path, f"{what} must be finite, got {brief(value)}")
        return w
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        _fail(path, f"{what} must be a number [rad/s] or a string such as '50Hz'"
                    + ("" if isinstance(value, bool) else f", got {brief(value)}"))
    if not finite_number(value):
        _fail(path, f"{what} must be a finite number [rad/s], got {brief(value)}")
    return float(value)


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
    if omega_max is not None and not omega_max > 0:
        _fail(("omega_max",), f"omega_max must be > 0 rad/s, got {omega_max:g}")
    sley: tuple[str, int, int, int] | None = None
    if analysis == "simulate":
        sley = _sley_settings(data.get("sley", {}), names, kind)
        units = tuple(map(_sley_units().get, names))
    else:
        if missing := [n for n in names if n not in roles]:     # each a .param, checked once
            # at the first one's key ([grid] or [sample.params]; a sample file's header: its table)
            at = (kind,) if "file" in data[kind] else (kind, missing[0]) if kind == "grid" \
                else (kind, "params", missing[0])
            _fail(at, f"{', '.join(missing)} is not a .param of {path}"
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
        canon["netlist_sha256"] = sha256(text)
    return StudySpec(text, str(path), analysis, names, points, omega, n_res, omega_max, source,
                     sley, canonical=canonical_json(canon), param_units=units)


def sha256(text: str | bytes) -> str:
    return hashlib.sha256(text.encode("utf-8") if isinstance(text, str) else text).hexdigest()


def canonical_json(data) -> str:
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
        if words := re.split(r"[#;]", line, maxsplit=1)[0].split():
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
    return names, points, {"method": "file", "columns": list(names),
                           "file_sha256": sha256(read_bytes(path, "a sample"))}


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
        value = None
        with contextlib.suppress(ValueError):
            value = float(text) if isinstance(text, str) else text
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
    npts = _integer(("omega", "points"), o.get("points", 200), "omega.points", 2,
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
    from ..sley.models import UNIT_ROLES

    return {n: _ROLE_UNITS[r] for n, r in UNIT_ROLES.items() if n not in ("branch", "beat_sign")}


def _sley_settings(table, names, kind: str) -> tuple[str, int, int, int]:
    if not isinstance(table, dict):
        _fail(("sley",), "[sley] must be a table (drive, variant, revolutions, "
                         "points_per_revolution)")
    _check_keys("sley", table)
    drive = table.get("drive", "one-side")
    if not isinstance(drive, str) or drive not in SLEY_QUANTITIES:
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


def setting(spec: StudySpec, name: str):
    """``spec.omega`` (min, max, points, log) of a sweep study's ω grid, or ``spec.sley``
    (drive, variant, revolutions, points_per_revolution) of a sley study; an error if
    the analysis has none."""
    if (value := getattr(spec, name)) is None:
        what = "omega grid" if name == "omega" else "[sley] preset"
        raise MechcircError(f"{spec.spec_source}: analysis {spec.analysis!r} has no {what}")
    return value


def omega_grid(spec: StudySpec):
    """The ω grid of a sweep study [rad/s]: ``spec.omega``'s points, geometric with log."""
    return _spaced(*setting(spec, "omega"))


def _spaced(lo: float, hi: float, n: int, log: bool):
    """``n`` points from ``lo`` to ``hi``, geometric with ``log`` (a grid axis, the ω grid)."""
    return (np.geomspace if log else np.linspace)(lo, hi, n)
