"""Netlist files (``.mcir``) to :class:`~mechcirc.circuit.Circuit`.

The language is documented, with its grammar, in ``docs/netlist.md``.  In
short, one statement per line::

    # comment to end of line; ';' also starts a comment
    .param NAME=EXPR [NAME=EXPR ...]
    mass   NAME N1 N2 VALUE [eta=EXPR]
    spring NAME N1 N2 VALUE [eta=EXPR] [backlash=EXPR] [damping=EXPR]
    damper NAME N1 N2 VALUE [eta=EXPR]
    lever  NAME P1 P2 S1 S2 ratio=EXPR
    drive  NAME N1 N2 velocity=EXPR      (or force=EXPR, or motion=..., below)
    .ic    NODE [x=EXPR] [v=EXPR]        (initial state, for transients)

``spring ... damping=D`` adds a damper of coefficient D in parallel, as the
element ``NAME_damping``; ``backlash=B`` puts a total clearance B in series
with the pair (Modelica ``ElastoBacklash``).  The frequency domain sees the
contact closed; :mod:`mechcirc.transient` integrates the clearance.

``drive ... motion=PATH.csv`` (a table of crank angle → displacement) or
``motion=LAW rise=DEG [dwell=DEG] return=DEG stroke=EXPR`` (a standard cam
law, :mod:`mechcirc.motion_laws`) gives the drive's motion over one revolution
of the main shaft, for :func:`mechcirc.periodic.periodic`.

A value (VALUE, a ``.param`` value, ``velocity=``/``force=``) may be followed,
after a space, by its unit: ``spring k1 a 0 5 N/mm``.  The unit is checked
against the element kind and the value converted to SI (:mod:`mechcirc.units`).

Every rejected token raises :class:`~mechcirc.errors.NetlistError` with the
file, line and column, what is wrong and what would be right.
"""

from __future__ import annotations

import functools
import gc
import math
import os
import re
import warnings
from dataclasses import fields
from typing import Any, Mapping, NamedTuple, NoReturn, cast
from pathlib import Path

from .circuit import ELEMENT_UNITS, Circuit, Drive, Element, ElementKind, Lever
from .errors import NetlistError, UnitMixWarning, clip
from .expressions import CONSTANTS, FUNCTIONS, Expr, evaluate, parse_expression
from .sources import did_you_mean, is_name, is_number, read_source, split_lines
from .units import (UnitError, convert, is_rotational, looks_like_unit, parse_unit,
                    split_quantity)

__all__ = ["parse", "load", "expressions_of", "check_param_names", "MAX_LINE_LENGTH", "MAX_STATEMENTS", "SYNTAX"]

#: Longest line accepted [characters]; longer lines are refused at once.
MAX_LINE_LENGTH = 100_000
#: Most statements a netlist may hold.  At the limit, a 10⁶-statement ladder
#: parses in 6 s, reduces in 21 s and sweeps 100 points in 14 s of CPU, with a
#: peak of 1.8 GB (docs/reliability.md); larger files are refused at once.
MAX_STATEMENTS = 1_000_000

_NAME = re.compile(r"[A-Za-z_][A-Za-z0-9_]*|[0-9]+")
#: An entry of ``_Parser.expressions``: (Expr, factor), or the fast path's raw number.
_Stored = tuple[Expr | float, float] | float

#: The form of each statement, quoted in error messages.
SYNTAX = {
    ".param": ".param NAME=EXPR [UNIT] [NAME=EXPR [UNIT] ...]",
    "mass": "mass NAME N1 N2 VALUE [UNIT] [eta=EXPR]",
    "spring": "spring NAME N1 N2 VALUE [UNIT] [eta=EXPR] [backlash=EXPR [UNIT]] "
              "[damping=EXPR [UNIT]]",
    "damper": "damper NAME N1 N2 VALUE [UNIT] [eta=EXPR]",
    "lever": "lever NAME P1 P2 S1 S2 ratio=EXPR",
    "drive": "drive NAME N1 N2 velocity=EXPR [UNIT]  or  drive NAME N1 N2 force=EXPR [UNIT]  "
             "or  drive NAME N1 N2 motion=PATH.csv  or  drive NAME N1 N2 motion=LAW "
             "rise=DEG [dwell=DEG] return=DEG stroke=EXPR [UNIT] [return_law=LAW]",
    ".ic": ".ic NODE [x=EXPR [UNIT]] [v=EXPR [UNIT]]",
}

#: The options of a drive with ``motion=`` (a table takes only ``motion``).
_MOTION_KEYS = ("motion", "rise", "dwell", "return", "stroke", "return_law")


#: Where the first positional field that carries a value is (elements: VALUE).
_VALUE_INDEX = {"mass": 3, "spring": 3, "damper": 3}

# -- the fast path ------------------------------------------------------------
# Most lines of a large netlist are plain element statements:
# ``KIND NAME N1 N2 NUMBER [UNIT] [eta=NUMBER] [# comment]``.  Such a line is
# matched by one precompiled pattern and its Element is built directly; the
# pattern only admits text on which the general path (tokenizer, slip checks,
# expression parser) cannot fail or read anything else, and every semantic
# check (unique name, distinct nodes, value > 0, the unit and its role) that
# does not pass sends the line to the general path, so each error message
# comes from the same code as before.
# Possessive quantifiers (``*+``, ``++``, ``?+``): no field can give back a character the
# next one would take, so backtracking into them never finds a match (25% faster).  An
# integer name with a leading zero (node 00 is 0) takes the general path, so that a
# matched line's names are the Element's as they stand.
_FAST_NAME = r"([A-Za-z_][A-Za-z0-9_]*+|[1-9][0-9]*+|0)"
_FAST_NUMBER = r"((?:[0-9]++\.?+[0-9]*+|\.[0-9]++)(?:[eE][-+]?+[0-9]++)?+)"
_FAST = re.compile(
    r"([ \t]*+)((?i:mass|spring|damper))[ \t]++" + _FAST_NAME + r"[ \t]++" + _FAST_NAME + r"[ \t]++"
    + _FAST_NAME + r"[ \t]++" + _FAST_NUMBER
    + r"(?:[ \t]++([A-Za-z\u00b5\u03bc][A-Za-z0-9*/^\-\u00b7\u00b2\u00b3\u00b5\u03bc]*+))?"
    + r"(?:[ \t]++eta=" + _FAST_NUMBER + r")?+[ \t]*+(?:[#;].*+)?+")
_FAST_KINDS: dict[str, ElementKind] = {"mass": "mass", "spring": "spring", "damper": "damper"}
#: A plain drive line: ``drive NAME N1 N2 velocity=NUMBER`` (or force=), no unit.
_FAST_DRIVE = re.compile(
    r"([ \t]*+)(?i:drive)[ \t]++" + _FAST_NAME + r"[ \t]++" + _FAST_NAME + r"[ \t]++"
    + _FAST_NAME + r"[ \t]++(velocity|force)=" + _FAST_NUMBER + r"[ \t]*+(?:[#;].*+)?+")

_new = object.__new__


def _element_fast(kind, name, n1, n2, value, eta, line, col) -> Element:
    """``Element(kind, name, n1, n2, value, eta, line, col)`` without the frozen
    dataclass's ``__init__`` (ten ``object.__setattr__`` calls, 2-3x slower): the
    same object, its instance dict filled item by item (keys stay shared)."""
    e = _new(Element)
    d = e.__dict__
    d["kind"] = kind
    d["name"] = name
    d["n1"] = n1
    d["n2"] = n2
    d["value"] = value
    d["eta"] = eta
    d["line"] = line
    d["col"] = col
    d["backlash"] = 0.0
    return e


# Only while Element has exactly these fields; a new field goes through __init__.
_make_element = _element_fast if tuple(f.name for f in fields(Element)) == (
    "kind", "name", "n1", "n2", "value", "eta", "line", "col", "backlash") \
    else Element


def _num_expr(value: float) -> Expr:
    """``parse_expression`` of a plain number: ``Expr("num", 0, value)``."""
    e = _new(Expr)
    d = e.__dict__
    d["kind"] = "num"
    d["col"] = 0
    d["value"] = value
    d["args"] = ()
    return e


if tuple(f.name for f in fields(Expr)) != ("kind", "col", "value", "args"):
    def _num_expr(value: float) -> Expr:      # noqa: F811 - Expr changed: use __init__
        return Expr("num", 0, value)


#: Units are few and parsed again on every line: memoise the one grammar's result
#: (a Unit is immutable; a failing unit raises each time, uncached).
_unit = functools.lru_cache(maxsize=1024)(parse_unit)


class _Token(NamedTuple):
    text: str
    col: int  # 1-based column of the token's first character


#: A token of a line without braces before its comment: a run of non-space characters
#: (``\s`` is exactly ``str.isspace``); where a comment starts.
_WORD = re.compile(r"\S+")
_COMMENT = re.compile("[#;]")


class _Line:
    """One source line, split into tokens; raises located errors."""

    def __init__(self, text: str, source: str, lineno: int):
        self.source, self.lineno = source, lineno
        self.tokens = self._split(text)

    def error(self, message: str, col: int, expected: str | None = None) -> NoReturn:
        raise NetlistError(message, self.source, self.lineno, col, expected)

    def _split(self, text: str) -> list[_Token]:
        comment = _COMMENT.search(text)
        end = len(text) if comment is None else comment.start()
        if "{" not in text[:end] and "}" not in text[:end]:     # no braces: split at spaces
            return [_Token(m.group(), m.start() + 1) for m in _WORD.finditer(text, 0, end)]
        tokens: list[_Token] = []
        end = len(text)         # where a comment starts (not in braces), or the line's end
        start, brace = None, None
        for i, c in enumerate(text):
            if brace is None and c in "#;":
                end = i
                break
            if c == "{":
                if brace is not None:
                    self.error("'{' inside braces", i + 1, "one level of braces: {EXPR}")
                brace = i
                if start is None:
                    start = i
            elif c == "}":
                if brace is None:
                    self.error("'}' without a matching '{'", i + 1)
                brace = None
            elif c.isspace() and brace is None:
                if start is not None:
                    tokens.append(_Token(text[start:i], start + 1))
                    start = None
            elif start is None:
                start = i
        if brace is not None:
            self.error("'{' is never closed", brace + 1, "'}' at the end of the expression")
        if start is not None:
            tokens.append(_Token(text[start:end], start + 1))
        return tokens


def _glued(tok: _Token) -> tuple[_Token, _Token | None]:
    """Split a value glued to its unit (``500g``, ``5N/mm``) into value and unit tokens.

    The one unit grammar (:mod:`mechcirc.units`) lets the space go, as pint
    does; only a plain number followed by a known unit is split, so
    expressions and malformed numbers are left to the expression parser.
    """
    parts = split_quantity(tok.text)
    if parts is None or not parts[1] or parts[1] == "1/s" or tok.text[len(parts[0])].isspace():
        return tok, None
    try:
        parse_unit(parts[1])
    except UnitError:
        return tok, None
    return _Token(parts[0], tok.col), _Token(parts[1], tok.col + len(parts[0]))


#: SPICE and spreadsheet habits, checked on each line before parsing it.
_DASHES = "\u2212\u2013\u2014\u2012\u2010"
#: A line without any of these characters has no dash or decimal-comma slip.
_SLIPS = re.compile(f"[,{_DASHES}]")

#: What a SPICE deck must change, said at its first error (not one slip a run).
_SPICE_NOTE = ("mechcirc writes its statements as mass, spring, damper, lever, drive and its "
               "numbers without SPICE suffixes (3e3 or 3 kN/m, not 3k)")
#: File name endings of SPICE decks.
_SPICE_SUFFIXES = (".cir", ".sp", ".spi", ".spice", ".net", ".ckt")


def _check_slips(line: "_Line", raw: str) -> None:
    """Name the common slips (spaces around '=', Unicode minus, decimal comma, '*' comments)."""
    toks = line.tokens
    if toks and toks[0].text.startswith("*"):
        line.error("'*' does not start a comment in mechcirc (it does in SPICE)", toks[0].col,
                   "'#' or ';' to start a comment; if this is a SPICE deck, " + _SPICE_NOTE)
    for i, tok in enumerate(toks if "=" in raw else ()):
        if tok.text == "=" or (tok.text.startswith("=") and i > 0) or \
                (tok.text.endswith("=") and i + 1 < len(toks)):
            line.error("spaces around '=': options are written without spaces", tok.col,
                       "NAME=VALUE with no spaces, e.g. velocity=0.1 or eta=0.5")
    for j, c in enumerate(raw if _SLIPS.search(raw) else ""):
        if c in "#;":
            break
        if c in _DASHES:
            line.error(f"a Unicode minus or dash {c!r} (U+{ord(c):04X}), as typed by word "
                       "processors", j + 1, "the ASCII hyphen-minus '-', e.g. 2e-6")
        if c == "," and 0 < j < len(raw) - 1 and raw[j - 1].isdigit() and raw[j + 1].isdigit():
            line.error("a decimal comma", j + 1, "a decimal point, e.g. 1.5 (not 1,5)")


#: The keywords a netlist statement begins with.
KEYWORDS = (".param", ".ic", "mass", "spring", "damper", "lever", "drive")


def _check_first_keyword(line: _Line) -> None:
    """A first statement that begins with no keyword, nor a slip of one ('sprnig'), means
    the file is not a netlist (/etc/passwd, a CSV): say so without quoting any of it."""
    word = line.tokens[0].text.lower()
    if word in KEYWORDS:
        return
    import difflib

    if not difflib.get_close_matches(word, KEYWORDS, n=1, cutoff=0.6):
        spice = str(line.source).lower().endswith(_SPICE_SUFFIXES)
        line.error("not a netlist: its first statement does not begin with a netlist "
                   "keyword (the file's text is not shown)", line.tokens[0].col,
                   "a .mcir netlist, whose statements begin with one of " + ", ".join(KEYWORDS)
                   + ("; the name is a SPICE deck's: " + _SPICE_NOTE if spice else ""))


def _check_count(line: _Line, keyword: str, npos: int, positional: list) -> None:
    """A clear error when a statement has fewer or more than ``npos`` positional fields."""
    if len(positional) < npos:
        fields = SYNTAX[keyword].split()[1:1 + npos]
        missing = fields[len(positional)]
        end = line.tokens[-1].col + len(line.tokens[-1].text)
        last = positional[-1] if positional else None
        if missing == "VALUE" and last is not None and last.text != "0" and \
                (quantity := split_quantity(last.text)) and is_number(quantity[0]):
            # 'mass m a 2': the value is there, read as node N2: a node is missing
            line.error(f"{keyword} line is missing a node: it has {len(positional)} of "
                       f"the fields {' '.join(fields)}, and {last.text!r}, read as "
                       f"{fields[len(positional) - 1]}, looks like the VALUE", last.col,
                       SYNTAX[keyword])
        line.error(f"{keyword} line is missing {missing}", end, SYNTAX[keyword])
    if len(positional) > npos:
        extra = positional[npos]
        line.error(f"unexpected {extra.text!r}: {keyword} takes {npos} fields",
                   extra.col, SYNTAX[keyword])


class _Parser:
    def __init__(self, text: str, source: str, overrides: Mapping[str, float] | None = None,
                 require_drive: bool = True):
        self.text, self.source = text, source
        self.require_drive = require_drive
        self.initial: list[tuple[str, float, float, int, int]] = []
        self.overrides = dict(overrides or {})
        self.params: dict[str, float] = {}
        self.param_lines: dict[str, int] = {}
        self.elements: list[Element] = []
        self.levers: list[Lever] = []
        self.drives: list[Drive] = []
        self.drive_rotational: bool | None = None
        self.drive_unit: str = ""           # (the text of the drive's unit, where it has one)
        self.names: dict[str, int] = {}
        #: Parsed expressions and unit factors, for symbolic formulas:
        #: ``("param", name)`` / ``(element, "value" | "eta")`` -> (Expr, factor); the fast
        #: path stores ``raw`` or ``(raw, factor)``; :func:`expressions_of` gives the Exprs.
        self.expressions: dict[tuple[str, str], _Stored] = {}
        #: node -> {True: (element, unit), False: ...}: rotational / translational units seen.
        self.node_kinds: dict[str, dict[bool, tuple[str, str, int]]] = {}

    # -- expressions -----------------------------------------------------
    def expr(self, line: _Line, tok: _Token, key: tuple[str, str] | None = None) -> float:
        """The value of the expression ``tok`` over the parameters defined so far."""
        text, col = tok.text, tok.col
        if text.startswith("{") and text.endswith("}"):      # one pair of enclosing braces
            text, col = text[1:-1], col + 1
        if not text.strip():
            line.error("empty expression", col, "a number or an expression")
        tree: Expr = parse_expression(text, source=self.source, line=line.lineno, col=col)
        for name in sorted(tree.names()):
            if name not in self.params and name not in CONSTANTS and name in self.param_lines:
                where = col + text.find(name)
                line.error(f"parameter {name!r} is used before it is defined "
                           f"(on line {self.param_lines[name]})", where,
                           "parameters defined on earlier .param lines or earlier on this line")
        value = evaluate(tree, self.params, source=self.source, line=line.lineno, col=col)
        if key is not None:
            self.expressions[key] = (tree, 1.0)
        if not math.isfinite(value):
            line.error(f"expression evaluates to {value}", col, "a finite number")
        return value

    # -- statements ------------------------------------------------------
    def run(self) -> Circuit:
        # A large netlist allocates millions of small objects that all live on:
        # the cyclic collector would walk them again and again (quadratic-looking
        # growth of the time per element).  Off while parsing, restored after.
        enabled = gc.isenabled()
        gc.disable()
        try:
            return self._run()
        finally:
            if enabled:
                gc.enable()

    def _run(self) -> Circuit:
        lines = split_lines(self.text)     # as editors and wc -l count them
        if not any(ln.strip() for ln in lines):
            raise NetlistError("the file is empty", self.source, 0, 0,
                               "element lines such as 'mass m1 a 0 2.5' and one 'drive' line")
        # (counted only where the lines could exceed the limit: no pass over every line)
        statements = 0 if len(lines) <= MAX_STATEMENTS else \
            sum(1 for ln in lines if ln.strip() and ln.lstrip()[0] not in "#;")
        if statements > MAX_STATEMENTS:
            raise NetlistError(f"the netlist has about {statements} statements, the limit is "
                               f"{MAX_STATEMENTS}", self.source, 0, 0,
                               "a smaller network (see 'mechcirc reduce')")
        parsed = self._split(lines)
        if self.overrides:
            check_param_names(self.overrides, self.param_lines, self.source)
        self._build(parsed)
        self._check_complete(parsed)
        self._check_initial()
        return self._circuit()

    def _split(self, lines: list[str]) -> list:
        """First pass: every line split (a ``_Line``, or a list of consecutive plain
        element lines kept as their matches, see _FAST, built in the second pass),
        and where each parameter is defined, so a use-before-definition can name
        the line."""
        parsed: list = []
        run: list[tuple[int, str, re.Match[str]]] | None = None
        fast = _FAST.fullmatch
        for lineno, raw in enumerate(lines, start=1):
            if len(raw) > MAX_LINE_LENGTH:
                raise NetlistError(f"line is {len(raw)} characters long, the limit is "
                                   f"{MAX_LINE_LENGTH}", self.source, lineno, 1)
            m = fast(raw)
            if m is not None:
                if run is None:
                    run = []
                    parsed.append(run)
                kind = m.group(2)
                run.append((lineno, _FAST_KINDS.get(kind) or _FAST_KINDS[kind.lower()], m))
                continue
            run = None
            if (m := _FAST_DRIVE.fullmatch(raw)) is not None:
                parsed.append((lineno, m))          # read by fast_drive
                continue
            line = _Line(raw, self.source, lineno)
            if not line.tokens:
                continue
            _check_slips(line, raw)
            if not parsed:
                _check_first_keyword(line)
            parsed.append(line)
            if line.tokens[0].text.lower() == ".param":
                for tok in line.tokens[1:]:
                    self.param_lines.setdefault(tok.text.split("=", 1)[0], lineno)
        return parsed

    def _build(self, parsed: list) -> None:
        """Second pass: the parameters first, then every other statement."""
        for line in parsed:
            if type(line) is _Line and line.tokens[0].text.lower() == ".param":
                self.param(line)
        handlers = {"mass": self.element, "spring": self.element, "damper": self.element,
                    "lever": self.lever, "drive": self.drive, ".ic": self.ic,
                    ".param": lambda line, keyword: None}       # (read above)
        for line in parsed:
            if type(line) is list:
                self.fast_elements(line)
                continue
            if type(line) is tuple:
                self.fast_drive(*line)
                continue
            keyword = line.tokens[0].text.lower()
            if keyword not in handlers:
                word = line.tokens[0].text
                line.error(f"unknown keyword {word!r}{did_you_mean(word.lower(), KEYWORDS)}",
                           line.tokens[0].col,
                           "one of .param, .ic, mass, spring, damper, lever, drive")
            handlers[keyword](line, keyword)

    def _check_complete(self, parsed: list) -> None:
        if not parsed:
            raise NetlistError("the file has no statements, only comments and blank lines",
                               self.source, 0, 0, "element lines and one 'drive' line")
        if not self.drives and self.require_drive:
            raise NetlistError("the netlist has no drive", self.source, 0, 0,
                               "one line 'drive NAME N1 N2 velocity=V0' (a netlist without "
                               "a drive can only be integrated: 'mechcirc transient')")
        if not self.elements:
            raise NetlistError("the netlist has no elements", self.source, 0, 0,
                               "mass, spring or damper lines")

    def _check_initial(self) -> None:
        """Each ``.ic`` names a node some element uses, other than the frame, once."""
        if not self.initial:        # (no pass over the nodes of 10⁶ elements for nothing)
            return
        known = {n for e in self.elements for n in (e.n1, e.n2)}
        known |= {n for lv in self.levers for n in lv.terminals}
        known |= {n for d in self.drives for n in (d.n1, d.n2)}
        seen_ic: dict[str, int] = {}
        for node, _, _, lineno, col in self.initial:
            if node == "0":
                raise NetlistError("the frame '0' cannot have an initial state", self.source,
                                   lineno, col, "a node other than 0")
            if node not in known:
                nodes = sorted(known - {"0"})
                raise NetlistError(f".ic names node {node!r}, which no element uses"
                                   f"{did_you_mean(node, nodes)}", self.source, lineno, col,
                                   "one of " + ", ".join(nodes[:20]))
            if node in seen_ic:
                raise NetlistError(f"node {node!r} has a second .ic (first on line "
                                   f"{seen_ic[node]})", self.source, lineno, col,
                                   "one .ic line per node")
            seen_ic[node] = lineno

    def _circuit(self) -> Circuit:
        name = _stem(self.source) if self.source != "<string>" else "circuit"
        drive = self.drives[0] if self.drives else None
        if drive is not None:
            rot = self.drive_rotational
            if rot is None:     # rotary when its nodes carry rotary units only
                kinds = [self.node_kinds.get(n, {}) for n in (drive.n1, drive.n2)]
                rot = any(True in k for k in kinds) and not any(False in k for k in kinds)
            else:               # its own unit: its nodes' elements must agree
                self._note_kind(drive.line, drive.name, rot, self.drive_unit, drive.col,
                                (drive.n1, drive.n2))
            # (the parser's own new Drive, not yet seen by anyone: set, not replaced)
            object.__setattr__(drive, "rotational", rot)
        elements, levers, params = tuple(self.elements), tuple(self.levers), dict(self.params)
        one_kind = {n: True in k for n, k in self.node_kinds.items() if len(k) == 1}
        return Circuit(elements=elements, drive=drive, levers=levers, name=name,
                       source=self.source, params=params,
                       initial=tuple((n, x, v) for n, x, v, _, _ in self.initial),
                       expressions=(elements, levers, drive, params, self.expressions),
                       node_kinds=one_kind)

    def with_unit(self, line: _Line, value: float, unit: _Token | None, role: str,
                  key: tuple[str, str] | None = None) -> float:
        """``value`` converted to SI by the unit token (if any), checked against ``role``."""
        if unit is None:
            return value
        try:
            u = _unit(unit.text)
            out = convert(value, u, role)
        except UnitError as exc:
            expected = exc.expected
            if unit.text in ("m", "k", "u", "n", "p", "f", "t", "g"):
                expected = (f"{expected}; note: mechcirc has no SPICE suffixes, "
                            f"'{unit.text}' is read as a unit")
            line.error(exc.message, unit.col + exc.offset, expected)
        if key is not None and isinstance(entry := self.expressions.get(key), tuple):
            self.expressions[key] = (entry[0], u.factor)
        return out

    def param(self, line: _Line):
        if len(line.tokens) == 1:
            line.error(".param needs at least one NAME=EXPR", line.tokens[0].col,
                       SYNTAX[".param"])
        previous = None
        for tok in line.tokens[1:]:
            if "=" not in tok.text and previous is not None and looks_like_unit(tok.text):
                if previous in self.overrides:
                    # The override is already SI; the unit is still checked.
                    self.with_unit(line, 1.0, tok, "param")
                else:
                    self.params[previous] = self.with_unit(line, self.params[previous], tok,
                                                           "param", ("param", previous))
                previous = None
                continue
            previous = None
            if "=" not in tok.text:
                line.error(f"{tok.text!r} is not NAME=EXPR", tok.col, SYNTAX[".param"])
            name, rhs = tok.text.split("=", 1)
            if not is_name(name):
                line.error(f"{name!r} is not a valid parameter name", tok.col,
                           "a letter or '_' followed by letters, digits or '_'")
            if name in CONSTANTS or name in FUNCTIONS:
                line.error(f"{name!r} is a built-in name and cannot be a parameter", tok.col)
            if name in self.params:
                line.error(f"parameter {name!r} is defined twice "
                           f"(first on line {self.param_lines[name]})", tok.col)
            value_tok, unit_tok = _glued(_Token(rhs, tok.col + len(name) + 1))
            self.params[name] = self.with_unit(line, self.expr(line, value_tok, ("param", name)),
                                               unit_tok, "param", ("param", name))
            previous = name if unit_tok is None else None       # a unit may follow
            if name in self.overrides:
                given = self.overrides[name]
                try:
                    value = float(given)
                except (TypeError, ValueError):
                    value = math.nan        # refused below, naming what was given
                if not math.isfinite(value):
                    line.error(f"parameter {name!r} set to {given!r}", tok.col,
                               "a finite number")
                self.params[name] = value
                self.expressions[("param", name)] = (Expr("num", 0, value), 1.0)

    def _fields(self, line: _Line, keyword: str, npos: int, allowed: tuple[str, ...]):
        """Split a statement into ``npos`` positional tokens, ``key=value`` options and units.

        A token right after a value (the VALUE field or an option) that looks
        like a unit (``kg``, ``N/mm``) is that value's unit; ``units`` maps
        ``"value"`` or the option's name to its token.
        """
        positional: list[_Token] = []
        options, units = {}, {}
        previous = None
        for tok in line.tokens[1:]:
            if previous is not None and "=" not in tok.text and looks_like_unit(tok.text):
                units[previous] = tok
                previous = None
                continue
            previous, head = None, tok.text.split("=", 1)[0]
            if "=" in tok.text and is_name(head):
                if head not in allowed:
                    line.error(f"unknown option {head!r} for {keyword}"
                               f"{did_you_mean(head, allowed)}", tok.col,
                               " or ".join(f"{a}=EXPR" for a in allowed) if allowed
                               else f"no options: {SYNTAX[keyword]}")
                if head in options:
                    line.error(f"option {head!r} given twice", tok.col)
                options[head], unit_tok = _glued(_Token(tok.text[len(head) + 1:],
                                                        tok.col + len(head) + 1))
                previous = head if unit_tok is None else None       # a unit may follow
                if unit_tok is not None:
                    units[head] = unit_tok
            else:
                if options:
                    line.error(f"{tok.text!r} after the options", tok.col, SYNTAX[keyword])
                if len(positional) == _VALUE_INDEX.get(keyword):
                    tok, unit_tok = _glued(tok)
                    previous = "value" if unit_tok is None else None    # a unit may follow
                    if unit_tok is not None:
                        units["value"] = unit_tok
                positional.append(tok)
        _check_count(line, keyword, npos, positional)
        return positional, options, units

    def _name(self, line: _Line, tok: _Token, what: str) -> str:
        if not _NAME.fullmatch(tok.text):
            line.error(f"{tok.text!r} is not a valid {what}", tok.col,
                       "an identifier (letters, digits, '_') or an integer")
        # node 00 is 0 (not by int(), which refuses more than 4300 digits)
        return tok.text.lstrip("0") or "0" if tok.text.isdigit() else tok.text

    def _new_name(self, line: _Line, tok: _Token) -> str:
        name = self._name(line, tok, "element name")
        if name in self.names:
            line.error(f"element name {name!r} is already used on line {self.names[name]}",
                       tok.col, "a unique name")
        self.names[name] = line.lineno
        return name

    def _two_ends(self, line: _Line, pos: list[_Token], what: str) -> tuple[str, str, str]:
        """The new name and the two nodes (they must differ) of an element or drive line."""
        name = self._new_name(line, pos[0])
        n1, n2 = [self._name(line, t, "node name") for t in pos[1:3]]
        if n1 == n2:
            line.error(f"both ends of {what} {name!r} are node {n1!r}", pos[2].col,
                       "two different nodes")
        return name, n1, n2

    def _value(self, line: _Line, tok: _Token, what: str, unit_tok: _Token | None, role: str,
               key: tuple[str, str], *, unit: str = "", zero: bool = False,
               expected: str = "a positive value") -> float:
        """The value of ``tok`` in SI (by its unit), refused unless > 0 (>= 0 with ``zero``)."""
        value = self.with_unit(line, self.expr(line, tok, key), unit_tok, role, key)
        if not (value >= 0 if zero else value > 0):
            line.error(f"{what} must be {'>=' if zero else '>'} 0{unit}, got {value:g}", tok.col,
                       expected)
        return value

    def fast_elements(self, run: list) -> None:
        """Build the elements of consecutive lines matched by ``_FAST``; a line that
        fails any check goes to :meth:`element`, which reports it as for any other line.

        One loop over the run with everything bound locally: per line, this is most
        of the parse time of a large netlist."""
        names, expressions, elements = self.names, self.expressions, self.elements
        append, unit_of, inf, make = elements.append, _unit, math.inf, _make_element
        for lineno, kind, m in run:
            indent, _, name, n1, n2, number, unit, eta_text = m.groups()
            value = raw = float(number)
            eta = 1.0 if eta_text is None else float(eta_text)
            u = None
            if unit is not None:
                try:
                    u = unit_of(unit)
                    value = convert(raw, u, kind)
                except UnitError:
                    value = 0.0                     # the general path says why
            if name in names or n1 == n2 or raw == inf or not value > 0 \
                    or not 0 < eta < inf:
                self.element(_Line(m.string, self.source, lineno), kind)
                continue
            names[name] = lineno
            # The parsed expression of a plain number, Expr("num", 0, raw), is
            # made by expressions_of() when asked (see _materialise).
            expressions[(name, "value")] = raw if u is None else (raw, u.factor)
            if eta_text is not None:
                expressions[(name, "eta")] = eta
            if u is not None:
                self._note_kind(lineno, name, is_rotational(u), unit, m.start(7) + 1, (n1, n2))
            append(make(kind, name, n1, n2, value, eta, lineno, len(indent) + 1))

    def fast_drive(self, lineno: int, m: re.Match[str]) -> None:
        """The Drive of a line matched by ``_FAST_DRIVE``, as :meth:`drive` makes it; a
        line that fails any check goes to :meth:`drive`, which reports it."""
        indent, name, n1, n2, key, number = cast(Any, m.groups())   # key: velocity|force
        value = float(number)
        if self.drives or name in self.names or n1 == n2 or value == math.inf:
            self.drive(_Line(m.string, self.source, lineno), "drive")
            return
        self.names[name] = lineno
        self.expressions[(name, key)] = (Expr("num", 0, value), 1.0)     # parse_expression's
        self.drive_rotational = None
        self.drives.append(Drive(name, n1, n2, key, value, lineno, len(indent) + 1))

    def element(self, line: _Line, kind: ElementKind):
        allowed = ("eta", "backlash", "damping") if kind == "spring" else ("eta",)
        pos, opts, units = self._fields(line, kind, 4, allowed)
        name, n1, n2 = self._two_ends(line, pos, kind)
        value = self._value(line, pos[3], f"{kind} {name!r}", units.get("value"), kind,
                            (name, "value"), unit=" " + ELEMENT_UNITS[kind])
        if "value" in units:
            unit_tok = units["value"]
            self._note_kind(line.lineno, name, is_rotational(_unit(unit_tok.text)),
                            unit_tok.text, unit_tok.col, (n1, n2))
        eta = self._value(line, opts["eta"], f"eta of {name!r}", units.get("eta"), "eta",
                          (name, "eta")) if "eta" in opts else 1.0
        spring = {"backlash": 0.0, "damping": 0.0}
        for key, role, unit, expected in (
                ("backlash", "displacement", "", "a total clearance >= 0 (length or angle)"),
                ("damping", "damper", " N·s/m", "a damping coefficient >= 0")):
            if key in opts:
                spring[key] = self._value(line, opts[key], f"{key} of {name!r}", units.get(key),
                                          role, (name, key), unit=unit, zero=True,
                                          expected=expected)
        backlash, damping = spring["backlash"], spring["damping"]
        self.elements.append(Element(kind, name, n1, n2, value, eta, line.lineno,
                                     line.tokens[0].col, backlash))
        if damping > 0:
            # The parallel damper is an ordinary element, so every frequency-domain
            # path (reduction, nodal, resonances) sees the linearised spring ∥ damper.
            companion = f"{name}_damping"
            if companion in self.names:
                line.error(f"damping={damping:g} adds the damper {companion!r}, but that "
                           f"name is already used on line {self.names[companion]}",
                           opts["damping"].col, "a different name for one of them")
            self.names[companion] = line.lineno
            self.elements.append(Element("damper", companion, n1, n2, damping, eta,
                                         line.lineno, line.tokens[0].col))

    def ic(self, line: _Line, kind: str):
        pos, opts, units = self._fields(line, kind, 1, ("x", "v"))
        node, values = self._name(line, pos[0], "node name"), {}
        for key, role in (("x", "displacement"), ("v", "velocity")):
            if key in opts:
                values[key] = self.with_unit(line, self.expr(line, opts[key]), units.get(key), role)
            if (u := units.get(key)) is not None:       # an angle or a length (no rad: m)
                self._note_kind(line.lineno, f".ic {node}", _unit(u.text).dim[1] == 0, u.text,
                                u.col, (node,))
        if not values:
            line.error(f".ic for node {node!r} gives neither x= nor v=",
                       line.tokens[-1].col + len(line.tokens[-1].text), SYNTAX[".ic"])
        self.initial.append((node, values.get("x", 0.0), values.get("v", 0.0), line.lineno,
                             pos[0].col))

    def _note_kind(self, lineno: int, name: str, rot: bool | None, unit_text: str, col: int,
                   nodes) -> None:
        """Warn once per node that carries both translational and rotational units (``rot``:
        whether ``name``'s unit is rotational, None for neither)."""
        if rot is None:
            return
        for node in nodes:
            if node == "0":
                continue
            seen = self.node_kinds.setdefault(node, {})
            other = seen.get(not rot)
            if other is not None and rot not in seen:
                kinds = ("rotational", "translational")[::1 if rot else -1]
                warnings.warn(UnitMixWarning(
                    f"{self.source}:{lineno}:{col}: node {node!r} gets a "
                    f"{kinds[0]} unit ({unit_text!r} of {name!r}) and a {kinds[1]} one "
                    f"({other[1]!r} of {other[0]!r}, line {other[2]}); one node is one "
                    "coordinate, a length or an angle: reflect the rotational part through "
                    "a lever (J/r², c_t/r²) or use separate nodes"), stacklevel=4)
            seen.setdefault(rot, (name, unit_text, lineno))

    def lever(self, line: _Line, kind: str):
        pos, opts, units = self._fields(line, kind, 5, ("ratio",))
        name = self._new_name(line, pos[0])
        p1, p2, s1, s2 = [self._name(line, t, "node name") for t in pos[1:5]]
        for side, a, b, tok in (("primary", p1, p2, pos[2]), ("secondary", s1, s2, pos[4])):
            if a == b:
                line.error(f"both {side} ends of lever {name!r} are node {a!r}", tok.col,
                           "two different nodes")
        if "ratio" not in opts:
            line.error(f"lever {name!r} needs ratio=EXPR", line.tokens[-1].col, SYNTAX["lever"])
        ratio = self._value(line, opts["ratio"], f"ratio of lever {name!r}", units.get("ratio"),
                            "ratio", (name, "ratio"))
        self.levers.append(Lever(name, p1, p2, s1, s2, ratio, line.lineno, line.tokens[0].col))

    def drive(self, line: _Line, kind: str):
        pos, opts, units = self._fields(line, kind, 3, ("velocity", "force") + _MOTION_KEYS)
        if self.drives:
            first = self.drives[0]
            line.error(f"a second drive; the netlist already has {first.name!r} on line "
                       f"{first.line}", line.tokens[0].col, "exactly one drive")
        name, n1, n2 = self._two_ends(line, pos, "drive")
        if "motion" in opts:
            self.drives.append(Drive(name, n1, n2, "velocity", 1.0, line.lineno,
                                     line.tokens[0].col, self.motion(line, opts, units)))
            return
        for key in _MOTION_KEYS:
            if key in opts:
                line.error(f"option {key!r} belongs to a motion law", opts[key].col,
                           "motion=LAW with rise=, dwell=, return=, stroke=")
        if len(opts) != 1:
            if opts:
                key, tok = list(opts.items())[1]
                where = tok.col - len(key) - 1
            else:
                where = line.tokens[-1].col + len(line.tokens[-1].text)
            line.error("a drive needs exactly one of velocity=EXPR, force=EXPR or motion=",
                       where, SYNTAX["drive"])
        (key, tok), = opts.items()
        amplitude = self.expr(line, tok, (name, key))
        amplitude = self.with_unit(line, amplitude, units.get(key), key, (name, key))
        # rad/s or N·m: a rotary drive (no unit: decided by its nodes' elements, in build)
        self.drive_rotational = None if units.get(key) is None else \
            _unit(units[key].text).dim in ((0, 0, -1), (1, 2, -2))
        self.drive_unit = "" if units.get(key) is None else units[key].text
        self.drives.append(Drive(name, n1, n2, key, amplitude, line.lineno,
                                 line.tokens[0].col))

    def motion(self, line: _Line, opts: dict, units: dict):
        """The :class:`~mechcirc.motion_laws.Motion` of ``drive ... motion=``: a law or a table."""
        from .motion_laws import LAWS, read_motion_table

        tok = opts["motion"]
        for key in ("velocity", "force"):
            if key in opts:
                line.error(f"a drive with motion= takes no {key}= (its velocity follows "
                           "from the motion and the shaft speed)", opts[key].col,
                           SYNTAX["drive"])
        text = tok.text
        if text not in LAWS and "." not in text and "/" not in text and os.sep not in text:
            line.error(f"unknown motion law {text!r}{did_you_mean(text, LAWS)}", tok.col,
                       "one of " + ", ".join(LAWS) + ", or a table file such as lift.csv")
        if text in LAWS:
            return self._motion_law(line, opts, units, tok)
        for key in _MOTION_KEYS[1:]:
            if key in opts:
                line.error(f"option {key!r} belongs to a motion law, not a table",
                           opts[key].col, "motion=PATH alone, or motion=LAW with "
                           "rise=, dwell=, return=, stroke=")
        base = os.path.dirname(self.source) if self.source != "<string>" else ""
        path = os.path.join(base, text)
        if not os.path.exists(path):
            line.error(f"motion table {path!r} does not exist", tok.col,
                       "a CSV file angle_deg,displacement, its path relative to the netlist")
        if "motion" in units:       # the table's displacements: m (translational) or rad (rotary)
            unit = units["motion"]
            if self.with_unit(line, 1.0, unit, "displacement") != 1.0:
                line.error(f"a motion table's displacements are read as they are, in SI; "
                           f"{unit.text!r} would scale them", unit.col,
                           "m (a translational drive) or rad (a rotary drive)")
            self.drive_rotational, self.drive_unit = _unit(unit.text).dim == (0, 0, 0), unit.text
        return read_motion_table(path, spec=f"motion={path}")

    def _motion_law(self, line: _Line, opts: dict, units: dict, tok):
        """The :class:`~mechcirc.motion_laws.Motion` of ``motion=LAW`` with its angles and stroke."""
        from .motion_laws import LAWS, cam_cycle

        text = tok.text
        for key in ("motion", "return_law"):
            if key in units:        # a unit glued to a law name would be dropped unread
                line.error(f"{key}={opts[key].text} is a law's name and takes no unit, "
                           f"got {units[key].text!r} after it", units[key].col,
                           "the stroke's unit after stroke= (stroke=20 mm, stroke=30 deg); "
                           "the angles after rise=, dwell=, return= (degrees by default)")
        values = {"dwell": 0.0}
        for key in ("rise", "dwell", "return", "stroke"):
            if key not in opts:
                if key == "dwell":
                    continue
                line.error(f"motion={text} needs {key}=", tok.col, SYNTAX["drive"])
            v = self.expr(line, opts[key])
            if key == "stroke":
                v = self.with_unit(line, v, units.get(key), "displacement")
                if key in units:    # an angle: a rotary drive (a length: translational)
                    self.drive_rotational = _unit(units[key].text).dim == (0, 0, 0)
                    self.drive_unit = units[key].text
            elif key in units:
                v = math.degrees(self.with_unit(line, v, units[key], "angle"))
            values[key] = v
        ret_law = None
        if "return_law" in opts:
            ret_law = opts["return_law"].text
            if ret_law not in LAWS:
                line.error(f"unknown motion law {ret_law!r}{did_you_mean(ret_law, LAWS)}",
                           opts["return_law"].col,
                           "one of " + ", ".join(LAWS))
        try:
            return cam_cycle(text, values["rise"], values["dwell"], values["return"],
                             values["stroke"], return_law=ret_law)
        except ValueError as exc:
            bad = "stroke" if "stroke" in str(exc) else "rise"
            line.error(str(exc), opts[bad].col if bad in opts else tok.col,
                       "rise + dwell + return <= 360 degrees, rise and return > 0, "
                       "a nonzero stroke")


def check_param_names(given, known, source: str) -> None:
    """Refuse a name of ``given`` (``params=``) that is no ``.param`` of ``known``: a
    :class:`NetlistError` naming them, the nearest, and the netlist's parameters.

    Parameters
    ----------
    given, known : iterable of str
        The names to set, and the ``.param`` names of the netlist.
    source : str
        The netlist's file name, for the message.
    """
    known = list(known)
    unknown = sorted(set(given) - set(known))
    if unknown:
        raise NetlistError(f"no .param named {', '.join(map(repr, unknown))} to set"
                           f"{did_you_mean(unknown[0], known)}", source, 0, 0,
                           "one of " + (", ".join(known) or "(none defined)"))


def expressions_of(circuit: Circuit) -> dict | None:
    """The parsed expressions behind ``circuit``'s values, if :func:`parse` made it.

    Maps ``("param", NAME)`` and ``(ELEMENT, "value" | "eta" | "ratio" |
    "velocity" | "force")`` to ``(Expr, unit factor)``; the SI value is the
    expression's value times the factor.  ``None`` for circuits built in code,
    and for a parsed circuit whose elements, levers, drive or ``.param`` values
    were replaced since (``dataclasses.replace(c, name=...)`` keeps them): the
    table is kept in :attr:`Circuit.expressions` with the very objects it was
    read for, so an edited circuit never shows a stale formula.

    Parameters
    ----------
    circuit : Circuit

    Returns
    -------
    dict or None
    """
    if not circuit.expressions:
        return None
    *made_for, expressions = circuit.expressions
    now = (circuit.elements, circuit.levers, circuit.drive, circuit.params)
    if any(a is not b for a, b in zip(made_for, now)):
        return None
    return _materialise(expressions)


def _materialise(expressions: dict) -> dict:
    """The table with the plain numbers the fast path stored (``raw`` or ``(raw, factor)``,
    raw a float) as ``(Expr("num", 0, raw), factor)``, order kept: a new dict, so that
    asking does not change the (frozen) circuit it was parsed for."""
    out = {}
    for key, entry in expressions.items():
        if type(entry) is float:
            out[key] = (_num_expr(entry), 1.0)
        elif type(entry[0]) is float:
            out[key] = (_num_expr(entry[0]), entry[1])
        else:
            out[key] = entry
    return out


def _stem(source: str) -> str:
    """``Path(source).stem``, without building the path where the file name is plain:
    a last component neither empty nor ``.``, whose stem has a character other than ``.``
    (there every Python's pathlib agrees)."""
    name = source.rpartition("/")[2]
    i = name.rfind(".")
    if os.sep != "/" or name in ("", ".") or 0 <= i and not (i < len(name) - 1 and
                                                           name[:i].lstrip(".")):
        return Path(source).stem
    return name if i < 0 else name[:i]


def parse(text: str, source: str = "<string>", *,
          params: Mapping[str, float] | None = None, require_drive: bool = True) -> Circuit:
    """Parse netlist ``text`` into a :class:`~mechcirc.circuit.Circuit`.

    Parameters
    ----------
    text : str
        The netlist.
    source : str
        Name used in error messages and as the circuit's name (its stem).
    params : mapping of str to float, optional
        Values [SI] that replace those of the named ``.param`` definitions
        (parameter studies); later parameters and elements use them.  A name
        the netlist does not define is an error.
    require_drive : bool
        If false, a netlist without a ``drive`` line is accepted and the
        circuit's ``drive`` is ``None`` (free vibration, :mod:`mechcirc.transient`).

    Returns
    -------
    Circuit
        The circuit (plain data: elements, levers, drive).

    Raises
    ------
    NetlistError
        For any problem in the text, with line and column.

    Examples
    --------
    >>> c = parse("mass m1 a 0 2\\nspring k1 a 0 800\\ndrive V a 0 velocity=1")
    >>> str(c.tree)
    'm1 | k1'
    """
    return _Parser(text, source, params, require_drive).run()


def load(path: str | os.PathLike, *, params: Mapping[str, float] | None = None,
         require_drive: bool = True) -> Circuit:
    """Read and parse the netlist file at ``path`` (UTF-8); ``params`` as in :func:`parse`.

    Parameters
    ----------
    path : str or path-like
        The netlist file (``.mcir``, UTF-8).
    params : mapping of str to float, optional
        Values [SI] that replace those of the named ``.param`` definitions.
    require_drive : bool
        If false, a netlist without a ``drive`` line is accepted.

    Returns
    -------
    Circuit
        As :func:`parse` of the file's text, named after the file.

    Raises
    ------
    NetlistError
        If the file is missing, unreadable, not UTF-8, or has an error.
    """
    source = os.fspath(path)
    if source.lower().endswith(".toml"):        # a scene, linkage or study file
        raise NetlistError("a TOML file (a scene, linkage or study), not a netlist", source,
                           expected="a .mcir netlist; a scene's circuit at a crank angle: "
                           f"mechcirc scene {clip(source, 60)} --theta DEG -o FILE.mcir")
    text = read_source(path, "a .mcir netlist")
    return parse(text, source=source, params=params, require_drive=require_drive)
