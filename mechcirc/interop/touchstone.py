"""A Touchstone (version 1) reader for measured one-port mobilities that cannot run code.

``skrf.Network(path)`` tries :func:`pickle.load` on a file before it tries
Touchstone, so a file named ``measured.s1p`` that is really a pickle runs
whatever its author put in it.  mechcirc therefore never hands a user's file
to scikit-rf: this module reads the bytes (bounded, see
:func:`mechcirc.sources.read_bytes`), decodes them as text and parses numbers
with :func:`float` — nothing in the file is ever executed or unpickled.

What is read (Touchstone 1.1):

* ``!`` starts a comment, anywhere on a line.
* The first option line ``# <unit> <parameter> <format> R <reference>``;
  every field optional, in any order, case-insensitive; defaults
  ``GHz S MA R 50``.  Units Hz, kHz, MHz, GHz; parameters S, Y, Z (G and H
  are refused); formats RI, MA, DB.  Later option lines are ignored, as the
  standard says.
* Data lines of a one-port: frequency, then one complex value as two numbers.

The value is turned into the mobility K [m/(N·s)]; Z and Y in a Touchstone
file are normalised to the reference R, into the dimensionless z = Z/R and
y = Y·R: S → K = R(1 + s)/(1 − s); Z → K = R·z; Y → K = R/y.  (scikit-rf 2.2
reads version-1 Y data as Y = y·R instead, which differs by R² unless R = 1.)
"""

from __future__ import annotations

import math
import os
import re

import numpy as np
from numpy.typing import NDArray

from ..errors import NetlistError
from ..sources import is_number, read_source, split_lines
from ..units import convert_frequency

__all__ = ["read_touchstone_one_port"]

_FREQ_UNITS = {"hz": 1.0, "khz": 1e3, "mhz": 1e6, "ghz": 1e9}
_PARAMS = {"s", "y", "z", "g", "h"}
_FORMATS = {"ri", "ma", "db"}


def _parse_options(tokens: list[str], source: str, line: int, col: int) -> tuple[float, str, str, float]:
    unit, param, fmt, R = "ghz", "s", "ma", 50.0
    rest = iter(tokens)
    for token in rest:
        tok = token.lower()
        if tok in _FREQ_UNITS:
            unit = tok
        elif tok in _PARAMS:
            param = tok
        elif tok in _FORMATS:
            fmt = tok
        elif tok == "r":
            value = next(rest, None)
            if value is None:
                raise NetlistError("option 'R' has no reference value", source, line, col,
                                   "'R <positive number>'")
            if not is_number(value):
                raise NetlistError(f"reference {value!r} is not a number", source, line,
                                   col, "'R <positive number>'")
            R = float(value)
            if not (math.isfinite(R) and R > 0):
                raise NetlistError(f"reference R = {value} must be finite and positive",
                                   source, line, col, "'R <positive number>'")
        else:
            raise NetlistError(f"unknown option {token!r} in the option line", source, line,
                               col, "a frequency unit (Hz, kHz, MHz, GHz), a parameter (S, Y, Z), "
                               "a format (RI, MA, DB) or 'R <reference>'")
    if param in ("g", "h"):
        raise NetlistError(f"{param.upper()} parameters are not supported", source, line, col,
                           "S, Y or Z parameters")
    return _FREQ_UNITS[unit], param, fmt, R


def _complex(a: float, b: float, fmt: str) -> complex:
    if fmt == "ri":
        return complex(a, b)
    try:
        mag = a if fmt == "ma" else 10.0 ** (a / 20.0)
    except OverflowError:       # dB beyond float64: refused below as a non-finite value
        mag = math.inf
    phase = math.radians(b)
    return complex(mag * math.cos(phase), mag * math.sin(phase))


def read_touchstone_one_port(path: str | os.PathLike) -> tuple[NDArray[np.float64], NDArray[np.complex128], str]:
    """Read a one-port Touchstone file: ``(omega [rad/s], K [m/(N·s)], name)``.

    ``name`` is the file's stem.  Frequencies must be finite, non-negative and
    strictly increasing; every value must give a finite K.

    Parameters
    ----------
    path : str or PathLike

    Returns
    -------
    tuple of (ndarray, ndarray of complex, str)

    Raises
    ------
    NetlistError
        With file, line and column, for anything that is not a valid
        one-port Touchstone 1.1 file of finite data (including a file with no
        data lines, a reference R ≤ 0, and files of more than one port).
    """
    source = os.fspath(path)
    text = read_source(path, "a Touchstone .s1p")
    match = re.search(r"\.s(\d+)p$", source, flags=re.IGNORECASE)
    if match and int(match.group(1)) != 1:
        raise NetlistError(f"has {int(match.group(1))} ports (by its extension), expected a "
                           "one-port", source, 0, 0, "a .s1p file")
    options = None
    freqs: list[float] = []
    values: list[complex] = []
    for number, raw in enumerate(split_lines(text), start=1):
        body = raw.split("!", 1)[0]
        stripped = body.strip()
        if not stripped:
            continue
        col = len(body) - len(body.lstrip()) + 1
        if stripped.startswith("#"):
            if options is None:
                options = _parse_options(stripped[1:].split(), source, number, col)
            continue
        if stripped.startswith("["):
            raise NetlistError("Touchstone 2.0 keywords are not supported", source, number, col,
                               "a Touchstone 1.1 file (option line '# Hz Z RI R 1' and data)")
        if options is None:
            options = _parse_options([], source, number, col)
        f, K = _data_line(stripped, options, source, number, col,
                          freqs[-1] if freqs else -math.inf)
        freqs.append(f)
        values.append(K)
    if not freqs:
        raise NetlistError("has no data lines", source, 0, 0,
                           "lines of 'frequency value value' after the option line")
    omega = convert_frequency(np.asarray(freqs, dtype=float), "Hz")
    name = os.path.splitext(os.path.basename(source))[0]
    return omega, np.asarray(values, dtype=complex), name


def _data_line(stripped: str, options, source: str, number: int, col: int,
               last_f: float) -> tuple[float, complex]:
    """A one-port data line: its frequency [Hz] and the mobility K it gives."""
    scale, param, fmt, R = options
    fields = stripped.split()
    if len(fields) != 3:
        raise NetlistError(f"data line has {len(fields)} numbers", source, number, col,
                           "3 numbers for a one-port: frequency and two parts of one value")
    bad = next((x for x in fields if not is_number(x)), None)
    if bad is not None:
        raise NetlistError(f"{bad!r} is not a number", source, number,
                           col + stripped.find(bad), "a decimal number")
    f, a, b = (float(x) for x in fields)
    if not all(math.isfinite(x) for x in (f, a, b)):
        raise NetlistError("data line has a number that is not finite", source, number, col,
                           "finite numbers")
    f *= scale
    if f < 0:
        raise NetlistError(f"frequency {fields[0]} is negative", source, number, col,
                           "a frequency ≥ 0")
    if f <= last_f:
        raise NetlistError(f"frequency {fields[0]} does not increase", source, number, col,
                           "frequencies in strictly increasing order")
    value = _complex(a, b, fmt)
    if param == "s":
        K = R * (1 + value) / (1 - value) if value != 1 else complex(math.inf)
    elif param == "z":
        K = R * value
    else:
        K = R / value if value != 0 else complex(math.inf)
    if not (math.isfinite(K.real) and math.isfinite(K.imag)):
        raise NetlistError("the value gives an infinite mobility K", source, number, col,
                           "a finite value")
    return f, K
