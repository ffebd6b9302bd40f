"""Mode shapes of the resonances and anti-resonances, energy per element, exact sensitivities.

:func:`modes` takes the eigenvectors of the same eigenproblem that
:func:`mechcirc.resonances.find_resonances` solves — (s²M + sD + Kₛ) v = 0 on
the null space of the lever constraints, with the drive held (resonances) or
released (anti-resonances) — and gives, for every root, a :class:`Mode`:

* the modal vector: the node velocities, complex for damped modes,
  normalised so that the largest is 1 (its phase is the reference);
* each mass's kinetic energy ½·mη·|Δv|² and each spring's potential energy
  ½·kη·|Δv|²/ωₙ² as a share of their sum (the shares sum to 1), and beside
  them each damper's part of the damping ratio, D_e / (2π E) with
  D_e = π·cη·|Δv|²/ωₙ the energy it dissipates in one cycle and E the sum
  above (for one degree of freedom the parts sum to ζ exactly; for light
  damping nearly);
* each element's velocity Δv = v(n1) − v(n2) and force Q = S(s)·Δv at the
  complex frequency s of the root (S = 1/K of the element's law);
* the exact relative sensitivities (p/ωₙ)·∂ωₙ/∂p of ωₙ to every element
  value, lever ratio and ``.param``, and p·∂ζ/∂p of the damping ratio.

Sensitivities are first-order eigenvalue perturbation of the quadratic
pencil P(s) = s²M + sD + Kₛ bordered by the constraints.  The matrices are
symmetric, so the left eigenvector is the right one transposed (not
conjugated) and

    ∂s/∂p = −wᵀ (∂T/∂p) w / vᵀ (2sM + D) v,

w = [v; q] with q the constraint forces (lever forces, and the drive's force
when held).  An element of value·η = y between nodes i, j contributes
∂T/∂y = s^(1−power) (e_i − e_j)(e_i − e_j)ᵀ (power from the law table:
s² for a mass, s for a damper, 1 for a spring); a lever's ratio r enters its
constraint row r(v_p1 − v_p2) − (v_s1 − v_s2) = 0.  Undamped, this is
∂λ/∂p = vᵀ(∂K/∂p − λ ∂M/∂p)v / vᵀMv with λ = ω².  An element's η enters only
as the product value·η: its relative sensitivity equals that of the value.
A ``.param`` acts through every value, η and ratio written with it: the
chain rule with the exact derivative of each expression
(:func:`mechcirc.expressions.evaluate` with ``tangent``), through later
parameters defined from it.

A root with ω_d = 0 (overdamped, ζ ≥ 1) is a decaying motion, not a
vibration: its :class:`Mode` has no shape and says so in ``note``; its ωₙ
sensitivities are still those of the real root.

:func:`sweep_sensitivity` gives the same derivatives of K(ω) and Q0(ω) on a
sweep, by the adjoint of the nodal system: A(ω) x = c (c = e_a − e_b) with A
complex symmetric gives K = cᵀx and ∂K/∂p = −xᵀ (∂A/∂p) x — one refined
solve per ω, whatever the number of parameters.  An element of value·η = y
adds S(ω)·(e_i − e_j)(e_i − e_j)ᵀ to A (S = y·(jω)^(−power), the law table),
so y·∂K/∂y = −S·(x_i − x_j)²; a lever's ratio r gives r·∂K/∂r =
−2r·q·(x_p1 − x_p2), q its force unknown; a ``.param`` the chain rule above.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass, field

import numpy as np

from .circuit import LAWS, Circuit, Drive
from .resonances import Resonance, Resonances, constraint_basis, pencil, resonance_pairs
from .errors import InputError, unknown_name
from .sources import NamedValues, did_you_mean, summary_repr

__all__ = ["Mode", "Modes", "SweepSensitivity", "modes", "sweep_sensitivity"]

#: Roots whose vectors are combined in one array operation (bounded memory: E × _CHUNK).
_CHUNK = 128


def _lazy(key: str, names: str):
    """A dictionary attribute of :class:`Mode` made from its arrays on first use."""
    def make(self) -> dict:
        values = self._dv() if key in ("velocity", "force") else self._values.get(key)
        if values is not None and key == "force":       # Q = y·s^(−power)·Δv
            y, power = self._names["law"]
            values = y * self.s ** -power * values
        if values is not None and key in ("shape", "velocity"):
            values = values.astype(complex)     # real for an undamped root: complex as documented
        what, where = ("node", " in this mode's shape") if names == "nodes" else \
            ("element", f" in this mode's {key}")
        return NamedValues(() if values is None else zip(self._names[names], values.tolist()),
                           what, where)
    make.__name__ = key
    make.__doc__ = f"See the class docstring ({key})."
    return functools.cached_property(make)


@dataclass(frozen=True)
class Mode:
    """One resonance or anti-resonance with its mode of vibration.

    Attributes
    ----------
    resonance : Resonance
        The root (kind, ωₙ, ω_d, ζ, error) as :func:`~mechcirc.resonances.find_resonances` gives it.
    shape : dict of str to complex
        Node → velocity in the mode [m/s], the largest |v| being 1 (real 1 at
        that node); every loaded node but the frame.  Empty for an
        overdamped root.
    energy : dict of str to float
        Mass or spring → its share of the mode's energy [1] (sum 1).
    dissipation : dict of str to float
        Damper → its part of the damping ratio [1] (see the module docstring).
    velocity, force : dict of str to complex
        Element → Δv = v(n1) − v(n2) [m/s] and Q [N] in the mode, for the
        shape as normalised.
    sensitivity : dict of str to float
        Element or lever → (p/ωₙ)·∂ωₙ/∂p [1], p its value (or ratio); the same
        for the element's η.
    zeta_sensitivity : dict of str to float
        Element or lever → p·∂ζ/∂p [1] (all 0 for an undamped network).
    param_sensitivity, param_zeta_sensitivity : dict of str to float
        The same with respect to each ``.param`` (empty for a circuit built in code).
    note : str
        Why there is no shape (overdamped root), else empty.
    """

    __repr__ = summary_repr

    resonance: Resonance
    param_sensitivity: dict = field(default_factory=dict)
    param_zeta_sensitivity: dict = field(default_factory=dict)
    note: str = ""
    # The per-node and per-element values as arrays and the names they go with (shared by
    # every mode of one call); the dictionaries above are made from them on first use
    # (thousands of elements times thousands of roots would otherwise be built up front).
    _values: dict = field(default_factory=dict, repr=False, compare=False)
    _names: dict = field(default_factory=dict, repr=False, compare=False)

    shape = _lazy("shape", "nodes")
    energy = _lazy("energy", "stored")
    dissipation = _lazy("dissipation", "dampers")
    velocity = _lazy("velocity", "elements")
    sensitivity = _lazy("sensitivity", "all")
    zeta_sensitivity = _lazy("zeta_sensitivity", "all")
    force = _lazy("force", "elements")

    def _dv(self) -> np.ndarray | None:
        """Δv of every element, from the shape (not kept: elements × roots values)."""
        v = self._values.get("shape")
        if v is None:
            return None
        ve, (ei, ej) = np.append(v, np.zeros(1, v.dtype)), self._names["ends"]
        return ve[ei] - ve[ej]

    @property
    def s(self) -> complex:
        """The complex frequency of the root, s = −ζωₙ + jω_d [1/s]."""
        r = self.resonance
        return complex(-r.zeta * r.omega, r.omega_d)


class Modes(list):
    """A list of :class:`Mode` that shows itself as the table of its roots
    (:class:`~mechcirc.resonances.Resonances`: ``repr`` and an HTML table in notebooks)."""

    def __repr__(self) -> str:
        return repr(Resonances(m.resonance for m in self))

    def _repr_html_(self) -> str:
        return Resonances(m.resonance for m in self)._repr_html_()


def modes(circuit: Circuit, omega_max: float | None = None) -> Modes:
    """The :class:`Mode` of every resonance and anti-resonance of ``circuit`` up to ``omega_max``.

    The roots are those of :func:`~mechcirc.resonances.find_resonances` (same
    order), taken from the eigen-solve that gives the vectors (the held ones, where
    every node has mass and there is no lever, from the released modes' secular
    equation): an undamped root not polished on K can differ from
    ``find_resonances``' in the last bits (both backward stable: errors of the
    order eps·λ_max/λ).  See the
    module docstring for what each mode holds.

    Parameters
    ----------
    circuit : Circuit
    omega_max : float, optional
        [rad/s]; None: every root.

    Returns
    -------
    Modes
        A list of Mode, shown as the table of their roots.

    Examples
    --------
    >>> from mechcirc import parse
    >>> from mechcirc.modes import modes
    >>> c = parse("drive V a 0 velocity=1\\nmass m a b 1\\nspring k b 0 100\\n")
    >>> (m,) = modes(c)
    >>> round(m.resonance.omega, 12), {k: round(v, 12) for k, v in m.energy.items()}
    (10.0, {'m': 0.5, 'k': 0.5})
    >>> {k: round(v, 12) for k, v in m.sensitivity.items()}
    {'m': -0.5, 'k': 0.5}
    """
    system = circuit.nodal
    pairs = resonance_pairs(circuit, omega_max, vectors=True)
    if not pairs:
        return Modes()
    M, D, Ks, G_released, G_held, _ = pencil(system)
    els = system.elements
    ei, ej, y, power, lever_ends, names = _stamped(system)
    kinds = np.array([e.kind for e in els])
    damper, el_names = kinds == "damper", [e.name for e in els]
    shared = {"nodes": list(system.nodes), "elements": el_names, "all": names,
              "stored": [n for n, d in zip(el_names, damper) if not d],
              "dampers": [n for n, d in zip(el_names, damper) if d], "law": (y, power),
              "ends": (ei, ej)}
    slopes = _param_slopes(circuit, names)
    # Constraint forces from the node rows, P(s) v + s Gᵀ q = 0: Gᵀ's pseudo-inverse,
    # once per problem (only levers need them).
    pinv = {kind: np.linalg.pinv(G.T) if system.levers else None
            for kind, G in (("resonance", G_held), ("antiresonance", G_released))}
    roots = _normalised(pairs, M, D, Ks, G_held, G_released)
    # The arithmetic for many roots at once: CHUNK roots of one kind (one constraint set).
    values: list = [None] * len(roots)
    # Once, not per chunk: each element's row among the distinct exponents 1 − power, and
    # in the per-law table of energy shares (mass, spring, damper).
    stamps = (ei, ej, y, (np.unique(1.0 - power, return_inverse=True), lever_ends), slopes,
              np.where(kinds == "mass", 0, np.where(kinds == "spring", 1, 2)), damper)
    for kind in ("resonance", "antiresonance"):
        idx = [i for i, (r, *_) in enumerate(roots) if r.kind == kind]
        for lo in range(0, len(idx), _CHUNK):
            part = idx[lo:lo + _CHUNK]
            S = np.array([roots[i][1] for i in part])
            V = np.column_stack([roots[i][2] for i in part])
            for i, vals in zip(part, _chunk_values(system, (M, D, Ks), pinv[kind], S, V,
                                                   stamps)):
                values[i] = vals
    return Modes(_mode(r, repeated, vals, p_rel, p_zeta, shared)
                 for (r, _, _, repeated), (vals, p_rel, p_zeta) in zip(roots, values))


def _normalised(pairs, M, D, Ks, G_held, G_released) -> list:
    """``(root, s, v, repeated)`` of every pair, v as the solver gives it (band roots
    get theirs by inverse iteration); scaled per chunk in :func:`_chunk_values`."""
    roots = []
    for r, v, repeated in pairs:
        s = complex(-r.zeta * r.omega, r.omega_d)
        if v is None:                       # a band root: no vector from the solver
            v = _inverse_iteration(M, D, Ks, G_held if r.kind == "resonance" else G_released, s)
        roots.append((r, s, v, repeated))
    return roots


def _chunk_values(system, pencil3, pinv, S, V, stamps) -> list:
    """Sensitivities, energies and element velocities of the roots ``S`` with
    vectors ``V`` (columns; scaled in place), one ``(values, param_rel, param_zeta)``
    per root."""
    ei, ej, y, laws, slopes, law_row, damper = stamps
    M, D, Ks = pencil3
    top, col = np.argmax(np.abs(V), axis=0), np.arange(S.size)
    V /= V[top, col]                        # 1 at the largest entry (real when undamped),
    V[top, col] = 1.0                       # exactly (a complex quotient may miss by an ulp)
    # Real vectors (undamped roots) keep every (element × root) array real: the complex
    # factors depend on the root and the law only, one row per law.
    Ve = np.vstack([V, np.zeros((1, S.size), V.dtype)])
    dV = Ve[ei] - Ve[ej]
    # In place where it can be (fresh E × roots arrays page-fault): a real Δv is not needed
    # beyond y·Δv².
    real = not np.iscomplexobj(dV)
    ya2 = np.multiply(dV, dV, out=dV) if real else dV.real ** 2 + dV.imag ** 2
    ya2 *= y[:, None]
    # a real dV now holds y·Δv² (ya2), so only a complex one is handed on as Δv
    rel, zeta = _root_sensitivity(system, M, D, Ks, pinv, S, V, None if real else dV, y,
                                  laws, ya2 if real else None)
    # Both are real-linear in ∂s/∂p, and a .param's slope is a real combination of them.
    p_rel, wn = {p: (row @ rel, row @ zeta) for p, row in slopes.items()}, np.abs(S)
    # Kinetic ½mη|Δv|², potential ½kη|Δv|²/ωₙ², nothing stored in a damper.
    share = np.vstack([np.full(S.size, 0.5), 0.5 / wn ** 2, np.zeros(S.size)])
    stored = ya2 * share[law_row]
    total, energy = stored.sum(axis=0), stored[~damper] if damper.any() else stored
    energy /= total
    dissipation = ya2[damper] / (2 * wn * total)
    return [({"sensitivity": rel[:, c], "zeta_sensitivity": zeta[:, c], "shape": V[:, c],
              "energy": energy[:, c], "dissipation": dissipation[:, c]},
             {p: float(x[0][c]) for p, x in p_rel.items()},
             {p: float(x[1][c]) for p, x in p_rel.items()}) for c in range(S.size)]


def _mode(r, repeated, vals, p_rel, p_zeta, shared) -> Mode:
    common: dict = {"param_sensitivity": p_rel, "param_zeta_sensitivity": p_zeta, "_names": shared}
    if r.omega_d == 0:
        return Mode(r, note=f"overdamped (zeta = {r.zeta:.4g} >= 1, omega_d = 0): "
                            "a decaying motion, not a mode of vibration",
                    _values={k: vals[k] for k in ("sensitivity", "zeta_sensitivity")},
                    **common)
    if repeated:
        common["note"] = ("a repeated root: its shape is one of a family (any "
                          "combination is a mode too) and the sensitivities hold for "
                          "this shape only")
    return Mode(r, _values=vals, **common)


def _stamped(system) -> tuple:
    """(row i, row j (−1 the reference), value·η, law power) of each loaded element, the
    rows of each lever's primary ends p1, p2 (shape (2, levers)), and the names: the
    elements, then the levers."""
    els, index = system.elements, {n: i for i, n in enumerate(system.nodes)}
    ei = np.array([index.get(e.n1, -1) for e in els], dtype=int)
    ej = np.array([index.get(e.n2, -1) for e in els], dtype=int)
    ends = np.array([[index.get(lv.p1, -1) for lv in system.levers],
                     [index.get(lv.p2, -1) for lv in system.levers]], dtype=int)
    y = np.array([e.value * e.eta for e in els])
    power = np.array([LAWS[e.kind].power for e in els])
    return ei, ej, y, power, ends, [e.name for e in els] + [lv.name for lv in system.levers]


@dataclass(frozen=True)
class SweepSensitivity:
    """Exact derivatives of K(ω) and of the drive's response on a sweep.

    The result of :func:`sweep_sensitivity`.

    Attributes
    ----------
    omega : ndarray of float, shape (n,)
        Angular frequency [rad/s].
    K : ndarray of complex, shape (n,)
        K(ω) [m/(N·s)] from the same nodal solve.
    drive : Drive
    value : dict of str to float
        Name → p, the element's value, the lever's ratio or the ``.param`` (SI).
    dK : dict of str to ndarray of complex
        Name → p·∂K/∂p [m/(N·s)] at each ω (0 for an element that carries no force;
        an element's η has the same derivative as its value).
    """

    __repr__ = summary_repr

    omega: np.ndarray
    K: np.ndarray
    drive: Drive
    value: dict
    dK: dict

    @property
    def quantity(self) -> str:
        """The drive's response: ``"Q0"`` (velocity drive, Q0 = V0/K) or ``"v0"`` (v0 = F0·K)."""
        return "v0" if self.drive.kind == "force" else "Q0"

    def relative(self, name: str, quantity: str | None = None) -> np.ndarray:
        """(p/|q|)·∂|q|/∂p [1] at each ω, q = ``"K"``, ``"Q0"`` or ``"v0"``
        (default :attr:`quantity`); a prescribed quantity has 0."""
        quantity = quantity or self.quantity
        with np.errstate(all="ignore"):
            rel = (self.dK[self._key(name)] / self.K).real
        if quantity == "K" or (quantity == "v0" and self.drive.kind == "force"):
            return rel
        if quantity == "Q0" and self.drive.kind == "velocity":
            return -rel
        if quantity in ("Q0", "v0"):
            return np.zeros_like(rel)
        raise ValueError(f"quantity must be 'K', 'Q0' or 'v0', got {quantity!r}")

    def derivative(self, name: str, quantity: str | None = None) -> np.ndarray:
        """∂|q|/∂p at each ω [unit of q per SI unit of p] (see :meth:`relative`)."""
        quantity, amp = quantity or self.quantity, abs(self.drive.amplitude)
        with np.errstate(all="ignore"):
            mag = {"K": np.abs(self.K), "Q0": amp / np.abs(self.K) if self.drive.kind ==
                   "velocity" else np.full(self.K.shape, amp),
                   "v0": amp * np.abs(self.K) if self.drive.kind == "force"
                   else np.full(self.K.shape, amp)}[quantity]
            return self.relative(name, quantity) * mag / self.value[self._key(name)]

    def _key(self, name: str) -> str:
        if name not in self.dK:
            raise unknown_name(name, self.dK, "parameter", " among the sensitivities computed")
        return name


def sweep_sensitivity(circuit: Circuit, omega, names=None) -> SweepSensitivity:
    """Exact p·∂K/∂p at each ω for element values, lever ratios and ``.param`` values.

    By the adjoint of the nodal system (module docstring): one refined solve
    per ω (:func:`mechcirc.nodal.solve`) gives the derivatives to every
    parameter at once.

    Parameters
    ----------
    circuit : Circuit
    omega : array_like of float
        Angular frequencies [rad/s], > 0.
    names : iterable of str, optional
        Elements, levers or ``.param`` values; default every one.

    Returns
    -------
    SweepSensitivity

    Raises
    ------
    InputError
        A name that is none of these (the message lists those that are).

    Examples
    --------
    >>> from mechcirc import parse
    >>> from mechcirc.modes import sweep_sensitivity
    >>> c = parse("drive V a 0 velocity=1\\nmass m a 0 2\\ndamper c a 0 4\\n")
    >>> s = sweep_sensitivity(c, [2.0])       # |Q0| = |4 + 4j|: each carries half
    >>> round(float(s.relative("m")[0]), 12), round(float(s.relative("c")[0]), 12)
    (0.5, 0.5)
    """
    from . import nodal
    from ._sweep import real_omega

    system = circuit.nodal
    ei, ej, y, power, lever_ends, stamped = _stamped(system)
    value, names = _values_named(circuit, names)
    omega = real_omega(omega)
    column = {name: k for k, name in enumerate(stamped)}
    slopes = _param_slopes(circuit, stamped) if set(names) & circuit.params.keys() else {}
    m = omega.size
    K = np.empty(m, complex)
    dK = {name: np.zeros(m, complex) for name in names}   # 0: carries no force
    # Chunks of ω: the solutions of one chunk are held (≤ 2**20 values), never all.
    chunk = max(1, 2**20 // (system.size + len(stamped) + 1))
    for at in range(0, m, chunk):
        w = omega[at:at + chunk]
        sol = nodal.solve(system, w)
        assert sol.x is not None            # kept by default
        K[at:at + w.size] = sol.K
        dK_all = _adjoint_products(system, sol.x, w, (ei, ej, y, power, lever_ends))
        for name in names:
            if name in column:
                dK[name][at:at + w.size] = dK_all[:, column[name]]
            elif name in slopes:
                with np.errstate(all="ignore"):
                    dK[name][at:at + w.size] = dK_all @ slopes[name]
    return SweepSensitivity(omega, K, circuit.require_drive(), {k: value[k] for k in names}, dK)


def _values_named(circuit: Circuit, names) -> tuple[dict, list]:
    """``(every element's, lever's and .param's value, the names asked (default all), checked)``."""
    value = {e.name: e.value for e in circuit.elements} | \
        {lv.name: lv.ratio for lv in circuit.levers} | \
        {p: float(v) for p, v in circuit.params.items()}
    names = list(value) if names is None else list(dict.fromkeys(names))
    unknown = [n for n in names if n not in value]
    if unknown:
        raise InputError(f"no element, lever or .param named {unknown[0]!r}"
                         f"{did_you_mean(unknown[0], value)} (there are: {', '.join(value)})")
    return value, names


def _adjoint_products(system, x, w, stamps) -> np.ndarray:
    """∂K/∂(value) of every stamped element, then every lever ratio, at the ω ``w``
    from the nodal solutions ``x`` (rows), shape (ω, elements + levers)."""
    ei, ej, y, power, ends = stamps
    n_nodes = len(system.nodes)
    xe = np.concatenate([x, np.zeros((w.size, 1), complex)], axis=1)
    ratio = np.array([lv.ratio for lv in system.levers])
    with np.errstate(all="ignore"):
        S = y * (1j * w[:, None]) ** (-power.astype(float))
        dv = xe[:, ei] - xe[:, ej]
        # Each lever's force unknown (after the node rows) times its ends' Δv.
        lever = -2 * ratio * xe[:, n_nodes:n_nodes + ratio.size] * (xe[:, ends[0]] - xe[:, ends[1]])
        return np.concatenate([-S * dv * dv, lever], axis=1)


def _root_sensitivity(system, M, D, Ks, pinv_GT, S, V, dV, y, laws, ya2=None) -> tuple:
    """(p/ωₙ)·∂ωₙ/∂p and p·∂ζ/∂p (from p·∂s/∂p) for every loaded element (value p) and
    lever (ratio p), in that order, one column a root: ``S`` the roots, ``V`` their
    vectors (columns), ``dV`` the elements' Δv (None when ``ya2`` is given); ``laws``
    the distinct exponents 1 − power and each element's row among them, and the levers'
    ends (:func:`_stamped`); ``pinv_GT`` the pseudo-inverse of the transposed
    constraint rows; ``ya2`` = y·Δv² when the vectors are real (then the element rows
    are computed in real arithmetic), else None."""
    MV, DV = M @ V, D @ V
    den = np.sum(V * (2 * S * MV + DV), axis=0)
    # The powers S ** (1 - power), one row per distinct exponent (element e's is row which[e]).
    (exponents, which), ends = laws
    coef = -(S[None, :] ** exponents[:, None]) / den    # p·∂s/∂p per unit y·Δv², a row a law
    if ya2 is not None:
        rel_law, zeta_law = _omega_zeta(S, coef)
        # Undamped, ∂s/∂p is imaginary: ζ rows of zeros, left untouched (no page faults).
        rel = ya2 * rel_law[which]
        zeta = ya2 * zeta_law[which] if zeta_law.any() else np.zeros(ya2.shape)
    else:
        rel, zeta = _omega_zeta(S, y[:, None] * dV * dV * coef[which])
    if not system.levers:
        return rel, zeta
    # Constraint forces q from the node rows: P(s) v + s Gᵀ q = 0 (exact at an eigenvector).
    q = -(pinv_GT @ (S * S * MV + S * DV + Ks @ V)) / S
    Ve = np.vstack([V, np.zeros((1, V.shape[1]))])
    ratio = np.array([lv.ratio for lv in system.levers])[:, None]
    lever_rel, lever_zeta = _omega_zeta(
        S, -2 * S * ratio * q[:ratio.size] * (Ve[ends[0]] - Ve[ends[1]]) / den)
    return np.vstack([rel, lever_rel]), np.vstack([zeta, lever_zeta])


def _omega_zeta(s, ds: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(p/ωₙ)·∂ωₙ/∂p and p·∂ζ/∂p from p·∂s/∂p, ωₙ = |s|, ζ = −Re s/|s| (s one root, or
    an array of roots matching the last axis of ``ds``)."""
    wn = np.abs(s)
    rel = (s.conjugate() * ds).real / wn ** 2
    return rel, -ds.real / wn + s.real * rel / wn


def _inverse_iteration(M, D, Ks, G, s: complex, steps: int = 3) -> np.ndarray:
    """The eigenvector at the polished root s by inverse iteration on the projected
    pencil (sparse LU): for roots of the band solver, which gives no vectors."""
    from scipy.sparse.linalg import splu

    Z = constraint_basis(G, M.shape[0])
    P = (Z.T @ (s * s * M + s * D + Ks) @ Z).tocsc().astype(complex)
    try:
        lu = splu(P)
    except RuntimeError:               # exactly singular at s: any nearby shift will do
        lu = splu((P + 1e-14 * abs(s) ** 2 * (Z.T @ M @ Z)).tocsc().astype(complex))
    u = np.random.default_rng(20261125).standard_normal(P.shape[0]) + 0j
    for _ in range(steps):
        u = lu.solve(u)
        u /= np.linalg.norm(u)
    return Z @ u


def _param_slopes(circuit: Circuit, names: list[str]) -> dict[str, np.ndarray]:
    """``.param`` → the vector (P/x)·∂x/∂P over ``names`` (loaded elements, then levers).

    x is each element's value (its η counts the same, and a spring's η also
    scales its ``damping=`` companion) or lever ratio; P the parameter's SI
    value.  From the parsed expressions (:func:`mechcirc.netlist.expressions_of`)
    differentiated exactly, parameters in the order defined.
    """
    from .expressions import evaluate
    from .netlist import expressions_of

    params = dict(circuit.params)
    # No .param: nothing to differentiate (and the expression table is not materialised).
    exprs = expressions_of(circuit) if params else None
    if not exprs:
        return {}
    position = {name: k for k, name in enumerate(names)}
    x = {e.name: e.value for e in circuit.elements} | {lv.name: lv.ratio for lv in circuit.levers}
    eta = {e.name: e.eta for e in circuit.elements}
    targets: dict[tuple, list[tuple[str, float]]] = {}
    for (name, what) in exprs:
        if what == "value" or what == "ratio":
            targets[(name, what)] = [(name, x.get(name, math.nan))]
        elif what == "eta":
            targets[(name, what)] = [(m, eta[name]) for m in (name, f"{name}_damping") if m in eta]
        elif what == "damping" and f"{name}_damping" in x:
            targets[(name, what)] = [(f"{name}_damping", x[f"{name}_damping"])]
    used = [(key, e, f) for key, (e, f) in exprs.items()
            if e.kind != "num" and (key[0] == "param" or key in targets) and e.names() & params.keys()]
    out = {}
    for p, value in params.items():
        tangent = {p: 1.0}
        row = np.zeros(len(names))
        for key, expr, factor in used:
            if key == ("param", p):
                continue
            d = factor * evaluate(expr, params, tangent=tangent)[1]
            if not d:
                continue
            if key[0] == "param":
                tangent[key[1]] = d
                continue
            for name, xv in targets[key]:
                if name in position:
                    row[position[name]] += value * d / xv
        out[p] = row
    return out
