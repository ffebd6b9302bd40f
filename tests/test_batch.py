"""mechcirc.batch: many designs of one netlist at once, against the single-design path."""

from __future__ import annotations

import math
import warnings
from pathlib import Path

import mpmath
import numpy as np
import pytest

from mechcirc import _jit, parse
from mechcirc.batch import designs
from mechcirc.errors import InputError, NetlistError, NotSeriesParallelError
from mechcirc.expressions import evaluate, evaluate_array, parse_expression
from mechcirc.resonances import find_resonances
from reference.inputs import STB
from reference.networks import UNSEEN_MODE_12_DECADES

OMEGA = np.geomspace(10, 1e4, 200)

# Masses to the frame (a regular mass matrix: the Cholesky path), a lever whose
# ratio is a parameter, units, a spring's damping= companion and a damper.
LEVER = """\
.param r=2 m=1.5 k=4e4 c=3
drive V a 0 velocity=0.2
mass  m1 a 0 {m} kg
spring k1 a b {k/1000} N/mm
lever L b 0 c 0 ratio=r
mass  m2 c 0 0.4
spring k2 c 0 {2*k}
"""
DAMPED = LEVER + "damper d1 b 0 c\n"


def stb_params(n, seed):
    rng = np.random.default_rng(seed)
    return {"eta1": rng.uniform(0.6, 1.0, n), "eta2": rng.uniform(1.0, 1.5, n),
            "eta3": rng.uniform(0.7, 1.1, n), "eta4": rng.uniform(0.8, 1.2, n)}


def one(text, params, d):
    return parse(text, params={k: float(v[d]) for k, v in params.items()})


@pytest.mark.parametrize("text, params", [
    (STB.read_text(), stb_params(25, 1)),
    (LEVER, {"r": np.linspace(0.5, 3, 7), "m": np.geomspace(0.1, 10, 7)}),
    (DAMPED, {"c": np.geomspace(1e-3, 1e3, 7), "k": np.linspace(1e3, 1e5, 7)}),
])
def test_batched_sweep_is_the_single_sweep(text, params):
    ds = designs(text, params)
    s = ds.sweep(OMEGA)
    assert s.single.size == 0 and not s.failed       # all through the batch
    flags, Q0, v0 = s.flags, s.Q0, s.v0
    for d in range(ds.size):
        ref = one(text, params, d).sweep(OMEGA)
        # The same compiled plan, a design at a time: the same numbers (the
        # brief's bound is 1e-13 relative; they are equal).
        np.testing.assert_array_equal(s.K[d], ref.K)
        np.testing.assert_array_equal(s.error[d], ref.error)
        np.testing.assert_array_equal(flags[d], ref.flags)
        np.testing.assert_array_equal(Q0[d], ref.Q0)
        np.testing.assert_array_equal(v0[d], ref.v0)


def test_flags_and_singular_points_match():
    # ω exactly on the pole of m | k (ω² = k/m = 100): K = +∞·j, flag 1, Q0 = 0.
    text = ".param k=100\nmass m a 0 1\nspring s a 0 k\ndrive V a 0 velocity=1\n"
    params = {"k": np.array([100.0, 400.0, 2500.0])}
    omega = np.array([5.0, 10.0, 20.0, 50.0])
    s = designs(text, params).sweep(omega)
    for d in range(3):
        ref = one(text, params, d).sweep(omega)
        np.testing.assert_array_equal(s.K[d], ref.K)
        np.testing.assert_array_equal(s.flags[d], ref.flags)
    assert s.flags[0, 1] == 1 and s.Q0[0, 1] == 0


@pytest.mark.parametrize("text, params, n_batched", [
    (STB.read_text(), stb_params(40, 2), 40),            # singular M: condensed
    (LEVER, {"m": np.geomspace(0.1, 10, 9)}, 9),          # regular M: Cholesky
    (LEVER, {"r": np.array([0.5, 2.0, 3.0])}, 3),         # ratio varies: a basis per design
    (DAMPED, {"c": np.geomspace(1e-2, 1e2, 5)}, 5),       # dampers: stacked eigvals + Newton
    (DAMPED, {"c": np.geomspace(1e-2, 1e2, 5), "r": np.linspace(0.3, 4, 5)}, 5),   # both
])
def test_batched_resonances_are_find_resonances(text, params, n_batched):
    ds = designs(text, params)
    res = ds.resonances(omega_max=2e4)
    assert ds.size - res.single.size == n_batched and not res.failed
    worst = largest = 0.0
    for d in range(ds.size):
        ref = find_resonances(one(text, params, d), 2e4)
        got = res.list(d)
        assert [r.kind for r in got] == [r.kind for r in ref]
        for a, b in zip(got, ref):
            worst = max(worst, abs(a.omega - b.omega) / b.omega)
            assert a.zeta == pytest.approx(b.zeta, abs=1e-12)
            # a finite bound that covers the root (the single path's bound added, as its
            # root is a reference only to within it), also where the eigen-solver's start
            # was within rounding of the root (no digit of K there: error inf before)
            assert abs(a.omega - b.omega) / b.omega <= a.error + b.error
            largest = max(largest, a.error)
    assert worst <= 1e-12
    assert largest <= 2e-12        # achieved 4.1e-13 (253 of the roots were inf before)


def test_batched_resonances_against_mpmath():
    # drive at a, m1 a–0, k1 a–b, m2 b–0, k2 b–0 (masses to the frame: Cholesky).
    # Resonance (a held): ω² = (k1 + k2)/m2.  Anti-resonance (a free): the
    # 2-DOF pencil det([[k1 − ω²m1, −k1], [−k1, k1 + k2 − ω²m2]]) = 0.
    text = ".param m1=1 m2=0.5 k1=1e4 k2=3e4\ndrive V a 0 velocity=1\nmass ma a 0 m1\n" \
           "spring ka a b k1\nmass mb b 0 m2\nspring kb b 0 k2\n"
    rng = np.random.default_rng(7)
    params = {"m1": rng.uniform(0.2, 3, 6), "m2": rng.uniform(0.2, 3, 6),
              "k1": rng.uniform(1e3, 1e5, 6), "k2": rng.uniform(1e3, 1e5, 6)}
    res = designs(text, params).resonances()
    assert res.single.size == 0
    mpmath.mp.dps = 40
    for d in range(6):
        m1, m2, k1, k2 = (mpmath.mpf(float(params[n][d])) for n in ("m1", "m2", "k1", "k2"))
        held = mpmath.sqrt((k1 + k2) / m2)
        # m1 m2 λ² − (k1 m2 + (k1 + k2) m1) λ + k1 k2 = 0; the released network
        # also has the rigid-free root only if k's vanish (they do not).
        a, b, c = m1 * m2, -(k1 * m2 + (k1 + k2) * m1), k1 * k2
        disc = mpmath.sqrt(b * b - 4 * a * c)
        free = sorted(mpmath.sqrt(x) for x in ((-b - disc) / (2 * a), (-b + disc) / (2 * a)))
        ref = sorted([("resonance", held)] + [("antiresonance", w) for w in free],
                     key=lambda t: t[1])
        got = res.list(d)
        assert [r.kind for r in got] == [k for k, _ in ref]
        for r, (_, w) in zip(got, ref):
            rel = abs(r.omega - float(w)) / float(w)
            assert rel <= 1e-15                      # achieved: ≤ 5.2e-16 (2-3 ulp)
            assert r.error >= rel                    # the estimate covers the error


def test_a_design_is_the_same_in_any_batch():
    text, params = STB.read_text(), stb_params(12, 3)
    ds = designs(text, params)
    s, r = ds.sweep(OMEGA), ds.resonances(omega_max=1e4)
    for d in (0, 5, 11):
        alone = designs(text, {k: v[d:d + 1] for k, v in params.items()})
        s1, r1 = alone.sweep(OMEGA), alone.resonances(omega_max=1e4)
        np.testing.assert_array_equal(s1.K[0], s.K[d])
        assert r1.list(0) == r.list(d)


def test_extremes_of_a_lossless_design_against_a_fine_grid():
    text = ".param k=100\nmass m a 0 1\nspring s a b k\nmass m2 b 0 2\ndrive V a 0 velocity=0.5\n"
    params = {"k": np.array([100.0, 1e4])}
    ds = designs(text, params)
    ex = ds.extremes(np.array([1.0, 30.0]))
    # k = 100: zero of K at ω = sqrt(k/m2) ≈ 7.07 and pole at sqrt(k(1/m + 1/m2)) ≈ 12.2
    assert ex.K_min[0] == 0 and ex.omega_at_K_min[0] == pytest.approx(math.sqrt(50), rel=1e-14)
    assert ex.K_max[0] == math.inf
    assert ex.omega_at_K_max[0] == pytest.approx(math.sqrt(150), rel=1e-14)
    assert ex.Q0_max[0] == math.inf
    # k = 1e4: no zero or pole below 30 rad/s (first at ω = sqrt(5000) ≈ 70.7); the
    # mass-like K = 1/(jω(m + m2 ∥ spring…)) falls: extremes at the band's ends,
    # checked on a fine grid of the closed form K = (jω m2 + k/(jω)) / ...
    w = np.geomspace(1.0, 30.0, 100001)
    s = 1j * w
    Y = s * 1 + 1 / (s / 1e4 + 1 / (s * 2))
    absK = np.abs(1 / Y)
    assert ex.K_max[1] == pytest.approx(absK.max(), rel=1e-12)
    assert ex.K_min[1] == pytest.approx(absK.min(), rel=1e-12)
    assert (ex.omega_at_K_max[1], ex.omega_at_K_min[1]) == (1.0, 30.0)
    assert ex.Q0_max[1] == pytest.approx(0.5 / absK.min(), rel=1e-12)
    # The band's end values taken from a sweep already made are the same numbers.
    band = np.geomspace(1.0, 30.0, 9)
    again = ds.extremes(band, sweep=ds.sweep(band))
    for name in ("K_min", "omega_at_K_min", "K_max", "omega_at_K_max", "Q0_max"):
        np.testing.assert_array_equal(getattr(again, name), getattr(ex, name))


def test_damped_designs_extremes_are_searched_at_once_as_peak_searches():
    params = {"c": np.array([1.0, 10.0])}
    ds = designs(DAMPED, params)
    ex = ds.extremes(np.geomspace(10, 1e3, 50))
    assert ex.single.size == 0
    from mechcirc import peak

    for d in range(2):
        c = one(DAMPED, params, d)
        # The same maximum to rounding (the one golden search, on the plan at per-design
        # points and on peak's sweeps: measured ≤ 1.2e-15); ω on its flat top to ≤ 3e-10.
        for got, want in ((ex.Q0_max[d], peak(c, 10, 1e3, quantity="Q0")),
                          (ex.K_max[d], peak(c, 10, 1e3, quantity="K")),
                          (1 / ex.K_min[d], peak(c, 10, 1e3, quantity="S"))):
            assert got == pytest.approx(want.value, rel=1e-14)
        assert ex.omega_at_Q0_max[d] == pytest.approx(peak(c, 10, 1e3).omega, rel=1e-8)


def test_batched_extremes_of_sharp_damped_peaks_against_mpmath():
    # m1 a–0, k a–b, m2 b–0, c b–0: max |Q0| = V0·max |Z| located in mpmath
    # (tests/test_sweep.py's reference), the resonance's ζ from 7e-6 to 0.21 (the last
    # design's maximum at the band's top).
    from test_sweep import _two_mass_max_impedance

    text = ".param m1=1 m2=0.5 k=1e4 c=3\ndrive V a 0 velocity=2\nmass ma a 0 m1\n" \
           "spring ka a b k\nmass mb b 0 m2\ndamper cb b 0 c\n"
    c = np.geomspace(1e-3, 30, 6)
    ex = designs(text, {"c": c}).extremes([10, 1000])
    assert ex.single.size == 0
    for d in range(c.size):
        ref = _two_mass_max_impedance(1, 0.5, 1e4, c[d], ex.omega_at_Q0_max[d], 10, 1000)
        assert ex.Q0_max[d] == pytest.approx(2 * ref, rel=1e-15)


def test_extremes_of_damped_designs_reuse_resonances_computed_without_a_band(monkeypatch):
    # resonances() without omega_max holds every root, so extremes() must not solve
    # them again for each of the three peaks (it did: 48 against 9 ms a design).
    import mechcirc.circuit

    params = {"c": np.array([1.0, 10.0])}
    ds = designs(DAMPED, params)
    res = ds.resonances()
    band = np.geomspace(10, 1e3, 50)
    want = ds.extremes(band)
    calls = []
    solve = mechcirc.circuit.Circuit.resonances
    monkeypatch.setattr(mechcirc.circuit.Circuit, "resonances",
                        lambda *a, **k: calls.append(1) or solve(*a, **k))
    got = ds.extremes(band, resonances=res)
    assert calls == []
    for name in ("K_max", "omega_at_K_max", "K_min", "Q0_max"):
        np.testing.assert_array_equal(getattr(got, name), getattr(want, name))


def test_invalid_designs_fail_with_the_parsers_message():
    text = ".param m=2\nmass m1 a 0 m\nspring k a 0 100\ndrive V a 0 velocity=1\n"
    ds = designs(text, {"m": [1.0, -1.0, 2.0]})
    assert list(ds.valid) == [True, False, True]
    s = ds.sweep([1.0, 2.0])
    assert list(s.failed) == [1] and "mass 'm1' must be > 0 kg, got -1" in s.failed[1]
    assert np.isfinite(s.K[[0, 2]]).all()


def test_bad_arguments_are_refused():
    text = ".param m=2\nmass m1 a 0 m\nspring k a 0 100\ndrive V a 0 velocity=1\n"
    with pytest.raises(InputError, match="different lengths"):
        designs(".param m=2 k=1\nmass m1 a 0 m\nspring s a 0 k\ndrive V a 0 velocity=1\n",
                {"m": [1.0, 2.0], "k": [1.0, 2.0, 3.0]})
    with pytest.raises(NetlistError, match="no .param named 'x'"):
        designs(text, {"x": [1.0]})
    with pytest.raises(InputError, match="one-dimensional"):
        designs(text, {"m": np.ones((2, 2))})


@pytest.mark.parametrize("source", ["a^2 * b - 3/a", "sqrt(a) + exp(b/10) * sin(a)",
                                    "log(a - 1)", "a / (b - 2)", "(a - 2) ** 0.5",
                                    "-a ** b", "degrees(radians(a)) + pi"])
def test_array_expressions_are_the_scalar_ones(source):
    expr = parse_expression(source)
    rng = np.random.default_rng(5)
    a = np.concatenate([rng.uniform(0.5, 4, 40), [1.0, 2.0]])
    b = np.concatenate([rng.uniform(-3, 3, 40), [2.0, 2.0]])
    values, bad = evaluate_array(expr, {"a": a, "b": b}, a.size)
    for i in range(a.size):
        try:
            ref = evaluate(expr, {"a": float(a[i]), "b": float(b[i])})
        except NetlistError:
            assert bad[i]
            continue
        assert not bad[i] and values[i] == ref          # the same IEEE operations


def test_without_the_compiled_kernel_the_sweep_is_batched_in_numpy(monkeypatch):
    from mechcirc import _tree_eval

    text, params = STB.read_text(), stb_params(4, 9)
    ref = designs(text, params)
    s_ref, r_ref = ref.sweep(OMEGA), ref.resonances(omega_max=1e4)
    monkeypatch.setattr(_tree_eval, "_KERNEL", [None])      # as without numba
    ds = designs(text, params)
    s, r = ds.sweep(OMEGA), ds.resonances(omega_max=1e4)
    # Sweep and resonances' polishing through the numpy evaluation over designs.
    assert list(s.single) == list(r.single) == []
    np.testing.assert_array_equal(s.K, s_ref.K)            # numpy path = compiled plan
    np.testing.assert_array_equal(s.flags, s_ref.flags)
    for d in range(4):
        for a, b in zip(r.list(d), r_ref.list(d)):
            assert a.kind == b.kind and a.omega == pytest.approx(b.omega, rel=1e-12)


def test_a_circuit_built_in_code_is_a_template_of_one_design():
    from mechcirc import Circuit, Drive, Element

    c = Circuit((Element("mass", "m", "a", "0", 2.0), Element("spring", "k", "a", "0", 800.0)),
                Drive("V", "a", "0", "force", 3.0))
    ds = designs(c)
    assert ds.size == 1 and ds.design(0) == c
    np.testing.assert_array_equal(ds.sweep([1.0, 10.0]).K[0], c.sweep([1.0, 10.0]).K)
    (r,) = ds.resonances().list(0)
    assert r.kind == "antiresonance" and r.omega == pytest.approx(20.0, rel=1e-15)
    with pytest.raises(InputError, match="built in code"):
        designs(c, {"k": [1.0]})


def test_cycle_map_is_one_batch_equal_to_each_angle_alone():
    # Every crank angle of the heald scene is one design (dampers: the stacked
    # eigvals path); each equals find_resonances on that angle's circuit.
    from mechcirc.scene import build, cycle_map, load_scene

    scene = load_scene(Path(__file__).resolve().parents[1] / "examples" / "heald_scene.toml")
    cmap = cycle_map(scene, points=24)
    states = scene.linkage.solve(cmap.theta)
    worst = 0.0
    for i in range(24):
        c = build(scene, cmap.theta[i], state=states[i]).circuit
        ref = c.resonances()
        got = sorted(cmap.resonances[i] + cmap.antiresonances[i], key=lambda r: (r.omega, r.kind))
        assert [r.kind for r in got] == [r.kind for r in ref]
        for a, b in zip(got, ref):
            worst = max(worst, abs(a.omega - b.omega) / b.omega)
            assert a.zeta == pytest.approx(b.zeta, rel=1e-12, abs=1e-15)
        # The batch forms η = r² from the motion's arrays (dot products summed in
        # another order than build's): equal to rounding, measured ≤ 2e-18 relative.
        np.testing.assert_allclose(cmap.Q0[i], c.sweep(cmap.harmonics * cmap.omega_shaft).Q0,
                                   rtol=1e-13, atol=0)
    assert worst <= 1e-12                    # measured ≤ 1.5e-14 (360 angles)


def test_batched_damped_resonances_against_mpmath():
    # drive at a; m1 a–0, k a–b, m2 b–0, c b–0.  Held (a fixed): m2 s² + c s + k = 0.
    # Released: det(s²M + sD + K) = s (m1 m2 s³ + m1 c s² + (m1 + m2) k s + c k), a
    # rigid root s = 0 (not reported) and a cubic: a complex pair and a real root
    # (an overdamped mode: ω_d = 0, ζ = 1).
    text = ".param m1=1 m2=0.5 k=1e4 c=3\ndrive V a 0 velocity=1\nmass ma a 0 m1\n" \
           "spring ka a b k\nmass mb b 0 m2\ndamper cb b 0 c\n"
    rng = np.random.default_rng(11)
    params = {"m1": rng.uniform(0.2, 3, 5), "m2": rng.uniform(0.2, 3, 5),
              "k": rng.uniform(1e3, 1e5, 5), "c": rng.uniform(0.1, 30, 5)}
    res = designs(text, params).resonances()
    assert res.single.size == 0
    mpmath.mp.dps = 40
    for d in range(5):
        m1, m2, k, c = (mpmath.mpf(float(params[n][d])) for n in ("m1", "m2", "k", "c"))
        held = mpmath.polyroots([m2, c, k])
        free = mpmath.polyroots([m1 * m2, m1 * c, (m1 + m2) * k, c * k], maxsteps=200,
                                extraprec=200)
        ref = [("resonance", s) for s in held if mpmath.im(s) >= 0] + \
            [("antiresonance", s) for s in free if mpmath.im(s) >= 0]
        ref.sort(key=lambda t: (float(abs(t[1])), t[0]))
        got = res.list(d)
        assert [r.kind for r in got] == [kd for kd, _ in ref]
        for r, (_, s) in zip(got, ref):
            wn = float(abs(s))
            rel = abs(r.omega - wn) / wn
            # Complex roots within 1e-15; the slow overdamped root (≈ 7 rad/s beside a
            # rigid root at 0) to 1.5e-13: P(s) formed in float64 limits Newton.
            assert rel <= 5e-13
            assert r.error >= rel                            # the estimate covers it
            assert r.zeta == pytest.approx(float(-mpmath.re(s) / abs(s)), rel=1e-12, abs=1e-15)
            assert r.omega_d == pytest.approx(float(abs(mpmath.im(s))), rel=1e-12, abs=1e-12)


def test_batched_damped_resonances_with_a_massless_node_against_mpmath():
    # drive at a; m1 a–0, k a–b, c b–0, k2 b–d, m2 d–0: node b has no mass, so both
    # mass matrices are singular (the reversed problem at a shift, _shifted_roots).
    # Held (a fixed): H(s) = c m2 s³ + (k + k2) m2 s² + c k2 s + k k2.  Released:
    # (m1 s² + k) H(s) − k² (m2 s² + k2) = s·(quartic), a rigid root s = 0 (not reported).
    text = ".param m1=1 m2=0.5 k=1e4 k2=3e4 c=30\ndrive V a 0 velocity=1\nmass ma a 0 m1\n" \
           "spring ka a b k\ndamper cb b 0 c\nspring kb b d k2\nmass md d 0 m2\n"
    rng = np.random.default_rng(5)
    n = 12
    params = {"m1": rng.uniform(0.2, 3, n), "m2": rng.uniform(0.2, 3, n),
              "k": rng.uniform(1e3, 1e5, n), "k2": rng.uniform(1e3, 1e5, n),
              "c": np.geomspace(1, 3000, n)}          # from ζ ≈ 0.001 to overdamped
    res = designs(text, params).resonances()
    # the five least damped (c ≤ 24): the massless node's fast root (≈ (k + k2)/c) beside
    # the slow ones leaves errors over MAX_STACKED_ERROR, so find_resonances takes them
    assert res.single.tolist() == [0, 1, 2, 3, 4] and not res.failed
    mpmath.mp.dps = 40
    worst = 0.0
    for d in range(n):
        m1, m2, k, k2, c = (mpmath.mpf(float(params[x][d])) for x in ("m1", "m2", "k", "k2", "c"))
        H = [c * m2, (k + k2) * m2, c * k2, k * k2]
        free = [m1 * H[0], m1 * H[1], m1 * H[2] + k * H[0], m1 * H[3] + k * H[1] - k * k * m2,
                k * H[2]]
        ref = [("resonance", s) for s in mpmath.polyroots(H, maxsteps=200, extraprec=200)
               if mpmath.im(s) >= 0] + \
            [("antiresonance", s) for s in mpmath.polyroots(free, maxsteps=200, extraprec=200)
             if mpmath.im(s) >= 0]
        ref.sort(key=lambda t: (float(abs(t[1])), t[0]))
        got = res.list(d)
        assert [r.kind for r in got] == [kd for kd, _ in ref] == \
            [r.kind for r in find_resonances(one(text, params, d))]
        for r, (_, s) in zip(got, ref):
            wn = float(abs(s))
            rel = abs(r.omega - wn) / wn
            worst = max(worst, rel)
            assert r.error >= rel                            # the estimate covers it
            assert r.zeta == pytest.approx(float(-mpmath.re(s) / abs(s)), rel=1e-12, abs=1e-15)
            assert r.omega_d == pytest.approx(float(abs(mpmath.im(s))), rel=1e-12, abs=1e-12)
    # Measured 2.4e-14 (the stacked ones left an overdamped root at 0.26 rad/s beside one
    # at 1.5e5 rad/s 4.6e-11 off, its estimate 1.3e-8); the complex roots within 2e-15.
    assert worst <= 1e-13


def test_batched_resonances_of_the_damped_heald_drive_agree_with_the_single_path():
    # heald_damped.mcir has one massless direction with the drive released: batched
    # since _shifted_roots (before, every design went through find_resonances).  The
    # single path polishes on K in double-double (1e-16 against mpmath); the
    # batched roots differ from it by at most 1.5e-13, each within its estimate.
    text = (Path(__file__).parents[1] / "netlists" / "heald_damped.mcir").read_text()
    ds = designs(text, {"eta1": np.linspace(0.6, 1.0, 6), "eta3": np.linspace(1.1, 0.7, 6)})
    res = ds.resonances()
    assert res.single.size == 0 and not res.failed
    for d in range(6):
        single = find_resonances(ds.design(d))
        got = res.list(d)
        assert [r.kind for r in got] == [r.kind for r in single] and len(got) == 6
        for r, ref in zip(got, single):
            assert abs(r.omega - ref.omega) <= (r.error + ref.error) * ref.omega
            assert abs(r.zeta - ref.zeta) <= 1e-12


def test_newton_polish_goes_on_beside_a_root_that_makes_its_matrix_exactly_singular():
    # P(s) = s² I + diag(4, 9): at s = 2j P has an exact zero pivot, which makes
    # numpy's stacked solve refuse the whole stack; the other design's root must
    # still be polished (3.1j → 3j), the exact one left where it is.
    from mechcirc.resonances import _newton_det

    Ms, Ds, Ks = np.stack([np.eye(2)] * 2), np.zeros((2, 2, 2)), np.stack([np.diag([4.0, 9.0])] * 2)
    s, step, kappa = _newton_det(np.array([[2j], [3.1j]]), np.ones((2, 1), bool), Ms, Ds, Ks)
    assert s[0, 0] == 2j and step[0, 0] == 0
    assert abs(s[1, 0] - 3j) < 1e-6 and step[1, 0] > 0
    # κ = (|s|²‖I‖_F + ‖diag(4, 9)‖_F)/(|s|·|2s|) with the null vector a unit vector:
    # (4√2 + √97)/8 = 1.94 at s = 2j, (9√2 + √97)/18 = 1.254 at 3j.
    assert kappa == pytest.approx([(4 * 2 ** 0.5 + 97 ** 0.5) / 8,
                                   (9 * 2 ** 0.5 + 97 ** 0.5) / 18], rel=1e-6)


def test_batched_roots_of_equal_omega_are_sorted_as_find_resonances_sorts():
    # The network above with c²(1/m2 − 1/m1) = k: the released cubic factors as
    # (s + c/m1)(s² + (k/c) s + k/m2), so a released pair has |s|² = k/m2, the held
    # pair's: a resonance and an anti-resonance of equal ω (distinct s: not merged).
    # find_resonances sorts by (ω, kind): the anti-resonance first.
    text = ".param m1=1 m2=0.5 k=1e4 c=3\ndrive V a 0 velocity=1\nmass ma a 0 m1\n" \
           "spring ka a b k\nmass mb b 0 m2\ndamper cb b 0 c\n"
    m2 = np.array([1.0, 1.0, 0.5, 1.0, 2.0, 1.0, 0.25])
    c = np.array([10.0, 20.0, 10.0, 4.0, 8.0, 2.0, 1.0])
    params = {"m1": 2 * m2, "m2": m2, "c": c, "k": c ** 2 / (2 * m2)}
    res = designs(text, params).resonances()
    assert res.single.size == 0
    ties = 0
    for d in range(c.size):
        got = res.list(d)
        wn = math.sqrt(params["k"][d] / m2[d])
        assert [r.kind for r in got] == ["antiresonance", "antiresonance", "resonance"]
        assert [r.omega for r in got] == pytest.approx([c[d] / (2 * m2[d]), wn, wn],
                                                       rel=1e-14)
        assert [r.kind for r in got] == [r.kind for r in find_resonances(one(text, params, d))]
        ties += got[1].omega == got[2].omega
    assert ties            # some designs' ω are equal to the bit: the tie is tested


@pytest.fixture
def numpy_only():
    """The numpy paths only (``mechcirc._jit.COMPILED`` False), as without numba."""
    from mechcirc import _jit

    saved = _jit.COMPILED
    _jit.COMPILED = False
    yield
    _jit.COMPILED = saved


@pytest.mark.parametrize("text, params", [
    (STB.read_text(), stb_params(25, 1)),
    (LEVER, {"r": np.linspace(0.5, 3, 7), "m": np.geomspace(0.1, 10, 7)}),
    (DAMPED, {"c": np.geomspace(1e-3, 1e3, 7), "k": np.linspace(1e3, 1e5, 7)}),
    # ω on the pole of m | k for the first design (ω² = k/m = 100): K = ∞, flagged.
    (".param k=100\nmass m a 0 1\nspring s a 0 k\ndrive V a 0 velocity=1\n",
     {"k": np.array([100.0, 400.0, 2500.0])}),
])
def test_numpy_batch_is_the_numpy_single_path(numpy_only, text, params):
    # ω = 0 and an exact pole send rows through the checked (1/0 = ∞) pass.
    omega = np.concatenate([[0.0, 10.0], OMEGA])
    ds = designs(text, params)
    s = ds.sweep(omega)
    assert s.single.size == 0 and not s.failed         # one numpy pass, no design alone
    flags = s.flags
    for d in range(ds.size):
        ref = one(text, params, d).sweep(omega)
        # The same IEEE operations per design: equal (the brief's bound is 1e-13 relative).
        np.testing.assert_array_equal(s.K[d], ref.K)
        np.testing.assert_array_equal(s.error[d], ref.error)
        np.testing.assert_array_equal(flags[d], ref.flags)


def test_numpy_batch_at_each_designs_own_points_and_in_chunks(numpy_only, monkeypatch):
    from mechcirc import _tree_eval
    from mechcirc.reduction import evaluate

    params = {"r": np.linspace(0.5, 3, 7), "m": np.geomspace(0.1, 10, 7)}
    ds = designs(LEVER, params)
    monkeypatch.setattr(_tree_eval, "_NUMPY_CHUNK", 3 * OMEGA.size)    # 3 designs per pass
    s = ds.sweep(OMEGA)
    rng = np.random.default_rng(5)
    w = rng.uniform(1.0, 1e3, (ds.size, 9))                       # (D, W): own points
    scaled = {e.name: (ds.values[i] * ds.eta[i])[:, None]
              for i, e in enumerate(ds.circuit.elements)}
    ratios = {lv.name: ds.ratios[i][:, None] for i, lv in enumerate(ds.circuit.levers)}
    K, err = evaluate(ds.circuit.tree, w, error=True, designs=(scaled, ratios))
    for d in range(ds.size):
        c = one(LEVER, params, d)
        np.testing.assert_array_equal(s.K[d], c.sweep(OMEGA).K)
        Kd, ed = evaluate(c.tree, w[d], error=True)
        np.testing.assert_array_equal(K[d], Kd)
        np.testing.assert_array_equal(err[d], ed)


def test_numpy_batch_resonances_are_find_resonances(numpy_only):
    # The batched secant polishes on the numpy evaluation over designs.
    test_batched_resonances_are_find_resonances(STB.read_text(), stb_params(12, 3), 12)


# A bridge (k1, k2, k5, m1, m2 between a, b, c and the frame: not series–parallel),
# with a lever in one variant: the nodal path, its designs' A(ω) stacked.
BRIDGE = """\
.param k5=3e4 m1=1.2 c=5 r=2
drive V a 0 velocity=0.1
mass  ma a 0 0.5
spring k1 a b 1e5
spring k2 a c 6e4
spring k5 b c {k5}
mass  m1 b 0 {m1}
lever L c 0 e 0 ratio=r
mass  m2 e 0 0.8
damper d1 e 0 {c}
"""


@pytest.mark.parametrize("params, n_single", [
    # a grid over the bridge's spring, a mass and the damper (1e-3: nearly lossless)
    ({k: v.ravel() for k, v in zip(("k5", "m1", "c"), np.meshgrid(
        np.geomspace(1e3, 1e6, 3), np.linspace(0.5, 3, 3), [1e-3, 5.0, 50.0]))}, 0),
    # the lever's ratio varies: every design stacked, each with its own ratio
    ({"r": np.array([2.0, 0.5, 2.0, 3.0]), "k5": np.array([1e3, 1e4, 1e5, 1e6])}, 0),
])
@pytest.mark.parametrize("compiled", [None, True])
def test_nodal_designs_stacked_are_the_single_nodal_sweep(params, n_single, compiled,
                                                          monkeypatch):
    # compiled True: the stacked residual by the compiled kernel, each point's own
    # element values (the single path's small dense systems keep numpy's).
    monkeypatch.setattr(_jit, "COMPILED", compiled)
    omega = np.geomspace(10, 1e4, 100)
    ds = designs(BRIDGE, params)
    with pytest.raises(NotSeriesParallelError):
        _ = ds.circuit.tree
    s = ds.sweep(omega)
    assert s.single.size == n_single and not s.failed
    flags = s.flags
    for d in range(ds.size):
        ref = one(BRIDGE, params, d).sweep(omega)
        assert ref.method == "nodal"
        # The brief's bound is 1e-13 relative; achieved: equal (the same solve,
        # residual and estimate per point, A(ω) from the same stamps).
        np.testing.assert_allclose(s.K[d], ref.K, rtol=1e-13, atol=0)
        np.testing.assert_allclose(s.error[d], ref.error, rtol=1e-13, atol=0)
        np.testing.assert_array_equal(flags[d], ref.flags)


def test_nodal_designs_in_groups_are_the_same(monkeypatch):
    import mechcirc.batch as batch

    params = {"k5": np.geomspace(1e3, 1e6, 7), "m1": np.linspace(0.5, 3, 7)}
    omega = np.geomspace(10, 1e4, 30)
    whole = designs(BRIDGE, params).sweep(omega)
    monkeypatch.setattr(batch, "_STACK_ENTRIES", 2 * 25)     # 2 designs a group (n = 5)
    grouped = designs(BRIDGE, params).sweep(omega)
    assert whole.single.size == grouped.single.size == 0
    np.testing.assert_array_equal(grouped.K, whole.K)
    np.testing.assert_array_equal(grouped.error, whole.error)


def test_nodal_designs_at_omega_zero_are_left_to_the_single_path():
    # ω = 0 (A(ω) not finite) is the single path's convention: the stack takes none.
    text = BRIDGE.replace("damper d1 e 0 {c}", "")
    params = {"k5": np.array([1e3, 3e4])}
    omega = np.array([0.0, 10.0, 100.0])
    s = designs(text, params).sweep(omega)
    assert s.single.size == 2
    for d in range(2):
        ref = one(text, params, d).sweep(omega)
        np.testing.assert_array_equal(s.K[d], ref.K)
        np.testing.assert_array_equal(s.flags[d], ref.flags)


def test_stiff_nodal_designs_the_float64_refinement_cannot_take_are_left_to_the_single_path():
    # A bridge with springs from 1e-9 to 1e18 N/m and masses from 1e-6 to 1e8 kg: the
    # stiffest designs need the single path's double-double LU at some ω; they are
    # swept alone (counted in .single), the others stacked, every row as the single path.
    text = """\
.param k5=3e4 ks=1e14
drive V a 0 velocity=0.1
mass  ma a 0 1e-6
spring k1 a b {ks}
spring k2 a c 6e-4
spring k5 b c {k5}
mass  m1 b 0 1.2
mass  m2 c 0 1e8
spring k3 c 0 1e-9
"""
    params = {"ks": np.geomspace(1e3, 1e18, 8), "k5": np.geomspace(1e-6, 1e12, 8)}
    omega = np.geomspace(1e-3, 1e6, 60)
    s = designs(text, params).sweep(omega)
    assert 0 < s.single.size < 8 and not s.failed           # measured: designs 6 and 7
    for d in range(8):
        ref = one(text, params, d).sweep(omega)
        np.testing.assert_allclose(s.K[d], ref.K, rtol=1e-13, atol=0)
        np.testing.assert_allclose(s.error[d], ref.error, rtol=1e-13, atol=0)
        np.testing.assert_array_equal(s.flags[d], ref.flags)


# -- resonances of designs on the nodal path ----------------------------------

def _assert_resonances_as_single(text, params, res, omega_max, error_rtol):
    worst = 0.0
    for d in range(len(next(iter(params.values())))):
        ref = find_resonances(one(text, params, d), omega_max)
        got = res.list(d)
        assert [r.kind for r in got] == [r.kind for r in ref]
        for a, b in zip(got, ref):
            worst = max(worst, abs(a.omega - b.omega) / b.omega)
            assert a.zeta == pytest.approx(b.zeta, rel=1e-12, abs=1e-300)
            assert a.omega_d == pytest.approx(b.omega_d, rel=1e-12, abs=1e-300)
            if error_rtol is None:
                assert a.error == b.error
            else:
                assert b.error / error_rtol <= a.error <= b.error * error_rtol
    assert worst <= 1e-12
    return worst


# The bridge without its damper; with a mass across the bridge (b–c) and a massless
# node x: a mass matrix that is not diagonal, every root polished on K.
UNDAMPED_BRIDGE = BRIDGE.replace("damper d1 e 0 {c}\n", "")
POLISHED_BRIDGE = UNDAMPED_BRIDGE.replace("spring k1 a b 1e5", "spring k1 a x 2e5\nspring k1b x b 2e5") \
    .replace("mass  m1 b 0 {m1}", "mass  m1 b 0 {m1}\nmass  m3 b c 0.3")


@pytest.mark.filterwarnings("ignore::mechcirc.errors.UnloadedElementWarning")
@pytest.mark.parametrize("variant", ["undamped", "polished", "damped"])
def test_nodal_designs_resonances_are_find_resonances(variant, monkeypatch):
    import mechcirc.batch as batch

    text = {"undamped": UNDAMPED_BRIDGE, "polished": POLISHED_BRIDGE, "damped": BRIDGE}[variant]
    # a grid over the bridge's spring and a mass, or the damper (1e-3: nearly lossless)
    names = ("k5", "c") if variant == "damped" else ("k5", "m1")
    grids = [np.geomspace(1e3, 1e6, 3),
             [1e-3, 5.0, 50.0] if variant == "damped" else np.linspace(0.5, 3, 3)]
    params = {k: v.ravel() for k, v in zip(names, np.meshgrid(*grids))}
    ds = designs(text, params)
    with pytest.raises(NotSeriesParallelError):
        _ = ds.circuit.tree
    polished = []
    monkeypatch.setattr(batch, "_polish_nodal",
                        lambda *a, f=batch._polish_nodal: polished.append(a[1].size) or f(*a))
    for omega_max in (None,) if variant == "damped" else (None, 300.0):
        res = ds.resonances(omega_max=omega_max)
        # all stacked, but for the design (k5 = 1e6, c = 1e-3) whose drive released
        # creeps: the slow root s = −4c/4.9 = −8.2e-4 rad/s, below 1e-6 of its scale,
        # has κ = 2.5e12 in the stacked Newton and is polished one by one (2.5e-15)
        assert list(res.single) == ([2] if variant == "damped" else []) and not res.failed
        # "undamped": a diagonal mass matrix, the eigenvalue bound stands and no root
        # is polished, here as in find_resonances: every number equal.  "polished":
        # every root polished by the same secant; ω equal (measured), but it starts
        # from the stacked eigen-solver's root, a few ulp from the single path's, so
        # the steps and their estimate differ: within 0.60 … 1.40 of each other
        # (measured; asserted within 4).  "damped": the stacked companion solve
        # instead of QZ: ω agrees to 2.1e-16, ζ to 5.7e-15, the estimates (≤ 2.8e-15)
        # within 0.60 … 1.41 (measured; asserted within 4).
        _assert_resonances_as_single(text, params, res, omega_max,
                                     None if variant == "undamped" else 4.0)
    assert bool(polished) == (variant != "undamped")


def test_nodal_designs_resonances_in_groups_and_with_a_varying_lever():
    import mechcirc.batch as batch

    text = POLISHED_BRIDGE
    params = {"k5": np.geomspace(1e3, 1e6, 7), "r": np.array([2.0, 2.0, 0.5, 2.0, 3.0, 2.0, 2.0])}
    whole = designs(text, params).resonances()
    # the lever's ratio is in the constraint basis: one basis per design, all stacked
    assert whole.single.size == 0 and not whole.failed
    _assert_resonances_as_single(text, params, whole, None, 4.0)
    old = batch._STACK_ENTRIES
    try:
        batch._STACK_ENTRIES = 2 * 49          # 2 designs a group (held system: n = 7)
        grouped = designs(text, params).resonances()
    finally:
        batch._STACK_ENTRIES = old
    for x in ("omega", "zeta", "error"):
        np.testing.assert_array_equal(getattr(grouped, x), getattr(whole, x))


# Random network 8 of mp_nodal.random_network (seed 2, levers): a design's lever ratio of
# 0.0075 where the template's is 1 gives the template's pivots a basis with entries of
# 556; the massless directions, judged on ZᵀMZ, then took a direction with mass for
# massless (its anti-resonance at 417.09 rad/s lost, two others 3e-5 off, estimates
# 1e-15).  The anti-resonance is a pole of K at 40 digits (|K| 2e13 there, 0.9 at 0.1 %).
SCALED_LEVERS = """.param q0=1 q1=1 p0=1
drive V n1 0 velocity=1
mass e0 n1 0 1.117551748696774
spring e1 n2 0 1.2101673381448574
mass e2 n3 0 0.25880170607472974
mass e3 n4 n2 2.100166422916516
mass e4 n5 n4 0.2557434159303942
spring e5 n6 n5 3.1696929760969965
spring e6 n6 n3 0.480311209376726
mass e7 n1 n3 0.42796641975578126
spring e8 n3 n5 {p0}
lever L0 n4 0 n1 0 ratio={q0}
lever L1 n1 0 n6 0 ratio={q1}
"""


def test_nodal_designs_resonances_on_their_own_lever_ratios():
    params = {"q0": np.array([0.007458215465094185, 0.5, 1.0]),
              "q1": np.array([0.24112214590470354, 2.0, 1.0]),
              "p0": np.array([8.078052160185429, 3.0, 1.0])}
    from reference import mp_nodal

    res = designs(SCALED_LEVERS, params).resonances()
    assert res.single.size == 0 and not res.failed         # every design stacked
    for d in range(3):
        ref = find_resonances(one(SCALED_LEVERS, params, d))
        assert [r.kind for r in res.list(d)] == [r.kind for r in ref]
        text = SCALED_LEVERS
        for k, v in params.items():
            text = text.replace("{%s}" % k, repr(float(v[d])))
        spec = mp_nodal.spec_of(text)
        for r in res.list(d):
            # each within its own estimate of the root of K (1/K) at 40 digits (the
            # single path's estimates differ: 8.2e-14 against 1.0e-15 for one root, both
            # honest; ω the same to an ulp)
            exact = mp_nodal.root(spec, 1j * r.omega, r.kind == "antiresonance").imag
            assert abs(r.omega - exact) <= r.error * exact
    # the anti-resonance the badly scaled basis lost (its value checked against mpmath above)
    assert res.list(0)[-1].kind == "antiresonance" and abs(res.list(0)[-1].omega - 417.09) < 0.01


def test_nodal_designs_whose_levers_constrain_more_than_the_templates_go_alone():
    # Two levers between n1 and n2, ratios q0 and q1: at the template's (1, 1) one
    # constraint is redundant, at a design's (q0·q1 ≠ 1) both hold and K is 0 (no root;
    # find_resonances finds none).  A stacked basis with the template's rank gave an
    # anti-resonance near 0.72 rad/s instead.
    text = """.param q0=1 q1=1 p0=1
drive V n1 0 velocity=1
mass e0 n1 0 0.1661530537863931
mass e1 n2 n1 1.177427953181215
mass e2 n3 n1 1.8146514794078459
spring e3 0 n1 {p0}
damper e4 n2 n1 0.005019284570437724
lever L0 n2 0 n1 0 ratio={q0}
lever L1 n1 0 n2 0 ratio={q1}
"""
    params = {"q0": np.array([0.14314037503707575, 2.0]), "q1": np.array([0.8035763248685399, 3.0]),
              "p0": np.array([0.4193203359608588, 1.0])}
    res = designs(text, params).resonances()
    np.testing.assert_array_equal(res.single, [0, 1])
    assert res.list(0) == [] and res.list(1) == []


def test_nodal_designs_resonances_against_mpmath():
    # A Wheatstone bridge (not series–parallel): ma a–0, k1 a–b, k2 a–c, k5 b–c,
    # m1 b–0, m2 c–0.  Drive held (v_a = 0): det(K_bc − λ M_bc) = 0, 2 DOF.  Released:
    # det(K − λM) over a, b, c has the rigid root λ = 0 (no spring to the frame);
    # the others solve ma m1 m2 λ² − c2 λ + c1 = 0 with c2 the masses of two nodes
    # times the third's stiffness, c1 each mass times the 2×2 minor of the others.
    text = ".param ma=0.5 m1=1.2 m2=0.8 k1=1e5 k2=6e4 k5=3e4\n" \
           "drive V a 0 velocity=1\nmass Ma a 0 ma\nspring K1 a b k1\nspring K2 a c k2\n" \
           "spring K5 b c k5\nmass M1 b 0 m1\nmass M2 c 0 m2\n"
    rng = np.random.default_rng(11)
    params = {"ma": rng.uniform(0.2, 3, 5), "m1": rng.uniform(0.2, 3, 5),
              "m2": rng.uniform(0.2, 3, 5), "k1": rng.uniform(1e3, 1e5, 5),
              "k2": rng.uniform(1e3, 1e5, 5), "k5": rng.uniform(1e3, 1e5, 5)}
    ds = designs(text, params)
    with pytest.raises(NotSeriesParallelError):
        _ = ds.circuit.tree
    res = ds.resonances()
    assert res.single.size == 0
    mpmath.mp.dps = 40

    def quadratic(a, b, c):                       # a λ² − b λ + c = 0 → the two ω
        disc = mpmath.sqrt(b * b - 4 * a * c)
        return [mpmath.sqrt((b - disc) / (2 * a)), mpmath.sqrt((b + disc) / (2 * a))]

    worst = 0.0
    for d in range(5):
        ma, m1, m2, k1, k2, k5 = (mpmath.mpf(float(params[n][d]))
                                  for n in ("ma", "m1", "m2", "k1", "k2", "k5"))
        Kaa, Kbb, Kcc = k1 + k2, k1 + k5, k2 + k5
        held = quadratic(m1 * m2, m1 * Kcc + m2 * Kbb, Kbb * Kcc - k5 ** 2)
        free = quadratic(ma * m1 * m2, ma * m1 * Kcc + ma * m2 * Kbb + m1 * m2 * Kaa,
                         ma * (Kbb * Kcc - k5 ** 2) + m1 * (Kaa * Kcc - k2 ** 2)
                         + m2 * (Kaa * Kbb - k1 ** 2))
        ref = sorted([("resonance", w) for w in held] + [("antiresonance", w) for w in free],
                     key=lambda t: t[1])
        got = res.list(d)
        assert [r.kind for r in got] == [k for k, _ in ref]
        for r, (_, w) in zip(got, ref):
            rel = abs(r.omega - float(w)) / float(w)
            worst = max(worst, rel)
            assert r.error >= rel                    # the estimate covers the error
    assert worst <= 1e-15                            # achieved: 3.8e-16 (≈ 2 ulp)


@pytest.mark.filterwarnings("ignore::mechcirc.errors.UnloadedElementWarning")
def test_nodal_designs_extremes_from_the_stacked_roots():
    from mechcirc import peak

    text = BRIDGE.replace("damper d1 e 0 {c}\n", "")
    params = {"k5": np.geomspace(1e3, 1e6, 4), "m1": np.linspace(0.5, 3, 4)}
    omega = np.geomspace(10, 1e3, 50)
    ds = designs(text, params)
    ex = ds.extremes(omega)
    assert ex.single.size == 0 and not ex.failed     # Foster, on the stacked roots
    for d in range(ds.size):
        c = one(text, params, d)
        kmax = peak(c, 10, 1e3, quantity="K")
        assert ex.K_max[d] == kmax.value
        if math.isinf(kmax.value):
            assert ex.omega_at_K_max[d] == pytest.approx(kmax.omega, rel=1e-12)


def test_a_balanced_bridge_design_is_left_to_the_single_path():
    # k1/m1 = k2/m2 (1e5/(4/3) = 6e4/0.8): the bridge balances, a mode of the held and
    # the released network coincide and cancel in K; find_resonances cancels it, the
    # stack leaves that design to it (counted), the other stays stacked.
    text = BRIDGE.replace("damper d1 e 0 {c}\n", "").replace("lever L c 0 e 0 ratio=r\n", "") \
        .replace("mass  m2 e 0 0.8", "mass  m2 c 0 0.8")
    params = {"m1": np.array([1.2, 4 / 3])}
    res = designs(text, params).resonances()
    np.testing.assert_array_equal(res.single, [1])
    _assert_resonances_as_single(text, params, res, None, None)


@pytest.mark.parametrize("compiled", [False, True])
def test_designs_on_an_empty_grid(monkeypatch, compiled):
    # A study's band can leave no grid point to evaluate (its extremes then come
    # from the exact roots): the numpy path of many designs indexed its first
    # column and raised IndexError there; the compiled path returned (D, 0).
    from mechcirc import _jit

    monkeypatch.setattr(_jit, "COMPILED", compiled)
    ds = designs(STB.read_text(), {"eta1": [0.7, 0.8, 0.9]})
    s = ds.sweep(np.array([]))
    assert s.K.shape == (3, 0)
    assert ds.sweep(np.array([50.0])).K.shape == (3, 1)


def test_network_shape_ignores_values_and_sees_nodes_names_and_drive():
    from mechcirc.batch import from_circuits, network_shape

    a = parse(LEVER)
    b = parse(LEVER.replace(".param r=2 m=1.5", ".param r=3 m=2.5").replace("velocity=0.2",
                                                                             "velocity=0.7"))
    assert network_shape(a) == network_shape(b)
    assert from_circuits([a, b]).values.shape[1] == 2
    for changed in (LEVER.replace("spring k2 c 0", "spring k2 c b"),       # a node
                    LEVER.replace("mass  m2", "mass  m3"),                 # a name
                    LEVER.replace("velocity=0.2", "force=0.2"),            # the drive kind
                    LEVER.replace("lever L b 0 c 0", "lever L b 0 0 c")):  # a lever's ends
        assert network_shape(parse(changed)) != network_shape(a)
        with pytest.raises(InputError, match="differs in topology"):
            from_circuits([a, parse(changed)])


def test_a_springs_damping_expression_varies_per_design_and_designs_pickle():
    """spring ... damping={c}: each design's K(ω) is the closed form
    1/(k/(jω) + c) + 1/(jωm); c = 0 removes the damper (another network), so that
    design is left to the single path and still right.  A pickled Designs (its
    compiled plans dropped) gives the same numbers."""
    import pickle

    text = ".param c=2 m=1\ndrive V a 0 velocity=1\nspring k a b 1e4 damping={c}\n" \
           "mass m b 0 {m}\n"
    c, m = np.array([0.5, 20.0, 0.0]), np.array([1.0, 2.0, 1.5])
    ds = designs(text, {"c": c, "m": m})
    assert ds.valid.tolist() == [True, True, False]
    w = np.geomspace(10, 1e3, 9)
    s = ds.sweep(w)
    ref = 1 / (1e4 / (1j * w) + c[:, None]) + 1 / (1j * w * m[:, None])
    np.testing.assert_allclose(s.K, ref, rtol=1e-13)
    assert s.single.tolist() == [2]
    again = pickle.loads(pickle.dumps(ds))
    assert "_plan_memo" not in vars(again) and "_plan_memo" in vars(ds)   # the plan is not shipped
    np.testing.assert_array_equal(again.sweep(w).K, s.K)


@pytest.mark.parametrize("text", [
    # numpy's eigvals refused a companion matrix beyond float64 (a LinAlgError, also
    # before the eighteenth session); the condition number's SVD did not converge.
    ".param p=1\ndrive F n1 0 force=1\nmass mg1 n1 0 {p*6.89479e-18}\n"
    "spring sg1 n1 0 {p*5.75774e-07}\ndamper dl1 n1 n2 4.35002e+156\n"
    "mass mg2 n2 0 {p*1.90547e+278}\ndamper dg2 n2 0 {p*0.0131869}\n"
    "damper dl2 n2 n3 2.21259e-77\nmass mg3 n3 0 {p*3.24094}\n",
    ".param p=1\ndrive V n1 0 velocity=1\nmass mg1 n1 0 {p*2.43599}\n"
    "damper dg1 n1 0 {p*3.30184e+196}\nmass ml1 n1 n2 20641.8\ndamper dg2 n2 0 {p*9.01351}\n",
    ".param p=1\ndrive V n1 0 velocity=1\ndamper dg1 n1 0 {p*3.4976e-292}\n"
    "spring sl1 n1 n2 5.55067\nspring sg2 n2 0 {p*0.199266}\n",
])
def test_designs_beyond_float64_go_one_by_one_without_a_crash(text):
    import warnings

    ds = designs(text, {"p": np.array([0.5, 1.0, 2.0])})
    with warnings.catch_warnings(action="ignore"):
        res = ds.resonances()
        ds.extremes([1.0, 1e4], resonances=res)
        for d in range(ds.size):
            if d in res.failed:
                continue
            ref = find_resonances(one(text, {"p": [0.5, 1.0, 2.0]}, d))
            got = res.list(d)
            assert [r.kind for r in got] == [r.kind for r in ref]
            assert all(np.isfinite(r.omega) for r in got)


def test_plans_of_two_selections_of_designs_in_turn():
    # The memo of the last plan was kept under the method's own name, so that a
    # second selection called the kept tuple (a TypeError).
    ds = designs(DAMPED, {"c": np.geomspace(1.0, 10.0, 4)})
    assert ds.plan(np.arange(4)).designs == 4
    assert ds.plan(np.array([1, 3])).designs == 2
    assert ds.plan(np.arange(4)).designs == 4


@pytest.mark.filterwarnings("ignore::mechcirc.errors.UnloadedElementWarning")
def test_a_pair_that_k_says_cancels_is_left_to_the_single_path():
    """The network of tests/test_resonances.py's mode in both problems (masses between
    nodes, values over 12 decades), one mass a parameter: the stacked solve also finds
    that mode in both problems 1.5e-7 apart (1e8 times its estimates).  Asked of K on
    the design's circuit, the pair cancels: the design goes one by one, where it is
    dropped, and both designs' lists are find_resonances' (two roots each, not four)."""
    text = ".param p=1\n" + UNSEEN_MODE_12_DECADES.replace("4.399311767373876",
                                                         "{p*4.399311767373876}")
    ds = designs(text, {"p": [1.0, 1.5]})
    res = ds.resonances()
    assert res.single.tolist() == [0, 1]
    for d in range(2):
        one = find_resonances(ds.design(d))
        assert [(r.kind, r.omega, r.error) for r in res.list(d)] == \
            [(r.kind, r.omega, r.error) for r in one]
        assert len(one) == 2 and max(r.omega for r in one) < 4


def test_stacked_damped_roots_stay_complex_where_the_companions_roots_are_all_real():
    """The stacked eigvals of the companion matrices is a real array when every root of the
    stack is real (springs of 1e-300 N/m: every root slow and real); the reversed problem's
    roots written into it lost their imaginary parts (a ComplexWarning escaped to the user,
    from resonances.py).  Now complex from the start: no warning, the single path's roots."""
    text = (".param k=1e5\ndrive V a 0 velocity=1\nspring k1 a b k\nmass m1 b 0 1\n"
            "spring k2 b c {2*k}\ndamper c2 b c 20\nmass m2 c 0 2\nspring k3 c d k\n"
            "mass m3 d 0 1.5\ndamper c3 d 0 10\n")
    for k in (1e-300, 1e-200, 1e-40):
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            got = designs(text, {"k": [k]}).resonances().list(0)
        ref = find_resonances(one(text, {"k": np.array([k])}, 0))
        assert [(r.kind, r.omega, r.zeta) for r in got] == [(r.kind, r.omega, r.zeta) for r in ref]


def test_a_slow_overdamped_root_the_stack_cannot_resolve_goes_one_by_one():
    """A 3-mass chain driven through a spring, released (the anti-resonances): it floats on
    its damper to the frame (c/2), a slow real root s ≈ −c/9 beside the rigid s = 0,
    ill-conditioned on the float64 pencil (4·eps·κ = 3.6e-4 at c = 0.01): Newton on det P
    left it 9.9e-6 off (within that error, but 1e-12 was documented).  Such a design now
    goes to find_resonances (double-double on K): the slow root against mpmath's det P at
    40 digits (the massless drive node condensed: k1 carries no force): 0.0 measured at
    c = 0.01, 1 and 20 (correctly rounded); asserted 1e-15."""
    text = (".param c=20 k=1e5\ndrive V a 0 velocity=1\nspring k1 a b k\nmass m1 b 0 1\n"
            "spring k2 b c {2*k}\ndamper c2 b c c\nmass m2 c 0 2\nspring k3 c d k\n"
            "mass m3 d 0 1.5\ndamper c3 d 0 {c/2}\n")
    cs = np.array([0.01, 1.0, 20.0])
    res = designs(text, {"c": cs}).resonances()
    mpmath.mp.dps = 40
    for d, c in enumerate(cs):
        k, c = mpmath.mpf(1e5), mpmath.mpf(float(c))
        M = mpmath.diag([1, 2, mpmath.mpf(1.5)])       # b, c, d (a massless, free)
        K = mpmath.matrix([[2 * k, -2 * k, 0], [-2 * k, 3 * k, -k], [0, -k, k]])
        C = mpmath.matrix([[c, -c, 0], [-c, c, 0], [0, 0, c / 2]])
        slow = res.list(d)[0]
        assert slow.kind == "antiresonance" and slow.zeta == 1.0
        s = mpmath.findroot(lambda x: mpmath.det(x * x * M + x * C + K), -slow.omega)
        assert abs(slow.omega + float(s)) <= 1e-15 * slow.omega
        assert slow.error <= 1e-13
