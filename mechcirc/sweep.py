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
    """The result of a frequency sweep: plain data (it pickles).

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
    circuit : Circuit or None
        The circuit swept (element forces and error estimates are computed
        from it on first use).
    """

    omega: NDArray[np.float64]
    K: NDArray[np.complex128]
    drive: Drive
    method: str
    name: str = "circuit"
    tree: Node | None = None
    circuit: Circuit | None = field(default=None, repr=False)
    _cache: dict = field(default_factory=dict, repr=False)

    def __repr__(self) -> str:
        n = self.omega.size
        band = f"{self.omega.min():.4g}…{self.omega.max():.4g} rad/s" if n else "empty"
        return f"Sweep({self.name!r}, {n} points, {band}, method={self.method!r})"

    def __getstate__(self):
        # The tree nests as deep as the network (a ladder of 10⁵ elements is
        # 5·10⁴ levels), deeper than pickle's recursion: rebuild it from the
        # circuit's flat element list instead.
        state = dict(self.__dict__)
        if state.get("circuit") is not None:
            state["tree"] = None
        return state

    def __setstate__(self, state):
        self.__dict__.update(state)
        if self.method == "sp" and self.tree is None and self.circuit is not None:
            object.__setattr__(self, "tree", self.circuit.tree)

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
        """Bound of the relative rounding error of K at each point [1] (inf on a pole or zero).

        Series–parallel: a forward error bound carried through the tree's sums
        (the cancellation at each node, see :func:`mechcirc.reduction.evaluate`);
        calibrated against 40-digit references in ``docs/accuracy.md``.
        Nodal: machine epsilon × the condition number of A(ω) (see
        :mod:`mechcirc.nodal`).
        """
        if "error" in self._cache:
            return self._cache["error"]
        if self.method == "sp":
            return _chunked(lambda w: evaluate(self.tree, w, error=True)[1],
                            self.omega, float)
        return _nodal_errors(self.circuit.nodal, self.omega)

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

    def peak(self, quantity: str = "Q0"):
        """The largest |``quantity``| over the band, located exactly; see :func:`peak`."""
        return peak(self, quantity)

    def to_skrf(self, **kwargs):
        """K as a one-port ``skrf.Network`` (Z parameters, m/(N·s)); see :func:`mechcirc.interop.skrf.to_skrf`."""
        from .interop.skrf import to_skrf

        return to_skrf(self, **kwargs)

    def _element(self, name: str):
        if "elements" not in self._cache:
            self._cache["elements"] = self._element_responses()
        elements = self._cache["elements"]
        if name not in elements:
            raise KeyError(f"no loaded element named {name!r}; elements: "
                           f"{', '.join(sorted(elements))}")
        return elements[name]

    def _element_responses(self) -> dict:
        if self.method == "sp":
            _, values = evaluate(self.tree, self.omega, keep=True)
            return push_down(self.tree, values, self.Q0, self.v0, self.omega)
        from . import nodal

        return nodal.element_response(self.circuit.nodal, self.omega, self.Q0)


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
    K = _chunked(lambda w: evaluate(tree, w), omega, complex)
    return Sweep(omega=omega, K=K, drive=circuit.drive, method="sp",
                 name=circuit.name, tree=tree, circuit=circuit)


def _sweep_nodal(circuit: Circuit, omega) -> Sweep:
    from . import nodal

    K = nodal.mobility(circuit.nodal, omega)
    return Sweep(omega=omega, K=K, drive=circuit.drive, method="nodal", name=circuit.name,
                 circuit=circuit)


def _nodal_errors(system, omega) -> NDArray[np.float64]:
    from . import nodal

    # eps·cond(A) bounds the error of x relative to ‖x‖; K = x_a − x_b can be
    # far smaller than ‖x‖ near a resonance (K → 0), and its relative error
    # larger by ‖x‖/|K| (a series m–k at 1e-13 from its resonance: 2e-4).
    err = nodal.condition_error(system, omega)
    if system.size > nodal.DENSE_LIMIT:
        return err                      # not estimated (NaN) for sparse systems

    def cancellation(w):
        x = nodal.solve_unit(system, w, refine=False)
        with np.errstate(all="ignore"):
            ratio = np.linalg.norm(x, axis=1) / np.abs(system.difference(x))
        return np.where(np.isnan(ratio), np.inf, np.maximum(ratio, 1.0))

    with np.errstate(invalid="ignore"):
        return err * _chunked(cancellation, omega, float)


def peak(*a, **k):  # placeholder, replaced below
    raise NotImplementedError
