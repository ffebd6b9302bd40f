"""Frequency sweeps: K(ω), the drive's force and velocity, per-element Q and v.

Under kinematic excitation (``drive ... velocity=V0``) the drive imposes the
velocity amplitude V0 [m/s] and the network answers with the force amplitude
Q0 = V0 / K (Grigoriev et al. 2002, eq. 8).  Under force excitation (``force=F0``) the
velocity amplitude is v0 = F0 · K.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, field, replace
from functools import cached_property
from typing import Any, Callable, Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .circuit import Circuit, Drive, units_of
from .errors import (InputError, MechcircError, NotSeriesParallelError, PeakAccuracyWarning,
                     TopologyError, warn)
from .reduction import Node, evaluate, push_down
from .sources import brief, data_frame, did_you_mean, name_index

__all__ = ["Sweep", "sweep", "Peak", "peak", "FLAG_OK", "FLAG_SINGULAR", "FLAG_NEAR_SINGULAR",
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

#: Sweep.plot marks resonances by default up to this many elements (an eigenproblem each).
PLOT_RESONANCES_ELEMENTS = 400


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
    notes : tuple of str
        What the caller should know about the result (e.g. a point budget hit).
    refine : bool
        Whether the nodal solves were refined (``sweep(..., refine=)``); the
        follow-up evaluations (:meth:`peak`, :meth:`plot`'s points near roots,
        :meth:`node_velocity`) solve the same way.
    """

    omega: NDArray[np.float64]
    K: NDArray[np.complex128]
    drive: Drive
    method: str
    name: str = "circuit"
    tree: Node | None = None
    circuit: Circuit | None = field(default=None, repr=False)
    notes: tuple[str, ...] = ()
    refine: bool = True
    _cache: dict = field(default_factory=dict, repr=False)

    def with_notes(self, notes: tuple[str, ...]) -> "Sweep":
        """The same sweep with ``notes`` (e.g. an adaptive grid's budget) added."""
        return replace(self, notes=self.notes + tuple(notes), _cache={})   # nothing cached

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
        return drive_force(self.K, self.drive.kind, self.drive.amplitude)

    @cached_property
    def v0(self) -> NDArray[np.complex128]:
        """Velocity amplitude at the drive [m/s]: V0 (velocity drive) or F0·K (force drive)."""
        return drive_velocity(self.K, self.drive.kind, self.drive.amplitude)

    @cached_property
    def error(self) -> NDArray[np.float64]:
        """Bound of the relative rounding error of K at each point [1] (inf on a pole or zero).

        Series–parallel: a forward error bound carried through the tree's sums
        (the cancellation at each node, see :func:`mechcirc.reduction.evaluate`);
        calibrated against 40-digit references in ``docs/accuracy.md``.
        Nodal: from the residual of the refined solution in double-double
        and the convergence of the refinement (a double-double LU where the
        float64 one stalls; :class:`mechcirc.nodal.Solution`), calibrated on
        the independent corpus of ``docs/accuracy.md``.
        """
        if "error" in self._cache:
            return self._cache["error"]
        if self.method == "sp":
            tree = _required(self.tree, "reduction tree")
            err = _chunked(lambda w: evaluate(tree, w, error=True)[1], self.omega, float)
        else:
            from . import nodal

            # normally cached by _sweep_nodal from the same refined solve
            err = nodal.mobility_and_error(_required(self.circuit, "circuit").nodal, self.omega)[1]
        return singular_error(self.K, err)

    @cached_property
    def flags(self) -> NDArray[np.int8]:
        """Per-point flag: 0 regular, :data:`FLAG_SINGULAR`, :data:`FLAG_NEAR_SINGULAR`."""
        return point_flags(self.K, self.Q0, self.v0, self.error)

    def force(self, name: str) -> NDArray[np.complex128]:
        """Force amplitude Q [N] through element ``name`` (from its n1 to its n2); a nodal
        sweep solves as it did (:attr:`refine`)."""
        return self._element(name)[0]

    def velocity(self, name: str) -> NDArray[np.complex128]:
        """Velocity difference amplitude v = v(n1) − v(n2) [m/s] across element ``name``; a
        nodal sweep solves as it did (:attr:`refine`)."""
        return self._element(name)[1]

    def node_velocity(self, name: str) -> NDArray[np.complex128]:
        """Velocity amplitude [m/s, or rad/s for a rotary drive] of node ``name`` against
        the frame ``0`` (its displacement amplitude is this over jω).

        By nodal analysis (:func:`mechcirc.nodal.solve_unit`, scaled by :attr:`Q0`),
        whichever method computed K; needs :attr:`circuit`.
        """
        if self.circuit is None:
            raise ValueError("node_velocity needs the sweep's circuit (Sweep.circuit is None)")
        system = self.circuit.nodal
        if name == "0":
            return np.zeros(self.omega.shape, dtype=complex)
        i = name_index(name, system.nodes, "node", " on a path of the drive")
        if "nodes" not in self._cache:
            from .nodal import solve_unit

            with np.errstate(all="ignore"):
                self._cache["nodes"] = solve_unit(system, self.omega, refine=self.refine) * self.Q0[:, None]
        return self._cache["nodes"][:, i]

    def peak(self, quantity: str | None = None) -> "Peak":
        """The largest |``quantity``| over the band, located exactly; see :func:`peak`."""
        return peak(self, quantity=quantity)

    def __repr__(self) -> str:
        """A one-line summary (the arrays are in the attributes, not in the repr)."""
        n = len(self.omega)
        band = f"omega {self.omega[0]:.4g}..{self.omega[-1]:.4g} rad/s" if n else "no points"
        with np.errstate(all="ignore"):
            absK = np.abs(self.K[np.isfinite(self.K)])
            kr = f", |K| {absK.min():.3g}..{absK.max():.3g} {self.units['K']}" if absK.size else ""
        flagged = int(np.count_nonzero(self.flags)) if n else 0
        return (f"<Sweep {self.name!r}: {n} points, {band}, method {self.method}, "
                f"{self.drive.kind} drive{kr}, {flagged} flagged>")

    @property
    def rotational(self) -> bool:
        """True for a rotary drive: K in rad/(N·m·s), Q0 in N·m, v0 in rad/s."""
        return bool(getattr(self.drive, "rotational", False))

    @property
    def units(self) -> dict[str, str]:
        """Unit labels from the drive (:func:`mechcirc.circuit.units_of`): keys v, Q, x, K."""
        return units_of(self.drive)

    def _columns(self) -> dict:
        cols = {"omega": self.omega, "K": self.K, "|K|": np.abs(self.K), "Q0": self.Q0,
                "|Q0|": np.abs(self.Q0)}
        if self.drive.kind == "force":
            cols |= {"v0": self.v0, "|v0|": np.abs(self.v0)}
        return cols | {"flag": self.flags, "error": self.error}

    def _column_units(self, columns) -> dict[str, str]:
        """The unit of each of the ``columns`` of :meth:`_columns` (from :attr:`units`)."""
        u = self.units
        units = {"omega": "rad/s", "K": u["K"], "Q0": u["Q"], "v0": u["v"], "flag": "",
                 "error": "1"}
        return {c: units[c.strip("|")] for c in columns}

    def to_dataframe(self):
        """The sweep as a ``pandas.DataFrame``, one row per frequency point.

        Columns: ``omega`` angular frequency [rad/s]; ``K`` the kinematic
        characteristic v/Q seen by the drive (complex) [m/(N·s), or
        rad/(N·m·s) for a rotary drive]; ``|K|`` its magnitude; ``Q0`` the
        drive's force amplitude (complex) [N, or N·m] and ``|Q0|``; for a force
        drive also ``v0`` the drive's velocity amplitude (complex) [m/s, or
        rad/s] and ``|v0|``; ``flag`` 0 regular, 1 on a pole or zero of K, 2
        within rounding of one (:attr:`flags`); ``error`` the bound of the
        relative rounding error of K [1] (:attr:`error`).  The values are those
        of the attributes of the same names; ``attrs["units"]`` maps each column
        to its unit (as :meth:`to_xarray`).  pandas is imported here only.
        """
        cols = self._columns()
        return data_frame(cols, self._column_units(cols))

    def to_xarray(self):
        """The sweep as an ``xarray.Dataset`` on the dimension ``omega`` [rad/s].

        Data variables as the columns of :meth:`to_dataframe` (``abs_K``,
        ``abs_Q0``, ``abs_v0`` for the magnitudes), each with a ``units``
        attribute.  Needs xarray (not a dependency of mechcirc): raises
        ImportError saying so when it is not installed.
        """
        try:
            import xarray as xr
        except ImportError:
            raise ImportError("Sweep.to_xarray needs xarray (pip install xarray); "
                              "Sweep.to_dataframe needs only pandas") from None
        cols = self._columns()
        units = self._column_units(cols)
        omega = cols.pop("omega")
        return xr.Dataset(
            {k.replace("|", "abs_", 1).rstrip("|"): ("omega", v, {"units": units[k]})
             for k, v in cols.items()},
            coords={"omega": ("omega", omega, {"units": units["omega"]})},
            attrs={"name": self.name, "method": self.method, "drive": self.drive.kind})

    def _repr_html_(self) -> str:
        """The summary as a small table for notebooks."""
        import html

        return "<pre>" + html.escape(repr(self)) + "</pre>"

    def to_skrf(self, **kwargs):
        """K as a one-port ``skrf.Network`` (Z parameters [m/(N·s)]).

        See :func:`mechcirc.interop.skrf.to_skrf`.
        """
        from .interop.skrf import to_skrf

        return to_skrf(self, **kwargs)

    def plot(self, ax=None, *, resonances=None, fig=None, title: str | None = None,
             unit: str = "rad/s"):
        """Plot this sweep: :func:`mechcirc.plotting.plot_sweep` (``ax=`` one panel of |K|,
        else three panels on ``fig`` or a new Figure); returns what it drew on.

        ``fig`` must be an *empty* Figure or SubFigure (one already holding Axes
        is refused with an InputError; pass ``fig.subfigures()`` beside yours).

        ``resonances=None`` marks the circuit's exact resonances in the band
        when that is cheap (at most :data:`PLOT_RESONANCES_ELEMENTS` elements);
        pass a list to choose them, or ``()`` for none.  ``unit``: the frequency
        axis in ``"rad/s"``, ``"Hz"`` or ``"rpm"``.
        """
        from .plotting import plot_sweep

        if resonances is None:
            resonances = self._cheap_resonances()
        return plot_sweep(self, title, resonances, ax=ax, fig=fig, unit=unit)

    def _cheap_resonances(self) -> list:
        if self.circuit is None or len(self.circuit.elements) > PLOT_RESONANCES_ELEMENTS \
                or self.omega.size == 0:
            return []
        from .resonances import find_resonances

        try:
            with warnings.catch_warnings(action="ignore"):
                found = find_resonances(self.circuit, omega_max=float(np.max(self.omega)))
        except MechcircError:          # too large or ill-scaled: the plot goes without
            return []
        lo = float(np.min(self.omega))
        return [r for r in found if r.omega >= lo]

    def _element(self, name: str):
        if "elements" not in self._cache:
            self._cache["elements"] = self._element_responses()
        elements = self._cache["elements"]
        name_index(name, elements, "loaded element")     # a KeyError naming the nearest
        return elements[name]

    def _element_responses(self) -> dict:
        if self.method == "sp":
            tree = _required(self.tree, "reduction tree")
            _, values = evaluate(tree, self.omega, keep=True)
            return push_down(tree, values, self.Q0, self.v0, self.omega)
        from . import nodal

        return nodal.element_response(_required(self.circuit, "circuit").nodal, self.omega,
                                      self.Q0, refine=self.refine)


# The per-point quantities of a sweep from K, written once for a sweep (shape (n,),
# scalar amplitude) and a batch of designs (shape (D, n), amplitudes of shape (D, 1)).

def drive_force(K: NDArray, kind: str, amplitude) -> NDArray[np.complex128]:
    """Q0 from K: V0/K (velocity drive) or F0 (force drive); see :attr:`Sweep.Q0`."""
    amplitude = np.asarray(amplitude, dtype=float)
    if kind == "force":
        return _constant(amplitude, K.shape)
    with np.errstate(all="ignore"):
        Q0 = amplitude / K
    if np.isfinite(Q0).all() and np.isfinite(K).all():
        return Q0           # no zero and no pole of K (the checks below cost twice these)
    # The limits at an exact zero or pole of K (see :func:`sweep`):
    # K = 0 → Q0 = +∞·j·sign(V0); K = ∞·j → Q0 = 0.
    zero = K == 0
    if zero.any():
        limit = np.zeros(K.shape, dtype=complex)
        limit.imag = np.copysign(np.inf, np.broadcast_to(amplitude, K.shape))
        Q0[zero] = limit[zero]
    Q0[np.isinf(K)] = 0.0
    return Q0


def drive_velocity(K: NDArray, kind: str, amplitude) -> NDArray[np.complex128]:
    """v0 from K: V0 (velocity drive) or F0·K (force drive); see :attr:`Sweep.v0`."""
    amplitude = np.asarray(amplitude, dtype=float)
    if kind == "velocity":
        return _constant(amplitude, K.shape)
    out = np.empty(K.shape, dtype=complex)
    with np.errstate(all="ignore"):
        # Part by part: a complex product would turn F0 · ∞j into nan + ∞j.
        out.real = amplitude * K.real
        out.imag = amplitude * K.imag
    out.real[np.isinf(K.imag) & (K.real == 0)] = 0.0
    return out


def _constant(amplitude: NDArray, shape: tuple) -> NDArray[np.complex128]:
    """The drive's amplitude as a complex array broadcast against K's ``shape``."""
    if amplitude.ndim == 0:     # (np.full: a third of broadcast_shapes' cost)
        return np.full(shape, complex(amplitude))
    return np.broadcast_to(amplitude, np.broadcast_shapes(shape, amplitude.shape)) \
        .astype(complex)


def singular_error(K: NDArray, err: NDArray) -> NDArray[np.float64]:
    """The error bound of K with inf on a pole or zero (flag 1: no relative error exists)."""
    err[~np.isfinite(K) | (K == 0)] = np.inf
    return err


def point_flags(K, Q0, v0, error) -> NDArray[np.int8]:
    """Per-point flags from K, Q0, v0 and the error bound; see :attr:`Sweep.flags`.

    ``Q0`` or ``v0`` may be given as anything that broadcasts against K (the
    drive's amplitude where the quantity is that constant)."""
    flags = (error > NEAR_SINGULAR_ERROR).view(np.int8) * np.int8(FLAG_NEAR_SINGULAR)
    flags[~np.isfinite(K) | (K == 0) | ~np.isfinite(Q0) | ~np.isfinite(v0)] = FLAG_SINGULAR
    return flags


def _required(value: Any, what: str) -> Any:
    """``value``, or the error for a :class:`Sweep` built by hand without the ``what`` a
    query needs."""
    if value is None:
        raise InputError(f"this Sweep was built without its {what}, which this query needs")
    return value


def sweep(circuit: Circuit, omega: ArrayLike, *, method: Method = "auto",
          refine: bool = True, error: bool = False) -> Sweep:
    """Evaluate ``circuit`` at each angular frequency in ``omega`` [rad/s].

    Parameters
    ----------
    circuit : Circuit
    omega : array_like of float
        Angular frequencies [rad/s], ≥ 0 (the main-shaft frequency of the papers).
    method : {"auto", "sp", "nodal"}
        ``"sp"``: series–parallel reduction tree (raises
        :class:`~mechcirc.errors.NotSeriesParallelError` if the network is not reducible);
        ``"nodal"``: nodal analysis; ``"auto"``: the tree where it exists, nodal analysis otherwise.
    refine : bool
        Nodal analysis only (the tree has no solve to refine): iterative
        refinement of each solution with residuals in double-double (the
        default; K then correct to about its rounding), or ``False`` for one
        plain solve per ω, faster, with a relative error of about eps·cond(A(ω)).
        Either way ``error`` is the estimate of the error of the K returned.
    error : bool
        Series–parallel tree: also the error bound (hence ``flags``) in the
        same pass over the tree as K, where asking ``Sweep.error`` or
        ``flags`` afterwards evaluates the tree again (the costs of both:
        docs/performance.md).  The same numbers either way.  Nodal analysis
        has its estimate from its solve in any case.

    Returns
    -------
    Sweep
        With ``omega``, ``K``, ``Q0``, ``v0``, ``flags``, ``error`` and
        per-element ``force(name)`` / ``velocity(name)``.

    Raises
    ------
    InputError
        ``omega`` is complex, not numbers, or not one-dimensional; ``method`` is unknown.

    Notes
    -----
    Singular points: at a point ω > 0 exactly on a pole of K, ``K = +∞·j`` (the
    limit from below: a lossless K = jX rises through its poles, Foster's
    reactance theorem; at ω = 0 the limit from above, −∞·j for a mass), ``Q0 = 0`` and ``v0 = +∞·j·F0``; exactly on a zero of K, ``K = 0``
    and ``Q0 = +∞·j·V0``.  Such points get :data:`FLAG_SINGULAR`.  The library
    does not warn (the flags are the per-point report; a study would drown in
    warnings); the command line prints a note naming those ω.

    Examples
    --------
    >>> from mechcirc import parse
    >>> c = parse("mass m a 0 2\\ndrive V a 0 velocity=0.1")
    >>> s = c.sweep([10.0])
    >>> float(s.Q0[0].imag), float(abs(s.Q0[0].real))   # V0 / K = V0 · jωm
    (2.0, 0.0)
    """
    omega = real_omega(omega)
    if method not in ("auto", "sp", "nodal"):
        raise InputError(f"method must be 'auto', 'sp' or 'nodal', got {method!r}"
                         f"{did_you_mean(str(method), ('auto', 'sp', 'nodal'))}")
    if method != "nodal":
        try:
            tree = circuit.tree
        except NotSeriesParallelError:
            if method == "sp":
                raise
        else:
            return _sweep_tree(circuit, tree, omega, error)
    return _sweep_nodal(circuit, omega, refine)


def real_omega(omega: ArrayLike) -> NDArray[np.float64]:
    """``omega`` as a 1-D float array, or :class:`InputError` saying why it is not one."""
    values = np.atleast_1d(np.asarray(omega))
    if values.dtype.kind == "c":
        if np.any(values.imag != 0):
            raise InputError("omega must be real angular frequencies [rad/s], got complex "
                             "values (K(ω) is evaluated on the real ω axis)")
        values = values.real
    try:
        values = values.astype(float)
    except (TypeError, ValueError):
        raise InputError(f"omega must be numbers [rad/s], got {brief(omega)}") from None
    if values.ndim != 1:
        raise InputError(f"omega must be one-dimensional, got shape {values.shape}")
    return values


def _chunked(fn: Callable, omega: NDArray, dtype):
    """``fn(omega)`` evaluated :data:`CHUNK_POINTS` points at a time into one array (a
    tuple of arrays where ``fn`` returns a tuple, ``dtype`` then one per array)."""
    if omega.size <= CHUNK_POINTS:
        return fn(omega)
    many = isinstance(dtype, tuple)
    outs = tuple(np.empty(omega.shape, dtype=d) for d in (dtype if many else (dtype,)))
    for start in range(0, omega.size, CHUNK_POINTS):
        part = fn(omega[start:start + CHUNK_POINTS])
        for out, values in zip(outs, part if many else (part,)):
            out[start:start + CHUNK_POINTS] = values
    return outs if many else outs[0]


def singular_limits(K: NDArray[np.complex128], omega) -> NDArray[np.complex128]:
    """K on an exact pole at ω > 0 is +∞·j (see :func:`sweep`), whatever sign
    rounding gave; at ω = 0 the limit from above stands (−∞·j for a mass)."""
    pole = np.isinf(K) & (omega > 0)
    if pole.any():
        K[pole] = complex(0.0, math.inf)
    return K


def _sweep_tree(circuit: Circuit, tree: Node, omega, error: bool = False) -> Sweep:
    if error:       # K and its bound in one pass (Sweep.error would evaluate again)
        K, err = _chunked(lambda w: evaluate(tree, w, error=True), omega, (complex, float))
    else:
        K = _chunked(lambda w: evaluate(tree, w), omega, complex)
    K = singular_limits(K, omega)
    return Sweep(omega=omega, K=K, drive=circuit.require_drive(), method="sp",
                 name=circuit.name, tree=tree, circuit=circuit,
                 _cache={"error": singular_error(K, err)} if error else {})


def _sweep_nodal(circuit: Circuit, omega, refine: bool = True) -> Sweep:
    from . import nodal

    # One solve gives K and its error estimate (the last refinement correction,
    # or the first one unrefined, see nodal.Solution), dense and sparse alike;
    # nodal.solve already applies the singular-point convention, and the
    # neighbours decide any point it left undetermined.
    solved = nodal.solve(circuit.nodal, omega, refine=refine, keep_x=False)
    K, err = _nodal_singular_limits(circuit.nodal, solved.K, solved.error, omega)
    K, err, notes = _tree_where_no_digit(circuit, omega, K, err)
    return Sweep(omega=omega, K=K, drive=circuit.require_drive(), method="nodal",
                 name=circuit.name, circuit=circuit, notes=notes, refine=refine,
                 _cache={"error": err})


def _tree_where_no_digit(circuit: Circuit, omega, K, err):
    """K from the series–parallel tree where nodal analysis knows fewer than six digits.

    A network whose element values span 20 decades can have cond(A(ω)) of
    1e35 even balanced (measured in mpmath), beyond the double-double LU's
    reach (about 1e30), while K is well conditioned: nodal analysis then
    returns a finite K with an error estimate above :data:`NEAR_SINGULAR_ERROR`
    (infinite, or as large as 3e-3 with the same network on another CPU: the
    rounding of an LU that far beyond its reach depends on the BLAS kernels).
    Where the network is a tree, its evaluation (with its own calibrated bound)
    replaces those points where that bound is the smaller, and a note says so;
    otherwise they stay as they are (flag 2).
    """
    lost = np.isfinite(K) & (K != 0) & ~(err <= NEAR_SINGULAR_ERROR) & (omega > 0)
    if not lost.any():
        return K, err, ()
    try:
        with warnings.catch_warnings(action="ignore"):  # the nodal path already said its warnings
            tree = circuit.tree
    except TopologyError:                        # not a tree (or not one seen from the drive)
        return K, err, ()
    Kt, et = evaluate(tree, omega[lost], error=True)
    better = et < err[lost]
    if not better.any():
        return K, err, ()
    at = np.flatnonzero(lost)[better]
    K, err = K.copy(), err.copy()
    K[at], err[at] = singular_limits(Kt[better], omega[at]), et[better]
    return K, err, (f"K at {at.size} ω from the series–parallel tree: nodal analysis "
                    "knows fewer than six digits there (A(ω) near or beyond the reach of "
                    "its double-double LU)",)


def _nodal_singular_limits(system, K, err, omega, delta: float = 1e-6):
    """The singular-point convention of :func:`sweep` for nodal analysis: (K, err), err
    infinite where K was not finite.

    Where A(ω) is singular the solve gives NaN.  K just below and above tells
    what the point is: a pole (K changes sign through it, K(ω⁻) ≈ −K(ω⁺)) gets
    K = +∞·j like the tree; otherwise the mode is not seen from the drive and K
    is the mean of its two neighbours (flagged by its error estimate, which is
    infinite there).
    """
    from . import nodal

    bad = ~np.isfinite(K) & (omega > 0)
    if not bad.any():
        return K, err
    w = omega[bad]
    with np.errstate(all="ignore"):
        below = nodal.mobility(system, w * (1 - delta))
        above = nodal.mobility(system, w * (1 + delta))
        pole = np.abs(below + above) < 0.5 * np.abs(below - above)
    K = K.copy()
    K[np.flatnonzero(bad)[pole]] = complex(0.0, math.inf)
    mean = (below + above) / 2
    keep = ~pole & np.isfinite(mean)
    K[np.flatnonzero(bad)[keep]] = mean[keep]
    return K, np.where(bad, np.inf, err)



@dataclass(frozen=True)
class Peak:
    """The largest magnitude of a response over a band (see :func:`peak`).

    Attributes
    ----------
    quantity : {"Q0", "v0", "K", "S"}
    value : float
        The peak magnitude (N, m/s or m/(N·s)); ``math.inf`` when unbounded.
    omega : float
        Where it is [rad/s]: the located maximum, or the (first) undamped
        resonance where the quantity is unbounded.
    unbounded : bool
        True when the band holds an undamped zero (Q0) or pole (v0, K) of K.
    poles : tuple of float
        Every ω [rad/s] in the band where the quantity is unbounded.
    grid_value, grid_omega : float
        The largest finite value on the sweep's grid and where (for comparison).
    note : str
        Empty when the peak was located around every resonance in the band;
        otherwise why the resonances could not be found, the peak then searched
        around the grid's largest value only (a narrow peak between two grid
        points may be missed; a :class:`~mechcirc.errors.PeakAccuracyWarning`
        said so).
    """

    quantity: str
    value: float
    omega: float
    unbounded: bool
    poles: tuple = ()
    grid_value: float = math.nan
    grid_omega: float = math.nan
    note: str = ""

    def __str__(self) -> str:
        if self.unbounded:
            at = ", ".join(f"{w:.10g}" for w in self.poles)
            text = f"max |{self.quantity}| = inf (undamped resonance at omega = {at} rad/s)"
        else:
            text = f"max |{self.quantity}| = {self.value:.7g} at omega = {self.omega:.10g} rad/s"
        return f"{text} ({self.note})" if self.note else text


#: Damping ratio below which a zero or pole of K counts as undamped for
#: :func:`peak` (the eigen-solver reports ζ = 0 for lossless modes).
UNDAMPED_ZETA = 1e-12


def peak(result: "Sweep | Circuit", omega_min: float | None = None,
         omega_max: float | None = None, quantity: str | None = None, *,
         method: Method = "auto", xtol: float = 1e-12,
         resonances: "list | MechcircError | None" = None) -> Peak:
    """The largest |Q0|, |v0|, |K| or |S| = 1/|K| over [``omega_min``, ``omega_max``], located exactly.

    Parameters
    ----------
    result : Sweep or Circuit
        A sweep (its band and grid are used unless given) or a circuit.
    omega_min, omega_max : float, optional
        The band [rad/s] (needed with a circuit).
    quantity : {"Q0", "v0", "K", "S"}, optional
        ``"S"`` (1/K) gives the smallest |K| as 1/value.  Default: ``"Q0"`` for a velocity drive, ``"v0"`` for a force drive.
    resonances : list of Resonance or MechcircError, optional
        The circuit's resonances up to at least the band's top, when already
        computed (otherwise :meth:`Circuit.resonances` is called); or the error
        that asking for them raised (then they are not asked for again: the
        search is the grid's, with :attr:`Peak.note`, as below).
    xtol : float
        Relative tolerance in ω of the golden-section search (also to 1e-9 of
        each bracket, :func:`golden_max`).  |q| is flat at its maximum, so the
        value is right to about machine precision (3.6e-16 from a 40-digit
        search, ζ down to 7e-6) while ω is located to about √eps ≈ 1e-8 of the
        bracket (the rounding of |q| hides it).
    method : {"auto", "sp", "nodal"}
        As :func:`sweep` (a sweep's own method when ``result`` is a sweep).

    Returns
    -------
    Peak
        Unbounded (``value = inf``, ``omega`` = the resonance) when the band
        holds an undamped zero of K (for Q0 and S) or pole of K (for v0 and K),
        found exactly by :meth:`Circuit.resonances`; otherwise the maximum
        located by a golden-section search around the grid's largest value and
        around every damped resonance of the right kind in the band; where the
        resonances cannot be found (e.g. more in the band than the band solver
        takes), around the grid's largest value only, with :attr:`Peak.note`
        saying so and a :class:`~mechcirc.errors.PeakAccuracyWarning`.

    Examples
    --------
    >>> from mechcirc import parse
    >>> from mechcirc import peak
    >>> c = parse("drive V a 0 velocity=1\\nmass m a b 1\\nspring k b 0 1e4")
    >>> print(peak(c, 10, 1000))   # doctest: +NORMALIZE_WHITESPACE
    max |Q0| = inf (undamped resonance at omega = 100 rad/s)
    """
    circuit, grid, lo, hi = _peak_band(result, omega_min, omega_max)
    method = method if grid is None else grid.method          # a sweep's own
    if quantity is None:
        quantity = "v0" if circuit.drive.kind == "force" else "Q0"
    if quantity not in ("Q0", "v0", "K", "S"):
        raise ValueError(f"quantity must be 'Q0', 'v0', 'K' or 'S', got {quantity!r}"
                         f"{did_you_mean(str(quantity), ('Q0', 'v0', 'K', 'S'))}")
    if quantity == "Q0" and circuit.drive.kind == "force":
        # Q0 is the applied force: constant.
        return Peak(quantity, abs(circuit.drive.amplitude), lo, False, (),
                    abs(circuit.drive.amplitude), lo)
    return _located_peak(circuit, grid, lo, hi, quantity, method, xtol, resonances)


def _located_peak(circuit, grid, lo: float, hi: float, quantity: str, method: Method,
                  xtol: float, resonances) -> Peak:
    """:func:`peak` once its arguments are checked: the exact roots, the grid, the bracket searches."""
    refine = True if grid is None else grid.refine     # solve as the sweep did
    found, note = _peak_roots(circuit, lo, hi, quantity, resonances)
    if note:
        warn(f"peak: {note}", PeakAccuracyWarning)
    undamped = tuple(r.omega for r in found if r.zeta <= UNDAMPED_ZETA)
    if grid is None:
        grid = sweep(circuit, peak_grid(lo, hi), method=method, refine=refine)
    q_grid = np.abs(getattr(grid, quantity))
    finite = np.isfinite(q_grid)
    i_grid = int(np.argmax(np.where(finite, q_grid, -1.0)))
    g_value = float(q_grid[i_grid]) if finite.any() else math.nan
    g_omega = float(grid.omega[i_grid]) if finite.any() else math.nan
    if undamped:
        return Peak(quantity, math.inf, undamped[0], True, undamped, g_value, g_omega, note)
    # Brackets: the grid's maximum with its neighbours, and each damped
    # resonance of the right kind ± four half-power bandwidths.
    w = grid.omega
    a, b = root_brackets(*(np.array([getattr(r, f) for r in found], dtype=float)
                           for f in ("omega", "omega_d", "zeta")))
    brackets = [(w[max(i_grid - 1, 0)], w[min(i_grid + 1, w.size - 1)])] + \
        list(zip(a.tolist(), b.tolist()))
    best_value, best_omega = _peak_search(circuit, method, quantity, lo, hi, brackets,
                                          g_value, g_omega, xtol, refine)
    if math.isinf(best_value):
        # An exact pole the eigen-solver did not report as undamped (or could
        # not be run): unbounded all the same.
        return Peak(quantity, math.inf, best_omega, True, (best_omega,), g_value, g_omega, note)
    return Peak(quantity, best_value, best_omega, False, (), g_value, g_omega, note)


def peak_grid(lo: float, hi: float) -> NDArray:
    """The 401 ω of :func:`peak`'s grid over [lo, hi] (log-spaced unless lo is 0)."""
    return np.geomspace(max(lo, hi * 1e-12), hi, 401) if lo > 0 else np.linspace(lo, hi, 401)


def root_brackets(omega, omega_d, zeta) -> tuple[NDArray, NDArray]:
    """The brackets :func:`peak` searches around damped roots (arrays of their ω, ω_d and
    ζ): four half-power bandwidths ζω (at least 1e-9 ω) either side of ω_d (ω if 0)."""
    centre = np.where(omega_d > 0, omega_d, omega)
    with np.errstate(invalid="ignore"):
        half = np.maximum(zeta * omega, 1e-9 * omega)
    return centre - 4 * half, centre + 4 * half


def _peak_band(result, omega_min, omega_max) -> tuple:
    """``(circuit, sweep or None, lo, hi)`` of :func:`peak`'s arguments, checked."""
    if isinstance(result, Sweep):
        circuit, grid, w = result.circuit, result, result.omega if result.omega.size else [math.nan]
        lo = float(np.min(w)) if omega_min is None else float(omega_min)
        hi = float(np.max(w)) if omega_max is None else float(omega_max)
    else:
        circuit, grid = result, None
        if omega_min is None or omega_max is None:
            raise ValueError("peak(circuit, ...) needs omega_min and omega_max")
        lo, hi = float(omega_min), float(omega_max)
    if not 0 <= lo < hi < math.inf:
        raise ValueError(f"need 0 <= omega_min < omega_max < inf (a band: a sweep of two ω "
                         f"or more), got {lo} and {hi}")
    return circuit, grid, lo, hi


def _peak_roots(circuit, lo: float, hi: float, quantity: str, resonances) -> tuple:
    """``(roots, note)``: the roots of ``circuit`` in [lo, hi] where |quantity| may be
    unbounded — zeros of K ("resonance") for Q0 and S, poles ("antiresonance") for v0 and
    K — from ``resonances`` when given, else computed; and ``""``, or why they could not
    be computed (then no roots: the search is the grid's)."""
    kind = "resonance" if quantity in ("Q0", "S") else "antiresonance"
    try:
        if isinstance(resonances, MechcircError):       # asked for already, and refused
            raise resonances
        # (asked for, only this kind is polished: the other's polish is half the work)
        found = circuit.resonances(omega_max=hi * (1 + 1e-9), kind=kind) \
            if resonances is None else resonances
        return [r for r in found if r.kind == kind
                and lo * (1 - 1e-12) <= r.omega <= hi * (1 + 1e-9)], ""
    except MechcircError as exc:    # e.g. more roots in the band than the band solver takes
        return [], (f"searched around the grid's largest value only, a narrow peak between "
                    f"two grid points may be missed: the resonances were not found ({exc})")


def _peak_search(circuit, method, quantity, lo, hi, brackets, best_value, best_omega, xtol,
                 refine=True):
    """The largest |quantity| of the band's ends, the grid's best and a golden-section
    search in each bracket, all brackets at once (:func:`golden_max`; solved as
    ``sweep(..., refine=refine)``): ``(value, omega)``."""

    def magnitude(w):
        w = np.asarray(w, dtype=float)
        s = sweep(circuit, w.ravel(), method=method, refine=refine)
        with np.errstate(all="ignore"):
            q = np.abs(getattr(s, quantity))
        return np.where(np.isfinite(q), q, np.inf).reshape(w.shape)

    for a, v in zip((lo, hi), magnitude([lo, hi]).tolist()):
        if not best_value >= v:
            best_value, best_omega = v, a
    inside = [(max(a, lo), min(b, hi)) for a, b in brackets if max(a, lo) < min(b, hi)]
    if inside:
        x, v = golden_max(magnitude, *np.array(inside).T, xtol)
        for xi, vi in zip(x.tolist(), v.tolist()):
            if vi > best_value or math.isnan(best_value):     # (∞ at a band's end stays)
                best_value, best_omega = vi, xi
        if best_omega in x:               # solved alone, as a sweep at that ω gives it
            best_value = float(magnitude([best_omega])[0])
    return best_value, best_omega


#: (3 − √5)/2: the golden section's step, the fraction of a bracket dropped each evaluation.
_GOLDEN = (3 - math.sqrt(5)) / 2


def golden_max(f, a: NDArray, b: NDArray, xtol: float = 1e-12) -> tuple[NDArray, NDArray]:
    """The maximum of ``f`` in each bracket [a, b] (arrays of one shape, ``f`` evaluating
    them all at once) by golden-section search until b − a ≤ ``xtol``·max(|a|, |b|) and
    ≤ 1e-9 of the bracket: the top of a peak of relative width ζ is flat to eps only
    within about 1e-8·ζ of it.  Returns ``(x, f(x))``.

    One evaluation a step for every bracket at once, where a Brent search (scipy's
    bounded ``minimize_scalar``) runs bracket by bracket and stops at √eps·|x|: on a
    sharp peak (ζ ≈ 1e-5) that left |q| 5.7e-10 below its top.
    """
    tol = np.minimum(xtol * np.maximum(np.abs(a), np.abs(b)), 1e-9 * (b - a))
    # Each bracket's own number of steps: its result does not depend on the others.
    with np.errstate(all="ignore"):
        steps = np.ceil(np.log(np.maximum((b - a) / np.maximum(tol, 1e-300), 1.0))
                        / -math.log1p(-_GOLDEN))
    x1, x2 = a + _GOLDEN * (b - a), b - _GOLDEN * (b - a)
    f1, f2 = f(x1), f(x2)
    for i in range(int(np.max(steps, initial=0))):
        go = i < steps
        left = go & (f1 >= f2)            # the maximum lies in [a, x2]
        right = go & ~left
        a, b = np.where(right, x1, a), np.where(left, x2, b)
        new = np.where(left, a + _GOLDEN * (b - a), b - _GOLDEN * (b - a))
        fn = f(new)
        x1, x2, f1, f2 = (np.where(left, new, np.where(right, x2, x1)),
                          np.where(left, x1, np.where(right, new, x2)),
                          np.where(left, fn, np.where(right, f2, f1)),
                          np.where(left, f1, np.where(right, fn, f2)))
    best = f1 >= f2
    return np.where(best, x1, x2), np.where(best, f1, f2)
