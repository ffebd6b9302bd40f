"""Many designs of one circuit at once: values as arrays over D designs.

A study, a cycle map or a sample explores thousands of variants of one
mechanism: the same netlist with other ``.param`` values (lever ratios,
masses, stiffnesses).  :func:`designs` parses the netlist once and evaluates
its ``.param`` expressions and element values over arrays of D designs
(:func:`mechcirc.expressions.evaluate_array`, no re-parsing, no ``eval``);
the result, :class:`Designs`, evaluates

* K, Q0, v0, the error bound and the flags on a D × W grid in one pass of the
  compiled series–parallel plan (:meth:`mechcirc.reduction.Plan.with_values`
  and :func:`mechcirc.reduction.evaluate_designs`: one design is the single
  sweep, the same code; without numba the same plan's tree evaluated by numpy
  over the designs, the single path's numbers); a network that is not
  series–parallel on the nodal path with the designs' A(ω) stacked, refined
  point by point as the single nodal sweep refines (:func:`_nodal_sweep`);
* the exact resonances of every design from stacked eigenvalue problems, one
  LAPACK call per stack, each root polished (:meth:`Designs.resonances`);
* the true extremes of |K| and |Q0| over a band (:meth:`Designs.extremes`).

A design the batch cannot take (a value that is not a positive finite
number, a topology that changes with the values, a nodal point that needs more
than the float64 refinement, an undamped mass matrix too close to singular for the
resonances) is
evaluated by the single-design path (:meth:`Designs.design` gives its
:class:`~mechcirc.circuit.Circuit`); the results say which and how many.
:func:`from_circuits` makes the designs of circuits built in code (a scene
at each crank angle).
"""

from __future__ import annotations

import functools
import math
import warnings
from dataclasses import dataclass, field, replace

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ._memo import Memos
from .circuit import Circuit, units_of
from .errors import InputError, MechcircError, NotSeriesParallelError
from ._sweep import (UNDAMPED_ZETA, real_omega, drive_force, drive_velocity, golden_max, peak,
                     peak_grid, point_flags, root_brackets, singular_error, singular_limits,
                     sweep as sweep_one)
from .reduction import evaluate_designs, plan
from .resonances import (MAX_UNKNOWNS, MAX_UNKNOWNS_DAMPED, POLISH_BELOW, Resonance, batched_roots,
                         constraint_basis, design_values, exact_basis, element_patterns, find_resonances,
                         g_and_bound, held_and_released, pencil, secant_polish, settled,
                         shared_roots_free, sorted_roots, stacked_problem, template_levers,
                         unbounded, design_bases, design_lever_values, design_verdict,
                         row_spacing)
from .sources import brief, data_frame, summary_repr

__all__ = ["designs", "from_circuits", "network_shape", "Designs", "DesignSweep", "DesignResonances",
           "DesignExtremes"]


def designs(netlist: "str | Circuit", params: dict | None = None, *,
            source: str = "<string>") -> "Designs":
    """D designs of one netlist, differing in their ``.param`` values.

    Parameters
    ----------
    netlist : str or Circuit
        Netlist text, or a circuit made by :func:`mechcirc.parse` /
        :func:`mechcirc.load` (its parsed expressions are reused).
    params : dict of str to array_like
        ``.param`` name → values [SI] over the designs: arrays of one length D
        (scalars are the same in every design).  Parameters defined from
        them follow, as :func:`mechcirc.parse` ``params=`` does.
    source : str
        Name of the netlist for messages (text input).

    Returns
    -------
    Designs

    Raises
    ------
    NetlistError
        The text has an error, or a name is not a ``.param`` of it.
    InputError
        The arrays have different lengths or are not one-dimensional.

    Examples
    --------
    >>> import numpy as np
    >>> from mechcirc import designs
    >>> d = designs(".param k=100\\nmass m a 0 1\\nspring s a 0 k\\ndrive V a 0 force=1",
    ...             params={"k": [100.0, 400.0]})
    >>> d.size, d.sweep([1.0, 50.0]).K.shape
    (2, (2, 2))
    >>> [round(r.omega, 9) for r in d.resonances().list(1)]
    [20.0]
    """
    from .netlist import check_param_names, expressions_of

    circuit, text = (netlist, None) if isinstance(netlist, Circuit) \
        else (_parsed(netlist, source), netlist)
    exprs, params = expressions_of(circuit), dict(params or {})
    if params and exprs is None:
        raise InputError("params= needs a circuit made by mechcirc.parse or mechcirc.load "
                         "(its .param expressions); this one was built in code")
    check_param_names(params, circuit.params, circuit.source)
    arrays, D = _param_arrays(params)
    return _build(circuit, text, exprs, arrays, D)


@functools.lru_cache(maxsize=8)
def _parsed(text: str, source: str) -> Circuit:
    """The circuit of a netlist text, parsed once for the last few texts: the chunks of a
    study or a benchmark repeat one netlist, and a Circuit is immutable, so its
    reduction, nodal system and plan (cached on it) are built once per process."""
    from .netlist import parse

    return parse(text, source=source)


def _param_arrays(params: dict) -> tuple[dict, int]:
    """The ``params=`` values as float arrays, and D; one-dimensional, of one length."""
    arrays = {}
    for name, v in params.items():
        a = np.asarray(v)
        if a.dtype.kind not in "biuf":
            raise InputError(f"params[{name!r}] must be numbers, got {brief(v)}")
        if a.ndim > 1:
            raise InputError(f"params[{name!r}] must be one-dimensional, got shape {a.shape}")
        arrays[name] = a.astype(float)
    sizes = {a.size for a in arrays.values() if a.ndim == 1}
    if len(sizes) > 1:
        raise InputError("params= arrays have different lengths: " + ", ".join(
            f"{n} {a.size}" for n, a in arrays.items() if a.ndim == 1))
    return arrays, (sizes.pop() if sizes else 1)


def network_shape(circuit: Circuit) -> tuple:
    """What two designs of one network share: elements, levers and drive by kind, name and nodes.

    Values, η, lever ratios and the drive amplitude are left out, so two circuits
    with equal shapes are designs of one network (:func:`from_circuits`).

    Parameters
    ----------
    circuit : Circuit
        A driven circuit.

    Returns
    -------
    tuple
        ``(elements, levers, drive)`` as lists and a tuple of plain values, comparable with ``==``.
    """
    d = circuit.require_drive()
    return ([(e.kind, e.name, e.n1, e.n2) for e in circuit.elements],
            [(lv.name, *lv.terminals) for lv in circuit.levers],
            (d.name, d.n1, d.n2, d.kind))


def from_circuits(circuits) -> "Designs":
    """The designs of several circuits of one topology (the same elements, levers and
    drive, in the same order, differing only in values, η, ratios and amplitude),
    e.g. a scene linearised at each crank angle.

    Parameters
    ----------
    circuits : sequence of Circuit
        The circuits, one per design.

    Returns
    -------
    Designs

    Raises
    ------
    InputError
        No circuits, or two of different topology (naming the first difference).
    """
    circuits = list(circuits)
    if not circuits:
        raise InputError("from_circuits needs at least one circuit")
    first = circuits[0]
    ref = network_shape(first)
    for i, c in enumerate(circuits[1:], start=1):
        if network_shape(c) != ref:
            raise InputError(f"circuit {i} ({c.name}) differs in topology from circuit 0 "
                             f"({first.name}): not designs of one network")
    values = np.array([[e.value for e in c.elements] for c in circuits], dtype=float).T
    etas = np.array([[e.eta for e in c.elements] for c in circuits], dtype=float).T
    ratios = np.array([[lv.ratio for lv in c.levers] for c in circuits], dtype=float).T
    amplitude = np.array([c.require_drive().amplitude for c in circuits], dtype=float)
    return Designs(first, {}, values, etas, ratios, amplitude,
                   _valid(values, etas, ratios, amplitude), None)


def _valid(values: NDArray, etas: NDArray, ratios: NDArray, amplitude: NDArray) -> NDArray:
    """The designs whose values form the template's network: every value, η, value·η and
    lever ratio positive and finite, and the drive's amplitude finite."""
    with np.errstate(all="ignore"):
        scaled = values * etas
        ok = np.isfinite(scaled) & (scaled > 0) & (values > 0) & (etas > 0)
    return ok.all(axis=0) & (np.isfinite(ratios) & (ratios > 0)).all(axis=0) & \
        np.isfinite(amplitude)


def _build(circuit: Circuit, text, exprs, arrays: dict, D: int) -> "Designs":
    """Every value of the circuit over the D designs, with the designs it cannot form."""
    from .expressions import evaluate_array

    arrays = {n: np.broadcast_to(a, (D,)).astype(float) for n, a in arrays.items()}
    bad = np.zeros(D, dtype=bool)
    for a in arrays.values():
        bad |= ~np.isfinite(a)

    def value(key, default):
        nonlocal bad
        if exprs is None or key not in exprs:
            return np.full(D, float(default))
        tree, factor = exprs[key]
        v, b = evaluate_array(tree, pvals, D)
        bad |= b
        return v * factor if factor != 1.0 else v

    pvals: dict = {}
    for name in circuit.params:
        pvals[name] = arrays[name] if name in arrays else value(("param", name),
                                                                 circuit.params[name])
    n_el = len(circuit.elements)
    values, etas = np.empty((n_el, D)), np.empty((n_el, D))
    for i, e in enumerate(circuit.elements):
        base, key = e.name, (e.name, "value")
        if exprs is not None and key not in exprs and e.name.endswith("_damping") \
                and (e.name[:-8], "damping") in exprs:
            base, key = e.name[:-8], (e.name[:-8], "damping")      # a spring's damping=
        values[i] = value(key, e.value)
        etas[i] = value((base, "eta"), e.eta)
        if e.kind == "spring" and exprs is not None and (e.name, "damping") in exprs:
            # damping= adds a damper where it is > 0: the topology must not change.
            comp = [f.value for f in circuit.elements if f.name == f"{e.name}_damping"]
            bad |= (value((e.name, "damping"), comp[0] if comp else 0.0) > 0) != bool(comp)
    ratios = np.array([value((lv.name, "ratio"), lv.ratio) for lv in circuit.levers]) \
        .reshape(len(circuit.levers), D)
    d = circuit.drive
    amplitude = value((d.name, d.kind), d.amplitude) if d is not None else np.zeros(D)
    bad |= ~_valid(values, etas, ratios, amplitude)
    return Designs(circuit, arrays, values, etas, ratios, amplitude, ~bad, text)


@dataclass(frozen=True, eq=False)
class Designs(Memos):
    """D designs of one circuit (see :func:`designs`): plain data, it pickles.

    Attributes
    ----------
    circuit : Circuit
        The template: the netlist with its own values.
    params : dict of str to ndarray
        The varied ``.param`` values, shape (D,).
    values, eta : ndarray, shape (E, D)
        Value [SI] and η of each of ``circuit.elements`` in each design.
    ratios : ndarray, shape (R, D)
        Ratio of each of ``circuit.levers``.
    amplitude : ndarray, shape (D,)
        The drive's amplitude (V0 [m/s] or F0 [N]).
    valid : ndarray of bool, shape (D,)
        The designs whose values form the template's network (every value
        positive and finite); the others are evaluated one by one
        (:meth:`design`), where parsing reports what is wrong.
    """

    __repr__ = summary_repr

    circuit: Circuit
    params: dict
    values: NDArray[np.float64]
    eta: NDArray[np.float64]
    ratios: NDArray[np.float64]
    amplitude: NDArray[np.float64]
    valid: NDArray[np.bool_]
    text: str | None = field(default=None, repr=False)

    @property
    def size(self) -> int:
        """D, the number of designs."""
        return self.valid.size

    def design(self, d: int) -> Circuit:
        """The :class:`~mechcirc.circuit.Circuit` of design ``d`` (the single-design path).

        From the netlist text when there is one (:func:`mechcirc.parse` with the
        design's ``params=``, so an invalid design raises its located error),
        else the template with the design's values.
        """
        if not (isinstance(d, (int, np.integer)) and -self.size <= d < self.size):
            raise InputError(f"design must be an index 0..{self.size - 1} of the {self.size} "
                             f"designs (a negative one counts from the end), got {brief(d)}")
        if self.text is not None:
            from .netlist import parse

            return parse(self.text, source=self.circuit.source,
                         params={n: float(a[d]) for n, a in self.params.items()})
        c = self.circuit
        return replace(
            c, elements=tuple(replace(e, value=float(self.values[i, d]),
                                      eta=float(self.eta[i, d]))
                              for i, e in enumerate(c.elements)),
            levers=tuple(replace(lv, ratio=float(self.ratios[i, d]))
                         for i, lv in enumerate(c.levers)),
            drive=None if c.drive is None else replace(c.drive,
                                                       amplitude=float(self.amplitude[d])))

    # -- the batched series–parallel plan ----------------------------------
    def plan(self, which: NDArray):
        """The template's plan with the values of designs ``which``, or None (not
        series–parallel); evaluated by the compiled kernel, or without it by numpy
        over the designs (:attr:`mechcirc.reduction.Plan.numpy`)."""
        # The last designs' plan is kept (a memo, never pickled): sweep, extremes and
        # resonances share it.
        key = which.tobytes()
        return self.memo("_plan_memo", lambda: (key, self._plan(which)),
                         lambda kept: kept[0] == key)[1]

    def _plan(self, which: NDArray):
        """:meth:`plan`, built."""
        try:
            tree = self.circuit.tree
        except NotSeriesParallelError:
            return None
        p = plan(tree)
        row = {e.name: i for i, e in enumerate(self.circuit.elements)}
        lev = {lv.name: i for i, lv in enumerate(self.circuit.levers)}
        rows = np.array([row[e.name] for e in p.leaves], dtype=np.int64)
        scaled = self.values[rows][:, which] * self.eta[rows][:, which]
        ratios = self.ratios[[lev[lv.name] for lv in p.levers]][:, which]
        return replace(p.with_values(scaled, ratios), numpy=(
            tree, {e.name: scaled[i][:, None] for i, e in enumerate(p.leaves)},
            {lv.name: ratios[i][:, None] for i, lv in enumerate(p.levers)}))

    def sweep(self, omega: ArrayLike) -> "DesignSweep":
        """K, Q0, v0, error bound and flags of every design at each ω [rad/s].

        The valid designs of a series–parallel network go through the compiled
        plan (without numba: numpy over the designs) in one pass, those of a
        nodal network stacked (:func:`_nodal_sweep`); the others (``DesignSweep.single``) through
        :func:`mechcirc.sweep` one by one.  Each row equals the single
        design's :class:`~mechcirc.Sweep` (K, error and flags).
        """
        omega = real_omega(omega)
        if not np.isfinite(omega).all() or (omega < 0).any():
            raise InputError("omega must be a one-dimensional array of finite values >= 0")
        D, W = self.size, omega.size
        batched = np.flatnonzero(self.valid)
        p = self.plan(batched) if batched.size else None
        if p is None:                   # not series–parallel: the nodal path, stacked
            batched, K, err = _nodal_sweep(self, batched, omega) if batched.size else \
                (batched, np.empty((0, W), dtype=complex), np.empty((0, W)))
        else:
            K, err = evaluate_designs(p, omega, error=True)
            K = singular_limits(K, omega[None, :])
        if batched.size < D:            # rows for the designs evaluated one by one below
            K, err = _spread(K, batched, D), _spread(err, batched, D)
        single = np.setdiff1d(np.arange(D), batched)
        alone, failed = _alone(self, single, lambda d, c: sweep_one(c, omega))
        for d in single.tolist():
            K[d], err[d] = (alone[d].K, alone[d].error) if d in alone else (np.nan, np.inf)
        return DesignSweep(omega, K, singular_error(K, err), self.circuit.require_drive().kind,
                           self.amplitude[:, None], single, failed)

    def resonances(self, omega_max: float | None = None) -> "DesignResonances":
        """Resonances and anti-resonances of every design up to ``omega_max`` [rad/s].

        Series–parallel designs: the nodal matrices of all designs formed at once
        from the stamps (:func:`mechcirc.nodal.stamps`); undamped, the pencils
        reduced by a batched Cholesky factorisation of the mass matrices and
        solved by one stacked ``eigvalsh`` call, every root polished by a batched
        secant on the design's own K(ω) (the plan, compiled or in numpy, with its error
        bound); damped, the companion matrices in one stacked ``eigvals`` call,
        every root polished by Newton on det(s²M + sD + K)
        (:func:`mechcirc.resonances.batched_roots`).  A network that is not
        series–parallel: the same stacked eigenproblems, every root polished as
        :func:`~mechcirc.resonances.find_resonances` polishes it, the complex
        secant on the design's own K(s) from the stacked nodal solve
        (:func:`_nodal_roots`); designs whose lever ratios differ from the template's
        each on a constraint basis of their own.  The others (an undamped mass matrix
        too close to singular, or a damped one that is singular beyond the reversed
        problem's reach, lever ratios whose constraints the template's pivots do not
        take, a mode in both the held and released problems) go through
        :func:`mechcirc.resonances.find_resonances` one by one (``single``).
        """
        D = self.size
        found = batched_roots(self, omega_max) or _nodal_roots(self, omega_max)
        none: NDArray = np.zeros(0, dtype=np.int64)
        which, pole, w, err = found if found is not None else (none,) * 4
        single = np.setdiff1d(np.arange(D), which)
        with warnings.catch_warnings(action="ignore"):
            alone, failed = _alone(self, single, lambda d, c: find_resonances(c, omega_max))
        R = max([w.shape[1] if w.ndim == 2 else 0] + [len(v) for v in alone.values()])
        live, kind = np.isfinite(w), np.full((D, R), "", dtype="<U13")
        out, count = np.full((4, D, R), np.nan), np.zeros(D, dtype=np.int64)
        if which.size:
            r = w.shape[1]
            count[which] = live.sum(axis=1)
            kind[which, :r] = np.where(live, np.where(pole, "antiresonance", "resonance"), "")
            with np.errstate(all="ignore"):             # w: the roots s, as _make reads them
                out[:, which, :r] = np.abs(w), np.abs(w.imag), -w.real / np.abs(w) + 0.0, err
        for d, roots in alone.items():
            count[d] = len(roots)
            for i, x in enumerate(roots):
                kind[d, i] = x.kind
                out[:, d, i] = x.omega, x.omega_d, x.zeta, x.error
        return DesignResonances(kind, out[0], out[1], out[2], out[3], count, omega_max,
                                single, failed)

    def extremes(self, omega: ArrayLike, resonances: "DesignResonances | None" = None,
                 sweep: "DesignSweep | None" = None) -> "DesignExtremes":
        """The true extremes of |K| and |Q0| over the band [min ω, max ω] of every design.

        Undamped designs: K = jX with X increasing between its poles (Foster's
        reactance theorem), so |K| is 0 at a resonance in the band, ∞ at an
        anti-resonance, and otherwise takes its extremes at the band's ends;
        |Q0| = |V0|/|K| likewise (velocity drive; a force drive's Q0 is F0).  The
        others: :func:`mechcirc.peak` on the single design (``single``).
        ``sweep``, this band's :meth:`sweep` already made, gives K at the band's
        ends (else they are evaluated).
        """
        if not isinstance(resonances, (DesignResonances, type(None))):
            raise TypeError(f"extremes(omega, resonances=None, sweep=None): resonances must be "
                            f"a DesignResonances (.resonances()), got {resonances!r}; the band "
                            "is omega: extremes([lo, hi])")
        omega = real_omega(omega)
        lo, hi = float(omega.min()), float(omega.max())
        if resonances is None:
            resonances = self.resonances(omega_max=hi * (1 + 1e-9))
        ends = None
        if sweep is not None and sweep.K.shape[0] == self.size:
            i, j = int(np.argmin(sweep.omega)), int(np.argmax(sweep.omega))
            if sweep.omega[i] == lo and sweep.omega[j] == hi:
                ends = sweep.K[:, [i, j]]
        return _extremes(self, lo, hi, resonances, ends)


#: Designs stacked on the nodal path at a time: their D + C, M and Kₛ hold at most
#: this many entries each (2²¹: 48 MB for the three).
_STACK_ENTRIES = 2 ** 21


def _nodal_sweep(ds: Designs, which: NDArray, omega: NDArray):
    """K and its error bound of designs ``which`` of a network that is not
    series–parallel, by the nodal path of :func:`mechcirc.nodal.solve` with the
    designs' A(ω) stacked: one batched inverse per chunk of (design, ω) points, each
    refined by :func:`mechcirc.nodal.refine_dd` with the residual and sensitivities
    of :class:`~mechcirc._nodal_residual.Pattern` at the design's values.

    Only small systems (the single path's dense solver) and ω > 0 (each design with its
    own lever ratios); a design with a point the single path would treat further (no
    contracting refinement: the double-double LU; a singular point) is left out.
    Returns ``(designs solved, K, error)``, shapes (D',), (D', W), (D', W).
    """
    from ._nodal_solvers import solver

    none = (which[:0], np.empty((0, omega.size), complex), np.empty((0, omega.size)))
    try:
        system = ds.circuit.nodal
    except MechcircError:                    # each design alone says what is wrong
        return none
    n, W = system.size, omega.size
    if solver(system).kind != "dense" or not which.size or not (omega > 0).all():
        return none
    group = max(1, _STACK_ENTRIES // (n * n))
    if which.size > group:
        out = [_nodal_sweep(ds, which[i:i + group], omega) for i in range(0, which.size, group)]
        return tuple(np.concatenate(x) for x in zip(*out))
    S, parts, levers = _stacked_matrices(ds, system, which)
    design, w = np.repeat(np.arange(which.size), W), np.tile(omega, which.size)
    K, e, rounding, _ = _stacked_solve(system, S, parts, design, w, levers)
    eps = np.finfo(float).eps
    with np.errstate(invalid="ignore"):
        done = (e <= np.maximum(16 * eps, 16 * rounding)) & np.isfinite(K)
        e = np.maximum(e + rounding + eps / 2, eps)
    err = np.where(done & (e < 1.0), e, np.nan)
    K, err = K.reshape(-1, W), err.reshape(-1, W)
    ok = ~np.isnan(err).any(axis=1)
    return which[ok], K[ok], err[ok]


def _stacked_solve(system, S: NDArray, parts: list, design: NDArray, w: NDArray, levers):
    """The refined nodal solve of :func:`mechcirc.nodal.solve` at points (design, ω) of
    stacked designs: ``S``, ``parts`` and ``levers`` from :func:`_stacked_matrices`,
    ``design[i]`` the row of point i in them, ``w[i]`` its ω (real, or complex: ω = −js
    for the resonances' polishing).  One batched inverse per chunk, each solution refined by
    :func:`mechcirc.nodal.refine_dd` with the residual and sensitivities of
    :class:`~mechcirc._nodal_residual.Pattern` at the design's values.

    Returns ``(K, estimate, rounding, S_data)`` per point as the single path's
    ``nodal._sweep`` has them before its singular-point treatment (the estimate
    infinite where the refinement did not contract and it exceeds 16 roundings); K
    NaN where A is exactly singular.
    """
    from . import nodal
    from ._dd import split
    from ._nodal_residual import pattern, residual_rounding
    from ._nodal_solvers import stacked_inverse

    n, m = system.size, design.size
    pat, rhs = pattern(system), system.injection()
    _ = pat.slot_plan           # (made once, before the copies below share it)
    K = np.full(m, complex(np.nan, np.nan))
    est, rho = np.full(m, np.inf), np.zeros(m)
    sens, sens_data = np.full(m, np.nan), np.full(m, np.nan)

    with np.errstate(all="ignore"):          # the Pattern's element and lever tables
        tables = (S, *split(S), *(np.where(pat.e_kind == i, S, 0.0) for i in range(3)),
                  levers[0], *split(levers[0]), levers[1])

    # Chunks as the single path's (nodal._sweep): the same memory per chunk.  The compiled
    # residual (real ω, each point's own element values) gives numpy's bits; the rest of
    # the refinement stays numpy's, as the single path's dense solve has it.
    chunk = max(1, min(2 ** 21 // (n * n), nodal._CHUNK_TERMS // (pat.n_terms + n)))
    kern = None if np.iscomplexobj(w) else nodal.kernels(n * m)
    for start in range(0, m, chunk):
        pts = np.arange(start, min(start + chunk, m))
        dc, ms, ks = (X[design[pts]] for X in parts)
        A = nodal.combine(dc, ms, ks, w[pts, None, None])
        # A point exactly singular: NaN there, the others kept, as the single
        # path's dense solver does.
        inv, good = stacked_inverse(A)
        if good is not None:
            pts, inv = pts[good], inv[good]
            if not pts.size:
                continue
        # The chunk's tables once; the refinement's points by their place in the chunk.
        local, wl, every = [t[design[pts]] for t in tables], w[pts], np.arange(pts.size)
        xh, xl, est[pts], rho[pts] = nodal.refine_dd(
            lambda r, rows=slice(None), inv=inv: np.einsum("kij,kj->ki", inv[rows], r),
            lambda p, xh, xl, rhs, local=local, wl=wl: _values_at(pat, local, p).residual(
                wl[p], xh, xl, rhs, kern), every, rhs, system, True, 4)
        K[pts] = nodal.difference_dd(system, xh, xl)
        sens[pts], sens_data[pts] = _values_at(pat, local, every).sensitivities(
            wl, xh + xl, K[pts])
    rounding = residual_rounding(system, sens)
    return K, np.where((rho >= 0.5) & (est > 16 * rounding), np.inf, est), rounding, sens_data


def _values_at(pat, local: list, p: NDArray):
    """A copy of the pattern ``pat`` at the values of points ``p`` of a chunk whose tables
    are ``local`` (:func:`_stacked_solve`'s: value·η, its two halves, by kind; each lever
    stamp's value, its two halves; each lever's |ratio|): all of them without a copy."""
    from copy import copy

    v = copy(pat)
    whole = p.size == local[0].shape[0]
    (v.e_val, high, low, v.e_m, v.e_k, v.e_c, v.s_val, s_high, s_low,
     v.l_r) = (t if whole else t[p] for t in local)
    v.e_vs, v.s_vs = (high, low), (s_high, s_low)
    return v


def _nodal_roots(ds: Designs, omega_max):
    """:func:`mechcirc.resonances.batched_roots` for a network that is not
    series–parallel: the roots of the valid designs (each with its own lever ratios),
    stacked in groups of :data:`_STACK_ENTRIES`; None when it solves none.

    Each group: the stacked eigenproblems of :func:`~mechcirc.resonances.stacked_problem`
    (drive held: resonances; released: anti-resonances), every root then polished as
    :func:`~mechcirc.resonances.find_resonances` polishes it (:func:`_polish_nodal`).
    Returns ``(designs, pole, s, error)`` as ``batched_roots`` does.
    """
    from . import nodal
    from ._nodal_solvers import DENSE_LIMIT

    try:
        try:
            _ = ds.circuit.tree
            return None                      # series–parallel: batched_roots takes it
        except NotSeriesParallelError:
            system = ds.circuit.nodal
            held = nodal.held(system)
    except MechcircError:                    # each design alone says what is wrong
        return None
    which = np.flatnonzero(ds.valid)
    if not which.size or held.size > DENSE_LIMIT:
        return None
    group = max(1, _STACK_ENTRIES // (held.size * held.size))
    # One basis for all when every lever ratio is the template's, else one per design
    # (decided for all the designs: the groups then give what one group gives).
    shared = template_levers(ds, system, which).size == which.size
    found = [f for f in (_nodal_group_roots(ds, system, held, which[i:i + group], omega_max,
                                            shared)
                         for i in range(0, which.size, group)) if f is not None]
    if not found:
        return None
    R = max(f[2].shape[1] for f in found)

    def pad(x, fill):
        return np.concatenate([np.pad(f[x], ((0, 0), (0, R - f[x].shape[1])),
                                      constant_values=fill) for f in found])
    return (np.concatenate([f[0] for f in found]), pad(1, False),
            pad(2, complex(np.nan, np.nan)), pad(3, np.nan))


def _nodal_group_roots(ds: Designs, system, held, which: NDArray, omega_max, shared: bool):
    """:func:`_nodal_roots` for one group of designs ``which`` (``shared``: one constraint
    basis for all, :func:`_group_basis`)."""
    *_, G_released, G_held, damped = pencil(system)
    B = element_patterns(system)
    S, parts, levers = _stacked_matrices(ds, system, which)
    bases = [_group_basis(ds, system, G, which, shared) for G in (G_held, G_released)]
    roots = [_pencil_roots(Z, B, S, damped, omega_max, exact) for Z, exact, _ in bases]
    if None in roots:
        return None
    (s_h, e_h, ok_h, must_h), (s_r, e_r, ok_r, must_r) = roots
    ok_h, ok_r = ok_h & bases[0][2], ok_r & bases[1][2]
    # A mode in both problems cancels in K (resonances._cancel): the single path's.
    keep = np.flatnonzero(shared_roots_free(((s_h, e_h, ok_h), (s_r, e_r, ok_r)), damped,
                                            must_h | must_r, design_verdict(ds, which)))
    if not keep.size:
        return None
    pole, s0, e0 = held_and_released(s_h[keep], s_r[keep], e_h[keep], e_r[keep])
    must = np.concatenate([np.repeat(must_h[keep, None], s_h.shape[1], 1),
                           np.repeat(must_r[keep, None], s_r.shape[1], 1)], axis=1)
    have = np.isfinite(s0)
    todo = have & (must | (e0 > POLISH_BELOW)) if not damped else have
    s, err = s0.copy(), e0.copy()
    if todo.any():
        d, r = np.nonzero(todo)
        stacks = [(system, S, parts, levers), (held, *_stacked_matrices(ds, held, which))]
        s[d, r], err[d, r] = _polish_nodal(stacks, keep[d], s0[d, r], pole[d, r], e0[d, r],
                                           damped, row_spacing(s0, pole)[d, r])
    s, err = settled(s, err, damped), np.maximum(err, np.finfo(float).eps)
    if omega_max is not None:
        s = np.where(np.abs(s) <= omega_max, s, np.nan)
    return (which[keep], *sorted_roots(pole, s, err))


def _group_basis(ds: Designs, system, G, which: NDArray, shared: bool):
    """``(Z, exact, ok)``: the basis of the constraint rows ``G`` for designs ``which``,
    the template's (n, k) where their lever ratios are ``shared`` (``exact``: see
    :func:`mechcirc.resonances.exact_basis`), else one per design (D', n, k) by
    :func:`mechcirc.resonances.design_bases`, ``ok`` false where a design's pivots are
    ill-conditioned or its constraints have a rank the template's have not (the single
    path takes it)."""
    if shared:
        return constraint_basis(G, len(system.nodes)).toarray(), exact_basis(G), True
    Z, ok = design_bases(ds, system, G, which)
    return Z, False, ok


def _pencil_roots(Z, B: dict, S, damped: bool, omega_max, exact: bool = True):
    """``(roots, errors, ok, must polish)`` on basis ``Z``, one for all (n, k) or one per
    design (D, n, k) (``exact``: see :func:`mechcirc.resonances.exact_basis`); None: too big."""
    if Z.shape[-1] > (MAX_UNKNOWNS_DAMPED if damped else MAX_UNKNOWNS):
        return None
    x, e, ok = stacked_problem(Z, B, S, damped, omega_max)
    if damped:                      # find_resonances polishes every damped root
        return x, e, ok, np.ones(S.shape[0], dtype=bool)
    # _undamped's bound eps·λmax/λ stands (no polishing below POLISH_BELOW)
    # only for a diagonal mass matrix without massless directions, on an exact basis.
    return 1j * x, e, ok, (unbounded(Z, B, S, exact) if Z.ndim == 2 else   # a design's
                           np.ones(S.shape[0], dtype=bool))      # own basis: no bound


def _polish_nodal(stacks: list, design: NDArray, s0: NDArray, pole: NDArray, e0: NDArray,
                  damped: bool, spacing=np.inf):
    """:func:`mechcirc.resonances.secant_polish` for roots of many designs: the root ``s0[i]``
    of the design in row ``design[i]`` of the stacks polished by the complex secant on
    its own K(s) (anti-resonances ``pole``: on 1/K = −q of the held system), g and its
    bound by :func:`mechcirc.resonances.g_and_bound`, from :func:`_stacked_solve` at
    every root at once.  ``stacks``: ``(system, S, parts, levers)`` of the network and of
    its drive-held system (:func:`_stacked_matrices`).  Returns ``(s, relative error)``.
    """
    from ._nodal_residual import total_error

    def evaluate(x, i, want):
        sys_, S, parts, levers = stacks[i]
        K, est, rounding, sens_data = _stacked_solve(sys_, S, parts, design[want], -1j * x[want],
                                                     levers)
        with np.errstate(all="ignore"):
            return K, total_error(sens_data, est + rounding) * np.abs(K)

    return secant_polish(lambda x: g_and_bound(pole, lambda i, want: evaluate(x, i, want),
                                               np.isfinite(x)), s0, e0, damped, spacing)


def _stacked_matrices(ds: Designs, system, which: NDArray):
    """The value·η of the nodal system's elements in designs ``which`` (D', E), their
    D + C, M and Kₛ as dense stacks (D', n, n) from the element stamp patterns, and the
    designs' levers ``(value of each lever stamp (D', stamps), |ratio| of each lever
    (D', levers))`` from which their C is stamped."""
    S = design_values(ds, system, which)
    B, n, nn = element_patterns(system), system.size, len(system.nodes)
    parts = []
    for kind in ("damper", "mass", "spring"):
        X = np.zeros((which.size, n, n))
        X[:, :nn, :nn] = (S @ B[kind].reshape(S.shape[1], -1)).reshape(-1, nn, nn)
        parts.append(X)
    levers = design_lever_values(ds, system, which)
    for t, (r, c) in enumerate(zip(*system.stamps["lever"][:2])):    # (a few stamps)
        parts[0][:, r, c] += levers[0][:, t]
    return S, parts, levers


def _alone(ds: Designs, which: NDArray, compute) -> tuple[dict, dict[int, str]]:
    """``compute(d, circuit)`` of each design ``d`` of ``which`` on the single-design path
    (:meth:`Designs.design`): the results and the messages of those that fail, by design."""
    results: dict = {}
    failed: dict[int, str] = {}
    for d in which.tolist():
        try:
            results[d] = compute(d, ds.design(d))
        except MechcircError as exc:
            failed[d] = str(exc)
    return results, failed


def _spread(rows: NDArray, where: NDArray, D: int) -> NDArray:
    """``rows`` placed at rows ``where`` of a (D, ...) array (the others unset)."""
    out = np.empty((D, *rows.shape[1:]), dtype=rows.dtype)
    out[where] = rows
    return out


@dataclass(frozen=True, eq=False)
class DesignSweep:
    """K and the drive's quantities of D designs on W frequencies (plain data).

    Attributes
    ----------
    omega : ndarray, shape (W,)
        [rad/s].
    K : ndarray of complex, shape (D, W)
        [m/(N·s)]; NaN in the rows of ``failed``.
    error : ndarray, shape (D, W)
        Bound of the relative error of K (inf on a pole or zero).
    kind : {"velocity", "force"}
        The drive's kind (V0 [m/s] or F0 [N]).
    amplitude : ndarray, shape (D, 1)
        The drive's amplitude.
    single : ndarray of int
        The designs evaluated one by one (not through the batch).
    failed : dict of int to str
        Designs that could not be evaluated, with the error message.
    """

    __repr__ = summary_repr

    omega: NDArray[np.float64]
    K: NDArray[np.complex128]
    error: NDArray[np.float64]
    kind: str
    amplitude: NDArray[np.float64]
    single: NDArray[np.int64]
    failed: dict

    @property
    def Q0(self) -> NDArray[np.complex128]:
        """Force amplitude at the drive [N], shape (D, W)."""
        return drive_force(self.K, self.kind, self.amplitude)

    @property
    def v0(self) -> NDArray[np.complex128]:
        """Velocity amplitude at the drive [m/s], shape (D, W)."""
        return drive_velocity(self.K, self.kind, self.amplitude)

    @property
    def flags(self) -> NDArray[np.int8]:
        """Per-point flags as :attr:`mechcirc.Sweep.flags`, shape (D, W)."""
        # The drive's own quantity is its amplitude at every ω: not formed in full.
        if self.kind == "velocity":
            return point_flags(self.K, self.Q0, self.amplitude, self.error)
        return point_flags(self.K, self.amplitude, self.v0, self.error)


@dataclass(frozen=True, eq=False)
class DesignResonances:
    """The resonances of D designs, as padded arrays (plain data).

    Row d holds design d's roots sorted as :func:`~mechcirc.resonances.find_resonances`
    sorts them, ``count[d]`` of them; the rest of the row is NaN (``kind`` "").

    Attributes
    ----------
    kind : ndarray of str, shape (D, R)
        "resonance" (K = 0) or "antiresonance" (K = ∞).
    omega, omega_d, zeta, error : ndarray, shape (D, R)
        As in :class:`~mechcirc.resonances.Resonance`.
    count : ndarray of int, shape (D,)
        Number of roots found in each design (the first ``count[d]`` columns).
    omega_max : float or None
        Upper end of the band searched [rad/s]; None: no upper end.
    single : ndarray of int
        The designs solved one by one by ``find_resonances``.
    failed : dict of int to str
        Designs whose resonances could not be found, with the message.
    """

    __repr__ = summary_repr

    kind: NDArray
    omega: NDArray[np.float64]
    omega_d: NDArray[np.float64]
    zeta: NDArray[np.float64]
    error: NDArray[np.float64]
    count: NDArray[np.int64]
    omega_max: float | None
    single: NDArray[np.int64]
    failed: dict

    def list(self, d: int) -> list:
        """Design ``d``'s roots as :class:`~mechcirc.resonances.Resonance` objects."""
        return [Resonance("antiresonance" if self.kind[d, i] == "antiresonance" else
                          "resonance", float(self.omega[d, i]),
                          float(self.omega_d[d, i]), float(self.zeta[d, i]),
                          float(self.error[d, i])) for i in range(int(self.count[d]))]


@dataclass(frozen=True, eq=False)
class DesignExtremes:
    """Extremes of |K| and |Q0| over a band, per design (shape (D,) each).

    ``K_min``/``K_max`` [m/(N·s)] and ``Q0_max`` [N] are the true values over
    [``omega_min``, ``omega_max``] (0 or inf where K has a zero or pole in the
    band), ``omega_at_*`` where they occur [rad/s] (the first resonance or
    anti-resonance when the value is 0 or inf); NaN for ``failed`` designs.  ``units``:
    the drive's unit labels (:func:`mechcirc.circuit.units_of`; N·m for a rotary drive).
    """

    __repr__ = summary_repr

    K_min: NDArray[np.float64]
    omega_at_K_min: NDArray[np.float64]
    K_max: NDArray[np.float64]
    omega_at_K_max: NDArray[np.float64]
    Q0_max: NDArray[np.float64]
    omega_at_Q0_max: NDArray[np.float64]
    single: NDArray[np.int64]
    failed: dict
    units: dict = field(default_factory=lambda: units_of(None))

    def to_dataframe(self):
        """One row per design: ``K_min``, ``K_max`` [m/(N·s)], ``Q0_max`` [N] (rad/(N·m·s),
        N·m for a rotary drive), each ``omega_at_*`` [rad/s], and ``failed``, why the
        design failed ("" if it did not); ``attrs["units"]`` the unit of each column."""
        cols = {name: getattr(self, name) for name in _EXTREMES}
        cols["failed"] = [self.failed.get(d, "") for d in range(len(self.K_min))]
        units = {"K_min": self.units["K"], "K_max": self.units["K"], "Q0_max": self.units["Q"],
                 "failed": ""}
        return data_frame(cols, {c: units.get(c, "rad/s") for c in cols})


#: The arrays of :class:`DesignExtremes`, one value per design.
_EXTREMES = ("K_min", "omega_at_K_min", "K_max", "omega_at_K_max", "Q0_max", "omega_at_Q0_max")


def _searched_extremes(ds: Designs, which: NDArray, lo: float, hi: float,
                       res: DesignResonances) -> tuple[NDArray, dict]:
    """The extremes of damped series–parallel designs ``which``, located as
    :func:`mechcirc.peak` locates them (its 401-point grid, the band's ends, a
    bracket around the grid's best point and one of four half-power bandwidths
    around each damped root of the kind that makes the quantity peak) with every
    design's brackets searched at once by :func:`mechcirc._sweep.golden_max`, as
    ``peak`` searches one design's, on the designs' own K (the plan at
    per-design points).  Left out: all, if ``res`` does not reach the
    band's top; designs with a lossless root in the band, or a K that is 0 or not
    finite where searched (``peak`` calls those unbounded).  Returns
    ``(designs solved, {extreme: values})``.
    """
    covered = res.omega_max is None or res.omega_max >= hi
    p = ds.plan(which) if which.size and covered else None
    if p is None:
        return which[:0], {}
    grid = peak_grid(lo, hi)
    absK = np.abs(evaluate_designs(p, np.concatenate([grid, [lo, hi]]))[0])
    ok = (np.isfinite(absK) & (absK > 0)).all(axis=1)
    live = res.count[which, None] > np.arange(res.omega.shape[1])
    with np.errstate(invalid="ignore"):
        w, wd, zeta = res.omega[which], res.omega_d[which], res.zeta[which]
        band = live & (w >= lo * (1 - 1e-12)) & (w <= hi * (1 + 1e-9))
    found: dict = {}
    for quantity, kind, sign in (("K", "antiresonance", 1), ("S", "resonance", -1)):
        roots = band & (res.kind[which] == kind)
        ok &= ~(roots & (zeta <= UNDAMPED_ZETA)).any(axis=1)
        with np.errstate(divide="ignore"):     # |K| = 0: those designs are not ok
            q = absK ** sign
        i = np.argmax(q[:, :-2], axis=1)
        ra, rb = root_brackets(w, wd, zeta)
        a = np.maximum(np.column_stack([grid[np.maximum(i - 1, 0)], ra]), lo)
        b = np.minimum(np.column_stack([grid[np.minimum(i + 1, grid.size - 1)], rb]), hi)
        use = np.column_stack([np.ones(which.size, bool), roots]) & (a < b)
        with np.errstate(divide="ignore", invalid="ignore"):
            x, v = golden_max(lambda om, sign=sign: np.abs(evaluate_designs(p, om)[0]) ** sign,
                              np.where(use, a, lo), np.where(use, b, hi))
        ok &= (np.isfinite(v) | ~use).all(axis=1)
        # peak's order: the grid's best, the band's ends, then each bracket in turn
        value, omega = q[np.arange(which.size), i], grid[i]
        for col, at in ((-2, lo), (-1, hi)):
            take = ~(value >= q[:, col])
            value, omega = np.where(take, q[:, col], value), np.where(take, at, omega)
        for r in range(x.shape[1]):
            take = use[:, r] & (v[:, r] > value)
            value, omega = np.where(take, v[:, r], value), np.where(take, x[:, r], omega)
        found[quantity] = value, omega
    (kmax, w_kmax), (smax, w_smax) = found["K"], found["S"]
    amp, force = np.abs(ds.amplitude[which]), ds.circuit.require_drive().kind == "force"
    out = {"K_max": kmax, "omega_at_K_max": w_kmax, "K_min": 1.0 / smax,
           "omega_at_K_min": w_smax, "Q0_max": amp if force else amp * smax,
           "omega_at_Q0_max": np.full(which.size, lo) if force else w_smax}
    return which[ok], {k: v[ok] for k, v in out.items()}


def _extremes(ds: Designs, lo: float, hi: float, res: DesignResonances,
              ends: NDArray | None) -> DesignExtremes:
    D = ds.size
    out = {k: np.full(D, np.nan) for k in _EXTREMES}
    with np.errstate(invalid="ignore"):
        undamped = np.where(res.count[:, None] > np.arange(res.omega.shape[1])[None, :],
                            res.zeta <= UNDAMPED_ZETA, True).all(axis=1)
    fast = np.flatnonzero(~np.isin(np.arange(D), res.single) & undamped)
    failed = dict(res.failed)
    if fast.size:
        if ends is None:
            ends = ds.sweep(np.array([lo, hi])).K
        Ke, amp = np.abs(ends[fast]), np.abs(ds.amplitude[fast])
        with np.errstate(invalid="ignore"):
            in_band = (res.omega[fast] >= lo * (1 - 1e-12)) & \
                (res.omega[fast] <= hi * (1 + 1e-9))
        for kind, name in (("resonance", "min"), ("antiresonance", "max")):
            hit = in_band & (res.kind[fast] == kind)
            if hit.shape[1] == 0:                     # no design has a root at all
                first, w_first = np.full(fast.size, -1), np.full(fast.size, np.nan)
            else:
                first = np.where(hit.any(axis=1), np.argmax(hit, axis=1), -1)
                w_first = np.where(first >= 0, res.omega[fast, np.maximum(first, 0)], np.nan)
            pick = np.argmin(Ke, axis=1) if name == "min" else np.argmax(Ke, axis=1)
            singular = 0.0 if name == "min" else np.inf
            out[f"K_{name}"][fast] = np.where(first >= 0, singular, Ke[np.arange(fast.size), pick])
            out[f"omega_at_K_{name}"][fast] = np.where(first >= 0, w_first, np.where(pick, hi, lo))
        if ds.circuit.require_drive().kind == "force":
            out["Q0_max"][fast] = amp
            out["omega_at_Q0_max"][fast] = lo
        else:
            with np.errstate(divide="ignore"):
                out["Q0_max"][fast] = amp / out["K_min"][fast]
            out["omega_at_Q0_max"][fast] = out["omega_at_K_min"][fast]
    rest = np.setdiff1d(np.flatnonzero(~np.isin(np.arange(D), list(res.failed))), fast)
    searched, found = _searched_extremes(ds, rest, lo, hi, res)
    for name, values in found.items():
        out[name][searched] = values
    rest = np.setdiff1d(rest, searched)

    def peaks(d, c):
        # The design's resonances once for all three (omega_max None: all of them).
        found = res.list(d) if res.omega_max is None or res.omega_max >= hi else None
        return [peak(c, lo, hi, quantity=q, resonances=found) for q in ("K", "S", "Q0")]

    done, more = _alone(ds, rest, peaks)
    failed.update(more)
    for d, (kmax, smax, qmax) in done.items():
        out["K_max"][d], out["omega_at_K_max"][d] = kmax.value, kmax.omega
        out["K_min"][d] = 1.0 / smax.value if smax.value else math.inf
        out["omega_at_K_min"][d] = smax.omega
        out["Q0_max"][d], out["omega_at_Q0_max"][d] = qmax.value, qmax.omega
    return DesignExtremes(**out, single=rest, failed=failed,
                          units=units_of(ds.circuit.require_drive()))
