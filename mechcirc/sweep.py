"""Frequency sweeps: K(ω), the drive's force and velocity, per-element Q and v.

Under kinematic excitation (``drive ... velocity=V0``) the drive imposes the
velocity amplitude V0 [m/s] and the network answers with the force amplitude
Q0 = V0 / K (DIGEST §1, eq. 8).  Under force excitation (``force=F0``) the
velocity amplitude is v0 = F0 · K.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property
from typing import Callable, Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .circuit import Circuit, Drive
from .errors import NotSeriesParallelError
from .reduction import Node, evaluate, push_down

__all__ = ["Sweep", "sweep", "FLAG_OK", "FLAG_SINGULAR", "FLAG_NEAR_SINGULAR",
           "NEAR_SINGULAR_ERROR", "Method"]

Method = Literal["auto", "sp", "nodal"]

#: ``Sweep.flags`` value of a regular point.
FLAG_OK = 0
#: ``Sweep.flags`` value of a point exactly on a pole or zero of K: K, Q0 or
#: v0 is 0, infinite or undefined there (NaN never appears unflagged).
FLAG_SINGULAR = 1
#: ``Sweep.flags`` value of a point within rounding of a pole or zero: the
#: estimated relative error of K (``Sweep.error``) exceeds
#: :data:`NEAR_SINGULAR_ERROR`, so K and Q0 have fewer than six correct digits.
FLAG_NEAR_SINGULAR = 2
NEAR_SINGULAR_ERROR = 1e-6
#: Points per chunk of a series–parallel evaluation: each temporary array then
#: holds at most 2**18 complex values (4 MiB), so a sweep of 10⁷ points needs
#: little more memory than its results (K alone is 160 MB there).
CHUNK_POINTS = 2**18


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
    method : {"sp", "nodal"}
        How K was computed: series–parallel reduction tree or nodal analysis.
    name : str
        The circuit's name.
    tree : Node or None
        The reduction tree (series–parallel method only).
    """

    omega: NDArray[np.float64]
    K: NDArray[np.complex128]
    drive: Drive
    method: str
    name: str = "circuit"
    tree: Node | None = None
    _responses: Callable = field(default=None, repr=False)
    _errors: Callable = field(default=None, repr=False)
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
    def error(self) -> NDArray[np.float64]:
        """Estimated relative rounding error of K at each point [1] (inf on a pole or zero).

        Series–parallel: condition of the tree's sums × machine epsilon × depth.
        Nodal: the drive component of the last iterative-refinement
        correction (:class:`mechcirc.nodal.Solution`), dense and sparse alike.
        """
        return self._errors()

    @cached_property
    def flags(self) -> NDArray[np.int8]:
        """Per-point flag: 0 regular, :data:`FLAG_SINGULAR`, :data:`FLAG_NEAR_SINGULAR`."""
        exact = ~np.isfinite(self.K) | (self.K == 0) | ~np.isfinite(self.Q0) | \
            ~np.isfinite(self.v0)
        near = self.error > NEAR_SINGULAR_ERROR
        return np.where(exact, FLAG_SINGULAR,
                        np.where(near, FLAG_NEAR_SINGULAR, FLAG_OK)).astype(np.int8)

    def force(self, name: str) -> NDArray[np.complex128]:
        """Force amplitude Q [N] through element ``name`` (from its n1 to its n2)."""
        return self._element(name)[0]

    def velocity(self, name: str) -> NDArray[np.complex128]:
        """Velocity difference amplitude v = v(n1) − v(n2) [m/s] across element ``name``."""
        return self._element(name)[1]

    def to_skrf(self, **kwargs):
        """K as a one-port ``skrf.Network`` (Z parameters, m/(N·s)); see :func:`mechcirc.interop.skrf.to_skrf`."""
        from .interop.skrf import to_skrf

        return to_skrf(self, **kwargs)

    def _element(self, name: str):
        if "elements" not in self._cache:
            self._cache["elements"] = self._responses(self.Q0, self.v0)
        elements = self._cache["elements"]
        if name not in elements:
            raise KeyError(f"no loaded element named {name!r}; elements: "
                           f"{', '.join(sorted(elements))}")
        return elements[name]


def sweep(circuit: Circuit, omega: ArrayLike, *, method: Method = "auto") -> Sweep:
    """Evaluate ``circuit`` at each angular frequency in ``omega`` [rad/s].

    Parameters
    ----------
    circuit : Circuit
    omega : array_like of float
        Angular frequencies [rad/s], ≥ 0 (the seeds' main-shaft frequency).
    method : {"auto", "sp", "nodal"}
        ``"sp"``: series–parallel reduction tree (raises
        :class:`~mechcirc.errors.NotSeriesParallelError` if the network is
        not reducible); ``"nodal"``: nodal analysis; ``"auto"``: the tree
        where it exists, nodal analysis otherwise.

    Returns
    -------
    Sweep
        With ``omega``, ``K``, ``Q0``, ``v0``, ``flags``, ``error`` and
        per-element ``force(name)`` / ``velocity(name)``.

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
    if method not in ("auto", "sp", "nodal"):
        raise ValueError(f"method must be 'auto', 'sp' or 'nodal', got {method!r}")
    if method != "nodal":
        try:
            tree = circuit.tree
        except NotSeriesParallelError:
            if method == "sp":
                raise
        else:
            return _sweep_tree(circuit, tree, omega)
    return _sweep_nodal(circuit, omega)


def _chunked(fn: Callable, omega: NDArray, dtype) -> NDArray:
    """``fn(omega)`` evaluated :data:`CHUNK_POINTS` points at a time into one array."""
    if omega.size <= CHUNK_POINTS:
        return fn(omega)
    out = np.empty(omega.shape, dtype=dtype)
    for start in range(0, omega.size, CHUNK_POINTS):
        out[start:start + CHUNK_POINTS] = fn(omega[start:start + CHUNK_POINTS])
    return out


def _sweep_tree(circuit: Circuit, tree: Node, omega) -> Sweep:
    def responses(Q0, v0):
        _, values = evaluate(tree, omega, keep=True)
        return push_down(tree, values, Q0, v0, omega)

    def errors():
        scale = np.finfo(float).eps * _depth(tree)
        return _chunked(lambda w: evaluate(tree, w, condition=True)[1] * scale, omega, float)

    K = _chunked(lambda w: evaluate(tree, w), omega, complex)
    return Sweep(omega=omega, K=K, drive=circuit.drive, method="sp",
                 name=circuit.name, tree=tree, _responses=responses, _errors=errors)


def _depth(root: Node) -> int:
    depth, stack = 1, [(root, 1)]
    while stack:
        node, d = stack.pop()
        depth = max(depth, d)
        kids = getattr(node, "children", None) or ((node.child,) if hasattr(node, "child") else ())
        stack.extend((c, d + 1) for c in kids)
    return depth


def _sweep_nodal(circuit: Circuit, omega) -> Sweep:
    from . import nodal

    system = circuit.nodal
    # One refined solve gives K and its error estimate (the last refinement
    # correction, see nodal.Solution), dense and sparse alike.
    K, err = nodal.mobility_and_error(system, omega)

    def responses(Q0, v0):
        return nodal.element_response(system, omega, Q0)

    def errors():
        return err

    return Sweep(omega=omega, K=K, drive=circuit.drive, method="nodal", name=circuit.name,
                 _responses=responses, _errors=errors)
