"""Frequency sweeps: K(ω), the drive's force and velocity, per-element Q and v.

Under kinematic excitation (``drive ... velocity=V0``) the drive imposes the
velocity amplitude V0 [m/s] and the network answers with the force amplitude
Q0 = V0 / K (DIGEST §1, eq. 8).  Under force excitation (``force=F0``) the
velocity amplitude is v0 = F0 · K.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .circuit import Circuit, Drive
from .reduction import Node, evaluate, push_down

__all__ = ["Sweep", "sweep", "FLAG_OK", "FLAG_SINGULAR"]

#: ``Sweep.flags`` value of a regular point.
FLAG_OK = 0
#: ``Sweep.flags`` value of a point on (or within rounding of) a pole or zero of K,
#: where K, Q0 or v0 is 0, infinite or undefined.
FLAG_SINGULAR = 1


@dataclass(frozen=True, eq=False)
class Sweep:
    """The result of a frequency sweep.

    Attributes
    ----------
    omega : ndarray of float, shape (n,)
        Angular frequency [rad/s].
    K : ndarray of complex, shape (n,)
        Kinematic characteristic v/Q seen by the drive [m/(N·s)].
    drive : Drive
    tree : Node
        The reduction tree that produced K.
    name : str
        The circuit's name.
    """

    omega: NDArray[np.float64]
    K: NDArray[np.complex128]
    drive: Drive
    tree: Node
    name: str = "circuit"
    _cache: dict = field(default_factory=dict, repr=False)

    @property
    def S(self) -> NDArray[np.complex128]:
        """Force characteristic Q/v = 1/K [N·s/m]."""
        with np.errstate(all="ignore"):
            return 1.0 / self.K

    @cached_property
    def Q0(self) -> NDArray[np.complex128]:
        """Force amplitude at the drive [N]: V0/K (velocity drive) or F0 (force drive)."""
        if self.drive.kind == "force":
            return np.full(self.omega.shape, self.drive.amplitude, dtype=complex)
        with np.errstate(all="ignore"):
            return self.drive.amplitude / self.K

    @cached_property
    def v0(self) -> NDArray[np.complex128]:
        """Velocity amplitude at the drive [m/s]: V0 (velocity drive) or F0·K (force drive)."""
        if self.drive.kind == "velocity":
            return np.full(self.omega.shape, self.drive.amplitude, dtype=complex)
        with np.errstate(all="ignore"):
            return self.drive.amplitude * self.K

    @cached_property
    def flags(self) -> NDArray[np.int8]:
        """Per-point flag: :data:`FLAG_SINGULAR` where K is 0, infinite or NaN, else 0."""
        bad = ~np.isfinite(self.K) | (self.K == 0) | ~np.isfinite(self.Q0) | ~np.isfinite(self.v0)
        return np.where(bad, FLAG_SINGULAR, FLAG_OK).astype(np.int8)

    def _elements(self) -> dict[str, tuple]:
        if "elements" not in self._cache:
            _, values = evaluate(self.tree, self.omega, keep=True)
            self._cache["elements"] = push_down(self.tree, values, self.Q0, self.v0, self.omega)
        return self._cache["elements"]

    def force(self, name: str) -> NDArray[np.complex128]:
        """Force amplitude Q [N] through element ``name`` (from its n1 to its n2)."""
        return self._element(name)[0]

    def velocity(self, name: str) -> NDArray[np.complex128]:
        """Velocity difference amplitude v = v(n1) − v(n2) [m/s] across element ``name``."""
        return self._element(name)[1]

    def _element(self, name: str):
        elements = self._elements()
        if name not in elements:
            raise KeyError(f"no loaded element named {name!r}; elements: "
                           f"{', '.join(sorted(elements))}")
        return elements[name]


def sweep(circuit: Circuit, omega: ArrayLike) -> Sweep:
    """Evaluate ``circuit`` at each angular frequency in ``omega`` [rad/s].

    Parameters
    ----------
    circuit : Circuit
    omega : array_like of float
        Angular frequencies [rad/s], ≥ 0 (the seeds' main-shaft frequency).

    Returns
    -------
    Sweep
        With ``omega``, ``K``, ``Q0``, ``v0``, ``flags`` and per-element
        ``force(name)`` / ``velocity(name)``.

    Examples
    --------
    >>> from mechcirc import parse
    >>> c = parse("mass m a 0 2\\ndrive V a 0 velocity=0.1")
    >>> s = c.sweep([10.0])
    >>> complex(s.Q0[0])            # V0 / K = V0 · jωm
    2j
    """
    omega = np.atleast_1d(np.asarray(omega, dtype=float))
    if omega.ndim != 1:
        raise ValueError(f"omega must be one-dimensional, got shape {omega.shape}")
    tree = circuit.tree
    K = evaluate(tree, omega)
    return Sweep(omega=omega, K=K, drive=circuit.drive, tree=tree, name=circuit.name)
