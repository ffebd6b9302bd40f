"""A :class:`~mechcirc.circuit.Circuit` back to netlist (``.mcir``) text.

:func:`write` is the inverse of :func:`mechcirc.parse` up to what text does not
carry: ``parse(write(c))`` has the same drive, elements (in order, values to
the last bit), levers and initial state as ``c``; the line and column numbers
are those of the new text, the name comes from the source it is parsed as, and
``.param`` definitions and expressions are not written (values are written
evaluated, in SI, with ``repr`` so that they read back exactly).

A spring followed by its damper ``NAME_damping`` (what the parser makes of
``damping=D``: same nodes, same η) is written on one line with ``damping=``
and that damper's value, the only place the damping is stored (the two come
back as they were); a damper of that name elsewhere is written as a damper.

Examples
--------
>>> from mechcirc import parse
>>> c = parse("drive V a 0 velocity=1\\nmass m1 a 0 2\\nspring k1 a 0 800 eta=0.5")
>>> print(write(c), end="")
drive V a 0 velocity=1.0
mass m1 a 0 2.0
spring k1 a 0 800.0 eta=0.5
"""

from __future__ import annotations

import math
import os
import re
from collections.abc import Mapping

from .circuit import Circuit, Drive, Element

__all__ = ["write"]

# The parser's name grammar (mechcirc.netlist._NAME); integers are read in
# canonical form ("007" → "7"), so only canonical integers round-trip.
_NAME = re.compile(r"[A-Za-z_][A-Za-z0-9_]*|0|[1-9][0-9]*")


def write(circuit: Circuit, header: tuple[str, ...] | list[str] | str = (),
          comments: Mapping[str, str] | None = None) -> str:
    """The netlist text of ``circuit``, with ``header`` lines as ``#`` comments first.

    Parameters
    ----------
    circuit : Circuit
        The drive may be None (a free-vibration circuit).
    header : str or sequence of str
        Comment lines (newlines inside one start new comment lines).
    comments : mapping of str to str, optional
        A comment for the line of the drive, element or lever of that name,
        written after it as ``   ; text`` (one line: newlines become spaces).

    Returns
    -------
    str
        One statement per line, ending with a newline: the drive, the
        elements and the levers in their order, then one ``.ic`` per initial state.

    Raises
    ------
    ValueError
        A name the netlist grammar cannot read back, or a value that is not a
        finite number.
    """
    if isinstance(header, str):
        header = (header,)
    notes = {k: " ".join(str(v).split()) for k, v in (comments or {}).items()}

    def noted(name: str, line: str) -> str:
        return f"{line}   ; {notes[name]}" if notes.get(name) else line

    out = [f"# {line}".rstrip() for h in header for line in str(h).split("\n")]
    if circuit.drive is not None:
        out.append(noted(circuit.drive.name, _drive_line(circuit.drive)))
    elements = circuit.elements
    i = 0
    while i < len(elements):
        e = elements[i]
        line = (f"{e.kind} {_names(e.name, e.n1, e.n2)} {_number(e.value)}"
                + (f" eta={_number(e.eta)}" if e.eta != 1.0 else "")
                + (f" backlash={_number(e.backlash)}" if e.backlash != 0.0 else ""))
        if i + 1 < len(elements) and _is_companion(e, elements[i + 1]):
            line += f" damping={_number(elements[i + 1].value)}"
            i += 1                       # the companion is written by damping=
        out.append(noted(e.name, line))
        i += 1
    out += [noted(lv.name, f"lever {_names(lv.name, *lv.terminals)} "
                           f"ratio={_number(lv.ratio)}") for lv in circuit.levers]
    out += [f".ic {_names(node)} x={_number(x0)} v={_number(v0)}"
            for node, x0, v0 in circuit.initial]
    return "\n".join(out) + "\n"


def _drive_line(d: Drive) -> str:
    """The ``drive`` statement of ``d``."""
    how = f"{d.kind}={_number(d.amplitude)}"
    if d.rotational:            # with its unit, so the text reads back as a rotary drive
        how += " rad/s" if d.kind == "velocity" else " N*m"
    if d.motion is not None:     # a table by its absolute path: the text may go elsewhere
        how = f"motion={os.path.abspath(d.motion.path)}" if d.motion.path else d.motion.spec
        if d.rotational and not d.motion.path:      # an angular stroke reads back rotary
            how = re.sub(r"(stroke=\S+)", r"\1 rad", how, count=1)
        elif d.rotational:                          # a table of angles reads back rotary
            how += " rad"
    return f"drive {_names(d.name, d.n1, d.n2)} {how}"


def _is_companion(spring: Element, e: Element) -> bool:
    """Whether ``e`` is the damper the parser adds for ``spring``'s ``damping=``."""
    return (spring.kind == "spring" and e.kind == "damper" and e.value > 0
            and e.name == f"{spring.name}_damping" and (e.n1, e.n2) == (spring.n1, spring.n2)
            and e.eta == spring.eta and e.backlash == 0.0)


def _names(*names: str) -> str:
    for n in names:
        if not isinstance(n, str) or not _NAME.fullmatch(n):
            raise ValueError(f"{n!r} is not a name a netlist can hold (letters, digits and "
                             "'_' not starting with a digit, or an integer without leading "
                             "zeros)")
    return " ".join(names)


def _number(x: float) -> str:
    x = float(x)
    if not math.isfinite(x):
        raise ValueError(f"{x!r} is not a finite number; a netlist value must be one")
    return repr(x)
