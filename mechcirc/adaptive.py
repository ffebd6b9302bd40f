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

from .circuit import Circuit
from .sweep import UNDAMPED_ZETA, Sweep, sweep

__all__ = ["adaptive_sweep", "UNDAMPED_OFFSETS"]

#: Relative distances from an undamped pole or zero where points are placed.
UNDAMPED_OFFSETS = (1e-4, 3e-4, 1e-3, 3e-3, 1e-2, 3e-2, 0.1)


def adaptive_sweep(circuit: Circuit, omega_min: float, omega_max: float, *,
                   tol: float = 0.005, initial: int = 41, max_points: int = 20_000,
                   method: str = "auto") -> Sweep:
    """Sweep ``circuit`` over [``omega_min``, ``omega_max``] [rad/s] on an adaptive grid.

    Parameters
    ----------
    tol : float
        Largest relative deviation [1] of |K| (undamped poles and zeros divided
        out) at an interval's midpoint from the log–log interpolation of its ends.
    initial : int
        Points of the starting logarithmic grid.
    max_points : int
        Upper bound on the number of points; reaching it is recorded in
        ``result.notes``.

    Returns
    -------
    Sweep
        On the final grid (``len(result.omega)`` tells how many points).
    """
    from .errors import SolverError

    if not 0 < omega_min < omega_max:
        raise ValueError(f"need 0 < omega_min < omega_max, got {omega_min} and {omega_max}")
    notes: list[str] = []
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
    zeros, poles = np.array(zeros), np.array(poles)

    def smooth(result: Sweep) -> np.ndarray:
        w = result.omega[:, None]
        with np.errstate(all="ignore"):
            log = np.log(np.abs(result.K))
            if poles.size:
                log = log + np.log(np.abs(1 - (w / poles) ** 2)).sum(axis=1)
            if zeros.size:
                log = log - np.log(np.abs(1 - (w / zeros) ** 2)).sum(axis=1)
        return log

    omega = np.unique(np.concatenate(grid))
    omega = omega[(omega >= omega_min) & (omega <= omega_max)]
    values = smooth(sweep(circuit, omega, method=method))
    while True:
        mid = np.sqrt(omega[:-1] * omega[1:])
        mid_values = smooth(sweep(circuit, mid, method=method))
        with np.errstate(all="ignore"):
            predicted = (values[:-1] + values[1:]) / 2          # log-log midpoint
            deviation = np.abs(np.expm1(mid_values - predicted))
        deviation = np.where(np.isnan(deviation), 0.0, deviation)
        split = np.flatnonzero(deviation > tol)
        if split.size == 0:
            break
        room = max_points - omega.size
        if split.size > room:
            notes.append(f"point budget of {max_points} reached: {split.size - room} "
                         f"interval(s) still deviate by more than tol = {tol:g} "
                         f"(largest {deviation.max():.3g})")
            split = split[np.argsort(deviation[split])[::-1][:room]]
            split.sort()
        omega = np.insert(omega, split + 1, mid[split])
        values = np.insert(values, split + 1, mid_values[split])
        if omega.size >= max_points:
            if not notes or "budget" not in notes[-1]:
                notes.append(f"point budget of {max_points} reached")
            break
    result = sweep(circuit, omega, method=method)
    return result.with_notes(tuple(notes)) if notes else result
