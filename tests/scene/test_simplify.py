"""mechcirc.simplify (issue 7 §4): exact merges, measured approximate steps, bad bands."""

from pathlib import Path

import numpy as np
import pytest

import mechcirc
from mechcirc.errors import MechcircError
from mechcirc import BandError, parse_band, simplify
from reference.inputs import STB

ROOT = Path(__file__).resolve().parents[2]


def _rel_err(full, reduced_text, omega, output=None):
    red = mechcirc.parse(reduced_text)
    a, b = full.sweep(omega), red.sweep(omega)
    if output is None:
        return np.max(np.abs(b.K - a.K) / np.abs(a.K))
    return np.max(np.abs(b.force(output) - a.force(output)) / np.abs(a.force(output)))


def test_stb_heald_mass_chain_collapses_exactly_to_eq6():
    c = mechcirc.load(STB)
    r = simplify(c, (10.0, 3000.0), 1e-12)
    assert r.error <= 1e-12
    assert r.elements_after < r.elements_before
    # Grigoriev et al. 2002 eq. (6): K1..K4 in series is one mass M_III (η_B = η1²η2, η_C = η1²η2η3²)
    e1, e2, e3 = 0.8, 1.25, 0.9
    m1, m2, m3, m4 = 2.0, 1.5, 1.2, 0.9
    eB, eC = e1 ** 2 * e2, e1 ** 2 * e2 * e3 ** 2
    M3 = m1 * m2 * m3 * m4 * e1 ** 2 * eB * eC / (
        m2 * m3 * m4 * e1 ** 2 * eB * eC + m1 * m3 * m4 * eB * eC
        + m1 * m2 * m4 * e1 ** 2 * eC + m1 * m2 * m3 * e1 ** 2 * eB)
    chain = [e for e in r.circuit.elements if e.kind == "mass" and {e.n1, e.n2} == {"T", "D"}]
    assert len(chain) == 1 and chain[0].value * chain[0].eta == pytest.approx(M3, rel=1e-13)
    w = np.geomspace(10.0, 3000.0, 3001)
    assert _rel_err(c, r.netlist, w) <= 1e-12
    assert all(s["relative_shift"] is not None and abs(s["relative_shift"]) < 1e-12
               for s in r.shifts)


def test_stiff_spring_is_shorted_exactly_when_the_closed_form_error_allows():
    c = mechcirc.parse("drive V a 0 velocity=1\nspring ks a b 1e6\nmass m b 0 1.0\n")
    x = 100.0 ** 2 * 1.0 / 1e6                 # ω²m/k at the band top
    expected = x / (1 - x)                      # |K_rigid − K| / |K| there, the band's worst
    r = simplify(c, (1.0, 100.0), 1.02 * expected)
    assert [e.name for e in r.circuit.elements] == ["m"]
    assert r.error == pytest.approx(expected, rel=1e-9)
    kept = simplify(c, (1.0, 100.0), 0.98 * expected)
    assert sorted(e.name for e in kept.circuit.elements) == ["ks", "m"]
    assert kept.error <= 1e-15


def _ladder(n, seed):
    rng = np.random.default_rng(seed)
    lines = ["drive V n0 0 velocity=1", f"mass m0 n0 0 {rng.uniform(0.5, 2)!r}"]
    for i in range(1, n):
        lines.append(f"spring k{i} n{i - 1} n{i} {rng.uniform(1e4, 1e7)!r}")
        lines.append(f"damper c{i} n{i - 1} n{i} {rng.uniform(1, 50)!r}")
        lines.append(f"mass m{i} n{i} 0 {rng.uniform(1e-3, 2)!r}")
    return mechcirc.parse("\n".join(lines))


@pytest.mark.parametrize("seed", [1, 2])
def test_reported_error_is_measured_and_never_above_tol(seed):
    c = _ladder(8, seed)
    band = (5.0, 800.0)
    previous = len(c.elements) + 1
    for tol in (1e-6, 1e-3, 3e-2, 0.3):
        r = simplify(c, band, tol, points=400)
        assert r.error <= tol
        # an independent re-evaluation on the log grid (a subset of the check points)
        assert _rel_err(c, r.netlist, np.geomspace(*band, 400)) <= r.error * (1 + 1e-9) + 1e-15
        assert r.elements_after <= previous or tol == 1e-6
        previous = r.elements_after
    assert previous < len(c.elements)


def test_force_output_element_is_kept_and_its_force_checked():
    c = _ladder(6, 3)
    r = simplify(c, (5.0, 800.0), 0.05, output="k3", points=300)
    assert "k3" in {e.name for e in r.circuit.elements}
    assert r.error <= 0.05
    assert _rel_err(c, r.netlist, np.geomspace(5.0, 800.0, 300), "k3") <= r.error * (1 + 1e-9)


def test_trials_that_unload_the_output_element_do_not_warn():
    """Reducing the STB heald network with its rod k0 as the output: trial circuits that
    leave k0 without load are measured and refused, and used to warn the user that k0
    "carries no force" (4 warnings), though k0 stays loaded in the result."""
    import warnings

    c = mechcirc.load(STB)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        r = simplify(c, (10.0, 300.0), 0.01, output="k0")
    assert not [w for w in caught if issubclass(w.category, mechcirc.UnloadedElementWarning)]
    assert "k0" in {e.name for e in r.circuit.elements} and r.error <= 0.01
    assert np.abs(r.circuit.sweep([100.0]).force("k0")).min() > 0


@pytest.mark.parametrize("band,match", [((100.0, 100.0), "not below"), ((300.0, 10.0), "not below"),
                                        ((0.0, 10.0), "must be > 0"),
                                        ((1.0, float("inf")), "finite")])
def test_bad_bands(band, match):
    c = _ladder(3, 0)
    with pytest.raises(BandError, match=match):
        simplify(c, band, 0.01)


def test_band_text_and_tol_and_output_are_checked():
    assert parse_band("10:2e3") == (10.0, 2000.0)
    for text in ("10", "a:b", "5:5", "1:2:3"):
        with pytest.raises(BandError):
            parse_band(text)
    c = _ladder(3, 0)
    with pytest.raises(BandError, match="tol"):
        simplify(c, (1.0, 10.0), 0.0)
    with pytest.raises(MechcircError, match="no element of that name"):
        simplify(c, (1.0, 10.0), 0.1, output="nope")


def test_circuits_with_levers_reduce_and_drop_idle_levers():
    import math

    from mechcirc.scene import build, load_scene

    model = build(load_scene(ROOT / "examples" / "heald_scene.toml"), math.radians(40.0),
                  reflect="lever")
    full = model.circuit
    r = simplify(full, (30.0, 480.0), 0.05, points=500)
    assert r.error <= 0.05
    assert len(r.circuit.levers) < len(full.levers)
    assert any("nothing on its secondary side" in s for s in r.steps)
    assert _rel_err(full, r.netlist, np.geomspace(30.0, 480.0, 500)) <= r.error * (1 + 1e-9)



def test_a_stiff_spring_behind_a_lever_is_shorted_and_the_lever_kept():
    """ks (1e9 N/m) between the lever's secondary b and the mass m2: shorted
    (_short_circuit renames the lever's nodes too), m2 moves to b and the lever stays,
    K = 1/(jω(m1 + r² m2)) exactly; the measured error is the closed form's largest
    |K_red/K_full − 1| on [1, 100] rad/s (reached at 100 rad/s)."""
    text = ("drive V a 0 velocity=1\nmass m1 a 0 1\nlever L a 0 b 0 ratio=2\n"
            "spring ks b c 1e9\nmass m2 c 0 3\n")
    w = np.geomspace(1.0, 100.0, 400)
    r = simplify(mechcirc.parse(text), (1.0, 100.0), 1e-3, points=50)
    assert r.steps == ("springs shorted as rigid: ks",)
    red = mechcirc.parse(r.netlist)
    [lever] = red.levers
    assert (lever.p1, lever.p2, lever.s1, lever.s2, lever.ratio) == ("a", "0", "b", "0", 2.0)
    np.testing.assert_allclose(red.sweep(w).K, 1 / (1j * w * (1 + 4 * 3)), rtol=1e-14)
    full = 1 / (1j * w + 4 / (1j * w / 1e9 + 1 / (1j * w * 3)))
    worst = np.max(np.abs((1 / (1j * w * 13)) / full - 1))
    assert r.error == pytest.approx(worst, rel=1e-6)


def test_a_spring_across_a_lever_side_is_not_shorted():
    """k2 across the lever's primary side c–0: shorting it would make that side one node
    (_short_circuit refuses: None), so the search keeps k2 and merges it in series with k1
    once the mass m behind the lever is dropped: K = jω(1/k1 + 1/k2) exactly, and the
    measured error is the closed form's largest |K_red/K_full − 1| on the 50 check points,
    K_full = jω/k1 + 1/(k2/(jω) + r² jω m)."""
    from mechcirc._simplify import _short_circuit

    c = mechcirc.parse("drive V a 0 velocity=1\nspring k1 a c 1e4\nlever L c 0 b 0 ratio=2\n"
                       "mass m b 0 10\nspring k2 c 0 1e7\n")
    k2 = next(e for e in c.elements if e.name == "k2")
    assert _short_circuit(list(c.elements), list(c.levers), c.drive, k2) is None
    r = simplify(c, (1.0, 10.0), 1e-3, points=50)
    assert r.steps == ("masses removed as negligible: m",
                       "removed lever L: nothing on its secondary side",
                       "merged in series: k1+k2 -> k1_ser")
    jw = 1j * np.geomspace(1.0, 10.0, 50)
    red = jw * (1 / 1e4 + 1 / 1e7)
    np.testing.assert_allclose(mechcirc.parse(r.netlist).sweep(jw.imag).K, red, rtol=1e-14)
    worst = np.max(np.abs(red / (jw / 1e4 + 1 / (1e7 / jw + 4 * jw * 10)) - 1))
    assert r.error == pytest.approx(worst, rel=1e-6)
