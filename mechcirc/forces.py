"""How the drive's force splits through the mechanism at one frequency.

:func:`element_forces` gives, for every element that carries force, the
complex amplitudes of the force Q through it [N] and of the velocity
difference v across it [m/s] at one ω [rad/s].  Phases are measured against
the drive's amplitude (V0 or F0, taken real and positive).
"""

from __future__ import annotations

import cmath
import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from .circuit import Circuit
from .errors import InputError
from .sources import positive_number

if TYPE_CHECKING:  # pragma: no cover
    from ._sweep import Method

__all__ = ["ElementForce", "element_forces"]


def _phase_deg(z: complex) -> float:
    if not math.isfinite(abs(z)):
        return math.nan
    deg = math.degrees(cmath.phase(z))
    # Rounding can leave a real negative number a hair below the cut: -180 -> 180.
    return 180.0 if deg <= -180.0 + 1e-9 else deg + 0.0


#: The rest of the docstring of a phase attribute of :class:`ElementForce`.
_PHASE = "[deg] in (−180, 180], relative to the drive's amplitude."


def _derived(field: str, of, doc: str) -> property:
    """A read-only attribute computed from a field: ``of(self.<field>)``, documented ``doc``."""
    return property(lambda self: of(getattr(self, field)), doc=doc)


@dataclass(frozen=True)
class ElementForce:
    """Force and velocity of one element at one ω.

    Attributes
    ----------
    name, kind, n1, n2 : str
        The element's name, kind and the nodes it joins, as in the netlist.
    Q : complex
        Force amplitude through the element from n1 to n2 [N].
    v : complex
        Velocity difference amplitude v(n1) − v(n2) [m/s].
    share : float
        |Q| / |Q0| [1], the part of the drive's force the element carries.
    """

    name: str
    kind: str
    n1: str
    n2: str
    Q: complex
    v: complex
    share: float

    Q_abs = _derived("Q", abs, "|Q| [N].")
    v_abs = _derived("v", abs, "|v| [m/s].")
    Q_phase_deg = _derived("Q", _phase_deg, "arg Q " + _PHASE)
    v_phase_deg = _derived("v", _phase_deg, "arg v " + _PHASE)


def element_forces(circuit: Circuit, omega: float, *, method: Method = "auto"
                   ) -> tuple[list[ElementForce], complex, complex, int]:
    """Q and v of every loaded element at ``omega`` [rad/s].

    Parameters
    ----------
    circuit : Circuit
        The circuit to load by its drive.
    omega : float
        ω [rad/s].
    method : {"auto", "sp", "nodal"}
        As :func:`mechcirc.sweep`.

    Returns
    -------
    rows : list of ElementForce
        In the netlist's order (elements carrying no force are left out).
    K : complex
        The kinematic characteristic seen by the drive [m/(N·s)].
    Q0 : complex
        The drive's force amplitude [N].
    flag : int
        The sweep flag of this ω (0 regular, 1 on a pole/zero, 2 near one).
    """
    if not (positive_number(omega)):
        raise InputError(f"omega must be a finite number > 0 rad/s, got {omega!r}")
    omega = float(omega)
    result = circuit.sweep(np.array([omega]), method=method)
    Q0, rows = complex(result.Q0[0]), []
    for e in circuit.elements:
        try:
            Q, v = complex(result.force(e.name)[0]), complex(result.velocity(e.name)[0])
        except KeyError:        # carries no force
            continue
        share = abs(Q) / abs(Q0) if abs(Q0) > 0 else math.inf      # Python floats: inf, no trap
        rows.append(ElementForce(e.name, e.kind, e.n1, e.n2, Q, v, share))
    return rows, complex(result.K[0]), Q0, int(result.flags[0])
