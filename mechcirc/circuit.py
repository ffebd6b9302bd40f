"""Mechanical circuits: two-pole elements, levers, the drive, and the :class:`Circuit`.

Conventions (Grigoriev et al. 2002):

* Every element is a two-pole between nodes ``n1`` and ``n2``; ``v`` is the
  difference of the nodes' velocities ``v(n1) - v(n2)`` [m/s] and ``Q`` the
  force passing through it from ``n1`` to ``n2`` [N].
* The complex kinematic characteristic (mobility) is ``K = v / Q`` [m/(N·s)];
  its reciprocal ``S = Q / v`` is the force characteristic [N·s/m].
* Element characteristics, with ``eta`` the product of lever ratios the paper
  attaches to the element (its reflection factor, default 1):

  ======  =============================  ===========
  kind    K(ω)                           value unit
  ======  =============================  ===========
  mass    −j / (ω · m · η)               kg
  spring  +j · ω / (k · η)               N/m
  damper  1 / (c · η)                    N·s/m
  ======  =============================  ===========

* Series elements carry the same ``Q`` and their K add; parallel elements
  share ``v`` and their 1/K add.
* Rotational systems use the same elements: inertia [kg·m²] as mass,
  torsional rigidity [N·m/rad] as spring, rotary damping [N·m·s/rad] as
  damper; then v is an angular velocity [rad/s], Q a moment [N·m] and K is in
  rad/(N·m·s).
* Node ``"0"`` is the frame.  ``omega`` is the main shaft's angular frequency
  [rad/s].
"""

from __future__ import annotations

from collections import Counter
from dataclasses import dataclass, field
from functools import cached_property
from typing import TYPE_CHECKING, Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ._memo import Memos
from .errors import NetlistError, NotSeriesParallelError, unknown_name

if TYPE_CHECKING:  # pragma: no cover - annotations of the delegates only
    from .motion_laws import Motion
    from .nodal import NodalSystem
    from .reduction import Node, Reduction
    from .resonances import Kind, Resonance
    from ._sweep import Method, Sweep

__all__ = ["Element", "Lever", "Drive", "Circuit", "element_mobility", "law_terms", "FRAME",
           "ELEMENT_UNITS", "Law", "LAWS", "element_unit", "node_names", "units_of"]

FRAME = "0"

ElementKind = Literal["mass", "spring", "damper"]


@dataclass(frozen=True)
class Law:
    """The law of one element kind: K(ω) = (jω)^power / (value·η).

    This table is the one place the element laws are written; every
    evaluation (numeric, nodal, symbolic, textual) derives from it.

    Attributes
    ----------
    power : int
        Exponent p of jω in K = (jω)^p / s, s = value·η: −1 for a mass
        (K = 1/(jωm)), +1 for a spring (K = jω/k), 0 for a damper (K = 1/c).
        The force characteristic is S = 1/K = s·(jω)^(−p), which enters the
        nodal matrix A(ω) = G + j(ωM − K/ω) in M (p = −1), G (0) or K (+1).
    unit : str
        SI unit of the value (translational reading).
    rotary_unit : str
        SI unit of the value in a rotary circuit (a drive in rad/s or N·m):
        an inertia, a torsional stiffness or a torsional damping.
    """

    power: int
    unit: str
    rotary_unit: str


#: Element kind → its :class:`Law`.
LAWS: dict[str, Law] = {"mass": Law(-1, "kg", "kg·m²"), "spring": Law(+1, "N/m", "N·m/rad"),
                        "damper": Law(0, "N·s/m", "N·m·s/rad")}

#: SI unit of each element kind's value (translational reading).
ELEMENT_UNITS: dict[str, str] = {kind: law.unit for kind, law in LAWS.items()}


@dataclass(frozen=True)
class Element:
    """A two-pole: mass, spring or damper between nodes ``n1`` and ``n2``.

    Attributes
    ----------
    kind : {"mass", "spring", "damper"}
    name : str
    n1, n2 : str
        Node names; ``"0"`` is the frame.
    value : float
        Mass [kg], stiffness [N/m] or damping coefficient [N·s/m], > 0.
    eta : float
        Reflection factor η [1], > 0 (the paper's product of lever ratios).
    line, col : int
        Where the element was defined (0 when built in code).
    backlash : float
        Springs only: total clearance B [m or rad] in series with the spring
        (Modelica ``ElastoBacklash`` law, see :mod:`mechcirc.transient._kernels`);
        0 for none.  The frequency domain takes the contact as closed.

    A spring's ``damping=D`` in a netlist is not a field: it is the damper
    element ``NAME_damping`` the parser adds in parallel (same nodes, same η),
    the one place every analysis and the netlist writer read it from.
    """

    kind: ElementKind
    name: str
    n1: str
    n2: str
    value: float
    eta: float = 1.0
    line: int = 0
    col: int = 0
    backlash: float = 0.0

    def mobility(self, omega: ArrayLike) -> NDArray[np.complex128]:
        """Kinematic characteristic K(ω) [m/(N·s)] of this element."""
        return element_mobility(self.kind, self.value * self.eta, omega)


def law_terms(kind: str, scaled_value, admittance: bool = False) -> tuple:
    """The law of one element kind as ``(real, inv, omega)`` with
    K(ω) = real + j·(inv/ω + omega·ω), or 1/K(ω) in that form with ``admittance``.

    ``scaled_value`` is value·η; pass a numpy float so that 1/0 = ∞ instead of
    ZeroDivisionError (callers hold ``np.errstate``).  Exactly one term is nonzero.
    Series–parallel reduction adds these terms over a node's leaves; nodal
    analysis stamps the same laws (``nodal.stamps``).

    Parameters
    ----------
    kind : {"m", "k", "c"}
    scaled_value : float or ndarray
        value·η.
    admittance : bool
        The terms of 1/K instead of K.

    Returns
    -------
    tuple of 3
        ``(real, inv, omega)``.
    """
    law = LAWS.get(kind)
    if law is None:
        raise ValueError(f"unknown element kind {kind!r}")
    p = law.power
    if admittance:
        p, c = -p, scaled_value
    else:
        c = 1.0 / scaled_value
    # (jω)^1 = j·ω, (jω)^−1 = −j/ω, (jω)^0 = 1.
    if p == 0:
        return c, 0.0, 0.0
    return (0.0, 0.0, c) if p > 0 else (0.0, -c, 0.0)


def element_mobility(kind: str, scaled_value: float, omega: ArrayLike) -> NDArray[np.complex128]:
    """K(ω) [m/(N·s)] of one element kind with value·η = ``scaled_value`` (by :func:`law_terms`).

    ω = 0 gives K = ∞ for a mass and 0 for a spring (no warnings are raised;
    callers flag non-finite results).

    Parameters
    ----------
    kind : {"m", "k", "c"}
        Mass, spring or damper.
    scaled_value : float
        value·η [kg, N/m or N·s/m].
    omega : array_like
        ω [rad/s].

    Returns
    -------
    ndarray of complex
        K(ω) [m/(N·s)].
    """
    law = LAWS.get(kind)
    if law is None:
        raise ValueError(f"unknown element kind {kind!r}")
    omega = np.asarray(omega, dtype=float)
    out = np.zeros(omega.shape, dtype=complex)
    with np.errstate(divide="ignore", invalid="ignore"):
        # (jω)^p / s filled part by part: a complex product such as 1j * inf
        # would give nan + inf·j at ω = 0 instead of -j∞.
        if law.power == 0:
            out.real = 1.0 / scaled_value
        elif law.power == 1:
            out.imag = omega / scaled_value                 # jω/s
        else:
            out.imag = -1.0 / (omega * scaled_value)        # 1/(jωs) = -j/(ωs)
    return out


@dataclass(frozen=True)
class Lever:
    """An ideal lossless lever (two-port): v_S = r · v_P and Q_P = r · Q_S.

    ``v_P = v(p1) - v(p2)``, ``v_S = v(s1) - v(s2)``.  Seen from the primary,
    a sub-network of characteristic K on the secondary appears as K / r²
    (a mass m reflects as m · r²).  ``ratio`` r [1] is > 0.
    """

    name: str
    p1: str
    p2: str
    s1: str
    s2: str
    ratio: float
    line: int = 0
    col: int = 0

    @property
    def terminals(self) -> tuple[str, str, str, str]:
        """The four nodes ``(p1, p2, s1, s2)``."""
        return self.p1, self.p2, self.s1, self.s2

    def reflect(self, K, ratio=None):
        """K [m/(N·s)] of a sub-network on the secondary, seen from the primary: K / r²
        (r the lever's ratio, or ``ratio``: an array of them over designs).

        Divided twice: r² overflows a float for r > 1.3e154."""
        r = self.ratio if ratio is None else ratio
        return K / r / r


@dataclass(frozen=True)
class Drive:
    """The excitation between ``n1`` and ``n2``.

    ``kind`` is ``"velocity"`` (kinematic excitation, amplitude V0 [m/s]) or
    ``"force"`` (force excitation, amplitude F0 [N]).  ``motion``, when given,
    is the drive's displacement over one revolution of the main shaft
    (:class:`mechcirc.motion_laws.Motion`, netlist ``motion=``) for
    :func:`mechcirc.periodic.periodic`; such a drive is a velocity drive of
    amplitude 1 m/s for the single-frequency analyses.
    """

    name: str
    n1: str
    n2: str
    kind: Literal["velocity", "force"]
    amplitude: float
    line: int = 0
    col: int = 0
    motion: Motion | None = None
    rotational: bool = field(default=False, compare=False)   # labels only


def units_of(drive: Drive | bool | None) -> dict[str, str]:
    """Unit labels of a circuit driven by ``drive``: keys ``v``, ``Q``, ``x``, ``K``.

    Translational: m/s, N, m, m/(N·s); rotary (``drive.rotational``, or ``drive``
    True: an element's own kind, :meth:`Circuit.rotational`): rad/s, N·m, rad,
    rad/(N·m·s).

    Parameters
    ----------
    drive : Drive, bool or None

    Returns
    -------
    dict[str, str]
    """
    if _rotary(drive):
        return {"v": "rad/s", "Q": "N·m", "x": "rad", "K": "rad/(N·m·s)"}
    return {"v": "m/s", "Q": "N", "x": "m", "K": "m/(N·s)"}


def element_unit(kind: str, drive: Drive | bool | None) -> str:
    """Unit label of an element's value in a circuit driven by ``drive``.

    ``kg``, ``N/m``, ``N·s/m``; in a rotary circuit (``drive.rotational``, or
    ``drive`` True: the element's own kind, :meth:`Circuit.rotational`)
    ``kg·m²``, ``N·m/rad``, ``N·m·s/rad`` (:data:`LAWS`).

    Parameters
    ----------
    kind : {"mass", "spring", "damper"}
    drive : Drive, bool or None

    Returns
    -------
    str
    """
    law = LAWS[kind]
    return law.rotary_unit if _rotary(drive) else law.unit


def _rotary(drive: Drive | bool | None) -> bool:
    """Whether labels are rotary: ``drive.rotational``, or ``drive`` itself when a bool."""
    return drive if isinstance(drive, bool) else drive is not None and drive.rotational


@dataclass(frozen=True)
class Circuit(Memos):
    """A mechanical circuit: elements, levers and one drive.

    Build one with :func:`mechcirc.parse` or :func:`mechcirc.load`, or
    directly from :class:`Element`, :class:`Lever` and :class:`Drive`.

    Attributes
    ----------
    elements : tuple of Element
    drive : Drive or None
        None only in a circuit read with ``require_drive=False`` (a transient
        with initial conditions and no drive); analyses that need the drive
        take it from :meth:`require_drive`.
    levers : tuple of Lever
    name : str
        A short name (the netlist's file stem), used in titles.
    source : str
        Where the circuit came from (file name or ``"<string>"``).
    params : dict
        The ``.param`` values [as written], for reference.
    initial : tuple of (str, float, float)
        Initial conditions ``(node, x0, v0)`` [m, m/s] from ``.ic`` lines
        (transients only; unnamed nodes start at rest).
    expressions : tuple
        Set by :func:`mechcirc.parse`: ``(elements, levers, drive, params,
        table)``, the parsed expressions and the objects they were read for;
        ``()`` for circuits built in code.  Read it through
        :func:`mechcirc.netlist.expressions_of`.  Not compared, not shown.
    node_kinds : dict of str to bool
        Set by :func:`mechcirc.parse`: each node whose elements carry units of one
        kind only, True for rotary (kg·m², N·m/rad, N·m·s/rad), False for
        translational; for labels (:meth:`rotational`).  Not compared, not shown.

    Analysis methods (``tree``, ``unloaded``, ``nodal``, ``sweep``,
    ``resonances``, ``two_port``, ``formula``) are one-line delegates to the
    functions of the modules that do the analysis, imported when called (as
    SciPy's ``lti.bode``): the function is the implementation, the method a
    convenience, and this module imports nothing above it when it is loaded.
    """

    elements: tuple[Element, ...]
    drive: Drive | None
    levers: tuple[Lever, ...] = ()
    name: str = "circuit"
    source: str = "<string>"
    params: dict = field(default_factory=dict, compare=False)
    initial: tuple = ()
    expressions: tuple = field(default=(), compare=False, repr=False)
    node_kinds: dict = field(default_factory=dict, compare=False, repr=False)

    def rotational(self, element: Element) -> bool:
        """Whether ``element`` is rotary, for its unit labels: its nodes' kind from the
        units written in the netlist (:attr:`node_kinds`), else the drive's."""
        kinds = [self.node_kinds[n] for n in (element.n1, element.n2) if n in self.node_kinds]
        return kinds[0] if kinds else self.drive is not None and self.drive.rotational

    def require_drive(self) -> Drive:
        """The drive; a :class:`~mechcirc.errors.NetlistError` if the circuit has none.

        Every analysis seen from the drive (K(ω), resonances, the reduction
        tree) takes the drive from here, so a circuit read with
        ``require_drive=False`` fails with a message, not an ``AttributeError``.
        """
        if self.drive is None:
            raise NetlistError(f"circuit {self.name!r} has no drive, and this analysis is "
                               "seen from one", self.source, 0, 0,
                               "one line 'drive NAME N1 N2 velocity=V0' (a netlist without "
                               "a drive can only be integrated: 'mechcirc transient')")
        return self.drive

    @cached_property
    def _reduction(self) -> Reduction:
        from .reduction import reduce_circuit

        return reduce_circuit(self)

    @property
    def tree(self) -> Node:
        """The series-parallel reduction tree seen from the drive.

        Prints as a nested expression, e.g. ``m1 + m2 + (k4 | (m5 + k5))``.
        Raises :class:`~mechcirc.errors.TopologyError` if the network is not
        series-parallel reducible.
        """
        return self._reduction.tree

    @property
    def unloaded(self) -> tuple[str, ...]:
        """Names of elements on no path between the drive terminals (they carry no force).

        From the series–parallel reduction, or from the nodal system's loaded part
        where the network is not series–parallel (a bridge, a lever across meshes).
        """
        try:
            return self._reduction.unloaded
        except NotSeriesParallelError:
            return self.nodal.unloaded

    @cached_property
    def nodal(self) -> NodalSystem:
        """The :class:`~mechcirc.nodal.NodalSystem` of the loaded network (built on first use)."""
        from .nodal import assemble, require_nonsingular

        system = assemble(self)
        require_nonsingular(system, self.source)
        return system

    def sweep(self, omega: ArrayLike, method: Method = "auto", *, refine: bool = True,
              error: bool = False) -> Sweep:
        """K(ω), Q0(ω) and per-element forces over ``omega`` [rad/s].

        See :func:`mechcirc.sweep` (``refine``: nodal analysis only; ``error``:
        the tree's error bound in the same pass as K).
        """
        from ._sweep import sweep

        return sweep(self, omega, method=method, refine=refine, error=error)

    def resonances(self, omega_max: float | None = None,
                   kind: Kind | None = None) -> list[Resonance]:
        """Zeros and poles of K(ω) up to ``omega_max`` [rad/s] (``kind``: only those).

        See :func:`mechcirc.resonances.find_resonances`.
        """
        from .resonances import find_resonances

        return find_resonances(self, omega_max=omega_max, kind=kind)

    def modes(self, omega_max: float | None = None) -> list:
        """The mode shape, energy shares and sensitivities of every root up to ``omega_max``.

        See :func:`mechcirc.modes.modes`.
        """
        from .modes import modes

        return modes(self, omega_max=omega_max)

    def periodic(self, rpm: float, **kwargs):
        """The drive's steady periodic force over one revolution at ``rpm``.

        See :func:`mechcirc.periodic.periodic`.
        """
        from .periodic import periodic

        return periodic(self, rpm, **kwargs)

    def speed_map(self, rpm_min: float, rpm_max: float, points: int = 200, **kwargs):
        """Peak drive force over the cycle against machine speed.

        See :func:`mechcirc.periodic.speed_map`.
        """
        from .periodic import speed_map

        return speed_map(self, rpm_min, rpm_max, points, **kwargs)

    def two_port(self, P1: str, P2: str, S1: str, S2: str, omega: ArrayLike, **kwargs):
        """Z parameters [m/(N·s)] between ports P1–P2 and S1–S2 as an ``skrf.Network``.

        See :func:`mechcirc.interop.skrf.two_port`.
        """
        from .interop.skrf import two_port

        return two_port(self, P1, P2, S1, S2, omega, **kwargs)

    def formula(self, **kwargs):
        """K(ω) as a SymPy expression nested as the reduction tree.

        See :func:`mechcirc.interop.formula.formula`.
        """
        from .interop.formula import formula

        return formula(self, **kwargs)

    def __repr__(self) -> str:
        """A one-line summary; the elements are in ``.elements`` (a netlist of 10⁵ elements
        would otherwise print megabytes)."""
        kinds = Counter(e.kind for e in self.elements)
        parts = [f"{n} {k}{'es' if k == 'mass' and n != 1 else '' if n == 1 else 's'}"
                 for k, n in kinds.items()]
        if self.levers:
            parts.append(f"{len(self.levers)} lever{'s' if len(self.levers) != 1 else ''}")
        d = self.drive
        driven = "no drive" if d is None else \
            f"{d.kind} drive {d.name!r} {d.amplitude:g} between {d.n1!r} and {d.n2!r}"
        return f"<Circuit {self.name!r}: {', '.join(parts) or 'no elements'}; {driven}>"

    def _repr_html_(self) -> str:
        import html

        return "<pre>" + html.escape(repr(self)) + "</pre>"

    def element(self, name: str) -> Element | Lever:
        """The element or lever called ``name``; an :class:`~mechcirc.errors.UnknownNameError`
        (a KeyError) naming the nearest if none."""
        for e in self.elements + self.levers:
            if e.name == name:
                return e
        raise unknown_name(name, [e.name for e in self.elements + self.levers])

    @property
    def nodes(self) -> list[str]:
        """All node names, frame first, then in order of appearance."""
        ends = () if self.drive is None else (self.drive.n1, self.drive.n2)
        return list(dict.fromkeys([FRAME, *node_names(self.elements, self.levers), *ends]))


def node_names(elements, levers=()) -> list[str]:
    """The node names of ``elements`` and ``levers``, in order of first appearance.

    Parameters
    ----------
    elements : sequence of Element
        Their nodes n1, n2 first, in order.
    levers : sequence of Lever, optional
        Then their terminals p1, p2, s1, s2.

    Returns
    -------
    list of str
    """
    names = [n for e in elements for n in (e.n1, e.n2)]
    names += [n for lv in levers for n in lv.terminals]
    return list(dict.fromkeys(names))
