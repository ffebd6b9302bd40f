"""Reading the text files mechcirc accepts (netlists, linkages, scenes), with located errors."""

from __future__ import annotations

import math
import numbers
import os
import re
import stat
from dataclasses import dataclass, fields
from typing import TYPE_CHECKING, TypeGuard

from .errors import InputError, NetlistError, did_you_mean, unknown_name

if TYPE_CHECKING:  # pragma: no cover - annotations only (numpy is imported where used)
    from numpy.typing import NDArray

__all__ = ["read_source", "read_bytes", "MAX_INPUT_BYTES", "split_lines", "line_col",
           "finite_number", "brief", "load_toml", "locate", "locate_path", "located", "Table",
           "unknown_key", "check_keys", "number_error", "checked_number", "did_you_mean",
           "is_number", "positive_number", "real_values", "summary_repr", "data_frame",
           "quantity_frame", "NamedValues"]

#: The largest input file mechcirc reads [bytes].  A netlist of the statement
#: limit is far below this; anything larger is refused before it is read.
MAX_INPUT_BYTES = 64 * 2**20


def read_bytes(path: str | os.PathLike, expected: str) -> bytes:
    """The bytes of the regular file ``path``, at most :data:`MAX_INPUT_BYTES`.

    Devices, pipes and sockets (``/dev/zero``, a FIFO) are refused before
    anything is read, and so is a file larger than the bound; at most
    ``MAX_INPUT_BYTES + 1`` bytes are ever read, so a file that grows while
    it is read cannot exhaust memory either.

    Parameters
    ----------
    path : str or PathLike
        The file to read.
    expected : str
        What the file should be, for messages.

    Returns
    -------
    bytes

    Raises
    ------
    NetlistError
        If the file is missing, a folder, not a regular file, unreadable or
        too large.
    """
    source = os.fspath(path)
    try:                # (the checks' NetlistErrors are no OSError: they pass through)
        info = os.stat(source)
        if stat.S_ISDIR(info.st_mode):
            raise NetlistError("is a directory", source, 0, 0, f"{expected} file")
        if not stat.S_ISREG(info.st_mode):
            raise NetlistError("is not a regular file (a device, pipe or socket); nothing was "
                               "read", source, 0, 0, f"{expected} file")
        if info.st_size > MAX_INPUT_BYTES:
            raise NetlistError(f"is {info.st_size:,} bytes, more than the limit of "
                               f"{MAX_INPUT_BYTES:,} bytes; nothing was read", source, 0, 0,
                               f"{expected} file")
        with open(source, "rb") as fh:
            data = fh.read(MAX_INPUT_BYTES + 1)
    except FileNotFoundError:
        raise NetlistError("no such file", source, 0, 0, f"the path of {expected}") from None
    except OSError as exc:
        raise NetlistError(f"cannot read: {exc.strerror}", source) from None
    if len(data) > MAX_INPUT_BYTES:
        raise NetlistError(f"grew past the limit of {MAX_INPUT_BYTES:,} bytes while it was "
                           "read", source, 0, 0, f"{expected} file")
    return data


def read_source(path: str | os.PathLike, expected: str) -> str:
    """The UTF-8 text of ``path`` (a byte-order mark dropped).

    Parameters
    ----------
    path : str or PathLike
        The text file, read by :func:`read_bytes`.
    expected : str
        What the file should be (e.g. ``"a .mcir netlist"``), for the messages.

    Returns
    -------
    str

    Raises
    ------
    NetlistError
        If the file is missing, a folder, not a regular file, larger than
        :data:`MAX_INPUT_BYTES`, unreadable, or not UTF-8 (then with the line
        and column of the first bad byte).
    """
    source = os.fspath(path)
    data = read_bytes(path, expected)
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as exc:
        before = data[:exc.start]
        line, col = before.count(b"\n") + 1, exc.start - (before.rfind(b"\n") + 1) + 1
        raise NetlistError(f"byte 0x{data[exc.start]:02x} is not valid UTF-8", source,
                           line, col, "a UTF-8 text file") from None
    return text.removeprefix("\ufeff")


# ------------------------------------------------------------------ lines and places
def split_lines(text: str) -> list[str]:
    """The lines of ``text`` as editors and ``wc -l`` count them.

    Only ``\\n`` ends a line (``\\r\\n`` too: its ``\\r`` is dropped).  Unlike
    :meth:`str.splitlines`, a form feed, vertical tab, lone ``\\r``, NEL
    (U+0085) or U+2028/U+2029 is a character of its line, not a line break,
    so a reported line number always names a line that ``wc -l`` and an
    editor show (TOML agrees: only LF and CRLF end a line there).

    Parameters
    ----------
    text : str
        The text to split.

    Returns
    -------
    list of str
    """
    lines = text.split("\n")
    if lines and lines[-1] == "":
        lines.pop()                   # the terminator of the last line starts no new one
    return [ln[:-1] if ln.endswith("\r") else ln for ln in lines]


def csv_rows(text: str, source: str, comments: bool = True):
    """The rows of CSV text, line by line: blank lines (and ``#`` comment lines) skipped.

    Parameters
    ----------
    text : str
        The file's text.
    source : str
        The file's name, for the error.
    comments : bool
        Skip lines starting with ``#``.

    Yields
    ------
    tuple
        ``(line, cells, columns, end)``: the 1-based line number, the cells as text,
        the 1-based column where each value starts (1 for all on a line with quotes),
        and the column after the row.

    Raises
    ------
    NetlistError
        A line that is not a CSV row (a lone carriage return, a stray quote).
    """
    import csv

    for lineno, line in enumerate(split_lines(text), start=1):
        if not line.strip() or (comments and line.lstrip().startswith("#")):
            continue
        try:
            cells = next(csv.reader([line]))
        except csv.Error as exc:
            raise NetlistError(f"not a CSV row ({exc})", source, lineno, 1,
                               "comma-separated values") from None
        cols, pos = [], 1
        for cell in cells:
            cols.append(pos + len(cell) - len(cell.lstrip()))
            pos += len(cell) + 1
        yield lineno, cells, ([1] * len(cells) if '"' in line else cols), pos


def line_col(text: str, index: int) -> tuple[int, int]:
    """1-based (line, column) of the character at ``index`` (lines as :func:`split_lines`).

    Parameters
    ----------
    text : str
        The whole text.
    index : int
        0-based index of the character in ``text``.

    Returns
    -------
    tuple of (int, int)
    """
    index = max(0, min(index, len(text)))
    line = text.count("\n", 0, index) + 1
    return line, index - (text.rfind("\n", 0, index) + 1) + 1


# ------------------------------------------------------------------ values
_NAME = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")


def is_name(value) -> TypeGuard[str]:
    """Whether ``value`` is a name: a str of ASCII letters, digits and ``_``, not
    starting with a digit.

    Parameters
    ----------
    value : object
        A TOML value or a netlist token: a parameter's, element's, body's name.

    Returns
    -------
    bool
        False for anything but a str.
    """
    return isinstance(value, str) and _NAME.fullmatch(value) is not None


def is_number(text: str) -> bool:
    """Whether ``float(text)`` reads ``text`` (``inf`` and ``nan`` included).

    Parameters
    ----------
    text : str
        A field of an input file (a netlist token, a Touchstone number).

    Returns
    -------
    bool
        False where ``float`` raises ``ValueError``.
    """
    try:
        float(text)
    except ValueError:
        return False
    return True


def finite_number(value) -> TypeGuard[float]:
    """A TOML integer or float that is a finite float64 (not a bool, not ``10**400``).

    Parameters
    ----------
    value : object
        A value as a TOML reader returned it.

    Returns
    -------
    bool
    """
    if not isinstance(value, (int, float)) or isinstance(value, bool):
        return False
    try:
        return math.isfinite(value)
    except OverflowError:              # an integer beyond float64's range
        return False


def real_number(value) -> bool:
    """Whether an argument given in code is a real number: an int, a float or a numpy
    number, but not a bool (an int to Python, ``True`` would read as 1).

    Parameters
    ----------
    value : object
        The argument, of any type.

    Returns
    -------
    bool
    """
    return isinstance(value, numbers.Real) and not isinstance(value, bool)


def positive_number(value) -> bool:
    """Whether an argument given in code is a :func:`real_number` that is finite and > 0
    (a speed, a time, a step).

    Parameters
    ----------
    value : object
        The argument, of any type: a number or not, finite or not.

    Returns
    -------
    bool
    """
    return real_number(value) and math.isfinite(value) and value > 0


def real_values(value, what: str, unit: str,
                error: type[Exception] = InputError) -> NDArray:
    """``value`` (a number or an array of them) as a float ndarray of its shape, else ``error``
    naming the argument: "theta must be a finite number [rad], got 'x'" (text, None, a
    complex, a bool, NaN or ±inf; "finite numbers" for a sequence).

    Parameters
    ----------
    value : object
        The argument as given in code.
    what, unit : str
        Its name and unit, for the message.
    error : exception class
        What to raise (:class:`~mechcirc.errors.InputError`, or the module's own).

    Returns
    -------
    numpy.ndarray of float
    """
    import numpy as np

    try:
        a = np.asarray(value)
        ok = a.dtype.kind in "iuf" and bool(np.all(np.isfinite(a)))
    except (TypeError, ValueError, OverflowError):      # a ragged list, an int past float64
        a, ok = None, False
    if a is None or not ok:
        many = isinstance(value, (list, tuple, np.ndarray)) and (a is None or a.ndim > 0)
        kind = "finite numbers" if many else "a finite number"
        raise error(f"{what} must be {kind} [{unit}], got {brief(value)}")
    return a.astype(float)


def number_error(value, what: str, *, positive: bool = False,
                 allow_zero: bool = False) -> tuple[str, str] | None:
    """None for a finite number (> 0 with ``positive``, ≥ 0 with ``allow_zero`` too),
    else ``(message, what is right)`` for the located error of every reader.

    Parameters
    ----------
    value : object
        A value as a TOML reader returned it.
    what : str
        The value's name, for the message.
    positive, allow_zero : bool
        Demand > 0; with ``allow_zero`` too, ≥ 0.

    Returns
    -------
    tuple of (str, str) or None
    """
    if finite_number(value) and (not positive or value > 0 or allow_zero and value == 0):
        return None
    need = "a finite number" + ("" if not positive else " ≥ 0" if allow_zero else " > 0")
    return f"{what} must be {need}, got {brief(value)}", need


def checked_number(text: str, source: str, value, what: str, section: str | None, key: str,
                   occurrence: int = 0, *, positive: bool = False, allow_zero: bool = False,
                   expected: str | None = None) -> float:
    """``float(value)`` if :func:`number_error` accepts it, else its error :func:`located`.

    Parameters
    ----------
    text, source, value, what, section, key, occurrence
        As :func:`located` and :func:`number_error`.
    positive, allow_zero : bool
        As :func:`number_error`.
    expected : str, optional
        What would be right (default: :func:`number_error`'s, e.g. "a finite number > 0").

    Returns
    -------
    float
    """
    bad = number_error(value, what, positive=positive, allow_zero=allow_zero)
    if bad:
        raise located(text, source, bad[0], section, key, occurrence=occurrence,
                      expected=bad[1] if expected is None else expected)
    return float(value)


def brief(value) -> str:
    """``repr(value)`` cut short for a message (a 400-digit integer is not a message).

    Parameters
    ----------
    value : object
        Anything; its ``repr`` is shortened.

    Returns
    -------
    str
    """
    text = repr(value)
    return text if len(text) <= 60 else text[:57] + "..."


def summary_repr(result) -> str:
    """``Name(field=value, ...)`` of a dataclass ``result``: an array as its shape, a tuple
    or list of more than 8 items as its length, any other value :func:`brief`: what a
    notebook shows of a result, not thousands of numbers.

    Parameters
    ----------
    result : dataclass instance
        The result shown (its fields with ``repr=True``).

    Returns
    -------
    str
    """
    shown = (f"{f.name}={_summary(getattr(result, f.name))}" for f in fields(result) if f.repr)
    return f"{type(result).__name__}({', '.join(shown)})"


def _summary(value) -> str:
    """One field of :func:`summary_repr`: an array's shape, a long tuple's or list's
    length, else :func:`brief`."""
    shape = "×".join(map(str, getattr(value, "shape", ())))
    if shape:
        return f"<array {shape}>"
    if isinstance(value, (tuple, list)) and len(value) > 8:
        return f"<{type(value).__name__} of {len(value)}>"
    return brief(value)


def data_frame(rows, units: dict[str, str]):
    """The ``pandas.DataFrame`` of every ``to_dataframe``: ``rows`` (columns by name, or one
    dict a row) in the columns of ``units``, ``attrs["units"]`` the unit of each column.

    Parameters
    ----------
    rows : dict of str to array, or list of dict
        The table, as pandas reads it.
    units : dict of str to str
        Column name -> its unit ("" for a flag or a name), in the columns' order.

    Returns
    -------
    pandas.DataFrame
        pandas is imported here only (an ImportError says so without it).
    """
    try:
        import pandas as pd
    except ImportError:
        raise ImportError("to_dataframe needs pandas (pip install pandas); the result's "
                          "arrays do not") from None
    df = pd.DataFrame(rows, columns=list(units))
    df.attrs["units"] = dict(units)
    return df


def quantity_frame(columns: dict, unit: dict[str, str]):
    """:func:`data_frame` of ``columns`` named ``QUANTITY`` or ``QUANTITY(NAME)`` (``Q``,
    ``F(k1)``, ``dv(m2)``), each column the unit ``unit[QUANTITY]``.

    Parameters
    ----------
    columns : dict of str to array
        The table's columns by name.
    unit : dict of str to str
        Quantity (the name before any ``(``) -> its unit.

    Returns
    -------
    pandas.DataFrame
    """
    return data_frame(columns, {c: unit[c.partition("(")[0]] for c in columns})


# ------------------------------------------------------------------ TOML with places
#: A TOML table header line, ``[a.b]`` or ``[[a]]`` (group 1: its name), with a comment.
TOML_HEADER = re.compile(r"^\s*\[\[?\s*([^\]]+?)\s*\]\]?\s*(#.*)?$")


def load_toml(text: str, source: str) -> dict:
    """Parse TOML ``text``; a syntax error becomes a :class:`NetlistError` at its line and column.

    Parameters
    ----------
    text, source : str
        The file's text and name, for errors.

    Returns
    -------
    dict
    """
    import tomllib

    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        m = re.search(r"\(at line (\d+), column (\d+)\)", str(exc))
        line, col = (int(m.group(1)), int(m.group(2))) if m else (0, 0)
        msg = re.sub(r"\s*\(at line \d+, column \d+\)", "", str(exc))
        if str(source).lower().endswith(".mcir"):
            msg += ("; this is a netlist (.mcir), read by 'mechcirc check' and 'mechcirc "
                    "sweep': this command reads a TOML file (a scene or a linkage)")
        raise NetlistError(f"TOML syntax: {msg}", source, line, col) from None
    except ValueError:
        # tomllib converts integers with int(), which refuses more than
        # sys.get_int_max_str_digits() (4300) digits.
        m = re.search(r"\d{4000,}", text)
        line, col = line_col(text, m.start()) if m else (0, 0)
        raise NetlistError("integer with thousands of digits", source, line, col,
                           "a number within float64's range") from None


def locate(text: str, section: str | None, key: str, value: str | None = None,
           occurrence: int = 0) -> tuple[int, int]:
    """1-based (line, col) of ``key = …`` in ``[section]`` (or its n-th ``[[section]]``).

    ``section=None`` means the top level.  With ``value``, the column of that
    quoted string on the line.  (0, 0) when not found.

    Parameters
    ----------
    text : str
        The TOML text.
    section : str or None
        The table's name; None for the top level.
    key : str
        The key to find.
    value : str, optional
        A quoted string on the key's line to point at.
    occurrence : int
        Which ``[[section]]`` (0-based).

    Returns
    -------
    tuple of (int, int)
    """
    in_section, seen = section is None, -1
    key_re = re.compile(r'^\s*["\']?' + re.escape(key) + r'["\']?\s*=')
    for n, line in enumerate(split_lines(text), start=1):
        m = TOML_HEADER.match(line)
        if m:
            in_section = False                     # top-level keys end at the first header
            if section is not None and m.group(1).replace(" ", "") == section:
                seen += 1
                in_section = seen == occurrence
            continue
        if in_section and key_re.match(line):
            col = line.index(key) + 1
            if value is not None:
                for quote in ('"', "'"):
                    pos = line.find(f"{quote}{value}{quote}")
                    if pos >= 0:
                        col = pos + 1
                        break
            return n, col
    return 0, 0


def locate_path(text: str, path: tuple[str, ...], value: str | None = None,
                occurrence: int = 0) -> tuple[int, int]:
    """(line, col) of the TOML key ``path`` (e.g. ``("grid", "eta2", "num")``), however written.

    Tries ``[a.b]`` then ``c = …`` (:func:`locate`, with ``value`` and ``occurrence``);
    ``[a]`` then the dotted key ``b.c = …`` (at ``c``), or ``b = {c = …}`` (the column of
    ``c`` on that line when it is there);
    the header ``[a.b.c]`` itself (or the first ``[a.b.c.x]``); the header ``[a.b]``
    (its ``occurrence``-th ``[[a.b]]``); and so on up to the top level.  (0, 0) when
    nothing matches.

    Parameters
    ----------
    text : str
        The TOML text.
    path : tuple of str
        The dotted key, one name per level.
    value : str, optional
        A quoted string on the key's line to point at.
    occurrence : int
        Which ``[[table]]`` holds the key (0-based).

    Returns
    -------
    tuple of (int, int)
    """
    path = tuple(str(p) for p in path)
    for cut in range(len(path) - 1, -1, -1):
        section = ".".join(path[:cut]) or None
        full = cut == len(path) - 1
        line, col = locate(text, section, path[cut], value if full else None,
                           occurrence if full else 0)
        if not line and not full:       # a dotted key, ``b.c = …`` in [a]
            dotted = ".".join(path[cut:])
            line, col = locate(text, section, dotted)
            if line:
                return line, col + len(dotted) - len(path[-1])
        if line:
            rest = path[cut + 1:]
            if rest:
                here = split_lines(text)[line - 1]
                m = re.search(r"[{,\s]" + re.escape(rest[-1]) + r"\s*=", here)
                if m:
                    col = m.start() + 2
            return line, col
        name = ".".join(path[:cut + 1])
        # [a.b] itself, or the first [a.b.x] (which makes [a.b] without a header): its name
        heads = [(n, m.start(1) + 1) for n, ln in enumerate(split_lines(text), start=1)
                 if (m := TOML_HEADER.match(ln))
                 and (m.group(1).replace(" ", "") + ".").startswith(name + ".")]
        if heads:
            return heads[min(occurrence if cut == len(path) - 2 else 0, len(heads) - 1)]
    return 0, 0


def located(text: str, source: str, message: str, section: str | None, key: str,
            value=None, occurrence: int = 0, expected: str | None = None,
            choices=None) -> NetlistError:
    """A :class:`NetlistError` placed at ``key`` of ``[section]`` (see :func:`locate_path`).

    Parameters
    ----------
    text, source : str
        The file's text and name, for errors.
    message : str
        What is wrong.
    section : str or None
        The table's name (dotted for a sub-table); None for the top level.
    key : str
        The key to point at.
    value : object, optional
        The offending value, looked for on the key's line when it is a str
        (anything else, e.g. a number where a name belongs, is not looked for).
    occurrence : int
        Which ``[[section]]`` (0-based).
    expected : str, optional
        What would be right.
    choices : sequence of str, optional
        The names ``value`` could have been: the nearest is said ("did you mean") and
        ``expected`` is "one of" them unless given.

    Returns
    -------
    NetlistError
    """
    if choices is not None:
        choices = [str(c) for c in choices]
        message += did_you_mean(value, choices) if isinstance(value, str) else ""
        expected = expected or f"one of {', '.join(choices) or '(none)'}"
    path = (*section.split("."), key) if section else (key,)
    line, col = locate_path(text, path, value if isinstance(value, str) else None, occurrence)
    return NetlistError(message, source, line, col, expected)


# ------------------------------------------------------------------ declared tables
@dataclass(frozen=True)
class Table:
    """The declarative description of one TOML table a reader accepts.

    Each reader (linkage, scene, study) declares its tables once, as data;
    :func:`check_keys` refuses an undeclared key with one message form,
    located at the key, and the description is the "expected" part of it.

    Attributes
    ----------
    name : str or None
        The table's name (``"cranks"``, ``"omega"``); None for the top level.
    keys : dict of str to str
        Each key it may hold, in the order the messages list them, and what
        the key holds.
    array : bool
        An array of tables (``[[name]]``), whose entries are counted from 1
        in messages.
    """

    name: str | None
    keys: dict[str, str]
    array: bool = False

    @property
    def header(self) -> str:
        """``[name]``, ``[[name]]`` or ``the top level``."""
        if self.name is None:
            return "the top level"
        return f"[[{self.name}]]" if self.array else f"[{self.name}]"

    @property
    def expected(self) -> str:
        """The declared keys, comma-separated."""
        return ", ".join(self.keys)


def unknown_key(table: Table, entry: dict, occurrence: int = 0) -> tuple[str, str] | None:
    """``(key, message)`` for the first key of ``entry`` that ``table`` does not declare.

    None when every key is declared.

    Parameters
    ----------
    table : Table
        The declared keys.
    entry : dict
        The table (or one ``[[table]]`` entry) as read.
    occurrence : int
        Which ``[[table]]`` entry (0-based), for the message.

    Returns
    -------
    tuple of (str, str) or None
    """
    for key in entry:
        if key not in table.keys:
            if table.name is None:
                return key, f"unknown top-level key {key!r}{did_you_mean(key, table.keys)}"
            where = table.header + (f" #{occurrence + 1}" if table.array else "")
            return key, f"unknown key {key!r} in {where}{did_you_mean(key, table.keys)}"
    return None


def name_index(name: str, names, what: str = "element", where: str = "") -> int:
    """The index of ``name`` in ``names``, else an :class:`~mechcirc.errors.UnknownNameError`
    (a KeyError): "no node named 'Mm' [where]; did you mean 'M'? (nodes: ...)" (``what`` the
    kind of name; see :func:`mechcirc.errors.unknown_name`)."""
    names = list(names)
    if name in names:
        return names.index(name)
    raise unknown_name(name, names, what, where)


class NamedValues(dict):
    """A plain dictionary of values by name whose look-up of a name not there raises
    :func:`~mechcirc.errors.unknown_name` ("no element named 'k44' in ...; did you mean
    'k4'?"), an UnknownNameError and so still a KeyError; ``get`` and ``in`` as a dict's.
    Pickles as a dict with its two words."""

    def __init__(self, items=(), what: str = "element", where: str = ""):
        super().__init__(items)
        self.what, self.where = what, where

    def __missing__(self, name):
        raise unknown_name(name, self, self.what, self.where)


def check_keys(text: str, source: str, table: Table, entry: dict, occurrence: int = 0) -> None:
    """Refuse an undeclared key of ``entry`` (see :func:`unknown_key`) at its line and column.

    Parameters
    ----------
    text, source : str
        The file's text, and its name for the message.
    table : Table
        The declared keys.
    entry : dict
        The table (or one ``[[table]]`` entry) as read.
    occurrence : int
        Which ``[[table]]`` entry (0-based).

    Raises
    ------
    NetlistError
        At the key (or, for an undeclared top-level table, at its header),
        listing the declared keys as what is expected.
    """
    found = unknown_key(table, entry, occurrence)
    if found is not None:
        key, message = found
        raise located(text, source, message, table.name, key, occurrence=occurrence,
                      expected=table.expected)
