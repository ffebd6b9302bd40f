"""Parameters of Mrázek's sley (beat-up) models and their validation.

The models (Mrázek):

One-side drive, eq. (4)::

    dφ2P/dt = ω2P
    (I2P + I4 μ²) dω2P/dt = −I4 μ ν ω2P² − C2 Δ(φ2P − φ2) + C4 μ Δ(φ4P − φ4)
                            − k2 (ω2P − ω2) + k4 μ (ω4P − ω4)
    dφ4P/dt = ω4P
    I4P dω4P/dt = −C4 Δ(φ4P − φ4) − k4 (ω4P − ω4) − M4

with φ2 = ω t the driven shaft (constant ω), φ4 = f24(φ2P), ω4 = μ ω2P,
μ = dφ4/dθ, ν = d²φ4/dθ² taken at θ = φ2P from :class:`mechcirc.kinematics.FourBar`.

Both-sides drive, eq. (9): a second crank 5P (I5P, C5, k5, driven by the same
shaft φ2) drives a second rocker 7 (I7; rod C7, k7 to the sley), transfer
functions μ57 = μ(φ5P), ν57 = ν(φ5P) of the same four-bar::

    (I5P + I7 μ57²) dω5P/dt = −I7 μ57 ν57 ω5P² − C5 Δ(φ5P − φ2) + C7 μ57 Δ(φ4P − φ7)
                              − k5 (ω5P − ω2) + k7 μ57 (ω4P − ω7)
    I4P dω4P/dt = −C4 Δ(φ4P − φ4) − C7 Δ(φ4P − φ7) − M4 − k4 (ω4P − ω4) − k7 (ω4P − ω7)

Clearance law, eqs. (8), (11): Δ(e) = 0 for |e| < ϕ, e − ϕ·sign(e) beyond; ϕ is
the half-width of the dead zone.  Damping acts on the relative velocity
throughout (also inside the dead zone).

Beat-up moment, eqs. (5)–(7): M4 = M0 sin(π (φ2P − φP + α/2) / σ) for
φP − α/2 < φ2P (mod 2π) < φP + α/2 and 0 elsewhere, φP the crank angle of the
front dead centre (crank and coupler extended).  Reading (Mrázek): σ = α, so
M4 is a half sine over the window; α is not printed — default 10°, the best fit to
the 98 printed cells of Tables 1 and 2 (docs/sley.md, examples/sley_alpha_fit.py).

Units: SI throughout — inertias [kg·m²], torsional rigidities [N·m/rad],
torsional damping [N·m·s/rad = kg·m²/s], angles [rad], ω [rad/s], moments [N·m],
link lengths [m].
"""

from __future__ import annotations

import math
from functools import lru_cache
from dataclasses import asdict, dataclass, fields, replace
from typing import Literal

from ..errors import GeometryError, ParameterError
from ..sources import did_you_mean

@lru_cache(maxsize=64)
def fourbar_of_lengths(l2P, l3, l4, d, branch):
    from ..kinematics import FourBar

    return FourBar(l2P, l3, l4, d, branch=branch)


__all__ = ["SleyParameters", "ParameterError", "Drive", "DEFAULT_ALPHA_DEG", "start_angle"]

Drive = Literal["one-side", "both-sides"]

#: Default beat-up interval α [deg]; not printed in the paper (Mrázek); the median
#: difference over the 98 printed cells is smallest at 10° (3.3 %; 40°: 4.6 %).
DEFAULT_ALPHA_DEG = 10.0


_POSITIVE = ("I2P", "I4", "I4P", "C2", "C4", "omega", "alpha", "l2P", "l3", "l4", "d")
_NONNEGATIVE = ("k2", "k4", "clearance", "M0")
_BOTH_POSITIVE = ("I5P", "I7", "C5", "C7")
_BOTH_NONNEGATIVE = ("k5", "k7")
#: The unit each parameter is read in (a key of :data:`mechcirc.units.ROLES`): ``--set
#: clearance=0.1deg`` is 0.1° in rad, ``--set clearance=2kN`` is refused.
UNIT_ROLES = {**dict.fromkeys(("I2P", "I4", "I4P", "I5P", "I7"), "rotary inertia"),
              **dict.fromkeys(("C2", "C4", "C5", "C7"), "rotary spring"),
              **dict.fromkeys(("k2", "k4", "k5", "k7"), "rotary damper"),
              **dict.fromkeys(("l2P", "l3", "l4", "d"), "length"),
              **dict.fromkeys(("clearance", "alpha"), "angle"),
              **dict.fromkeys(("branch", "beat_sign"), "ratio"),
              "omega": "omega", "M0": "moment"}


@dataclass(frozen=True)
class SleyParameters:
    """All parameters of one sley model (one-side eq. (4) or both-sides eq. (9)).

    Parameters
    ----------
    drive : {"one-side", "both-sides"}
        Layout: crank and linkage on one side (Fig. 1) or on both (Fig. 2).
    I2P, I4, I4P : float
        Inertias of crank 2P, rocker 4 and sley with reed 4P [kg·m²], > 0.
    C2, C4 : float
        Torsional rigidities of the rods crank shaft→2P and rocker 4→sley [N·m/rad], > 0.
    k2, k4 : float
        Viscous torsional damping of those rods [kg·m²/s], ≥ 0.
    omega : float
        Crank shaft speed ω [rad/s], > 0 (constant).
    clearance : float
        Half-width ϕ of the dead zone on every elastic connection [rad], ≥ 0.
    M0 : float
        Amplitude of the beat-up moment [N·m], ≥ 0.
    alpha : float
        Beat-up interval α [rad] (σ = α), in (0, 2π); default 10° (not printed; fitted).
    I5P, I7, C5, C7, k5, k7 : float or None
        Second crank, second rocker and their rods (both-sides drive only)
        [kg·m², N·m/rad, kg·m²/s].
    l2P, l3, l4, d : float
        Crank, coupler, rocker and frame lengths [m]; default the paper's
        29, 37, 188, 189 mm.
    branch : {+1, -1}
        Four-bar assembly mode (:class:`~mechcirc.kinematics.FourBar`); +1 gives
        the printed ε4T range [−2319, 2915] s⁻² at ω = 100 s⁻¹.
    beat_sign : {-1, +1}
        Sign with which M4 enters the sley equation: −1 is eq. (4)/(9) as
        printed (``… − M4``, default); +1 makes the beat-up moment act in the
        direction of the rigid sley acceleration at the front dead centre (the
        cloth pushing the reed back), which is what the printed ε4P of variants 3
        and 4 against 1 and 5 suggest (see ``docs/sley.md``).
    label : str
        Free text naming the variant (for reports).

    Raises
    ------
    ParameterError
        A parameter is missing, not finite, or out of range (ω ≤ 0 included).
    GeometryError
        The four-bar cannot be assembled or its crank cannot turn fully.
    """

    drive: Drive = "one-side"
    I2P: float = 0.005
    I4: float = 0.025
    I4P: float = 0.35
    C2: float = 1e5
    C4: float = 5e4
    k2: float = 7.0
    k4: float = 29.0
    omega: float = 100.0
    clearance: float = 0.0
    M0: float = 0.0
    alpha: float = math.radians(DEFAULT_ALPHA_DEG)
    I5P: float | None = None
    I7: float | None = None
    C5: float | None = None
    C7: float | None = None
    k5: float | None = None
    k7: float | None = None
    l2P: float = 0.029
    l3: float = 0.037
    l4: float = 0.188
    d: float = 0.189
    branch: int = 1
    beat_sign: int = -1
    label: str = ""

    def __post_init__(self):
        if self.drive not in ("one-side", "both-sides"):
            raise ParameterError(f"drive must be 'one-side' or 'both-sides', got {self.drive!r}"
                                 f"{did_you_mean(str(self.drive), ('one-side', 'both-sides'))}")
        if isinstance(self.omega, (int, float)) and math.isfinite(self.omega) and self.omega <= 0:
            raise ParameterError(
                f"crank speed omega must be > 0 rad/s, got {self.omega!r}: the model "
                "integrates forward in crank angle at a constant speed; for the opposite "
                "sense of rotation use branch=-1 (the mirror-image linkage)")
        checks = [(n, False) for n in _POSITIVE] + [(n, True) for n in _NONNEGATIVE]
        if self.drive == "both-sides":
            checks += [(n, False) for n in _BOTH_POSITIVE] + [(n, True) for n in _BOTH_NONNEGATIVE]
        for name, zero_ok in checks:
            value = getattr(self, name)
            if value is None:
                raise ParameterError(f"{name} is required for the {self.drive} drive")
            if isinstance(value, bool) or not isinstance(value, (int, float)) \
                    or not math.isfinite(value):
                raise ParameterError(f"{name} must be a finite number, got {value!r}")
            if value < 0 or (value == 0 and not zero_ok):
                bound = "≥ 0" if zero_ok else "> 0"
                raise ParameterError(f"{name} must be {bound}, got {value!r}")
            object.__setattr__(self, name, float(value))
        if not self.alpha < 2 * math.pi:
            raise ParameterError(f"beat-up interval alpha must be < 2π rad, got {self.alpha!r}")
        for name in ("branch", "beat_sign"):
            if getattr(self, name) not in (1, -1):
                raise ParameterError(f"{name} must be +1 or -1, got {getattr(self, name)!r}")
        fb = self.fourbar()          # raises GeometryError when it cannot be assembled
        if not fb.is_full_turn_crank_rocker:
            raise GeometryError(
                f"the beat-up drive needs a crank-rocker whose crank turns fully; lengths "
                f"l2P={self.l2P:g}, l3={self.l3:g}, l4={self.l4:g}, d={self.d:g} m give a "
                f"{fb.grashof_class} {fb.linkage_type}")

    def fourbar(self):
        """The beat-up four-bar (crank 2P, coupler 3, rocker 4, frame) as a ``FourBar``."""
        return fourbar_of_lengths(self.l2P, self.l3, self.l4, self.d, self.branch)

    def second_side(self) -> tuple[float, float, float, float, float, float]:
        """``(I5P, I7, C5, C7, k5, k7)`` of a both-sides drive (checked when it was made)."""
        I5P, I7, C5, C7, k5, k7 = self.I5P, self.I7, self.C5, self.C7, self.k5, self.k7
        if I5P is None or I7 is None or C5 is None or C7 is None or k5 is None or k7 is None:
            raise ParameterError(f"the {self.drive} drive has no second crank side")
        return I5P, I7, C5, C7, k5, k7

    @property
    def sigma(self) -> float:
        """σ of eq. (7) [rad]; our reading σ = α (Mrázek)."""
        return self.alpha

    def replace(self, **overrides) -> "SleyParameters":
        """A copy with some fields changed (validated again).

        Raises
        ------
        ParameterError
            An override names no parameter.
        """
        known = {f.name for f in fields(self)}
        unknown = sorted(set(overrides) - known)
        if unknown:
            raise ParameterError(f"unknown sley parameter(s) {', '.join(unknown)}"
                                 f"{did_you_mean(unknown[0], sorted(known))} "
                                 f"(known: {', '.join(sorted(known))})")
        return replace(self, **overrides)

    def as_dict(self) -> dict:
        """Plain dict of every field (for JSON)."""
        return asdict(self)


def start_angle(params: SleyParameters) -> float:
    """First crank angle θ0 in [0, 2π) with ν(θ0) = 0 (zero rigid sley acceleration) [rad].

    Parameters
    ----------
    params : SleyParameters
        The sley's parameters.

    Returns
    -------
    float
    """
    return linkage_constants(params.l2P, params.l3, params.l4, params.d, params.branch)[0]


@lru_cache(maxsize=64)
def linkage_constants(l2P, l3, l4, d, branch) -> tuple[float, float, float, float, float]:
    """The four-bar's (start angle θ0 of :func:`start_angle`, beat-up crank angle φP,
    offset of the sley's mid-swing from its pose angle, ν min, ν max), once a geometry."""
    import numpy as np
    from scipy.optimize import brentq

    fb = fourbar_of_lengths(l2P, l3, l4, d, branch)
    th = np.linspace(0.0, 2.0 * math.pi, 721)
    st = fb.evaluate(th)
    idx = np.flatnonzero(np.sign(st.nu[:-1]) * np.sign(st.nu[1:]) <= 0)
    i = int(idx[0])
    theta0 = float(th[i])
    if st.nu[i] != 0.0:
        theta0 = float(brentq(lambda t: fb.transfer(t)[2], th[i], th[i + 1], xtol=1e-14))
    (_, lo), (_, hi) = fb.nu_extrema()
    sley_off = fb.transfer(0.0)[0] - 0.5 * (st.phi4.max() + st.phi4.min())
    return theta0, fb.dead_centres()[0].theta, sley_off, lo, hi
