"""Presets (Tables 1, 2 with the digest's readings) and parameter validation."""

import math

import pytest

from mechcirc.errors import GeometryError, MechcircError
from mechcirc.sley import PAPER, ParameterError, SleyParameters, all_presets, preset


def test_table1_readings():
    p = preset("one-side", 3)
    assert (p.I2P, p.I4, p.I4P, p.C2, p.C4, p.k2, p.k4) == (0.005, 0.025, 0.35, 1e5, 5e4, 7.0, 29.0)
    assert (p.omega, p.clearance, p.M0) == (100.0, 0.001, 500.0)
    assert math.isclose(math.degrees(p.alpha), 10.0)
    v6 = preset("one-side", 6)
    assert (v6.C2, v6.C4, v6.k2, v6.k4) == (5e4, 1e4, 5.0, 13.0)   # C4 read as 1e4
    assert preset("one-side", 7).omega == 40.0
    assert (preset("one-side", 4).I4P, preset("one-side", 4).k4) == (0.45, 33.0)


def test_table2():
    p = preset("both-sides", 6)
    assert (p.C2, p.C5, p.C4, p.C7, p.k2, p.k5, p.k4, p.k7) == (5e4, 5e3, 1e4, 1e4, 5, 1.6, 13, 13)
    q = preset("both-sides", 1)
    assert (q.I5P, q.I7, q.C5, q.k5) == (0.005, 0.025, 1e4, 2.2)


def test_all_presets_and_paper():
    ps = all_presets()
    assert len(ps) == 14 and len({p.label for p in ps}) == 14
    assert set(PAPER) == {"one-side", "both-sides"}
    assert all(len(PAPER[d]) == 7 for d in PAPER)


@pytest.mark.parametrize("omega", [0.0, -100.0])
def test_omega_rejected(omega):
    with pytest.raises(ParameterError, match="omega must be > 0") as info:
        preset("one-side", 1, omega=omega)
    assert isinstance(info.value, MechcircError) and isinstance(info.value, ValueError)


@pytest.mark.parametrize("kw, text", [
    (dict(C2=0.0), "C2 must be > 0"), (dict(k4=-1.0), "k4 must be ≥ 0"),
    (dict(clearance=-1e-3), "clearance"), (dict(I4P=math.nan), "finite"),
    (dict(alpha=7.0), "alpha"), (dict(beat_sign=0), "beat_sign"), (dict(foo=1), "unknown"),
])
def test_bad_parameters(kw, text):
    with pytest.raises(ParameterError, match=text):
        preset("one-side", 1, **kw)


def test_both_sides_needs_second_crank():
    with pytest.raises(ParameterError, match="I5P is required"):
        SleyParameters(drive="both-sides")


def test_bad_variant_and_drive():
    with pytest.raises(ParameterError, match="variant"):
        preset("one-side", 8)
    with pytest.raises(ParameterError, match="drive"):
        preset("sideways", 1)


def test_unassemblable_geometry():
    with pytest.raises(GeometryError, match="cannot be assembled"):
        preset("one-side", 1, l2P=0.5)           # crank longer than the other three together
    with pytest.raises(GeometryError, match="crank-rocker"):
        preset("one-side", 1, l2P=0.1)           # assembles, but the crank cannot turn fully
