"""Units of netlist values and of command-line frequencies: a small table, parsed by hand.

A netlist value may be followed, after a space, by its unit: ``mass m1 a 0
250 g``, ``spring k1 a 0 5 N/mm``, ``drive V a 0 velocity=0.1 m/s``.  The
unit is checked against what the value is (a stiffness in kg is an error,
located at the unit) and the value converted to SI.

Grammar (no spaces inside a unit; ``·`` may replace ``*``)::

    unit   := factor (("*" | "·" | "/") factor)*
    factor := ATOM ("^" ["-"] DIGITS | "²" | "³")?

Each ``/`` divides by the one factor after it (``N*s/m`` is N·s·m⁻¹,
``kg/m/s`` is kg·m⁻¹·s⁻¹).  ATOM is one of :data:`ATOMS`.

Why a table and not pint: pint is well kept and would parse more, but
importing it and building its registry takes about 0.64 s on the reference
machine, five times the 0.13 s of ``import mechcirc``; the netlist needs a
dozen units, so a table of exact SI factors (checked against pint in
``tests/test_units.py`` when pint is installed) costs nothing at import.

Angles: the radian is dimensionless, as in SI (so N·m/rad is a torque per
radian and kg·m² an inertia); ``deg`` is π/180.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass

__all__ = ["Unit", "UnitError", "ATOMS", "ROLES", "parse_unit", "looks_like_unit",
           "convert", "parse_omega", "OMEGA_UNITS"]

# Dimensions are exponents of (kg, m, s).
_MASS, _LENGTH, _TIME = (1, 0, 0), (0, 1, 0), (0, 0, 1)
_FORCE = (1, 1, -2)
_NONE = (0, 0, 0)

#: Known atoms: SI factor and dimension (kg, m, s exponents).  Factors are
#: exact ratios ``(numerator, denominator)`` combined as fractions (only
#: ``deg`` is a float), so ``kg*mm^2`` is exactly 1e-6.
ATOMS: dict[str, tuple[tuple[int, int] | float, tuple[int, int, int]]] = {
    "kg": ((1, 1), _MASS), "g": ((1, 1000), _MASS), "t": ((1000, 1), _MASS),
    "N": ((1, 1), _FORCE), "kN": ((1000, 1), _FORCE),
    "m": ((1, 1), _LENGTH), "mm": ((1, 1000), _LENGTH), "cm": ((1, 100), _LENGTH),
    "s": ((1, 1), _TIME), "ms": ((1, 1000), _TIME),
    "rad": ((1, 1), _NONE), "deg": (math.pi / 180, _NONE),
}

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
    "displacement": {(0, 1, 0): "length (m, mm)", (0, 0, 0): "angle (rad, deg)"},
}

_DIM_NAMES = {(1, 0, 0): "a mass", (1, 2, 0): "a moment of inertia",
              (1, 0, -2): "a stiffness", (1, 2, -2): "a moment or torsional rigidity",
              (1, 0, -1): "a damping", (1, 2, -1): "a rotary damping",
              (0, 1, -1): "a velocity", (0, 0, -1): "a frequency or angular velocity",
              (1, 1, -2): "a force", (0, 1, 0): "a length", (0, 0, 1): "a time",
              (0, 0, 0): "dimensionless"}

_FACTOR = re.compile(r"([A-Za-z]+)(?:\^(-?\d+)|(²)|(³))?")


class UnitError(ValueError):
    """A unit that cannot be parsed; ``offset`` is the 0-based position of the culprit."""

    def __init__(self, message: str, offset: int, expected: str | None = None):
        self.message, self.offset, self.expected = message, offset, expected
        super().__init__(message)


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
    """True if ``text`` is meant as a unit (starts with a letter; only unit characters)."""
    return bool(text) and text[0].isascii() and text[0].isalpha() and \
        all(c.isascii() and (c.isalnum() or c in "*/^-") or c in "·²³" for c in text)


def parse_unit(text: str) -> Unit:
    """Parse ``text`` (see the module docstring) into a :class:`Unit`.

    Raises
    ------
    UnitError
        With the offset of the unknown atom or stray character.
    """
    from fractions import Fraction     # here: fractions imports decimal (~3 ms)

    factor, dim = Fraction(1), [0, 0, 0]
    i, sign = 0, 1
    known = ", ".join(ATOMS)
    while True:
        m = _FACTOR.match(text, i)
        if m is None:
            raise UnitError(f"unexpected {text[i:i + 1]!r} in unit {text!r}" if i < len(text)
                            else f"unit {text!r} ends after an operator", i,
                            f"units built from {known} with * / ^")
        atom = m.group(1)
        if atom not in ATOMS:
            raise UnitError(f"unknown unit {atom!r}", i, f"one of {known}")
        power = int(m.group(2)) if m.group(2) else 2 if m.group(3) else 3 if m.group(4) else 1
        f, d = ATOMS[atom]
        f = Fraction(*f) if isinstance(f, tuple) else f
        factor *= f ** (sign * power)
        for k in range(3):
            dim[k] += sign * power * d[k]
        i = m.end()
        if i == len(text):
            return Unit(text, float(factor), tuple(dim))
        op = text[i]
        if op not in "*·/":
            raise UnitError(f"unexpected {op!r} in unit {text!r}", i, "'*' or '/' between units")
        sign = -1 if op == "/" else 1
        i += 1


def convert(value: float, unit: Unit, role: str) -> float:
    """``value`` in ``unit`` converted to SI, after checking the unit fits ``role``.

    Raises
    ------
    UnitError
        If the unit measures something else than ``role`` expects (offset 0).
    """
    allowed = ROLES.get(role)
    if allowed is not None and unit.dim not in allowed:
        what = " or ".join(v.split(" (")[0] for v in allowed.values())
        raise UnitError(f"unit {unit.text!r} is {unit.describe()}; a {role} value needs {what}",
                        0, " or ".join(allowed.values()))
    return value * unit.factor


#: Units accepted for angular frequencies on the command line: factor to rad/s.
OMEGA_UNITS = {"rad/s": 1.0, "Hz": 2 * math.pi, "rpm": 2 * math.pi / 60, "1/s": 1.0}

_OMEGA = re.compile(r"\s*([-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?|[-+]?inf|nan)\s*"
                    r"([A-Za-z/1]*)\s*")


def parse_omega(text: str) -> float:
    """An angular frequency [rad/s] from ``"314"``, ``"314rad/s"``, ``"50Hz"`` or ``"3000rpm"``.

    Raises
    ------
    ValueError
        Saying which units are accepted.
    """
    m = _OMEGA.fullmatch(text)
    if m is None:
        raise ValueError(f"{text!r} is not a frequency (expected a number with an optional "
                         f"unit: {', '.join(OMEGA_UNITS)}, e.g. 50Hz or 3000rpm)")
    number, unit = m.groups()
    if not unit:
        return float(number)
    for name, factor in OMEGA_UNITS.items():
        if unit.lower() == name.lower():
            return float(number) * factor
    raise ValueError(f"unknown frequency unit {unit!r} in {text!r} (expected "
                     f"{', '.join(OMEGA_UNITS)}; no unit means rad/s)")
