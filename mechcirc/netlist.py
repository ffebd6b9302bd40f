"""Netlist files (``.mcir``) to :class:`~mechcirc.circuit.Circuit`.

The language is documented, with its grammar, in ``docs/netlist.md``.  In
short, one statement per line::

    # comment to end of line; ';' also starts a comment
    .param NAME=EXPR [NAME=EXPR ...]
    mass   NAME N1 N2 VALUE [eta=EXPR]
    spring NAME N1 N2 VALUE [eta=EXPR]
    damper NAME N1 N2 VALUE [eta=EXPR]
    lever  NAME P1 P2 S1 S2 ratio=EXPR
    drive  NAME N1 N2 velocity=EXPR      (or force=EXPR)

Every rejected token raises :class:`~mechcirc.errors.NetlistError` with the
file, line and column, what is wrong and what would be right.
"""

from __future__ import annotations

import math
import os
import re
from dataclasses import dataclass
from pathlib import Path

from .circuit import ELEMENT_UNITS, Circuit, Drive, Element, Lever
from .errors import NetlistError
from .expressions import CONSTANTS, FUNCTIONS, Expr, evaluate, parse_expression

__all__ = ["parse", "load", "MAX_LINE_LENGTH", "SYNTAX"]

#: Longest line accepted [characters]; longer lines are refused at once.
MAX_LINE_LENGTH = 100_000

_NAME = re.compile(r"[A-Za-z_][A-Za-z0-9_]*|[0-9]+")
_IDENT = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")

#: The form of each statement, quoted in error messages.
SYNTAX = {
    ".param": ".param NAME=EXPR [NAME=EXPR ...]",
    "mass": "mass NAME N1 N2 VALUE [eta=EXPR]",
    "spring": "spring NAME N1 N2 VALUE [eta=EXPR]",
    "damper": "damper NAME N1 N2 VALUE [eta=EXPR]",
    "lever": "lever NAME P1 P2 S1 S2 ratio=EXPR",
    "drive": "drive NAME N1 N2 velocity=EXPR  or  drive NAME N1 N2 force=EXPR",
}


@dataclass(frozen=True)
class _Token:
    text: str
    col: int  # 1-based column of the token's first character


class _Line:
    """One source line, split into tokens; raises located errors."""

    def __init__(self, text: str, source: str, lineno: int):
        self.source, self.lineno = source, lineno
        self.tokens = self._split(text)

    def error(self, message: str, col: int, expected: str | None = None):
        raise NetlistError(message, self.source, self.lineno, col, expected)

    def _split(self, text: str) -> list[_Token]:
        tokens: list[_Token] = []
        i, n = 0, len(text)
        start = None
        brace = None
        while i < n:
            c = text[i]
            if brace is None and c in "#;":
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
            i += 1
        if brace is not None:
            self.error("'{' is never closed", brace + 1, "'}' at the end of the expression")
        if start is not None:
            tokens.append(_Token(text[start:i], start + 1))
        return tokens


def _unbrace(text: str, col: int) -> tuple[str, int]:
    """Strip one pair of enclosing braces, moving the column past the '{'."""
    if text.startswith("{") and text.endswith("}"):
        return text[1:-1], col + 1
    return text, col


class _Parser:
    def __init__(self, text: str, source: str):
        self.text, self.source = text, source
        self.params: dict[str, float] = {}
        self.param_lines: dict[str, int] = {}
        self.elements: list[Element] = []
        self.levers: list[Lever] = []
        self.drives: list[Drive] = []
        self.names: dict[str, int] = {}

    # -- expressions -----------------------------------------------------
    def expr(self, line: _Line, text: str, col: int, *, defined: dict[str, float]) -> float:
        text, col = _unbrace(text, col)
        if not text.strip():
            line.error("empty expression", col, "a number or an expression")
        tree: Expr = parse_expression(text, source=self.source, line=line.lineno, col=col)
        for name in sorted(tree.names()):
            if name not in defined and name not in CONSTANTS and name in self.param_lines:
                where = col + text.find(name)
                line.error(f"parameter {name!r} is used before it is defined "
                           f"(on line {self.param_lines[name]})", where,
                           "parameters defined on earlier .param lines or earlier on this line")
        value = evaluate(tree, defined, source=self.source, line=line.lineno, col=col)
        if not math.isfinite(value):
            line.error(f"expression evaluates to {value}", col, "a finite number")
        return value

    # -- statements ------------------------------------------------------
    def run(self) -> Circuit:
        lines = self.text.splitlines()
        if not any(ln.strip() for ln in lines):
            raise NetlistError("the file is empty", self.source, 0, 0,
                               "element lines such as 'mass m1 a 0 2.5' and one 'drive' line")
        parsed = []
        # First pass: split every line, and note where each parameter is defined
        # so a use-before-definition can name the line.
        for lineno, raw in enumerate(lines, start=1):
            if len(raw) > MAX_LINE_LENGTH:
                raise NetlistError(f"line is {len(raw)} characters long, the limit is "
                                   f"{MAX_LINE_LENGTH}", self.source, lineno, 1)
            line = _Line(raw, self.source, lineno)
            if not line.tokens:
                continue
            parsed.append(line)
            if line.tokens[0].text.lower() == ".param":
                for tok in line.tokens[1:]:
                    name = tok.text.split("=", 1)[0]
                    self.param_lines.setdefault(name, lineno)
        for line in parsed:
            if line.tokens[0].text.lower() == ".param":
                self.param(line)
        for line in parsed:
            keyword = line.tokens[0].text.lower()
            if keyword == ".param":
                continue
            handler = {"mass": self.element, "spring": self.element, "damper": self.element,
                       "lever": self.lever, "drive": self.drive}.get(keyword)
            if handler is None:
                line.error(f"unknown keyword {line.tokens[0].text!r}", line.tokens[0].col,
                           "one of .param, mass, spring, damper, lever, drive")
            handler(line, keyword)
        if not parsed:
            raise NetlistError("the file has no statements, only comments and blank lines",
                               self.source, 0, 0, "element lines and one 'drive' line")
        if not self.drives:
            raise NetlistError("the netlist has no drive", self.source, 0, 0,
                               "one line 'drive NAME N1 N2 velocity=V0'")
        if not self.elements:
            raise NetlistError("the netlist has no elements", self.source, 0, 0,
                               "mass, spring or damper lines")
        name = Path(self.source).stem if self.source != "<string>" else "circuit"
        return Circuit(elements=tuple(self.elements), drive=self.drives[0],
                       levers=tuple(self.levers), name=name, source=self.source,
                       params=dict(self.params))

    def param(self, line: _Line):
        if len(line.tokens) == 1:
            line.error(".param needs at least one NAME=EXPR", line.tokens[0].col,
                       SYNTAX[".param"])
        for tok in line.tokens[1:]:
            if "=" not in tok.text:
                line.error(f"{tok.text!r} is not NAME=EXPR", tok.col, SYNTAX[".param"])
            name, rhs = tok.text.split("=", 1)
            if not _IDENT.fullmatch(name):
                line.error(f"{name!r} is not a valid parameter name", tok.col,
                           "a letter or '_' followed by letters, digits or '_'")
            if name in CONSTANTS or name in FUNCTIONS:
                line.error(f"{name!r} is a built-in name and cannot be a parameter", tok.col)
            if name in self.params:
                line.error(f"parameter {name!r} is defined twice "
                           f"(first on line {self.param_lines[name]})", tok.col)
            self.params[name] = self.expr(line, rhs, tok.col + len(name) + 1,
                                          defined=self.params)

    def _fields(self, line: _Line, keyword: str, npos: int, allowed: tuple[str, ...]):
        """Split a statement into ``npos`` positional tokens and ``key=value`` options."""
        positional, options = [], {}
        for tok in line.tokens[1:]:
            head = tok.text.split("=", 1)[0]
            if "=" in tok.text and _IDENT.fullmatch(head):
                if head not in allowed:
                    line.error(f"unknown option {head!r} for {keyword}", tok.col,
                               " or ".join(f"{a}=EXPR" for a in allowed) if allowed
                               else f"no options: {SYNTAX[keyword]}")
                if head in options:
                    line.error(f"option {head!r} given twice", tok.col)
                options[head] = _Token(tok.text[len(head) + 1:], tok.col + len(head) + 1)
            else:
                if options:
                    line.error(f"{tok.text!r} after the options", tok.col, SYNTAX[keyword])
                positional.append(tok)
        if len(positional) < npos:
            missing = SYNTAX[keyword].split()[1 + len(positional)]
            end = line.tokens[-1].col + len(line.tokens[-1].text)
            line.error(f"{keyword} line is missing {missing}", end, SYNTAX[keyword])
        if len(positional) > npos:
            extra = positional[npos]
            line.error(f"unexpected {extra.text!r}: {keyword} takes {npos} fields",
                       extra.col, SYNTAX[keyword])
        return positional, options

    def _name(self, line: _Line, tok: _Token, what: str) -> str:
        if not _NAME.fullmatch(tok.text):
            line.error(f"{tok.text!r} is not a valid {what}", tok.col,
                       "an identifier (letters, digits, '_') or an integer")
        text = tok.text
        if text.isdigit():
            text = str(int(text))
        return text

    def _new_name(self, line: _Line, tok: _Token) -> str:
        name = self._name(line, tok, "element name")
        if name in self.names:
            line.error(f"element name {name!r} is already used on line {self.names[name]}",
                       tok.col, "a unique name")
        self.names[name] = line.lineno
        return name

    def _positive(self, line: _Line, tok: _Token, what: str, unit: str) -> float:
        value = self.expr(line, tok.text, tok.col, defined=self.params)
        if not value > 0:
            line.error(f"{what} must be > 0{' ' + unit if unit else ''}, got {value:g}",
                       tok.col, "a positive value")
        return value

    def element(self, line: _Line, kind: str):
        pos, opts = self._fields(line, kind, 4, ("eta",))
        name = self._new_name(line, pos[0])
        n1 = self._name(line, pos[1], "node name")
        n2 = self._name(line, pos[2], "node name")
        if n1 == n2:
            line.error(f"both ends of {kind} {name!r} are node {n1!r}", pos[2].col,
                       "two different nodes")
        value = self._positive(line, pos[3], f"{kind} {name!r}", ELEMENT_UNITS[kind])
        eta = self._positive(line, opts["eta"], f"eta of {name!r}", "") if "eta" in opts else 1.0
        self.elements.append(Element(kind, name, n1, n2, value, eta, line.lineno,
                                     line.tokens[0].col))

    def lever(self, line: _Line, kind: str):
        pos, opts = self._fields(line, kind, 5, ("ratio",))
        name = self._new_name(line, pos[0])
        nodes = [self._name(line, t, "node name") for t in pos[1:5]]
        if nodes[0] == nodes[1]:
            line.error(f"both primary ends of lever {name!r} are node {nodes[0]!r}",
                       pos[2].col, "two different nodes")
        if nodes[2] == nodes[3]:
            line.error(f"both secondary ends of lever {name!r} are node {nodes[2]!r}",
                       pos[4].col, "two different nodes")
        if "ratio" not in opts:
            line.error(f"lever {name!r} needs ratio=EXPR", line.tokens[-1].col, SYNTAX["lever"])
        ratio = self._positive(line, opts["ratio"], f"ratio of lever {name!r}", "")
        self.levers.append(Lever(name, *nodes, ratio, line.lineno, line.tokens[0].col))

    def drive(self, line: _Line, kind: str):
        pos, opts = self._fields(line, kind, 3, ("velocity", "force"))
        if self.drives:
            first = self.drives[0]
            line.error(f"a second drive; the netlist already has {first.name!r} on line "
                       f"{first.line}", line.tokens[0].col, "exactly one drive")
        name = self._new_name(line, pos[0])
        n1 = self._name(line, pos[1], "node name")
        n2 = self._name(line, pos[2], "node name")
        if n1 == n2:
            line.error(f"both ends of drive {name!r} are node {n1!r}", pos[2].col,
                       "two different nodes")
        if len(opts) != 1:
            if opts:
                key, tok = list(opts.items())[1]
                where = tok.col - len(key) - 1
            else:
                where = line.tokens[-1].col + len(line.tokens[-1].text)
            line.error("a drive needs exactly one of velocity=EXPR or force=EXPR", where,
                       SYNTAX["drive"])
        (key, tok), = opts.items()
        amplitude = self.expr(line, tok.text, tok.col, defined=self.params)
        self.drives.append(Drive(name, n1, n2, key, amplitude, line.lineno,
                                 line.tokens[0].col))


def parse(text: str, source: str = "<string>") -> Circuit:
    """Parse netlist ``text`` into a :class:`~mechcirc.circuit.Circuit`.

    Parameters
    ----------
    text : str
        The netlist.
    source : str
        Name used in error messages and as the circuit's name (its stem).

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
    return _Parser(text, source).run()


def load(path: str | os.PathLike) -> Circuit:
    """Read and parse the netlist file at ``path`` (UTF-8).

    Raises
    ------
    NetlistError
        If the file is missing, unreadable, not UTF-8, or has an error.
    """
    source = os.fspath(path)
    try:
        data = Path(path).read_bytes()
    except FileNotFoundError:
        raise NetlistError("no such file", source, 0, 0, "the path of a .mcir netlist") from None
    except IsADirectoryError:
        raise NetlistError("is a directory", source, 0, 0, "a .mcir netlist file") from None
    except OSError as exc:
        raise NetlistError(f"cannot read: {exc.strerror}", source) from None
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as exc:
        before = data[:exc.start]
        lineno = before.count(b"\n") + 1
        col = exc.start - (before.rfind(b"\n") + 1) + 1
        raise NetlistError(f"byte 0x{data[exc.start]:02x} is not valid UTF-8", source,
                           lineno, col, "a UTF-8 text file") from None
    return parse(text.removeprefix("\ufeff"), source=source)
