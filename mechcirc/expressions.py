"""Safe arithmetic expressions for netlist values (no ``eval``).

Grammar (``^`` is a synonym of ``**``; ``**`` binds tighter than unary minus
on its left and is right-associative, as in Python)::

    expr    := term (("+" | "-") term)*
    term    := unary (("*" | "/") unary)*
    unary   := ("-" | "+") unary | power
    power   := atom (("**" | "^") unary)?
    atom    := NUMBER | NAME | NAME "(" expr ")" | "(" expr ")"

Numbers are decimal floats (``1e5``, ``.5``, ``2.``).  Names are parameters or
the constant ``pi``; functions are ``sqrt sin cos tan exp log radians degrees``.

The text is tokenised and parsed by hand into a small tree of tuples, so each
error carries its column.  Work is bounded: at most :data:`MAX_LENGTH`
characters and :data:`MAX_DEPTH` levels of nesting; overflow is an error.
"""

from __future__ import annotations

import math
import operator
import re
from dataclasses import dataclass
from typing import Callable, Mapping, NoReturn, cast

from .errors import NetlistError
from .units import SPICE_SUFFIXES, UnitError, looks_like_unit, parse_unit

__all__ = ["Expr", "parse_expression", "evaluate", "evaluate_array", "postorder", "FUNCTIONS", "CONSTANTS",
           "OPERATORS", "MAX_LENGTH", "MAX_DEPTH"]

#: Longest expression accepted [characters]; longer text is refused at once.
MAX_LENGTH = 10_000
#: Deepest nesting accepted (parentheses, unary signs, powers); deeper input
#: would otherwise exhaust Python's recursion limit.
MAX_DEPTH = 100

FUNCTIONS: dict[str, Callable[[float], float]] = {
    "sqrt": math.sqrt, "sin": math.sin, "cos": math.cos, "tan": math.tan,
    "exp": math.exp, "log": math.log, "radians": math.radians,
    "degrees": math.degrees,
}
CONSTANTS: dict[str, float] = {"pi": math.pi}
#: The binary operators of the grammar (``^`` is parsed as ``**``); they apply as well
#: to numpy arrays and SymPy expressions.
OPERATORS: dict[str, Callable] = {"+": operator.add, "-": operator.sub, "*": operator.mul,
                                  "/": operator.truediv, "**": operator.pow}

_TOKEN = re.compile(r"""
    (?P<ws>\s+)
  | (?P<num>(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?)
  | (?P<name>[A-Za-z_][A-Za-z_0-9]*)
  | (?P<op>\*\*|[-+*/^()])
""", re.VERBOSE)


#: A whole text that is one number or one name (ASCII, as the tokens above match them).
_ATOM = re.compile(r"(?P<num>(?:[0-9]+\.?[0-9]*|\.[0-9]+)(?:[eE][+-]?[0-9]+)?)"
                   r"|(?P<name>[A-Za-z_][A-Za-z_0-9]*)")


@dataclass(frozen=True)
class Expr:
    """A parsed expression: a tree node with its column in the source line.

    ``kind`` is ``"num"`` (``value`` a float), ``"name"`` (``value`` a str),
    ``"neg"`` (``args`` one operand), ``"call"`` (``value`` the function name,
    ``args`` one operand) or a binary operator ``"+" "-" "*" "/" "**"``.
    """

    kind: str
    col: int
    value: float | str | None = None
    args: tuple["Expr", ...] = ()

    def names(self) -> set[str]:
        """Parameter names used in the expression."""
        return {cast(str, node.value) for node in postorder(self) if node.kind == "name"}


def postorder(root: Expr) -> list[Expr]:
    """The nodes of ``root``, operands before their operator, left before right.

    Iterative: a flat sum of thousands of terms nests as deep as it is long
    (``((1 + 1) + 1) + ...``), beyond Python's recursion limit.

    Parameters
    ----------
    root : Expr

    Returns
    -------
    list of Expr
    """
    out: list[Expr] = []
    stack: list[tuple[Expr, bool]] = [(root, False)]
    while stack:
        node, expanded = stack.pop()
        if expanded or not node.args:
            out.append(node)
            continue
        stack.append((node, True))
        stack.extend((a, False) for a in reversed(node.args))
    return out


class _Parser:
    def __init__(self, text: str, source: str, line: int, col: int):
        self.text, self.source, self.line, self.col0 = text, source, line, col
        self.tokens = self._tokenise()
        self.pos = 0

    def error(self, message: str, col: int, expected: str | None = None) -> NoReturn:
        raise NetlistError(message, self.source, self.line, self.col0 + col + 1, expected)

    def _tokenise(self):
        tokens = []
        i, text = 0, self.text
        while i < len(text):
            m = _TOKEN.match(text, i)
            if m is None:
                hint = "a number, a name, an operator + - * / ** ^ or a parenthesis"
                if text[i] == ",":
                    hint = "a decimal point, e.g. 1.5 (not 1,5)"
                elif text[i] in "\u2212\u2013\u2014\u2012\u2010":
                    hint = "the ASCII hyphen-minus '-', e.g. 2e-6"
                self.error(f"unexpected character {text[i]!r} in expression", i, hint)
            kind = m.lastgroup
            if kind == "num" and m.end() < len(text) and (text[m.end()].isalnum()
                                                         or text[m.end()] in "._"):
                end = m.end()
                while end < len(text) and (text[end].isalnum() or text[end] in "._" or (
                        text[end] in "+-" and text[end - 1] in "eE")):
                    end += 1
                glued = text[m.end():].split(maxsplit=1)[0]     # e.g. "N/mm" of "5N/mm"
                self.error(f"malformed number {text[i:end]!r}", i,
                           _number_hint(text[i:end], m.group(), glued))
            if kind != "ws":                    # ^ is **
                tokens.append((kind, "**" if m.group() == "^" else m.group(), i))
            i = m.end()
        tokens.append(("end", "", len(text)))
        return tokens

    def peek(self):
        return self.tokens[self.pos]

    def take(self):
        tok = self.tokens[self.pos]
        self.pos += 1
        return tok

    def parse(self) -> Expr:
        if self.peek()[0] == "end":
            self.error("empty expression", 0, "a number or an expression")
        e = self.expr(0)
        kind, tok, col = self.peek()
        if kind != "end":
            what = "')' without a matching '('" if tok == ")" else f"unexpected {tok!r}"
            self.error(what, col, "an operator or the end of the expression")
        return e

    def _deeper(self, depth: int, col: int) -> int:
        if depth >= MAX_DEPTH:
            self.error(f"expression nested more than {MAX_DEPTH} levels deep", col)
        return depth + 1

    def _chain(self, depth: int, ops: tuple[str, str], operand: Callable[[int], Expr]) -> Expr:
        """``operand (op operand)*`` for the operators ``ops``, grouped from the left."""
        left = operand(depth)
        while self.peek()[1] in ops and self.peek()[0] == "op":
            _, op, col = self.take()
            left = Expr(op, col, None, (left, operand(depth)))
        return left

    def expr(self, depth: int) -> Expr:
        return self._chain(depth, ("+", "-"), self.term)

    def term(self, depth: int) -> Expr:
        return self._chain(depth, ("*", "/"), self.unary)

    def unary(self, depth: int) -> Expr:
        kind, tok, col = self.peek()
        if kind == "op" and tok in ("-", "+"):
            self.take()
            operand = self.unary(self._deeper(depth, col))
            return Expr("neg", col, None, (operand,)) if tok == "-" else operand
        return self.power(depth)

    def power(self, depth: int) -> Expr:
        base = self.atom(depth)
        kind, tok, col = self.peek()
        if kind == "op" and tok == "**":
            self.take()
            return Expr("**", col, None, (base, self.unary(self._deeper(depth, col))))
        return base

    def atom(self, depth: int) -> Expr:
        kind, tok, col = self.take()
        if kind == "num":
            value = float(tok)
            if math.isinf(value):
                self.error(f"number {tok[:20]}{'...' if len(tok) > 20 else ''} is too "
                           "large for float64", col, "a magnitude below 1.8e308")
            return Expr("num", col, value)
        if kind == "name":
            if self.peek()[1] == "(" and self.peek()[0] == "op":
                if tok not in FUNCTIONS:
                    from .sources import did_you_mean

                    self.error(f"unknown function {tok!r}{did_you_mean(tok, FUNCTIONS)}", col,
                               "one of " + ", ".join(sorted(FUNCTIONS)))
                self.take()
                arg = self.expr(self._deeper(depth, col))
                self._close(col)
                return Expr("call", col, tok, (arg,))
            if tok in FUNCTIONS:
                self.error(f"function {tok!r} needs an argument in parentheses", col,
                           f"{tok}(...)")
            return Expr("name", col, tok)
        if kind == "op" and tok == "(":
            inner = self.expr(self._deeper(depth, col))
            self._close(col)
            return inner
        if kind == "end":
            self.error("expression ends too early", col, "a number, a name or '('")
        self.error(f"unexpected {tok!r}", col, "a number, a name or '('")

    def _close(self, open_col: int):
        if self.take()[:2] != ("op", ")"):
            self.error("'(' is never closed", open_col, "')'")


def parse_expression(text: str, *, source: str = "<string>", line: int = 0,
                     col: int = 1) -> Expr:
    """Parse ``text`` into an :class:`Expr`; ``col`` is where ``text`` starts (1-based).

    Parameters
    ----------
    text : str
    source : str
        File name for errors.
    line, col : int
        Where ``text`` starts.

    Returns
    -------
    Expr

    Raises
    ------
    NetlistError
        With the column of the offending character, for any syntax problem
        or input beyond the stated limits.
    """
    if len(text) > MAX_LENGTH:
        raise NetlistError(f"expression is {len(text)} characters long, the limit is "
                           f"{MAX_LENGTH}", source, line, col)
    # A lone number or parameter name (most values) is its own tree: the parser would
    # give the same one; a number too large, a function name or anything else goes to it.
    atom = _ATOM.fullmatch(text)
    if atom is not None:
        if atom.lastgroup == "name":
            if text not in FUNCTIONS:
                return Expr("name", 0, text)
        elif (value := float(text)) != math.inf:
            return Expr("num", 0, value)
    return _Parser(text, source, line, col - 1).parse()


def evaluate(expr: Expr, params: Mapping[str, float], *, source: str = "<string>",
             line: int = 0, col: int = 1, tangent: Mapping[str, float] | None = None):
    """Evaluate ``expr`` in float64 with the parameter values ``params``.

    ``col`` is the column where the expression text started, so errors
    (undefined name, division by zero, overflow, domain error) point at the
    offending operator or name.

    With ``tangent`` (the derivatives of the parameters with respect to some
    variable; names not given have 0), returns ``(value, derivative)``: the
    exact derivative of the expression, carried through every operation by the
    rules of calculus (forward mode), as sensitivities need it.

    Parameters
    ----------
    expr : Expr
    params : Mapping[str, float]
    source : str
        File name for errors.
    line, col : int
        Where the expression text starts.
    tangent : Mapping[str, float], optional
        Derivatives of the parameters.

    Returns
    -------
    float or tuple of (float, float)
        The value, or ``(value, derivative)`` with ``tangent``.
    """
    def fail(message: str, node: Expr, expected: str | None = None) -> NoReturn:
        raise NetlistError(message, source, line, col + node.col, expected)    # node.col: 0-based

    if expr.kind == "num" and tangent is None:
        return expr.value
    values: dict[int, float] = {}
    # Operands first (iteratively: see postorder), so errors come left to right.
    if tangent is None:
        for node in postorder(expr):
            values[id(node)] = _node_value(node, params, values, fail)
        return values[id(expr)]
    slopes: dict[int, float] = {}
    for node in postorder(expr):
        args = [values[id(a)] for a in node.args]
        r = values[id(node)] = _node_value(node, params, values, fail)
        slopes[id(node)] = _slope(node, args, r, [slopes.pop(id(a)) for a in node.args],
                                  tangent)
    return values[id(expr)], slopes[id(expr)]


def _node_value(node: Expr, params: Mapping[str, float], values: dict, fail) -> float:
    """The value of ``node`` for :func:`evaluate`, its operands popped from ``values``
    (by ``id``); ``fail(message, node, expected=None)`` raises the located error."""
    k, v = node.kind, cast(str, node.value)   # v is a float for "num", else a str
    if k == "num":
        return cast(float, v)
    if k == "name":
        if v in params:
            return params[v]
        if v in CONSTANTS:
            return CONSTANTS[v]
        from .sources import did_you_mean

        fail(f"undefined parameter {v!r}{did_you_mean(v, [*params, *CONSTANTS])}", node,
             "a parameter defined by an earlier .param line")
    if k == "neg":
        return -values.pop(id(node.args[0]))
    if k == "call":
        x = values.pop(id(node.args[0]))
        try:
            return FUNCTIONS[v](x)
        except (ValueError, OverflowError):
            fail(f"{v}({x!r}) is undefined or out of range", node)
    a, b = values.pop(id(node.args[0])), values.pop(id(node.args[1]))
    return _binary(k, a, b, lambda message: fail(message, node))


def _binary(k: str, a: float, b: float, fail) -> float:
    """``a k b`` in float64; ``fail(message)`` for a division by zero, an overflow or
    a power that is not real."""
    try:
        r = OPERATORS[k](a, b)
    except ZeroDivisionError:
        fail("division by zero" if k == "/" else f"{a!r} ** {b!r} divides by zero")
    except OverflowError:
        fail(f"{a!r} {k} {b!r} overflows float64")
    if isinstance(r, complex):
        fail(f"{a!r} ** {b!r} is not a real number")
    if math.isinf(r) and not (math.isinf(a) or math.isinf(b)):
        fail(f"{a!r} {k} {b!r} overflows float64")
    return r


#: d f(x) / dx of each function, from x and f(x).
_DERIVATIVES: dict[str, Callable[[float, float], float]] = {
    "sqrt": lambda x, r: 0.5 / r, "sin": lambda x, r: math.cos(x),
    "cos": lambda x, r: -math.sin(x), "tan": lambda x, r: 1.0 + r * r,
    "exp": lambda x, r: r, "log": lambda x, r: 1.0 / x,
    "radians": lambda x, r: math.pi / 180, "degrees": lambda x, r: 180 / math.pi,
}


def _slope(node: Expr, args: list, r: float, d: list, tangent: Mapping[str, float]) -> float:
    """The derivative of ``node`` (value ``r``, operands ``args`` with derivatives ``d``)."""
    k = node.kind
    if k == "num":
        return 0.0
    if k == "name":
        return float(tangent.get(str(node.value), 0.0))
    if k == "neg":
        return -d[0]
    if k == "call":
        return _DERIVATIVES[str(node.value)](args[0], r) * d[0] if d[0] else 0.0
    (a, b), (da, db) = args, d
    if k == "+":
        return da + db
    if k == "-":
        return da - db
    if k == "*":
        return da * b + a * db
    if k == "/":
        return (da - r * db) / b
    # a ** b: each term only where its operand moves (a ** (b - 1) or log a may not exist).
    return (b * a ** (b - 1) * da if da else 0.0) + (r * math.log(a) * db if db else 0.0)



def evaluate_array(expr: Expr, params: Mapping, size: int):
    """``expr`` over ``size`` designs at once: ``params`` maps names to arrays of shape
    (size,) (or floats).  Returns ``(values, bad)``: float64 arrays of shape (size,)
    and the mask of the designs where :func:`evaluate` would raise (an undefined
    operation, an overflow: their value is then meaningless; evaluate them one by
    one to get the located error).  The operators are numpy's IEEE operations, as
    :func:`evaluate`'s; the functions are applied value by value with the same
    ``math`` functions, so each design's value is the one :func:`evaluate` gives.

    Parameters
    ----------
    expr : Expr
    params : Mapping[str, float or ndarray]
    size : int
        Number of designs.

    Returns
    -------
    tuple of (ndarray, ndarray of bool)
        ``(values, bad)``, shape (size,).
    """
    import numpy as np

    values: dict[int, np.ndarray] = {}
    bad = np.zeros(size, dtype=bool)
    with np.errstate(all="ignore"):
        for node in postorder(expr):
            k, v = node.kind, cast(str, node.value)   # v is a float for "num", else a str
            if k == "num":
                r = np.full(size, v)
            elif k == "name":
                if v in params:
                    r = np.broadcast_to(np.asarray(params[v], dtype=float), (size,)).copy()
                elif v in CONSTANTS:
                    r = np.full(size, CONSTANTS[v])
                else:
                    raise NetlistError(f"undefined parameter {v!r}")
            elif k == "neg":
                r = -values.pop(id(node.args[0]))
            elif k == "call":
                r = _each(FUNCTIONS[v], values.pop(id(node.args[0])))
            else:
                a, b = values.pop(id(node.args[0])), values.pop(id(node.args[1]))
                # ** as Python's pow, as evaluate (numpy's may differ by an ulp)
                r = _each(OPERATORS[k], a, b) if k == "**" else OPERATORS[k](a, b)
            bad |= ~np.isfinite(r)
            values[id(node)] = r
    return values[id(expr)], bad


def _each(f: Callable[..., float], *xs):
    """``f`` applied value by value to the arrays ``xs`` (Python floats, as :func:`evaluate`
    computes), NaN where it raises or its value is complex."""
    import numpy as np

    def value(*x: float) -> float:
        try:
            r = f(*x)
        except (ValueError, OverflowError, ZeroDivisionError):
            return math.nan
        return math.nan if isinstance(r, complex) else r

    return np.frompyfunc(value, len(xs), 1)(*xs).astype(float)


def _number_hint(bad: str, number: str, glued: str = "") -> str:
    """What a malformed number should have been; a glued-on unit gets its own advice.

    ``glued`` is everything after the number up to the next space, so that a
    compound unit (``5N/mm``) is advised whole, not cut at its first operator.
    """
    for rest in (glued, bad[len(number):]):
        if rest and looks_like_unit(rest):
            try:
                parse_unit(rest)
            except UnitError:
                continue
            return f"a space between the number and its unit: '{number} {rest}'"
    rest = bad[len(number):]
    if rest.lower() in SPICE_SUFFIXES:
        return (f"no SPICE suffixes in mechcirc: write {number}e3 for {number}k, "
                f"{number}e-3 for {number}m, or give a unit after the number "
                f"(e.g. {number} kN/m)")
    return "a number such as 12, 1.5, .5, 2. or 1e-3"
