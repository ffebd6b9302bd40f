"""The analysis methods of :class:`~mechcirc.circuit.Circuit` and :class:`~mechcirc.sweep.Sweep`.

``circuit.py`` holds plain data at the bottom of the package and imports
nothing above it; the conveniences ``Circuit.tree``, ``.unloaded``,
``.nodal``, ``.sweep``, ``.resonances``, ``.two_port``, ``.formula`` and
``Sweep.to_skrf`` need the layers above (reduction, nodal analysis, sweeps,
resonances, interop).  They are thin wrappers defined here, in the top layer,
and attached when :mod:`mechcirc` is imported (which importing any of its
modules does first).  Each wrapper only calls the function of its module.

Why attached here rather than written as methods in ``circuit.py`` with a
function-local import: a local import is still a dependency (it only moves
the circle from import time to call time), and ``tests/test_import_graph.py``
counts it; ``Circuit.sweep`` importing :mod:`mechcirc.sweep`, which imports
:mod:`mechcirc.circuit`, would close a circle through the bottom layer.  The
rule is that conveniences needing a higher layer live in that layer; this is
the top layer.  They stay discoverable: :data:`ATTACHED` lists them, each has
a docstring that ``help(Circuit)`` shows, and the ``Circuit`` docstring and
the index in :mod:`mechcirc` name every one (``tests/test_methods.py``).
"""

from __future__ import annotations

from functools import cached_property

from numpy.typing import ArrayLike

from .circuit import Circuit
from .reduction import Node, reduce_circuit
from .sweep import Sweep, sweep

# nodal, resonances and interop are imported inside the wrappers (downward,
# so no circle), to keep ``import mechcirc`` free of scipy.linalg & co.

__all__: list[str] = []


def _reduction(self):
    return reduce_circuit(self)


def tree(self) -> Node:
    """The series-parallel reduction tree seen from the drive.

    Prints as a nested expression, e.g. ``m1 + m2 + (k4 | (m5 + k5))``.
    Raises :class:`~mechcirc.errors.TopologyError` if the network is not
    series-parallel reducible.
    """
    return self._reduction.tree


def unloaded(self) -> tuple[str, ...]:
    """Names of elements on no path between the drive terminals (they carry no force)."""
    return self._reduction.unloaded


def nodal(self):
    """The :class:`~mechcirc.nodal.NodalSystem` of the loaded network (built on first use)."""
    from .nodal import assemble, require_nonsingular

    system = assemble(self)
    require_nonsingular(system)
    return system


def circuit_sweep(self, omega: ArrayLike, method: str = "auto") -> Sweep:
    """K(ω), Q0(ω) and per-element forces over ``omega`` [rad/s]; see :func:`mechcirc.sweep.sweep`."""
    return sweep(self, omega, method=method)


def resonances(self, omega_max: float | None = None) -> list:
    """Zeros and poles of K(ω) up to ``omega_max`` [rad/s]; see :func:`mechcirc.resonances.find_resonances`."""
    from .resonances import find_resonances

    return find_resonances(self, omega_max=omega_max)


def two_port(self, P1: str, P2: str, S1: str, S2: str, omega: ArrayLike, **kwargs):
    """Z parameters [m/(N·s)] between ports P1–P2 and S1–S2 as an ``skrf.Network``; see :func:`mechcirc.interop.skrf.two_port`."""
    from .interop import skrf as skrf_interop

    return skrf_interop.two_port(self, P1, P2, S1, S2, omega, **kwargs)


def formula(self, **kwargs):
    """K(ω) as a SymPy expression nested as the reduction tree; see :func:`mechcirc.interop.formula.formula`."""
    from .interop import formula as formula_module

    return formula_module.formula(self, **kwargs)


def to_skrf(self, **kwargs):
    """K as a one-port ``skrf.Network`` (Z parameters, m/(N·s)); see :func:`mechcirc.interop.skrf.to_skrf`."""
    from .interop import skrf as skrf_interop

    return skrf_interop.to_skrf(self, **kwargs)


def _attach(cls, name, value):
    if isinstance(value, cached_property):
        value.__set_name__(cls, name)
    setattr(cls, name, value)


_CIRCUIT = (("tree", property(tree)), ("unloaded", property(unloaded)),
            ("nodal", cached_property(nodal)), ("sweep", circuit_sweep),
            ("resonances", resonances), ("two_port", two_port), ("formula", formula))

#: The public names attached, per class.
ATTACHED: dict[str, tuple[str, ...]] = {"Circuit": tuple(name for name, _ in _CIRCUIT),
                                        "Sweep": ("to_skrf",)}

_attach(Circuit, "_reduction", cached_property(_reduction))
for _name, _value in _CIRCUIT:
    if callable(_value) and not isinstance(_value, (property, cached_property)):
        _value.__qualname__ = f"Circuit.{_name}"
    _attach(Circuit, _name, _value)
_attach(Sweep, "to_skrf", to_skrf)
to_skrf.__qualname__ = "Sweep.to_skrf"
