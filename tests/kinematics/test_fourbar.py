"""Tests of mechcirc.kinematics.fourbar against independent references.

References: finite differences of positions, an independent circle-circle
intersection for C, the law of cosines, and Mrázek's printed ε4T range.
"""

import math
import warnings

import numpy as np
import pytest

from mechcirc.errors import GeometryError
from mechcirc.kinematics import FourBar

MRAZEK = (29.0, 37.0, 188.0, 189.0)

GEOMETRIES = [
    MRAZEK,
    (35.0, 110.0, 120.0, 150.0),   # a patent-like beat-up crank-rocker
    (10.0, 30.0, 25.0, 30.0),      # crank-rocker, rocker swinging across the frame line
    (30.0, 50.0, 45.0, 15.0),      # double-crank (drag link)
]


def _circle_point(a, b, c, d, theta, branch):
    """C by intersecting circle(B, b) with circle(D, c), written independently.

    The branch picks the intersection on the clockwise (+1) side of the ray D→B.
    """
    B = np.array([a * math.cos(theta), a * math.sin(theta)])
    D = np.array([d, 0.0])
    v = B - D
    e = np.hypot(*v)
    x = (c * c - b * b + e * e) / (2 * e)        # along D→B
    h = math.sqrt(c * c - x * x)                  # perpendicular
    u = v / e
    n_ccw = np.array([-u[1], u[0]])
    C = D + x * u - branch * h * n_ccw
    return B, C


@pytest.mark.parametrize("geom", GEOMETRIES)
@pytest.mark.parametrize("branch", [1, -1])
def test_positions_close_the_loop_and_match_circle_intersection(geom, branch):
    a, b, c, d = geom
    fb = FourBar(a, b, c, d, branch=branch)
    theta = np.linspace(0.0, 2 * math.pi, 97)
    st = fb.evaluate(theta)
    for k, th in enumerate(theta):
        B, C = _circle_point(a, b, c, d, th, branch)
        C_from_rocker = np.array([d + c * math.cos(st.phi4[k]), c * math.sin(st.phi4[k])])
        C_from_coupler = B + b * np.array([math.cos(st.phi3[k]), math.sin(st.phi3[k])])
        np.testing.assert_allclose(C_from_rocker, C, rtol=0, atol=1e-11 * d)
        np.testing.assert_allclose(C_from_coupler, C, rtol=0, atol=1e-11 * d)


@pytest.mark.parametrize("geom", GEOMETRIES)
@pytest.mark.parametrize("branch", [1, -1])
def test_mu_nu_against_finite_differences(geom, branch):
    fb = FourBar(*geom, branch=branch)
    theta = np.linspace(0.05, 2 * math.pi, 61)
    h = 1e-4
    p = {k: fb.rocker_angle(theta + k * h) for k in (-2, -1, 0, 1, 2)}
    q = {k: fb.evaluate(theta + k * h).phi3 for k in (-2, -1, 0, 1, 2)}
    # fourth-order central differences
    d1 = lambda f: (f[-2] - 8 * f[-1] + 8 * f[1] - f[2]) / (12 * h)
    d2 = lambda f: (-f[-2] + 16 * f[-1] - 30 * f[0] + 16 * f[1] - f[2]) / (12 * h * h)
    scale_mu = np.max(np.abs(fb.mu(theta)))
    scale_nu = np.max(np.abs(fb.nu(theta)))
    np.testing.assert_allclose(fb.mu(theta), d1(p), rtol=0, atol=1e-8 * scale_mu)
    np.testing.assert_allclose(fb.nu(theta), d2(p), rtol=0, atol=1e-5 * scale_nu)
    st = fb.evaluate(theta)
    np.testing.assert_allclose(st.mu3, d1(q), rtol=0, atol=1e-8 * np.max(np.abs(st.mu3)))
    np.testing.assert_allclose(st.nu3, d2(q), rtol=0, atol=1e-5 * np.max(np.abs(st.nu3)))


def test_mrazek_theoretical_rocker_acceleration():
    """Mrázek, Table 1: ε4T ∈ [−2319, 2915] s⁻² at ω = 100, [−371, 466] at ω = 40."""
    fb = FourBar(*MRAZEK)
    lo, hi = fb.rocker_acceleration_range(100.0)
    assert (round(lo), round(hi)) == (-2319, 2915)
    lo, hi = fb.rocker_acceleration_range(40.0)
    assert (round(lo), round(hi)) == (-371, 466)
    # the refined extremum is no worse than a dense independent grid
    th = np.linspace(0, 2 * math.pi, 200001)
    eps = fb.rocker_acceleration(th, 100.0)
    assert lo * (100 / 40) ** 2 <= eps.min() + 1e-6
    assert hi * (100 / 40) ** 2 >= eps.max() - 1e-6
    assert abs(eps.max() - hi * (100 / 40) ** 2) < 1e-3


def test_mirror_branch_flips_the_acceleration_range():
    lo, hi = FourBar(*MRAZEK, branch=-1).rocker_acceleration_range(100.0)
    assert (round(lo), round(hi)) == (-2915, 2319)


def test_scalar_fast_path_equals_vectorised():
    fb = FourBar(*MRAZEK)
    theta = np.linspace(-7.0, 13.0, 101)
    st = fb.evaluate(theta)
    for k, th in enumerate(theta):
        phi4, mu, nu = fb.transfer(float(th))
        assert phi4 == pytest.approx(st.phi4[k], rel=1e-14, abs=1e-14)
        assert mu == pytest.approx(st.mu[k], rel=1e-12, abs=1e-15)
        assert nu == pytest.approx(st.nu[k], rel=1e-12, abs=1e-15)
    assert isinstance(fb.rocker_angle(0.5), float)
    assert isinstance(fb.nu(0.5), float)


@pytest.mark.parametrize("geom", GEOMETRIES)
@pytest.mark.parametrize("branch", [1, -1])
def test_branch_continuous_over_several_revolutions(geom, branch):
    fb = FourBar(*geom, branch=branch)
    theta = np.linspace(-2 * math.pi, 4 * math.pi, 60001)
    st = fb.evaluate(theta)
    dth = theta[1] - theta[0]
    # a step of φ4 must be explained by μ: no 2π jumps, no branch flips
    step = np.diff(st.phi4)
    np.testing.assert_array_less(np.abs(step - st.mu[:-1] * dth),
                                 2.0 * np.max(np.abs(st.nu)) * dth ** 2 + 1e-12)
    # periodic (crank-rocker) or advancing by one turn per turn (double-crank)
    n = 20000  # samples per revolution
    shift = 2 * math.pi if fb.linkage_type == "double-crank" else 0.0
    np.testing.assert_allclose(st.phi4[n:] - st.phi4[:-n], shift, atol=1e-10)


def test_grashof_classification():
    assert FourBar(*MRAZEK).grashof_class == "Grashof"
    assert FourBar(*MRAZEK).linkage_type == "crank-rocker"
    assert FourBar(30, 50, 45, 15).linkage_type == "double-crank"
    assert FourBar(30, 10, 30, 25).linkage_type == "double-rocker"
    assert FourBar(30, 40, 10, 35).linkage_type == "rocker-crank"
    nong = FourBar(30, 40, 33, 45)        # 30 + 45 > 40 + 33
    assert nong.grashof_class == "non-Grashof"
    assert nong.linkage_type == "triple-rocker"
    assert FourBar(20, 30, 40, 50).grashof_class == "change-point"


def test_dead_centres_mrazek_by_law_of_cosines():
    a, b, c, d = MRAZEK
    fb = FourBar(a, b, c, d)
    front, back = fb.dead_centres()
    # at the dead centres A, B, C are collinear: |AC| = b ± a
    for dc, ac in ((front, b + a), (back, b - a)):
        C = np.array([d + c * math.cos(dc.phi4), c * math.sin(dc.phi4)])
        assert np.hypot(*C) == pytest.approx(ac, rel=1e-12)
        assert fb.mu(dc.theta) == pytest.approx(0.0, abs=1e-12)   # rocker at rest
        # angle at D of triangle ACD by the law of cosines
        ang_D = math.acos((c * c + d * d - ac * ac) / (2 * c * d))
        assert abs(math.pi - abs(dc.phi4)) == pytest.approx(ang_D, rel=1e-12)
        assert dc.nu == pytest.approx(fb.nu(dc.theta), rel=1e-14)
    front_angle = math.acos((c * c + d * d - (a + b) ** 2) / (2 * c * d))
    back_angle = math.acos((c * c + d * d - (b - a) ** 2) / (2 * c * d))
    assert fb.swing() == pytest.approx(front_angle - back_angle, rel=1e-12)
    assert math.degrees(fb.swing()) == pytest.approx(17.75, abs=0.01)
    # the rocker's extremes found by brute force are the dead centres
    th = np.linspace(0, 2 * math.pi, 100001)
    phi4 = fb.rocker_angle(th)
    assert phi4.max() - phi4.min() == pytest.approx(fb.swing(), rel=1e-8)


def test_transmission_angle_range_against_grid():
    for geom in ((35.0, 110.0, 120.0, 150.0), MRAZEK, (30.0, 50.0, 45.0, 15.0)):
        fb = FourBar(*geom)
        th = np.linspace(0, 2 * math.pi, 200001)
        g = fb.evaluate(th).gamma
        tr = fb.transmission_range()
        assert tr.gamma_min == pytest.approx(g.min(), abs=1e-9)
        # γ has a kink at 90°, so the grid can miss the top by |dγ/dθ|·Δθ/2 (< 1e-4 here)
        assert g.max() <= tr.gamma_max + 1e-12
        assert tr.gamma_max - g.max() < 1e-4
        for t in tr.theta_at_min:
            assert float(fb.evaluate(t).gamma) == pytest.approx(tr.gamma_min, abs=1e-12)
        for t in tr.theta_at_max:
            assert float(fb.evaluate(t).gamma) == pytest.approx(tr.gamma_max, abs=1e-12)
        # γ is the acute version of the interior angle BCD (law of cosines)
        np.testing.assert_allclose(g, np.minimum(fb.interior_angle(th),
                                                 math.pi - fb.interior_angle(th)), atol=1e-12)


@pytest.mark.parametrize("lengths, word", [
    ((10, 20, 30, 70), "frame"),
    ((100, 20, 30, 40), "crank"),
    ((0.0, 20, 30, 40), "crank"),
    ((-1, 20, 30, 40), "crank"),
    ((10, float("nan"), 30, 40), "coupler"),
])
def test_impossible_geometry(lengths, word):
    with pytest.raises(GeometryError, match=word):
        FourBar(*lengths)


def test_bad_branch():
    with pytest.raises(GeometryError, match="branch"):
        FourBar(*MRAZEK, branch=0)


def test_locking_names_the_crank_angle():
    fb = FourBar(30, 10, 30, 25)               # double-rocker: crank cannot turn
    lo, hi = fb.crank_range()
    assert fb.rocker_angle(0.5 * (lo + hi)) == fb.rocker_angle(0.5 * (lo + hi))
    with pytest.raises(GeometryError, match=r"locks.*θ = 0°"):
        fb.rocker_angle(np.array([0.0, 0.5 * (lo + hi)]))
    with pytest.raises(GeometryError, match="locks"):
        fb.transfer(math.pi)
    with pytest.raises(GeometryError, match="crank-rocker only"):
        fb.dead_centres()
    # the reachable window's ends are where the coupler and rocker line up (γ → 0)
    assert float(fb.evaluate(lo + 1e-9).gamma) < 1e-3
    assert float(fb.evaluate(hi - 1e-9).gamma) < 1e-3


# ------------------------------------------------------------- change points
@pytest.mark.parametrize("dims,kind,crossings", [
    ((30, 100, 30, 100), "parallelogram", (0.0, 180.0)),
    ((30, 100, 100, 30), "deltoid", (0.0,)),
    ((30, 30, 100, 100), "deltoid", (0.0, 180.0)),
    ((20, 30, 40, 50), "change-point", (180.0,)),
    ((20, 60, 50, 30), "change-point", (0.0,)),
])
def test_change_point_linkages_are_classified_and_crossings_located(dims, kind, crossings):
    fb = FourBar(*dims)
    assert fb.grashof_class == "change-point" and fb.linkage_type == kind
    got = tuple(math.degrees(t) for t in fb.branch_crossings())
    assert got == pytest.approx(crossings)
    a, b, c, d = dims
    for th in fb.branch_crossings():
        # independent check: B on the frame line and BD equal to b + c or |b − c|,
        # so C is on the same line (all four joints collinear)
        bd = math.hypot(a * math.cos(th) - d, a * math.sin(th))
        assert min(abs(bd - (b + c)), abs(bd - abs(b - c))) < 1e-12 * max(dims)  # rounding only


def test_change_point_summary_withholds_nu_and_says_why():
    doc = FourBar(30, 100, 30, 100).summary(100.0)
    assert doc["nu_min"] is None and doc["eps4T_max"] is None
    assert doc["branch_crossings_deg"] == [0.0, 180.0]
    assert any("assembly modes cross" in n for n in doc["notes"])
    assert "dead_centres" not in doc          # no longer called a crank-rocker
    with pytest.raises(GeometryError, match="branch crossing"):
        FourBar(30, 100, 30, 100).transfer(0.0)


def test_deltoid_summary_says_b_falls_on_d_not_that_the_joints_line_up():
    # 50/30/30/50: at θ = 0, B = (a, 0) = D, so C may lie anywhere on the circle of
    # radius c about D; the joints are not in line there and the angles are undefined
    (note,) = FourBar(50, 30, 30, 50).summary()["notes"]
    assert "B falls on D at θ = 0°" in note and "one line" not in note
    # the rhombus has both: B on D at 0°, the four joints in line at 180°
    (note,) = FourBar(40, 40, 40, 40).summary()["notes"]
    assert "B falls on D at θ = 0°" in note and "one line at θ = 180°" in note
    (note,) = FourBar(30, 100, 30, 100).summary()["notes"]
    assert "B falls on D" not in note and "one line at θ = 0° and 180°" in note


def _fd_nu(fb, th, h=1e-4):
    """ν by second differences of the rocker angle (positions only), unwrapped."""
    phi = np.unwrap(np.array([fb.rocker_angle(np.asarray(th) + k * h) for k in (-1, 0, 1)]),
                    axis=0)
    return (phi[0] - 2 * phi[1] + phi[2]) / (h * h)


@pytest.mark.parametrize("dims", [(60, 40, 50, 30), (30, 40, 50, 60), (30, 50, 20, 60),
                                  (40, 30, 40, 30), (30, 30, 50, 50), (20, 50, 60, 30),
                                  (30, 100, 100, 30)])
def test_change_point_nu_extrema_say_unbounded_at_the_crossing(dims):
    """The closed form switches assembly mode at a branch crossing, so the rocker angle has a
    kink there: μ jumps and ν is ±inf (the jump's sign), found from the rocker angle's slopes
    on each side (positions only, not the ν formula).  The other extremum is the finite one
    of the smooth pieces, checked against second differences of the rocker angle on a dense
    grid.  On main: ν ≈ ±2e15 at the crossing, of either sign, or the crossing's NaN taken as
    the extremum, and numpy's RuntimeWarnings."""
    fb = FourBar(*dims)
    lo, hi = fb.crank_range()
    jumps = {}
    for tc in fb.branch_crossings():
        h = 1e-5
        slope = [(fb.rocker_angle(t + h) - fb.rocker_angle(t - h)) / (2 * h)
                 for t in (tc - 1e-3, tc + 1e-3)]
        jumps[tc] = slope[1] - slope[0]
        assert abs(jumps[tc]) > 0.1               # a kink: the closed form switches branch
    th = np.linspace(lo, hi, 200_001) if fb.crank_rotates_fully else \
        np.linspace(lo + 1e-3, hi - 1e-3, 200_001)        # second differences inside the range
    far = np.all([np.abs((th - tc + np.pi) % (2 * np.pi) - np.pi) > 1e-2 for tc in jumps],
                 axis=0)
    with np.errstate(all="ignore"):
        ref = _fd_nu(fb, th[far])
    ref = ref[np.isfinite(ref)]
    for n in (3, 4, 7, 3600):
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            (tmin, nmin), (tmax, nmax) = fb.nu_extrema(n)
        for value, where, sign, best in ((nmin, tmin, -1, ref.min()), (nmax, tmax, 1, ref.max())):
            down = [tc for tc, j in jumps.items() if sign * j > 0]
            if down:
                assert value == sign * math.inf
                assert where in down
                continue
            assert math.isfinite(value)
            if n == 3600:
                assert value == pytest.approx(best, rel=1e-4, abs=1e-6)
                assert sign * (value - best) >= -1e-6 * max(1.0, abs(best))


# A deltoid with crank = frame and coupler = rocker: at θ = 0 the joint B lies on D, the
# coupler lies on the rocker and both may turn freely there (the rocker angle is undefined).
# Elsewhere it moves as a kite: C stays on the perpendicular bisector of BD, which passes
# through A, so C = s·e^{iθ/2} with |C − D| = c, s = a cos(θ/2) ± √(c² − a² sin²(θ/2)).
B_ON_D = [(50.0, 30.0, 30.0, 50.0), (5.0, 4.0, 4.0, 5.0), (2.0, 1.0, 1.0, 2.0),
          (30.0, 100.0, 100.0, 30.0), (3.0, 3.0, 3.0, 3.0)]


def _kite_rocker_angles(a, c, th):
    """Both rocker angles φ4 = arg(C − D) of the kite at crank angles ``th`` (D = (a, 0))."""
    root = np.sqrt(c * c - (a * np.sin(th / 2)) ** 2)
    return [np.angle(s * np.exp(0.5j * th) - a) for s in (a * np.cos(th / 2) + root,
                                                            a * np.cos(th / 2) - root)]


@pytest.mark.parametrize("branch", [1, -1])
@pytest.mark.parametrize("dims", B_ON_D)
def test_deltoid_with_b_on_d_moves_where_it_is_assembled(dims, branch):
    """On main the closed form's reference angle was taken from a grid through θ = 0, where
    B = D gives 0/0: φ4, μ and ν came out NaN at every crank angle, θ = 0 was reported as a
    lock and nu_extrema raised or returned NaN."""
    a, b, c, d = dims
    fb = FourBar(*dims, branch=branch)
    lo, hi = fb.crank_range()
    th = np.linspace(lo, hi, 2001)[1:-1] if not fb.crank_rotates_fully else \
        np.linspace(0.0, 2 * np.pi, 2001)[1:-1]
    th = th[np.abs(th) > 1e-6]                     # off the singular position θ = 0
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        s = fb.evaluate(th)
    assert np.all(np.isfinite(s.phi4)) and np.all(np.isfinite(s.mu))
    # positions: one of the kite's two rocker angles; μ: central differences of that one
    ref = _kite_rocker_angles(a, c, th)
    err = np.min([np.abs(_wrap(s.phi4 - r)) for r in ref], axis=0)
    assert np.max(err) < 1e-12
    h = 1e-6
    k = np.argmin([np.abs(_wrap(s.phi4 - r)) for r in ref], axis=0)
    fd = np.choose(k, [_wrap(p - m) / (2 * h) for p, m in zip(_kite_rocker_angles(a, c, th + h),
                                                             _kite_rocker_angles(a, c, th - h))])
    far = np.abs(s.gamma) > 1e-2                   # off the lock ends, where μ → ∞
    assert np.max(np.abs(fd - s.mu)[far] / (1 + np.abs(s.mu[far]))) < 1e-6
    # θ = 0: assembled (no lock), but B = D, so the rocker angle is undefined
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        at0 = fb.evaluate(np.array([0.0]))
        assert np.isnan(at0.phi4[0]) and np.isnan(at0.mu[0])
        assert fb.interior_angle(0.0) == 0.0       # B = D: the angle BCD closes
        with pytest.raises(GeometryError, match="singular position at θ = 0°"):
            fb.transfer(0.0)
        extrema = fb.nu_extrema()
        doc = fb.summary(10.0)
    assert doc["branch_crossings_deg"] in ([0.0], [0.0, 180.0])
    # ν: ±inf at θ = 0 where the closed form's μ jumps (its sign), else the extremum of
    # second differences of the kite's rocker angle, CROSSING_GAP = 1e-3 off θ = 0 and
    # (a rocking crank) off the lock ends
    # (the rhombus a = b = c = d is also a parallelogram, its joints in line at θ = π too)
    crossings = (0.0, math.pi) if a == b else (0.0,)
    hi = math.pi - (1e-3 if a == b else 0.0) if fb.crank_rotates_fully else hi - 1e-3
    side = np.linspace(1e-3, hi, 100_001)
    grid = np.concatenate([-side[::-1], side])
    h = 1e-5
    branch_of = _kite_branch(fb, grid)
    phi = [np.choose(branch_of, _kite_rocker_angles(a, c, grid + k * h)) for k in (-1, 0, 1)]
    nu_ref = (_wrap(phi[2] - phi[1]) - _wrap(phi[1] - phi[0])) / (h * h)
    jumps = {}
    for tc in crossings:
        t = tc + np.array([-1e-3, 1e-3])
        mu_at = np.choose(_kite_branch(fb, t), [_wrap(p - m) / 2e-6 for p, m in zip(
            _kite_rocker_angles(a, c, t + 1e-6), _kite_rocker_angles(a, c, t - 1e-6))])
        jumps[tc] = mu_at[1] - mu_at[0]
    for (where, value), sign, best in zip(extrema, (-1, 1), (nu_ref.min(), nu_ref.max())):
        down = [tc for tc, jump in jumps.items() if abs(jump) > 1e-3 and sign * jump > 0]
        if down:
            assert where in down and value == sign * math.inf
        else:
            assert value == pytest.approx(best, rel=1e-4, abs=1e-5)


def _kite_branch(fb, th):
    """Which of :func:`_kite_rocker_angles` the closed form's φ4 is at ``th`` (0 or 1)."""
    a, c = fb.crank, fb.rocker
    phi4 = fb.evaluate(th).phi4
    return np.argmin([np.abs(_wrap(phi4 - r)) for r in _kite_rocker_angles(a, c, th)], axis=0)


def _wrap(x):
    return np.angle(np.exp(1j * np.asarray(x, dtype=float)))


def test_grashof_linkage_has_no_crossings():
    assert FourBar(*MRAZEK).branch_crossings() == ()
    assert FourBar(*MRAZEK).summary()["notes"] == []


def test_lengths_whose_squares_overflow_are_refused():
    with pytest.raises(GeometryError, match="out of range"):
        FourBar(1e308, 37, 1e308, 189)
    with pytest.raises(GeometryError, match="square"):
        FourBar(*MRAZEK).summary(1e300)
