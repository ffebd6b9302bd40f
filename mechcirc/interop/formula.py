"""K(ω) in closed form, as a SymPy expression built from the reduction tree.

Each element contributes its characteristic (see :mod:`mechcirc.circuit`)::

    mass  −j/(ω·m·η)      spring  jω/(k·η)      damper  1/(c·η)

series nodes add, parallel nodes add reciprocals, and a lever of ratio r
divides its secondary's K by r².  A network without a series–parallel tree
(a bridge) is solved from its nodal equations instead (mobility analogy, as
in :mod:`mechcirc.nodal`), giving one factored fraction.  The expression is nested exactly as the
tree is (the factored form the papers print); ``expand=True`` brings it over
one common denominator with numerator and denominator multiplied out.

Symbols.  ω is ``omega`` (positive).  An element whose value is written as a
plain number becomes a positive symbol named after the element (``m1``,
``k4``); a value written with ``.param`` names keeps that expression, and a
parameter defined by a plain number is a symbol of its own name (``eta1``)
while one defined by an expression (``etaB={eta1^2 * eta2}``) is replaced by
it.  Numbers are taken as exact decimals (0.8 → 4/5).  :func:`symbol_values`
gives every symbol's SI value, for ``expr.subs(...)`` or ``lambdify``.

SymPy is an optional extra (``pip install mechcirc[formula]``), imported only
inside these functions.
"""

from __future__ import annotations

from fractions import Fraction
from typing import TYPE_CHECKING

from .. import reduction
from ..errors import MechcircError, NotSeriesParallelError
from ..limits import MAX_FORMULA_ELEMENTS

if TYPE_CHECKING:  # pragma: no cover
    from ..circuit import Circuit

__all__ = ["formula", "formula_and_values", "symbol_values", "OMEGA", "MAX_NODAL_UNKNOWNS",
           "MAX_TREE_DEPTH"]

#: Name of the angular-frequency symbol [rad/s].
OMEGA = "omega"
#: Largest nodal system solved symbolically for networks without a tree.
MAX_NODAL_UNKNOWNS = 12
#: Deepest reduction tree turned into a formula.  SymPy's printers recurse
#: about 7 frames per level on a cold cache (a 120-level tree took 857 of
#: Python's default 1,000, so it failed under pytest with coverage); at 64
#: levels (a 32-rung ladder) ``str`` and ``latex`` take about 470, which leaves
#: half the limit to the caller (a notebook, a debugger, a test runner).
MAX_TREE_DEPTH = 64


def _sympy():
    try:
        import sympy
    except ImportError:  # pragma: no cover - depends on the installation
        raise MechcircError("closed-form formulas need SymPy: pip install 'mechcirc[formula]'"
                            ) from None
    return sympy


def _number(sp, value: float):
    """An exact rational from a float, read as the shortest decimal that gives it."""
    return sp.Rational(str(Fraction(repr(float(value)))))


class _Builder:
    def __init__(self, circuit: "Circuit"):
        from ..netlist import expressions_of

        self.sp = _sympy()
        self.circuit = circuit
        self.exprs = expressions_of(circuit) or {}
        self.omega = self.sp.Symbol(OMEGA, positive=True)
        self.values: dict = {}          # Symbol -> SI value (Rational)
        self.params: dict[str, object] = {}
        self.taken = set(circuit.params)

    def _symbol(self, name: str, value: float):
        sym = self.sp.Symbol(name, positive=True)
        self.values[sym] = _number(self.sp, value)
        return sym

    def _expr(self, tree):
        """A netlist Expr as SymPy, parameters resolved (iterative: long sums)."""
        from ..expressions import OPERATORS, postorder

        sp = self.sp
        funcs = {"sqrt": sp.sqrt, "sin": sp.sin, "cos": sp.cos, "tan": sp.tan, "exp": sp.exp,
                 "log": sp.log, "radians": lambda x: x * sp.pi / 180,
                 "degrees": lambda x: x * 180 / sp.pi}
        out: dict[int, object] = {}
        for node in postorder(tree):
            k = node.kind
            if k == "num":
                v = _number(sp, node.value)
            elif k == "name":
                v = sp.pi if node.value == "pi" and node.value not in self.circuit.params \
                    else self.param(node.value)
            elif k == "neg":
                v = -out[id(node.args[0])]
            elif k == "call":
                v = funcs[node.value](out[id(node.args[0])])
            else:
                v = OPERATORS[k](out[id(node.args[0])], out[id(node.args[1])])
            out[id(node)] = v
        return out[id(tree)]

    def _written(self, key: tuple[str, str]):
        """The expression written for ``key`` (times its unit's factor), or None for a number."""
        entry = self.exprs.get(key)
        if entry is None or entry[0].kind == "num":
            return None
        return self._expr(entry[0]) * _number(self.sp, entry[1])

    def param(self, name: str):
        if name not in self.params:
            v = self._written(("param", name))
            self.params[name] = self._symbol(name, self.circuit.params[name]) if v is None else v
        return self.params[name]

    def field(self, owner: str, field: str, value: float, symbol_name: str | None):
        """A value of an element or lever: its symbol, or the expression written for it."""
        if (v := self._written((owner, field))) is not None:
            return v
        return _number(self.sp, value) if symbol_name is None else self._symbol(symbol_name, value)

    def ratio(self, lever):
        """A lever's ratio: its symbol ``r_NAME``, or the expression written for it."""
        return self.field(lever.name, "ratio", lever.ratio, f"r_{lever.name}")

    def element_name(self, name: str, kind: str) -> str:
        base = name if not name.isdigit() else f"{kind[0]}{name}"
        return base if base not in self.taken else f"{base}_{kind}"

    def element_value(self, e):
        value = self.field(e.name, "value", e.value, self.element_name(e.name, e.kind))
        eta = self.field(e.name, "eta", e.eta, None) if e.eta != 1 or \
            (e.name, "eta") in self.exprs else self.sp.Integer(1)
        return value * eta

    def build(self):
        try:
            tree = self.circuit.tree
        except NotSeriesParallelError:
            return self.build_nodal()
        depth = reduction.depth(tree)
        if depth > MAX_TREE_DEPTH:
            raise MechcircError(
                f"the reduction tree is {depth} levels deep; formulas are built up to "
                f"{MAX_TREE_DEPTH} levels (SymPy recurses once per level)")
        return self.build_tree(tree)

    def build_nodal(self):
        """K from the nodal equations, solved symbolically (networks without a tree)."""
        from ..nodal import assemble, stamps

        sp = self.sp
        w = self.omega
        system = assemble(self.circuit)
        size = len(system.elements) + len(system.levers)
        if size > MAX_FORMULA_ELEMENTS:
            raise MechcircError(
                f"the network has no series–parallel tree and {size} elements; its formula "
                f"grows with the number of spanning trees, so a symbolic solution is "
                f"attempted up to {MAX_FORMULA_ELEMENTS} elements (13 took 6 s and 25,000 "
                "characters); evaluate it numerically instead: mechcirc sweep FILE "
                "--method nodal, or mechcirc forces FILE --omega W")
        if system.size > MAX_NODAL_UNKNOWNS:
            raise MechcircError(
                f"the network has no series–parallel tree and {system.size} nodal unknowns; "
                f"a symbolic solution is attempted up to {MAX_NODAL_UNKNOWNS}")
        index = {n: i for i, n in enumerate(system.nodes)}      # absent: the reference
        n = system.size
        A = sp.zeros(n, n)
        for kind, i, j, sign, source, uses_ratio in stamps(system.elements, system.levers, index):
            if kind == "lever":
                y = self.ratio(source) if uses_ratio else 1
            else:
                y = 1 / self.leaf(source)     # Q/v = 1/K
            A[i, j] += y if sign > 0 else -y
        rhs = sp.Matrix(system.injection().astype(int).tolist())
        # Cramer's rule on B = jω·A, whose entries are polynomials (no 1/ω):
        # K = x_a − x_b = (det B_a − det B_b) / det B, with B_i the matrix B whose
        # column i is jω·rhs.  Division-free determinants (Berkowitz) and one
        # division of common monomials at the end: symbolic LU divided at every
        # step and spent its time in nested polynomial GCDs (6 elements: 31 s),
        # and a full cancel() alone took 25 s on a 2×2 grid of 8 elements.
        B = (sp.I * w * A).applyfunc(sp.expand)
        den = B.det(method="berkowitz")
        num = sp.Integer(0)
        for node, sign in ((system.a, 1), (system.b, -1)):
            if node >= 0:
                Bi = B.copy()
                Bi[:, node] = sp.I * w * rhs
                num += sign * Bi.det(method="berkowitz")
        return _lowest_terms(sp, sp.expand(num), sp.expand(den))

    def leaf(self, e):
        """K(ω) = (jω)^p / (value·η) of element ``e`` (:data:`mechcirc.circuit.LAWS`)."""
        from ..circuit import LAWS

        return (self.sp.I * self.omega) ** LAWS[e.kind].power / self.element_value(e)

    def build_tree(self, tree):
        sp = self.sp
        out: dict[int, object] = {}
        for node in reduction.postorder(tree):
            if isinstance(node, reduction.Leaf):
                K = self.leaf(node.element)
            elif isinstance(node, reduction.Series):
                K = sp.Add(*(out[id(c)] for c in node.children))
            elif isinstance(node, reduction.Parallel):
                K = 1 / sp.Add(*(1 / out[id(c)] for c in node.children))
            else:
                K = out[id(node.child)] / self.ratio(node.lever) ** 2
            out[id(node)] = K
        return out[id(tree)]


def _lowest_terms(sp, num, den):
    """``num/den`` with the monomial common to both divided out (ω^k, a symbol's power).

    Cheap (no multivariate GCD); a fraction from the nodal equations keeps no
    other common factor unless part of the network is decoupled.
    """
    gens = sorted(num.free_symbols | den.free_symbols, key=str)
    if not gens or num == 0:
        return num / den
    pn, pd = sp.Poly(num, *gens), sp.Poly(den, *gens)
    (mn, qn), (md, qd) = pn.terms_gcd(), pd.terms_gcd()
    common = [min(a, b) for a, b in zip(mn, md)]
    scale_n = sp.Mul(*[g ** (a - c) for g, a, c in zip(gens, mn, common)])
    scale_d = sp.Mul(*[g ** (b - c) for g, b, c in zip(gens, md, common)])
    return (scale_n * qn.as_expr()) / (scale_d * qd.as_expr())


def formula(circuit: "Circuit", *, expand: bool = False, numeric: bool = False):
    """K(ω) [m/(N·s)] of ``circuit`` as a SymPy expression.

    Parameters
    ----------
    circuit : Circuit
        Any circuit.  Without a series–parallel tree (a bridge), K comes from
        the nodal equations solved symbolically (up to
        :data:`MAX_NODAL_UNKNOWNS` unknowns) as one factored fraction.
    expand : bool
        Bring K over one denominator, numerator and denominator multiplied
        out (``sympy.together`` then ``expand`` of each); by default K stays
        nested as the reduction tree.
    numeric : bool
        Substitute every symbol but ω by its value (exact rationals).

    Returns
    -------
    sympy.Expr
        K(ω), in the symbols of the element names and ``omega``.

    Examples
    --------
    >>> import mechcirc
    >>> c = mechcirc.parse("mass m a 0 2\\nspring k a 0 800\\ndrive V a 0 velocity=1")
    >>> formula(c)
    1/(-I*k/omega + I*m*omega)
    """
    return formula_and_values(circuit, expand=expand, numeric=numeric)[0]


def formula_and_values(circuit: "Circuit", *, expand: bool = False, numeric: bool = False):
    """``(formula(circuit, ...), symbol_values(circuit))`` built once.

    Parameters
    ----------
    circuit : Circuit
    expand, numeric : bool
        As :func:`formula`.

    Returns
    -------
    tuple of (sympy.Expr, dict)
    """
    b = _Builder(circuit)
    K = b.build()
    if numeric:
        K = K.subs(b.values)
    if expand:
        num, den = b.sp.fraction(b.sp.together(K))
        K = b.sp.expand(num) / b.sp.expand(den)
    return K, dict(b.values)


def symbol_values(circuit: "Circuit") -> dict:
    """``{Symbol: value}`` of every symbol :func:`formula` uses except ω (SI, exact rationals).

    Parameters
    ----------
    circuit : Circuit

    Returns
    -------
    dict[sympy.Symbol, sympy.Rational]
    """
    return formula_and_values(circuit)[1]
