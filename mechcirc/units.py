"""One unit grammar for every value mechcirc reads: netlists, command-line options, TOML.

A quantity is a number, an optional space and an optional unit::

    quantity := NUMBER [" "] [unit]          e.g. 500g  500 g  2 kN/mm  50Hz  3000 rpm
    unit     := factor (("*" | "·" | "/") factor)*
    factor   := ATOM ("^" ["-"] DIGITS | "²" | "³")?
    ATOM     := a name of :data:`ATOMS`, or an SI prefix (G M k c m u µ n) and a
                base of :data:`PREFIXABLE` (kHz, kN, mm, ms, g, mrad, ...)

Each ``/`` divides by the one factor after it (``N*s/m`` is N·s·m⁻¹,
``kg/m/s`` is kg·m⁻¹·s⁻¹).  :func:`parse_quantity` is the one place that
reads a quantity; the netlist (:mod:`mechcirc.netlist`), every command-line
option that takes a frequency or a parameter, and the study and scene TOML
readers call it.  The page ``docs/units.md`` documents the grammar.

The unit is checked against what the value is (a stiffness in kg is an
error, located at the unit) and the value converted to SI.

Why a table and not pint: pint is well kept and would parse more, but
importing it and building its registry takes about 0.64 s on the reference
machine, five times the 0.13 s of ``import mechcirc``; the netlist needs a
dozen units, so a table of exact SI factors (checked against pint in
``tests/test_units.py``) costs nothing at import.

Angles: the radian is dimensionless, as in SI (so N·m/rad is a torque per
radian and kg·m² an inertia); ``deg`` is π/180.  Frequencies: ``Hz`` and
``rpm`` count revolutions, so as an angular frequency 1 Hz is 2π rad/s and
1 rpm is 2π/60 rad/s (pint, which treats Hz as 1/s, would say 1 rad/s: the
one place where mechcirc departs from it, on purpose — ω = 2πf).
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass

from .errors import UnitError, did_you_mean

__all__ = ["Unit", "UnitError", "ATOMS", "PREFIXES", "PREFIXABLE", "ROLES", "parse_unit",
           "looks_like_unit", "convert", "parse_quantity", "split_quantity", "is_bare_number", "parse_omega",
           "OMEGA_UNITS", "is_rotational", "SPICE_SUFFIXES", "FREQUENCY_UNITS", "in_unit",
           "convert_frequency", "in_unit_of"]

# Dimensions are exponents of (kg, m, s).
_MASS, _LENGTH, _TIME = (1, 0, 0), (0, 1, 0), (0, 0, 1)
_FORCE = (1, 1, -2)
_NONE = (0, 0, 0)
_FREQ = (0, 0, -1)

#: rad/s per Hz and per rpm, the one source of these factors (:data:`ATOMS`,
#: :data:`OMEGA_UNITS`, :data:`FREQUENCY_UNITS`, :func:`convert_frequency`): Hz and
#: rpm count revolutions (2π rad) per second and per minute, ω = 2π·f = 2π·n/60.
_HZ, _RPM = 2 * math.pi, 2 * math.pi / 60

#: Known atoms: SI factor and dimension (kg, m, s exponents).  Factors are
#: exact ratios ``(numerator, denominator)`` combined as fractions (only
#: ``deg``, ``Hz`` and ``rpm`` are floats), so ``kg*mm^2`` is exactly 1e-6.
ATOMS: dict[str, tuple[tuple[int, int] | float, tuple[int, int, int]]] = {
    "kg": ((1, 1), _MASS), "g": ((1, 1000), _MASS), "t": ((1000, 1), _MASS),
    "N": ((1, 1), _FORCE), "kN": ((1000, 1), _FORCE),
    "m": ((1, 1), _LENGTH), "mm": ((1, 1000), _LENGTH), "cm": ((1, 100), _LENGTH),
    "s": ((1, 1), _TIME), "ms": ((1, 1000), _TIME),
    "rad": ((1, 1), _NONE), "deg": (math.pi / 180, _NONE),
    "Hz": (_HZ, _FREQ), "rpm": (_RPM, _FREQ),
    "min": ((60, 1), _TIME), "h": ((3600, 1), _TIME),
}

#: SI prefixes and their exact factors.
PREFIXES: dict[str, tuple[int, int]] = {
    "G": (10**9, 1), "M": (10**6, 1), "k": (1000, 1), "c": (1, 100), "m": (1, 1000),
    "u": (1, 10**6), "µ": (1, 10**6), "μ": (1, 10**6), "n": (1, 10**9),
}
#: Base units that take an SI prefix (kg, mm, ms, kN, kHz, mrad, µm, ...).
PREFIXABLE = ("g", "m", "s", "N", "Hz", "rad")

#: SPICE's value suffixes: mechcirc does not read them (``3k`` is an error
#: with a hint; ``3m`` is three metres, a unit, not 3e-3).
SPICE_SUFFIXES = ("f", "p", "n", "u", "m", "k", "meg", "g", "t", "mil")

#: What each kind of value may be given in: role -> (dimension -> description).
ROLES: dict[str, dict[tuple[int, int, int], str]] = {
    "mass": {(1, 0, 0): "mass (kg, g, t)", (1, 2, 0): "moment of inertia (kg*m^2)"},
    "spring": {(1, 0, -2): "stiffness (N/m, N/mm, kN/m)",
               (1, 2, -2): "torsional rigidity (N*m/rad)"},
    "damper": {(1, 0, -1): "damping (N*s/m)", (1, 2, -1): "rotary damping (N*m*s/rad)"},
    "velocity": {(0, 1, -1): "velocity (m/s, mm/s)", (0, 0, -1): "angular velocity (rad/s)"},
    "force": {(1, 1, -2): "force (N, kN)", (1, 2, -2): "moment (N*m)"},
    "eta": {(0, 0, 0): "a ratio (dimensionless)"},
    "ratio": {(0, 0, 0): "a ratio (dimensionless)"},
    "omega": {(0, 0, -1): "angular frequency (rad/s, Hz, kHz, rpm)"},
    "length": {(0, 1, 0): "length (m, mm, cm)"},
    "angle": {(0, 0, 0): "angle (rad, deg)"},
    "time": {(0, 0, 1): "time (s, ms, min)"},
    "displacement": {(0, 1, 0): "length (m, mm)", (0, 0, 0): "angle (rad, deg)"},
    "point mass": {(1, 0, 0): "mass (kg, g, t)"},
    "axial spring": {(1, 0, -2): "stiffness (N/m, N/mm, kN/m)"},
    "axial damper": {(1, 0, -1): "damping (N*s/m)"},
    "rotary inertia": {(1, 2, 0): "moment of inertia (kg*m^2)"},
    "rotary spring": {(1, 2, -2): "torsional rigidity (N*m/rad)"},
    "rotary damper": {(1, 2, -1): "rotary damping (N*m*s/rad, kg*m^2/s)"},
    "moment": {(1, 2, -2): "moment (N*m)"},
}

#: Dimensions of the rotational member of each translational/rotational pair
#: (inertia, torsional rigidity, rotary damping, moment): a node that carries
#: both kinds gets a warning from the netlist.
_ROTATIONAL = {(1, 2, 0), (1, 2, -2), (1, 2, -1)}
_TRANSLATIONAL = {(1, 0, 0), (1, 0, -2), (1, 0, -1)}

_DIM_NAMES = {(1, 0, 0): "a mass", (1, 2, 0): "a moment of inertia",
              (1, 0, -2): "a stiffness", (1, 2, -2): "a moment or torsional rigidity",
              (1, 0, -1): "a damping", (1, 2, -1): "a rotary damping",
              (0, 1, -1): "a velocity", (0, 0, -1): "a frequency or angular velocity",
              (1, 1, -2): "a force", (0, 1, 0): "a length", (0, 0, 1): "a time",
              (0, 0, 0): "dimensionless"}

_FACTOR = re.compile(r"([A-Za-zµμ]+)(?:\^(-?\d+)|(²)|(³))?")


@dataclass(frozen=True)
class Unit:
    """A parsed unit: ``value_SI = value · factor``; ``dim`` the (kg, m, s) exponents."""

    text: str
    factor: float
    dim: tuple[int, int, int]

    def describe(self) -> str:
        """A phrase naming the quantity the unit measures ("a stiffness", ...)."""
        return _DIM_NAMES.get(self.dim, "kg^{} m^{} s^{}".format(*self.dim))


def looks_like_unit(text: str) -> bool:
    """True if ``text`` is meant as a unit (starts with a letter; only unit characters).

    Parameters
    ----------
    text : str
        What follows a number (``"mm"``, ``"N/m"``, or something else).

    Returns
    -------
    bool
    """
    return bool(text) and (text[0].isascii() and text[0].isalpha() or text[0] in "µμ") and \
        all(c.isascii() and (c.isalnum() or c in "*/^-") or c in "·²³µμ" for c in text)


def _atom(name: str):
    """``(factor, dim)`` of an atom or a prefixed base, or None if unknown."""
    if name in ATOMS:
        return ATOMS[name]
    for prefix, pf in PREFIXES.items():
        base = name[len(prefix):]
        if name.startswith(prefix) and base in PREFIXABLE:
            bf, dim = ATOMS[base]
            if isinstance(bf, tuple):
                return (pf[0] * bf[0], pf[1] * bf[1]), dim
            return pf[0] / pf[1] * bf, dim
    return None


def is_rotational(unit: "Unit") -> bool | None:
    """True for an inertia, torsional rigidity or rotary damping; False for the
    translational mass, stiffness or damping; None for anything else.

    Parameters
    ----------
    unit : Unit

    Returns
    -------
    bool or None
    """
    return True if unit.dim in _ROTATIONAL else False if unit.dim in _TRANSLATIONAL else None


def parse_unit(text: str) -> Unit:
    """Parse ``text`` (see the module docstring) into a :class:`Unit`.

    Parameters
    ----------
    text : str
        A unit such as ``"N·m/rad"`` or ``"kg*m^2"``.

    Returns
    -------
    Unit

    Raises
    ------
    UnitError
        With the offset of the unknown atom or stray character.
    """
    from fractions import Fraction     # here: fractions imports decimal (~3 ms)

    factor, dim = Fraction(1), [0, 0, 0]
    i, sign = 0, 1
    known = ", ".join(ATOMS) + " and prefixed " + "/".join(PREFIXABLE)
    while True:
        m = _FACTOR.match(text, i)
        if m is None:
            raise UnitError(f"unexpected {text[i:i + 1]!r} in unit {text!r}" if i < len(text)
                            else f"unit {text!r} ends after an operator", i,
                            f"units built from {known} with * / ^")
        atom = m.group(1)
        found = _atom(atom)
        if found is None:
            raise UnitError(f"unknown unit {atom!r}{did_you_mean(atom, ATOMS)}", i,
                            f"one of {known}")
        power = int(m.group(2)) if m.group(2) else 2 if m.group(3) else 3 if m.group(4) else 1
        f, d = found
        f = Fraction(*f) if isinstance(f, tuple) else f
        factor *= f ** (sign * power)
        dim = [x + sign * power * y for x, y in zip(dim, d)]
        i = m.end()
        if i == len(text):
            return Unit(text, float(factor), (dim[0], dim[1], dim[2]))
        op = text[i]
        if op not in "*·/":
            raise UnitError(f"unexpected {op!r} in unit {text!r}", i, "'*' or '/' between units")
        sign = -1 if op == "/" else 1
        i += 1


def convert(value: float, unit: Unit, role: str) -> float:
    """``value`` in ``unit`` converted to SI, after checking the unit fits ``role``.

    Parameters
    ----------
    value : float
    unit : Unit
    role : str
        A key of :data:`ROLES`; a name with no entry (``""``) accepts any unit.

    Returns
    -------
    float
        ``value · unit.factor``.

    Raises
    ------
    UnitError
        If the unit measures something else than ``role`` expects (offset 0), or the
        SI value overflows float64.
    """
    allowed = ROLES.get(role)
    if allowed is not None and unit.dim not in allowed:
        what = " or ".join(v.split(" (")[0] for v in allowed.values())
        article = "an" if role[0] in "aeiou" else "a"
        noun = "an angular frequency" if role == "omega" else f"{article} {role}"
        raise UnitError(f"unit {unit.text!r} is {unit.describe()}; {noun} value needs {what}",
                        0, " or ".join(allowed.values()))
    si = value * unit.factor
    if math.isinf(si) and math.isfinite(value):     # 1e306 km: not a number float64 holds
        raise UnitError(f"{value:g} {unit.text} is {si} in SI units (float64 ends at 1.8e308)",
                        0, "a value within float64's range once converted")
    return si


#: Units accepted for angular frequencies (a subset of the grammar, quoted in messages).
OMEGA_UNITS = {"rad/s": 1.0, "Hz": _HZ, "kHz": 1000 * _HZ, "rpm": _RPM, "1/s": 1.0}

#: Units in which a frequency is shown: unit -> (column name, rad/s per unit).
#: Hz and rpm count revolutions: f = ω/2π, n = 60·ω/2π (docs/units.md).
FREQUENCY_UNITS = {"rad/s": ("omega", 1.0), "Hz": ("f", _HZ), "rpm": ("n", _RPM)}


def convert_frequency(value, from_unit: str = "rad/s", to_unit: str = "rad/s"):
    """``value`` (a number or an array) in ``from_unit`` converted to ``to_unit``.

    The one conversion between angular frequency [rad/s], frequency [Hz] and
    shaft speed [rpm], through rad/s with the factors of :data:`FREQUENCY_UNITS`
    (ω = 2π·f = 2π·n/60): ``value · factor(from_unit) / factor(to_unit)``, the
    same numbers as :func:`parse_quantity` gives for ``"600rpm"`` or ``"50Hz"``.

    Parameters
    ----------
    value : float or ndarray
    from_unit, to_unit : {"rad/s", "Hz", "rpm"}
        The keys of :data:`FREQUENCY_UNITS`.

    Returns
    -------
    float or ndarray

    Raises
    ------
    UnitError
        For another unit, naming the three.

    Examples
    --------
    >>> convert_frequency(3000, "rpm", "rad/s") == 100 * math.pi
    True
    >>> convert_frequency(50 * 2 * math.pi, to_unit="Hz")
    50.0
    """
    try:
        (_, a), (_, b) = FREQUENCY_UNITS[from_unit], FREQUENCY_UNITS[to_unit]
    except KeyError:
        bad = to_unit if from_unit in FREQUENCY_UNITS else from_unit
        raise UnitError(f"unknown frequency unit {bad!r}{did_you_mean(str(bad), FREQUENCY_UNITS)}",
                        0, "rad/s, Hz or rpm") from None
    return value * a / b


def in_unit(omega, unit: str = "rad/s"):
    """Angular frequency ``omega`` [rad/s] (a number or an array) in ``unit`` of
    :data:`FREQUENCY_UNITS`: ``convert_frequency(omega, "rad/s", unit)``.

    Parameters
    ----------
    omega : float or ndarray
    unit : {"rad/s", "Hz", "rpm"}

    Returns
    -------
    float or ndarray
    """
    return convert_frequency(omega, "rad/s", unit)


_NUMBER = r"[-+]?(?:(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?|inf|nan)"
_QUANTITY = re.compile(r"\s*(" + _NUMBER + r")\s*(\S.*?)?\s*", re.IGNORECASE)


def _not_a_quantity(text: str, role: str | None, what: str) -> UnitError:
    """The error for a ``text`` that is not a number with an optional unit."""
    if any(c in text for c in _MINUS_SIGNS):
        return UnitError(f"{what} {text!r} has a Unicode minus or dash", 0,
                         "the ASCII hyphen-minus '-', e.g. 2e-6")
    if re.fullmatch(r"\s*[-+]?\d+,\d+\s*\S*\s*", text):
        return UnitError(f"{what} {text!r} has a decimal comma", 0,
                         f"a decimal point: {text.strip().replace(',', '.', 1)!r}")
    example = "50Hz, 50 Hz, 3000rpm or 314 (rad/s)" if role == "omega" else "12, 1.5e3, 500 g"
    noun = "a frequency" if role == "omega" else "a number with an optional unit"
    return UnitError(f"{what} {text!r} is not {noun}", 0, f"a quantity such as {example}")


def split_quantity(text: str) -> tuple[str, str] | None:
    """``(number, unit)`` texts of a quantity (``unit`` may be ""), or None if it is not one.

    ``"500g"`` and ``"500 g"`` both give ``("500", "g")``.  Only the shape is
    checked here; :func:`parse_quantity` checks the unit.

    Parameters
    ----------
    text : str

    Returns
    -------
    tuple of (str, str) or None
    """
    m = _QUANTITY.fullmatch(text)
    if m is None:
        return None
    number, unit = m.group(1), m.group(2) or ""
    return None if unit and not (looks_like_unit(unit) or unit == "1/s") else (number, unit)


def is_bare_number(text: str) -> bool:
    """Whether ``text`` is a number with no unit (``"500"``, not ``"500 g"`` or ``"abc"``).

    Parameters
    ----------
    text : str
        A value as typed (a word of the command line, a ``--set`` value).

    Returns
    -------
    bool
        True for a bare number; False for a quantity with a unit or for no quantity at all.
    """
    parts = split_quantity(text)
    return parts is not None and not parts[1]


def parse_quantity(text: str, role: str | None = None, *, what: str = "value") -> float:
    """The SI value of a quantity ``text`` such as ``"500g"``, ``"2 kN/mm"``, ``"50 Hz"``.

    Parameters
    ----------
    text : str
        A number, an optional space and an optional unit (see the module
        docstring).  No unit means the value is already SI.
    role : str, optional
        A key of :data:`ROLES` the unit must fit (``"omega"``, ``"spring"``,
        ``"mass"``, ...); None accepts any unit and converts it to SI.
    what : str
        What the value is, for messages.

    Returns
    -------
    float
        The value in SI units.

    Raises
    ------
    UnitError
        Saying what is wrong and what is accepted (``offset`` into ``text``).

    Examples
    --------
    >>> parse_quantity("500g", "mass") == parse_quantity("500 g", "mass") == 0.5
    True
    >>> parse_quantity("2 kN/mm", "spring")
    2000000.0
    >>> round(parse_quantity("3000rpm", "omega"), 6)
    314.159265
    """
    text = str(text)
    parts = split_quantity(text)
    if parts is None:
        raise _not_a_quantity(text, role, what)
    number, unit = parts
    value = float(number)
    if not unit:
        return value
    if role == "omega":     # frequencies keep their historic case-insensitive names (HZ, RPM)
        unit = next((n for n in OMEGA_UNITS if n.lower() == unit.lower()), unit)
    if unit == "1/s":
        u = Unit("1/s", 1.0, (0, 0, -1))
    else:
        try:
            u = parse_unit(unit)
        except UnitError as exc:
            hint = exc.expected
            if unit.lower() in SPICE_SUFFIXES:
                hint = (f"no SPICE suffixes in mechcirc: write {number}e3 for {number}k, "
                        f"or a unit such as {number} kN/m")
            raise UnitError(exc.message, text.index(unit) + exc.offset, hint) from None
    try:
        return convert(value, u, role or "")
    except UnitError as exc:
        raise UnitError(exc.message, text.index(unit), exc.expected) from None


_MINUS_SIGNS = "\u2212\u2013\u2014\u2012\u2010"


def parse_omega(text: str) -> float:
    """An angular frequency [rad/s] from ``"314"``, ``"314 rad/s"``, ``"50Hz"``, ``"3000 rpm"``.

    Parameters
    ----------
    text : str
        A number, with or without a unit of frequency (rad/s, Hz, rpm, ...).

    Returns
    -------
    float

    Raises
    ------
    ValueError
        Saying which units are accepted.
    """
    try:
        return parse_quantity(text, "omega", what="frequency")
    except UnitError as exc:
        message = exc.message.replace("unknown unit", "unknown frequency unit")
        raise ValueError(f"{message} (expected {exc.expected}; no unit means rad/s)") from None


def in_unit_of(text: str, role: str | None, unit: str = "", *, what: str = "value") -> float:
    """A quantity ``text`` read as ``role`` (:func:`parse_quantity`) and given in ``unit``.

    A bare number already is in ``unit`` ("" : SI); a number with a unit is converted
    by the ratio of the two units, so ``"120 deg"`` in ``"deg"`` is exactly 120 and
    ``"2 cm"`` in ``"mm"`` is 20.

    Parameters
    ----------
    text : str
    role : str or None
        As :func:`parse_quantity`.
    unit : str
        The unit of the result and of a bare number ("" : SI).
    what : str
        What the value is, for messages.

    Returns
    -------
    float
    """
    value = parse_quantity(text, role, what=what)       # the number, its unit checked
    number, given = split_quantity(str(text)) or ("", "")
    if unit and given:
        value = float(number) * (parse_quantity("1 " + given, role) / parse_unit(unit).factor)
    return value


def in_si(text: str, source: str, value, role: str | None, section: str | None, key: str,
          occurrence: int = 0, what: str = "value", unit: str = ""):
    """A TOML string such as ``"600 rpm"`` read in this grammar as ``role`` and converted
    to SI (to ``unit`` if given: :func:`in_unit_of`), or its error
    :func:`~mechcirc.sources.located` at ``key``; other values as they are."""
    if not isinstance(value, str):
        return value
    from .sources import located

    try:
        return in_unit_of(value, role, unit, what=what)
    except UnitError as exc:
        raise located(text, source, exc.message, section, key, occurrence=occurrence,
                      expected=exc.expected) from None
