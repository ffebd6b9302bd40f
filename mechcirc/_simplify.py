"""Model only what the output needs in a band: reduce a netlist, measure the error.

Given a circuit, a band [W1, W2] [rad/s], a tolerance T and an output (K at
the drive, or the force in one element), :func:`simplify` removes or merges
what does not matter for that output in that band:

* exact steps: elements on no path between the drive's nodes (they carry no
  force) and elements whose two ends became one node are removed; same-kind
  elements in parallel merge (S adds: Σ value·η); same-kind elements in series
  through a node with nothing else on it merge (K adds: 1/Σ 1/(value·η));
* approximate steps, kept only while the *measured* error stays ≤ T: springs
  stiff enough to act as rigid are shorted (their nodes merged; the masses
  there then merge exactly), and masses, springs and dampers that matter too
  little are removed.  Candidates are ordered by their share of the drive's
  power over the band, max |v_e·Q_e| / |v0·Q0| (from one sweep of the
  current circuit), and accepted as the longest prefix of that order whose
  measured error is ≤ T (a bisection: O(log n) trial circuits); rounds repeat
  on the reduced circuit until one accepts nothing.

The error is measured, never estimated: the output of the reduced and the
full circuit are evaluated on the check grid — ``points`` log-spaced
frequencies over the band plus, for each resonance and anti-resonance of the
full circuit in the band, the frequencies ω₀(1 ± 10⁻³) beside it — and the
worst relative error max |y_red − y_full| / |y_full| is reported.  Points
where the full output is exactly 0 or infinite are left out (and counted).
Between check points the error is not measured; near an undamped resonance
the relative error is large for any shift of it, which is why resonance
shifts are reported separately.

The output element is never removed or merged.  Levers follow merged nodes;
a lever with nothing on one side carries no force and is removed (exact).
"""

from __future__ import annotations

import math
import time
import warnings
from dataclasses import dataclass, replace

import numpy as np

from .circuit import FRAME, Circuit, Element
from .errors import BandError, MechcircError, TopologyError, UnloadedElementWarning
from .netlist_writer import write as write_netlist      # the package's one netlist writer
from .sources import did_you_mean, summary_repr
from .units import parse_omega

__all__ = ["BandError", "Simplified", "simplify", "parse_band", "check_band", "write_netlist"]


def parse_band(text: str) -> tuple[float, float]:
    """``"W1:W2"`` → (W1, W2) [rad/s], with 0 < W1 < W2 finite.

    Parameters
    ----------
    text : str
        The band as ``W1:W2``, each a number with an optional unit of angular
        frequency (as ``--omega-min``).

    Returns
    -------
    tuple of float
        (W1, W2) [rad/s].

    Raises
    ------
    BandError
    """
    parts = str(text).split(":")
    if len(parts) != 2:
        raise BandError(f"band {text!r} is not W1:W2 (two angular frequencies in rad/s)")
    try:
        w1, w2 = parse_omega(parts[0]), parse_omega(parts[1])     # 1Hz:50Hz as 10:2000
    except ValueError as exc:
        raise BandError(f"band {text!r}: {exc}") from None
    return check_band((w1, w2))


def check_band(band) -> tuple[float, float]:
    """(W1, W2) as floats, checked: finite, 0 < W1 < W2 [rad/s].

    Raises
    ------
    BandError
    """
    try:
        w1, w2 = (float(x) for x in band)
    except (TypeError, ValueError):
        raise BandError(f"band must be two angular frequencies (W1, W2) [rad/s], got "
                        f"{band!r}") from None
    if not (math.isfinite(w1) and math.isfinite(w2)):
        raise BandError(f"band limits must be finite, got {w1:g}:{w2:g}")
    if w1 >= w2:
        raise BandError(f"band W1 = {w1:g} rad/s is not below W2 = {w2:g} rad/s (need W1 < W2)")
    if w1 <= 0:
        raise BandError(f"band W1 = {w1:g} rad/s must be > 0 (masses have K = ∞ at ω = 0)")
    return w1, w2




@dataclass(frozen=True, eq=False)
class Simplified:
    """A reduced circuit with its measured error against the full one.

    Attributes
    ----------
    circuit, full : Circuit
        Reduced and full circuits.
    band : tuple of float
        (W1, W2) [rad/s].
    tol : float
        The tolerance asked for [1].
    output : str or None
        Element whose force is the output; None for K at the drive.
    error : float
        Measured worst relative error of the output over the check grid [1], ≤ tol.
    points : int
        Number of check points used (``skipped`` more were exactly on a zero or pole).
    steps : tuple of str
        What was removed or merged, in order.
    shifts : list of dict
        Each resonance/anti-resonance of the full circuit in the band: ``kind``,
        ``full`` and ``reduced`` ωₙ [rad/s] (None if gone) and ``relative_shift``.
    netlist : str
        The reduced circuit as ``.mcir`` text.
    seconds : float
        Time spent [s].
    """

    __repr__ = summary_repr

    circuit: Circuit
    full: Circuit
    band: tuple
    tol: float
    output: str | None
    error: float
    points: int
    skipped: int
    steps: tuple
    shifts: list
    netlist: str
    seconds: float = 0.0
    trials: int = 0

    @property
    def elements_before(self) -> int:
        return len(self.full.elements)

    @property
    def elements_after(self) -> int:
        return len(self.circuit.elements)

    def as_dict(self) -> dict:
        return {"band": list(self.band), "tol": self.tol, "output": self.output,
                "error": self.error, "points": self.points, "skipped_points": self.skipped,
                "elements_before": self.elements_before, "elements_after": self.elements_after,
                "levers": len(self.circuit.levers), "steps": list(self.steps),
                "resonances": self.shifts, "trials": self.trials, "seconds": self.seconds,
                "netlist": self.netlist}


# ----------------------------------------------------------------- helpers
def _trial_sweep(circuit: Circuit, omega):
    """The sweep of a trial circuit: one that leaves an element without load is measured
    (and refused), not warned about (the user was told of a trial's unloaded output)."""
    with warnings.catch_warnings(action="ignore", category=UnloadedElementWarning):
        return circuit.sweep(omega)


def _output(circuit: Circuit, omega, output):
    s = _trial_sweep(circuit, omega)
    with np.errstate(all="ignore"):
        return s.K if output is None else s.force(output)


def _unique(name, taken):
    n, k = name, 1
    while n in taken:
        k += 1
        n = f"{name}_{k}"
    taken.add(n)
    return n


def _exact(elements, levers, drive, protect, steps, taken):
    """Apply the exact clean-ups until none applies; returns (elements, levers)."""
    levers, changed = list(levers), True
    while changed:
        fixed = {FRAME, drive.n1, drive.n2} | {n for lv in levers
                                              for n in lv.terminals}
        elements, c1 = _drop_self_loops(elements, protect, steps)
        levers, c2 = _drop_idle_levers(elements, levers, drive, steps)
        elements, levers, c3 = _drop_unloaded(elements, levers, drive, protect, steps)
        elements, c4 = _merge_parallel(elements, protect, steps, taken)
        elements, c5 = _merge_series(elements, fixed, protect, steps, taken)
        changed = c1 or c2 or c3 or c4 or c5
    return elements, levers


def _drop_self_loops(elements, protect, steps):
    """Remove elements whose two ends are one node (they carry no force)."""
    keep = [e for e in elements if e.n1 != e.n2 or e.name in protect]
    if len(keep) == len(elements):
        return elements, False
    gone = [e.name for e in elements if e not in keep]
    steps.append(f"removed {_some(gone)}: both ends on one node")
    return keep, True


def _drop_idle_levers(elements, levers, drive, steps):
    """Remove each lever with nothing on one side: it transmits no force (Q_P = r·Q_S = 0)."""
    kept = list(levers)
    for lv in levers:
        used = {drive.n1, drive.n2} | {n for e in elements for n in (e.n1, e.n2)} | \
            {n for x in kept if x is not lv for n in x.terminals}
        for side, nodes in (("primary", (lv.p1, lv.p2)), ("secondary", (lv.s1, lv.s2))):
            if not any(n in used for n in nodes if n != FRAME):
                steps.append(f"removed lever {lv.name}: nothing on its {side} side")
                kept.remove(lv)
                break
    return kept, len(kept) < len(levers)


def _drop_unloaded(elements, levers, drive, protect, steps):
    """Remove the elements and levers on no path of the drive (they carry no force)."""
    from .topology import force_groups, loaded_groups

    # The groups' indices: the elements', then the levers' from len(elements) on.
    kept = set(loaded_groups(force_groups(elements, levers), drive.n1, drive.n2))
    first_lever = len(elements)
    gone = [e.name for i, e in enumerate(elements) if i not in kept and e.name not in protect]
    gone_l = [lv.name for i, lv in enumerate(levers, first_lever) if i not in kept]
    if not (gone or gone_l):
        return elements, levers, False
    steps.append(f"removed {_some(gone + gone_l)}: on no path of the drive "
                 "(carry no force)")
    elements = [e for i, e in enumerate(elements) if i in kept or e.name in protect]
    levers = [lv for i, lv in enumerate(levers, first_lever) if i in kept]
    return elements, levers, True


def _merge_parallel(elements, protect, steps, taken):
    """Merge same-kind elements on the same node pair (value·η adds)."""
    groups: dict = {}
    for e in elements:
        if e.name not in protect:
            groups.setdefault((e.kind, frozenset((e.n1, e.n2))), []).append(e)
    merged = []
    for (kind, _), es in groups.items():
        if len(es) < 2:
            continue
        name, drop = _unique(f"{es[0].name}_par", taken), {id(e) for e in es}
        new = Element(kind, name, es[0].n1, es[0].n2, sum(e.value * e.eta for e in es))
        elements = [e for e in elements if id(e) not in drop] + [new]
        merged.append(f"{'+'.join(_short([e.name for e in es]))} -> {name}")
    if merged:
        steps.append(f"merged in parallel: {'; '.join(_short(merged, 6))}")
    return elements, bool(merged)


def _merge_series(elements, fixed, protect, steps, taken):
    """Merge two same-kind elements through a node (not in ``fixed``) with nothing else on it."""
    incident: dict = {}
    for e in elements:
        for n in (e.n1, e.n2):
            incident.setdefault(n, []).append(e)
    series, used = [], set()
    for node, es in incident.items():
        if node in fixed or len(es) != 2:
            continue
        a, b = es
        if a.kind != b.kind or a.name in protect or b.name in protect \
                or id(a) in used or id(b) in used:
            continue
        ends = (a.n2 if a.n1 == node else a.n1, b.n2 if b.n1 == node else b.n1)
        if ends[0] == ends[1]:
            continue
        value = 1.0 / (1.0 / (a.value * a.eta) + 1.0 / (b.value * b.eta))
        name = _unique(f"{a.name}_ser", taken)
        new = Element(a.kind, name, ends[0], ends[1], value)
        used |= {id(a), id(b)}
        elements = [e for e in elements if e is not a and e is not b] + [new]
        series.append(f"{a.name}+{b.name} -> {name}")
    if series:
        steps.append(f"merged in series: {'; '.join(_short(series, 6))}")
    return elements, bool(series)


def _short(items, limit=8):
    items = list(items)
    return items if len(items) <= limit else items[:limit] + [f"… ({len(items) - limit} more)"]


def _some(names):
    return ", ".join(_short(names))


def _short_circuit(elements, levers, drive, el):
    """Merge the nodes of ``el`` (a spring treated as rigid): (elements, levers), or None.

    None when that would short the drive or make a lever's side a single node.
    """
    a, b = el.n1, el.n2
    keep, gone = (a, b) if b != FRAME else (b, a)     # the frame absorbs the other node
    if {gone, keep} == {drive.n1, drive.n2} or gone in (drive.n1, drive.n2):
        return None

    def ren(n):
        return keep if n == gone else n

    new_levers = []
    for lv in levers:
        if ren(lv.p1) == ren(lv.p2) or ren(lv.s1) == ren(lv.s2):
            return None
        new_levers.append(replace(lv, p1=ren(lv.p1), p2=ren(lv.p2), s1=ren(lv.s1),
                                  s2=ren(lv.s2)))
    return ([replace(e, n1=ren(e.n1), n2=ren(e.n2)) for e in elements if e is not el],
            new_levers)


def _check_grid(full: Circuit, band, points, output):
    w1, w2 = band
    inband = [r for r in _resonances(full, w2 * 1.001) if w1 <= r.omega <= w2]
    extra = [r.omega * (1 + s) for r in inband for s in (-1e-3, 1e-3)]    # two beside each
    grid = np.unique(np.concatenate([np.geomspace(w1, w2, points), np.clip(extra, w1, w2)]))
    y = _output(full, grid, output)
    ok = np.isfinite(y) & (y != 0)
    return grid[ok], y[ok], int(np.count_nonzero(~ok)), inband


def simplify(circuit: Circuit, band, tol: float, *, output: str | None = None,
             points: int = 2000) -> Simplified:
    """Reduce ``circuit`` for ``output`` over ``band`` with measured relative error ≤ ``tol``.

    Parameters
    ----------
    circuit : Circuit
    band : (float, float)
        (W1, W2) [rad/s], 0 < W1 < W2.
    tol : float
        Largest relative error of the output allowed at any check point [1], > 0.
    output : str, optional
        Name of the element whose force is the output; default K at the drive.
    points : int
        Log-spaced check points over the band (≥ 10); resonances add two each.

    Returns
    -------
    Simplified

    Raises
    ------
    BandError
        W1 ≥ W2, a limit ≤ 0 or not finite, ``tol`` not positive.
    MechcircError
        ``output`` names no element of the circuit, or an element that carries
        no force.
    """
    t0 = time.perf_counter()
    band, protect = _check_arguments(circuit, band, tol, points, output)
    grid, y_full, skipped, inband = _check_grid(circuit, band, points, output)
    if grid.size == 0:
        raise MechcircError("the output is zero or infinite at every check point of the band")
    search, drive = _Search(circuit, grid, y_full, output, protect), circuit.require_drive()
    taken = {e.name for e in circuit.elements} | {lv.name for lv in circuit.levers} | \
        {drive.name}
    current, steps, error = _exact_first(search, taken, tol)
    current, error = _approximate(search, current, error, taken, tol, steps)
    reduced_circuit = Circuit(tuple(current[0]), drive, tuple(current[1]),
                              name=circuit.name + "_reduced", source=circuit.source)
    shifts = _shifts(inband, reduced_circuit, band)
    header = (f"{circuit.name} reduced by mechcirc simplify for "
              f"{'K at the drive' if output is None else 'the force in ' + output}",
              f"band {band[0]!r}:{band[1]!r} rad/s, tol {tol!r}; measured worst relative error "
              f"{error!r} on {grid.size} check points",
              f"{len(circuit.elements)} elements -> {len(current[0])}, "
              f"{len(circuit.levers)} levers -> {len(current[1])}") + tuple(steps)
    return Simplified(reduced_circuit, circuit, band, float(tol), output, float(error),
                      int(grid.size), skipped, tuple(steps), shifts,
                      write_netlist(reduced_circuit, header), time.perf_counter() - t0,
                      search.trials)


def _check_arguments(circuit: Circuit, band, tol, points, output) -> tuple[tuple, set]:
    """The checked band and the names never to remove or merge (the output element)."""
    band = check_band(band)
    if not (isinstance(tol, (int, float)) and math.isfinite(tol) and tol > 0):
        raise BandError(f"tol must be a positive number, got {tol!r}")
    if isinstance(points, bool) or not isinstance(points, int) or points < 10:
        raise BandError(f"points must be an integer ≥ 10, got {points!r}")
    protect = set()
    if output is not None:
        names = {e.name for e in circuit.elements}
        if output not in names:
            raise MechcircError(f"output {output!r}: no element of that name"
                                f"{did_you_mean(output, sorted(names))} "
                                f"(elements: {_some(sorted(names))})")
        protect.add(output)
    return band, protect


@dataclass
class _Search:
    """The full circuit's output on the check grid, which every trial is measured against."""

    circuit: Circuit
    grid: np.ndarray
    y_full: np.ndarray
    output: str | None
    protect: set
    trials: int = 0

    def measure(self, state) -> float:
        """Worst relative error of the output of ``state`` = (elements, levers) on the grid."""
        self.trials += 1
        elements, levers = state
        if self.output is not None and self.output not in {e.name for e in elements}:
            return math.inf
        try:
            c = Circuit(tuple(elements), self.circuit.drive, tuple(levers),
                        name=self.circuit.name, source=self.circuit.source)
            y = _output(c, self.grid, self.output)
        except (MechcircError, KeyError, np.linalg.LinAlgError):
            return math.inf
        with np.errstate(all="ignore"):
            err = np.abs(y - self.y_full) / np.abs(self.y_full)
        return float(np.max(err)) if np.all(np.isfinite(err)) else math.inf

    def candidates(self, state) -> list[tuple[str, str]]:
        """(element, action) ordered by the element's share of the drive's power, smallest first.

        share = max over the grid of |v_e·Q_e| / |v0·Q0|; a spring that deforms
        little for the force it carries (|v_e|/|v0| < |Q_e|/|Q0|) is a candidate to
        short, any other spring, mass or damper a candidate to remove.
        """
        elements, levers = state
        try:
            c = Circuit(tuple(elements), self.circuit.drive, tuple(levers))
            sw = _trial_sweep(c, self.grid)
            V, Q = np.abs(sw.v0), np.abs(sw.Q0)
            out = []
            for e in elements:
                if e.name in self.protect:
                    continue
                v, q = np.abs(sw.velocity(e.name)) / V, np.abs(sw.force(e.name)) / Q
                share = float(np.max(v * q))
                short = e.kind == "spring" and float(np.max(v)) < float(np.max(q))
                out.append((share, e.name, "short" if short else "open"))
        except (MechcircError, KeyError, np.linalg.LinAlgError):
            return []
        out.sort()
        return [(name, action) for _, name, action in out]

    def apply(self, base, cands, taken):
        """``base`` with ``cands`` applied, then the exact clean-ups: (state, steps, done).

        ``done`` lists (name, action, kind) of the candidates applied; (None, [], [])
        when the result has no path for the drive.
        """
        drive = self.circuit.drive
        els, levers = list(base[0]), list(base[1])
        done = []
        for name, action in cands:
            match = next((e for e in els if e.name == name), None)
            if match is None:
                continue
            if action == "open":
                els = [e for e in els if e is not match]
            else:
                shorted = _short_circuit(els, levers, drive, match)
                if shorted is None:
                    continue
                els, levers = shorted
            done.append((name, action, match.kind))
        st: list[str] = []
        try:
            state = _exact(els, levers, drive, self.protect, st, set(taken))
        except TopologyError:
            return None, [], []
        return state, st, done


def _exact_first(search: _Search, taken: set, tol: float):
    """The exact clean-ups of the whole circuit if their error is ≤ tol: (state, steps, error)."""
    circuit = search.circuit
    current = (list(circuit.elements), list(circuit.levers))
    trial_steps: list[str] = []
    try:
        reduced = _exact(*current, circuit.drive, search.protect, trial_steps, taken)
    except TopologyError:
        reduced = current
    err = search.measure(reduced)
    return (reduced, trial_steps, err) if err <= tol else (current, [], search.measure(current))


def _approximate(search: _Search, current, error: float, taken: set, tol: float,
                 steps: list[str]):
    """Rounds of approximate steps until one accepts nothing: (state, error); appends to steps."""
    for _round in range(8):
        cands = search.candidates(current)
        if not cands:
            break
        best = _longest_prefix(search, current, cands, taken, tol)
        if best is None:
            break
        current, st, done, error = best
        taken |= {x.name for x in current[0]}
        steps += _describe(done) + st
    return current, error


def _longest_prefix(search: _Search, current, cands, taken: set, tol: float):
    """The longest prefix of ``cands`` with a measured error ≤ tol (bisection), or None.

    Returns (state, steps, done, error) of that prefix.
    """
    best = None
    lo, hi = 0, len(cands)
    while lo < hi:
        mid = (lo + hi + 1) // 2
        els, st, done = search.apply(current, cands[:mid], taken)
        e = search.measure(els) if els is not None else math.inf
        if e <= tol:
            lo, best = mid, (els, st, done, e)
        else:
            hi = mid - 1
    return best


def _describe(done) -> list[str]:
    """One step line per (kind, action) of the applied candidates (name, action, kind)."""
    lines = []
    for kind, action, verb in (("spring", "short", "shorted as rigid"),
                               ("spring", "open", "removed as negligible"),
                               ("mass", "open", "removed as negligible"),
                               ("damper", "open", "removed as negligible")):
        names = [n for n, a, k in done if k == kind and a == action]
        if names:
            plural = "masses" if kind == "mass" else kind + "s"
            lines.append(f"{plural} {verb}: {_some(names)}")
    return lines


def _resonances(circuit: Circuit, omega_max: float) -> list:
    """The resonances of ``circuit`` up to ``omega_max``; none where they cannot be found."""
    try:
        return list(circuit.resonances(omega_max=omega_max))
    except MechcircError:
        return []


def _shifts(inband, reduced: Circuit, band) -> list[dict]:
    found = _resonances(reduced, band[1] * 1.5)
    out, used = [], set()
    for r in inband:
        cands = [(abs(q.omega - r.omega), i) for i, q in enumerate(found)
                 if q.kind == r.kind and i not in used]
        if cands:
            d, i = min(cands)
            if d <= 0.5 * r.omega:
                used.add(i)
                out.append({"kind": r.kind, "full": r.omega, "reduced": found[i].omega,
                            "relative_shift": (found[i].omega - r.omega) / r.omega})
                continue
        out.append({"kind": r.kind, "full": r.omega, "reduced": None, "relative_shift": None})
    return out
