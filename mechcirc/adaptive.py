"""Adaptive frequency grids: dense where |K| bends, sparse elsewhere.

The grid starts from a coarse logarithmic grid plus points around every
resonance and anti-resonance found exactly (:mod:`mechcirc.resonances`):

* damped ones: at the damped natural frequency and at ±¼, ±½, 1, 2, 4
  half-power bandwidths (ζ·ωₙ);
* undamped ones, where |K| or |Q0| is unbounded: at relative distances
  10⁻⁴ … 10⁻¹ on either side (not on the pole itself: the value there only
  says how close a float falls).

Then every interval whose midpoint (geometric mean) differs from the log–log
interpolation of its ends by more than ``tol`` is split, until none is or
``max_points`` is reached.  The test is made on |K| with the undamped poles
and zeros divided out, |K| · Π|1 − ω²/ω_p²| / Π|1 − ω²/ω_z²|, which is smooth
through them: the grid is refined where the response bends, not chased into
an infinite peak.  |Q0| = V0/|K| and |v0| = F0·|K| bend where |K| does.
When the budget is hit, the result's ``notes`` say so.
"""

from __future__ import annotations

import numpy as np

from . import limits
from .circuit import Circuit
from ._sweep import UNDAMPED_ZETA, Method, Sweep, sweep
from .errors import InputError, SolverError
from .sources import real_number

__all__ = ["adaptive_sweep", "UNDAMPED_OFFSETS"]

#: Relative distances from an undamped pole or zero where points are placed.
UNDAMPED_OFFSETS = (1e-4, 3e-4, 1e-3, 3e-3, 1e-2, 3e-2, 0.1)


def adaptive_sweep(circuit: Circuit, omega_min: float, omega_max: float, *,
                   tol: float = 0.005, initial: int = 41, max_points: int | None = None,
                   method: Method = "auto") -> Sweep:
    """Sweep ``circuit`` over [``omega_min``, ``omega_max``] [rad/s] on an adaptive grid.

    Parameters
    ----------
    circuit : Circuit
    omega_min, omega_max : float
        The band [rad/s].
    tol : float
        Largest relative deviation [1] of |K| (undamped poles and zeros divided
        out) at an interval's midpoint from the log–log interpolation of its ends.
    initial : int
        Points of the starting logarithmic grid.
    max_points : int, optional
        Upper bound on the number of points (default :data:`~mechcirc.limits.MAX_ADAPTIVE_POINTS`);
        reaching it is recorded in ``result.notes``.
    method : {"auto", "sp", "nodal"}
        As :func:`mechcirc.sweep`.

    Returns
    -------
    Sweep
        On the final grid (``len(result.omega)`` tells how many points).

    Raises
    ------
    InputError
        The starting grid alone (``initial`` points and those placed around
        each resonance) would exceed the work bound.

    Notes
    -----
    The work is bounded: each K evaluation costs about one operation per
    element, and every point is evaluated about three times (as a point, as a
    midpoint before it, and in the final sweep), so the refinement stops when
    points × 3 × (elements + levers) would pass
    :data:`~mechcirc.limits.MAX_ADAPTIVE_WORK` (series–parallel tree) or
    :data:`~mechcirc.limits.MAX_ADAPTIVE_NODAL_WORK` (nodal analysis, about
    100 times dearer per element); ``result.notes`` then says so, with the bound.
    """
    if not (real_number(omega_min) and real_number(omega_max) and 0 < omega_min < omega_max):
        raise InputError(f"need 0 < omega_min < omega_max, got {omega_min} and {omega_max}")
    max_points = limits.MAX_ADAPTIVE_POINTS if max_points is None else max_points
    notes: list[str] = []
    omega, zeros, poles = _start_grid(circuit, omega_min, omega_max, initial, notes)
    first = sweep(circuit, omega, method=method)
    evaluations, work = _work_bound(circuit, first.method, omega.size)

    def smooth(w):
        return _smooth(sweep(circuit, w, method=method), zeros, poles)

    omega = _refine(omega, _smooth(first, zeros, poles), smooth, tol,
                    (max_points, evaluations, work), notes)
    result = sweep(circuit, omega, method=method)
    return result.with_notes(tuple(notes)) if notes else result


def _work_bound(circuit: Circuit, method: str, n_start: int) -> tuple[int, str]:
    """``(K evaluations allowed, the bound in words)``; InputError if ``n_start`` is over it."""
    size = max(1, len(circuit.elements) + len(circuit.levers))
    bound = limits.MAX_ADAPTIVE_WORK if method == "sp" else limits.MAX_ADAPTIVE_NODAL_WORK
    evaluations = bound // size
    work = (f"work bound of {bound:,} element evaluations ({evaluations:,} evaluations of K "
            f"on this network of {size:,} elements and levers, method {method})")
    if 3 * n_start > evaluations:
        raise InputError(f"adaptive sweep: its starting grid of {n_start:,} points is over "
                         f"the {work}; start from fewer points or a narrower band, or sweep "
                         "a fixed grid")
    return evaluations, work


def _start_grid(circuit, omega_min, omega_max, initial, notes):
    """The starting grid: ``initial`` log points and points around each resonance
    found below 1.5 ``omega_max``; and the undamped zeros and poles of K (divided
    out of |K| before the grid is refined)."""
    grid = [np.geomspace(omega_min, omega_max, initial)]
    try:
        found = circuit.resonances(omega_max=omega_max * 1.5)
    except SolverError as exc:      # too large for the eigen-solver: refine on |K| alone
        found = []
        notes.append(f"resonances not located ({exc}); the grid is refined on |K| alone")
    zeros, poles = [], []
    for r in found:
        if r.zeta <= UNDAMPED_ZETA:
            (zeros if r.kind == "resonance" else poles).append(r.omega)
            d = np.array(UNDAMPED_OFFSETS)
            grid.append(r.omega * np.concatenate([1 - d, 1 + d]))
            continue
        centre = r.omega_d if r.omega_d > 0 else r.omega
        half = max(r.zeta * r.omega, 1e-6 * r.omega)
        offsets = np.array([0, 0.25, 0.5, 1, 2, 4]) * half
        grid.append(centre + np.concatenate([-offsets[1:], offsets]))
    omega = np.unique(np.concatenate(grid))
    return omega[(omega >= omega_min) & (omega <= omega_max)], np.array(zeros), np.array(poles)


def _smooth(result: Sweep, zeros, poles) -> np.ndarray:
    """log |K| with the undamped zeros and poles divided out."""
    w = result.omega[:, None]
    with np.errstate(all="ignore"):     # (no poles or zeros: their sums are 0)
        return (np.log(np.abs(result.K)) + np.log(np.abs(1 - (w / poles) ** 2)).sum(axis=1)
                - np.log(np.abs(1 - (w / zeros) ** 2)).sum(axis=1))


def _refine(omega, values, smooth, tol, budget, notes):
    """Split every interval whose midpoint deviates from the log–log interpolation
    of its ends by more than ``tol``, until none does or the ``budget``
    (points, K evaluations, its description) is spent (said in ``notes``)."""
    max_points, evaluations, work = budget
    # The midpoint of each interval (geometric mean) and its value, kept between
    # rounds: a round evaluates only the two new midpoints of each split interval.
    mid = np.sqrt(omega[:-1] * omega[1:])
    mid_values, used = smooth(mid), omega.size + mid.size
    while True:
        with np.errstate(all="ignore"):
            predicted = (values[:-1] + values[1:]) / 2          # log-log midpoint
            deviation = np.abs(np.expm1(mid_values - predicted))
        deviation = np.where(np.isnan(deviation), 0.0, deviation)
        split = np.flatnonzero(deviation > tol)
        if split.size == 0:
            return omega
        # A split adds a point and two midpoints; the final sweep evaluates every point.
        room_points = max_points - omega.size
        room_work = (evaluations - used - omega.size) // 3
        room = max(0, min(room_points, room_work))
        full = split.size > room
        if full:
            which = f"point budget of {max_points}" if room_points <= room_work else work
            notes.append(f"{which} reached: {split.size - room} interval(s) still deviate "
                         f"by more than tol = {tol:g} (largest {deviation.max():.3g})")
            if room == 0:
                return omega
            split = np.sort(split[np.argsort(deviation[split])[::-1][:room]])
        new = mid[split]
        left, right = np.sqrt(omega[split] * new), np.sqrt(new * omega[split + 1])
        omega = np.insert(omega, split + 1, new)
        if full:                 # the last round: its new midpoints would not be used
            return omega
        values = np.insert(values, split + 1, mid_values[split])
        fresh = smooth(np.concatenate([left, right]))
        used += 2 * split.size
        mid[split], mid_values[split] = left, fresh[:split.size]
        mid = np.insert(mid, split + 1, right)
        mid_values = np.insert(mid_values, split + 1, fresh[split.size:])

