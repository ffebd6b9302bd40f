"""A study's files: the journal of finished rows (each with its CRC-32) and
resuming from it, the output written whole from it (CSV with its sidecar, or
Parquet), the provenance they record, and the K(ω) curves file."""

import contextlib
import csv
import io
import json
import os
import re
import zlib
from pathlib import Path
from typing import TextIO

import numpy as np

from ..errors import MechcircError
from ..outputs import OutputSet, atomic_open, atomic_path
from ..sources import brief
from .spec import StudySpec, canonical_json, column_units, omega_grid, sha256

__all__ = ["read_rows", "journal_path", "sidecar_path", "provenance"]


def journal_record(row: dict, columns: list[str]) -> list[str]:
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


def csv_text(records) -> str:
    """CSV lines of ``records`` (lists of cells) as the csv module writes them."""
    buf = io.StringIO()
    csv.writer(buf).writerows(records)
    return buf.getvalue()


@contextlib.contextmanager
def curve_writer(path, spec: StudySpec):
    """``write(rows, K)`` appending a task's K(ω) curves to the Parquet file ``path``
    (long format, see :func:`run_study`), which appears only if the block ends
    cleanly; None without ``path``."""
    if path is None:
        yield None
        return

    import pyarrow as pa
    import pyarrow.parquet as pq

    omega, record = omega_grid(spec), provenance(spec)
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


def resumed_rows(spec: StudySpec, output, journal: str, parquet: bool) -> list[dict]:
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
    return [r for r in done if r["index"] < len(spec.points) and
            tuple(r[p] for p in spec.params) == spec.points[r["index"]]]


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
    return canonical if tag == _SPEC_LINE and digest == "sha256=" + sha256(canonical) else None


def open_journal(journal: str, spec: StudySpec, done: list[dict]) -> TextIO:
    """A fresh journal holding the spec and the verified rows, open for appending.

    A resumed journal is rewritten, not appended to: its last line may lack
    its terminator.
    """
    columns = spec.columns
    with atomic_open(journal, "w", newline="", encoding="utf-8") as fh:
        fh.write(f"{_SPEC_LINE} sha256={spec.sha256} {spec.canonical}\n")
        w = csv.writer(fh)
        w.writerow([*columns, _CHECK])
        w.writerows(journal_record(r, columns) for r in done)
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
    from .. import __version__

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
            return canonical_json(json.load(fh)["spec"])
    except (OSError, ValueError, KeyError, TypeError):
        return None


def write_output(output, parquet: bool, spec: StudySpec, journal: str) -> None:
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
            fh.write(csv_text([columns]).encode("utf-8"))
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
    Each row is one line (:func:`journal_record`), and is checked against its CRC again.
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
        # each point's first row, by index (int64 views, empty or not)
        offs = np.asarray(offset)[np.unique(np.asarray(index), return_index=True)[1]]
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


def require_pyarrow():
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
    types, units = {c: arrow[_cell_type(c)] for c in columns}, record["units"]
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
        recorded = canonical_json(json.loads(table.schema.metadata[b"mechcirc"])["spec"])
    except (TypeError, KeyError, ValueError):
        recorded = None
    return recorded, table
