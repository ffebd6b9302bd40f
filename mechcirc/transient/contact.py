"""Where a clearance's contact opens and closes in a transient: angle, duration, impact.

A clearance element (``spring ... backlash=B``, the ElastoBacklash law of
:mod:`._kernels`) transmits nothing while it is open: in the gap, or pulled
apart (spring and damping parts summing to ≤ 0).  For every stretch of
samples where its force is 0 after a contact, :func:`separations` reports
when it opened, when it closed again and with which relative velocity (the
impact), the instants refined between samples by linear interpolation of the
law's unclipped values (error of order dt, not dt²: the law's slope changes at
the flank, so the interpolation is only first order there; 1.7e-4 s at
dt = 1e-3 s on a sampled sine); the impact velocity is extrapolated
from the open side, where the motion is smooth.  A contact or an opening
shorter than the output step can fall between two samples and go unseen.  With a drive given by its motion over
a shaft revolution the instants are also cam angles, θ = Ωt.

For a cam follower held on its cam by a spring (one flank of the clearance in
use, the other out of reach) an opening is the follower's *jump*.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

__all__ = ["Separation", "separations"]


@dataclass(frozen=True)
class Separation:
    """One opening of a clearance's contact (plain data).

    Attributes
    ----------
    element : str
        The clearance spring.
    t_open, t_close : float
        When the contact opened and closed again [s] (``t_close`` NaN when
        still open at the end of the run).
    impact_velocity : float
        Relative velocity v(n1) − v(n2) at closing [m/s or rad/s] (NaN when
        still open): its size the speed of the impact, its sign the flank's
        (positive closing the gap's upper side, negative its lower side).
    angle_deg, duration_deg : float
        Shaft angle at opening [deg, 0…360] and the angle turned while open
        (NaN without a motion drive; ``duration_deg`` NaN when still open).
    revolution : int
        Which revolution of the shaft it opened in (0 first; −1 without a
        motion drive).
    """

    element: str
    t_open: float
    t_close: float
    impact_velocity: float
    angle_deg: float = math.nan
    duration_deg: float = math.nan
    revolution: int = -1

    @property
    def duration(self) -> float:
        """How long the contact stayed open [s] (NaN when still open)."""
        return self.t_close - self.t_open


def _root(t, f, k):
    """The zero of f between samples k−1 and k (linear)."""
    f0, f1 = f[k - 1], f[k]
    s = f0 / (f0 - f1) if f0 != f1 else 1.0
    return t[k - 1] + s * (t[k] - t[k - 1]), s


def separations(time, e, w, stiffness, damping, gap, name, omega_shaft=None):
    """The openings of one clearance element over a run.

    Parameters
    ----------
    time : ndarray
        Sample times [s].
    e, w : ndarray
        Its relative displacement and velocity x(n1) − x(n2), v(n1) − v(n2).
    stiffness, damping, gap : float
        c, d and the total clearance B of the law.
    name : str
        The element's name.
    omega_shaft : float, optional
        Shaft speed Ω [rad/s] of a motion drive (θ = Ωt), for the angles.

    Returns
    -------
    list of Separation
        In time order; an opening at the first sample (never in contact
        before) is not one.
    """
    half, fd = 0.5 * gap, damping * w
    up = stiffness * (e - half)
    up = up + np.minimum(up, fd)                  # > 0: contact on the upper flank
    lo = stiffness * (e + half)
    lo = lo + np.maximum(lo, fd)                  # < 0: contact on the lower flank
    closed, out = (up > 0) | (lo < 0), []
    n = time.size
    # openings: closed at k-1, open at k; each closes at the first closed sample after it
    opens = np.flatnonzero(closed[:-1] & ~closed[1:]) + 1
    closes = np.flatnonzero(~closed[:-1] & closed[1:]) + 1
    after = np.searchsorted(closes, opens, side="right")
    for k, a in zip(opens.tolist(), after.tolist()):
        j = int(closes[a]) if a < closes.size else n
        t_open = _root(time, up if up[k - 1] > 0 else lo, k)[0]
        t_close, v_imp = math.nan, math.nan
        if j < n:
            t_close, _ = _root(time, up if up[j] > 0 else lo, j)
            # w from the open side (smooth in flight; the contact changes it at once)
            slope = (w[j - 1] - w[j - 2]) / (time[j - 1] - time[j - 2]) if j - 2 >= k else 0.0
            v_imp = float(w[j - 1] + slope * (t_close - time[j - 1]))
        angle = dur = math.nan
        rev = -1
        if omega_shaft:
            theta = omega_shaft * t_open
            rev = int(theta // (2 * math.pi))
            angle = math.degrees(theta - 2 * math.pi * rev)
            dur = math.degrees(omega_shaft * (t_close - t_open))
        out.append(Separation(name, float(t_open), float(t_close), v_imp, angle, dur, rev))
    return out
