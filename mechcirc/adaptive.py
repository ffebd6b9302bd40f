"""Adaptive frequency grids: dense where |Q0| and |K| bend, sparse elsewhere.

The grid starts from a coarse logarithmic grid plus points around every
resonance and anti-resonance found exactly (:mod:`mechcirc.resonances`): at
the damped natural frequency and at ±¼, ±½, 1, 2, 4 half-power bandwidths
(ζ·ωₙ).  Then every interval whose midpoint (geometric mean) differs from
the log–log interpolation of its ends by more than ``tol`` in |Q0|, |v0| or
|K| is split, until none is or ``max_points`` is reached.
"""

from __future__ import annotations

import numpy as np

from .circuit import Circuit
from .sweep import Sweep, sweep

__all__ = ["adaptive_sweep"]


def adaptive_sweep(circuit: Circuit, omega_min: float, omega_max: float, *,
                   tol: float = 0.005, initial: int = 41, max_points: int = 20_000,
                   method: str = "auto") -> Sweep:
    """Sweep ``circuit`` over [``omega_min``, ``omega_max``] [rad/s] on an adaptive grid.

    Parameters
    ----------
    tol : float
        Largest relative deviation [1] of |K|, |Q0| or |v0| at an interval's
        midpoint from the log–log interpolation of its ends.
    initial : int
        Points of the starting logarithmic grid.
    max_points : int
        Upper bound on the number of points.

    Returns
    -------
    Sweep
        On the final grid (``len(result.omega)`` tells how many points).
    """
    if not 0 < omega_min < omega_max:
        raise ValueError(f"need 0 < omega_min < omega_max, got {omega_min} and {omega_max}")
    grid = [np.geomspace(omega_min, omega_max, initial)]
    for r in circuit.resonances(omega_max=omega_max * 1.5):
        centre = r.omega_d if r.omega_d > 0 else r.omega
        half = max(r.zeta * r.omega, 1e-6 * r.omega)
        offsets = np.array([0, 0.25, 0.5, 1, 2, 4]) * half
        grid.append(centre + np.concatenate([-offsets[1:], offsets]))
    omega = np.unique(np.concatenate(grid))
    omega = omega[(omega >= omega_min) & (omega <= omega_max)]
    values = _magnitudes(sweep(circuit, omega, method=method))
    while omega.size < max_points:
        mid = np.sqrt(omega[:-1] * omega[1:])
        mid_values = _magnitudes(sweep(circuit, mid, method=method))
        with np.errstate(all="ignore"):
            predicted = np.sqrt(values[:, :-1] * values[:, 1:])   # log-log midpoint
            deviation = np.abs(mid_values / predicted - 1)
        deviation = np.where(np.isnan(deviation), 0.0, deviation).max(axis=0)
        split = np.flatnonzero(deviation > tol)
        if split.size == 0:
            break
        split = split[:max_points - omega.size]
        omega = np.insert(omega, split + 1, mid[split])
        values = np.insert(values, split + 1, mid_values[:, split], axis=1)
    return sweep(circuit, omega, method=method)


def _magnitudes(result: Sweep) -> np.ndarray:
    return np.abs(np.vstack([result.K, result.Q0, result.v0]))
