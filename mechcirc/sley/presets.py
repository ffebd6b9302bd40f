"""Mrázek's Tables 1 and 2: the 14 parameter variants and the printed results.

Readings of cells the OCR lost in our copy of the paper, stated once here and in every preset:

* **k2 = 7 kg·m²/s** for Table 1 variants 1–5 and 7 (the cell is missing; Table 2
  gives k2 = 7 with the same C2 = 1e5).
* **Table 1 variant 6: C4 = 1e4 N·m/rad** (printed "10⁶", read as 10⁴ by analogy
  with Table 2's variant 6).
* **α = σ = 10°** for the beat-up moment (neither is printed): the best fit to the
  98 printed cells (median |difference| 3.3 %, against 4.6 % at 40°; docs/sley.md).
* Table 1's ε4P of variants 6 and 7 lost the minus sign of the minimum (printed
  "5277", "598"); we take them as −5277 and −598.  Table 2 variant 1's ε2P min
  likewise (−1292).  Table 1 variant 6's M2V is printed "279 / 101", impossible
  as min / max; the minimal edit, a lost minus sign as in the other cells, gives
  −279 / 101, which we use (``docs/sley.md`` discusses the alternative −101 / 279).
* The four-bar is 29 / 37 / 188 / 189 mm, assembly ``branch=+1`` of
  :class:`~mechcirc.kinematics.FourBar`, the one whose ε4T = ν ω² spans the
  printed [−2319, 2915] s⁻² at ω = 100 s⁻¹.

Table 2 (both sides): I2P = I5P = 0.005, I4 = I7 = 0.025, C2 = 1e5, C5 = 1e4,
C4 = C7 = 5e4, k2 = 7, k5 = 2.2, k4 = k7 = 29; variants 4, 5: I4P = 0.45,
k4 = k7 = 33; variant 6: C2 = 5e4, C5 = 5e3, C4 = C7 = 1e4, k2 = 5, k5 = 1.6,
k4 = k7 = 13; ω, ϕ, M0 as in Table 1.
"""

from __future__ import annotations

from functools import lru_cache
from typing import cast

from .models import Drive, ParameterError, SleyParameters

__all__ = ["preset", "all_presets", "PAPER", "VARIANTS"]

VARIANTS = tuple(range(1, 8))

# Rows shared by both tables: omega [rad/s], clearance [rad], M0 [N m], I4P [kg m^2]
_OMEGA = {1: 100.0, 2: 100.0, 3: 100.0, 4: 100.0, 5: 100.0, 6: 100.0, 7: 40.0}
_CLEARANCE = {1: 0.0, 2: 0.01, 3: 0.001, 4: 0.001, 5: 0.001, 6: 0.001, 7: 0.001}
_M0 = {1: 0.0, 2: 0.0, 3: 500.0, 4: 500.0, 5: 0.0, 6: 0.0, 7: 500.0}
_I4P = {1: 0.35, 2: 0.35, 3: 0.35, 4: 0.45, 5: 0.45, 6: 0.35, 7: 0.35}


def _table1(v: int) -> dict:
    """Table 1's row ``v``: Table 2's without the second crank side (the readings of its
    lost cells, k2 = 7 and variant 6's C4 = 1e4, are Table 2's values)."""
    return {k: x for k, x in _table2(v).items() if k not in ("I5P", "I7", "C5", "C7", "k5", "k7")}


def _table2(v: int) -> dict:
    row = dict(I2P=0.005, I5P=0.005, I4=0.025, I7=0.025, I4P=_I4P[v],
               C2=1e5, C5=1e4, C4=5e4, C7=5e4, k2=7.0, k5=2.2, k4=29.0, k7=29.0,
               omega=_OMEGA[v], clearance=_CLEARANCE[v], M0=_M0[v])
    if v in (4, 5):
        row.update(k4=33.0, k7=33.0)
    if v == 6:
        row.update(C2=5e4, C5=5e3, C4=1e4, C7=1e4, k2=5.0, k5=1.6, k4=13.0, k7=13.0)
    return row


def preset(drive: str = "one-side", variant: int = 3, **overrides) -> SleyParameters:
    """Parameters of a variant of Table 1 (one-side) or Table 2 (both-sides).

    Parameters
    ----------
    drive : {"one-side", "both-sides"}
        Table 1 or Table 2.
    variant : int
        1 … 7.
    **overrides
        Any :class:`SleyParameters` field, e.g. ``alpha=math.radians(30)``.

    Returns
    -------
    SleyParameters
        With ``label`` like ``"one-side variant 3"``.  Readings of lost cells:
        k2 = 7 (Table 1 variants 1–5, 7), Table 1 variant 6 C4 = 1e4, α = σ = 10°.

    Raises
    ------
    ParameterError
        Unknown drive, variant or override.

    Examples
    --------
    >>> p = preset("one-side", 6)
    >>> p.C4, p.k2, p.omega
    (10000.0, 5.0, 100.0)
    """
    if isinstance(variant, bool) or variant not in VARIANTS:
        raise ParameterError(f"variant must be one of 1..7, got {variant!r}")
    # made once (frozen, so one object serves every call; a drive that is no str, which the
    # parameters refuse, is not hashed)
    params = (_preset if isinstance(drive, str) else _preset.__wrapped__)(drive, variant)
    return params.replace(**overrides) if overrides else params


@lru_cache(maxsize=32, typed=True)
def _preset(drive, variant: int) -> SleyParameters:
    row = _table1(variant) if drive == "one-side" else _table2(variant)
    return SleyParameters(drive=cast(Drive, drive), label=f"{drive} variant {variant}", **row)


def all_presets(**overrides) -> list[SleyParameters]:
    """The 14 presets: Table 1 variants 1–7, then Table 2 variants 1–7.

    Parameters
    ----------
    **overrides
        Parameter values applied to every preset (as :func:`preset`).

    Returns
    -------
    list of SleyParameters
        The 14 presets, in the order above.
    """
    return [preset(drive, v, **overrides) for drive in ("one-side", "both-sides")
            for v in VARIANTS]


#: The paper's printed results: PAPER[drive][variant][quantity] = (min, max).
#: Units: accelerations [rad/s²], moments [N·m].  Lost minus signs restored as
#: described in the module docstring (M2V of Table 1 variant 6 read as −279 / 101).
#: Table 1's ε4T, the rigid four-bar's (ν ω²), depends on the variant's ω only
#: (``_EPS4T``), so its rows give the other quantities.
_EPS4T = {100.0: (-2319, 2915), 40.0: (-371, 466)}
PAPER = {
    "one-side": {v: {"eps4T": _EPS4T[_OMEGA[v]], **row} for v, row in {
        1: {"eps2P": (-1666, 938), "eps4P": (-2756, 5686), "M2V": (-194, 193)},
        2: {"eps2P": (-32388, 54960), "eps4P": (-2848, 6975), "M2V": (-426, 272)},
        3: {"eps2P": (-11837, 13954), "eps4P": (-2754, 7039), "M2V": (-182, 196)},
        4: {"eps2P": (-13602, 15413), "eps4P": (-2767, 6472), "M2V": (-266, 232)},
        5: {"eps2P": (-13586, 15398), "eps4P": (-2814, 6033), "M2V": (-271, 232)},
        6: {"eps2P": (-8501, 7945), "eps4P": (-5277, 4443), "M2V": (-279, 101)},
        7: {"eps2P": (-3563, 5696), "eps4P": (-598, 1760), "M2V": (-52, 50)},
    }.items()},
    "both-sides": {
        1: {"eps2P": (-1292, 923), "eps4P": (-2639, 4434), "eps5P": (-2415, 1885), "M2V": (-201, 250)},
        2: {"eps2P": (-21656, 24770), "eps4P": (-4664, 6822), "eps5P": (-11493, 8034), "M2V": (-274, 273)},
        3: {"eps2P": (-10738, 10481), "eps4P": (-3287, 5393), "eps5P": (-3012, 3410), "M2V": (-289, 327)},
        4: {"eps2P": (-11016, 10415), "eps4P": (-3175, 5266), "eps5P": (-2849, 3355), "M2V": (-281, 319)},
        5: {"eps2P": (-11074, 9674), "eps4P": (-3203, 5257), "eps5P": (-2848, 3375), "M2V": (-280, 319)},
        6: {"eps2P": (-8236, 7306), "eps4P": (-4017, 4626), "eps5P": (-4764, 3229), "M2V": (-296, 167)},
        7: {"eps2P": (-2607, 4786), "eps4P": (-534, 1928), "eps5P": (-1203, 2500), "M2V": (-52, 43)},
    },
}
