"""Change-point four-bars written as linkage files move through their branch crossing.

On the branch whose velocity is continuous (the dyad changes sides where its
joints line up), by both solvers and both backends, to the same numbers.
References: the parallelogram's closed form (coupler angle constant, rocker
angle = crank angle, rates 0 and ω, accelerations 0), and for a general
change point the four-bar's closed form evaluated with mpmath at 60 digits
(positions by the circle intersection, rates by the transfer functions μ, μ3,
ν, ν3 of :mod:`mechcirc.kinematics.fourbar`'s docstring, the assembly side
changed at each crossing), independent of the code under test.
"""

import math

import mpmath as mp
import numpy as np
import pytest

from test_linkage_solver import TEMPLATE as FOURBAR_FILE
from test_sliders import SLIDER_CRANK

from mechcirc.errors import GeometryError
from mechcirc.kinematics import parse_linkage

# The parallelogram 30/60/30/60 posed at 45°: its joints line up 135° of crank rotation
# from the pose (absolute 180°).
PARALLELOGRAM = FOURBAR_FILE.format(bx=21.213203435596427, by=21.213203435596427,
                                    cx=81.21320343559643, cy=21.213203435596427, d=60.0,
                                    omega=1.0)

# the dyads are numpy on either backend (one source since the thirteenth session): once;
# the Newton compiled (plain Python without numba) and batched numpy
SOLVERS = [("dyads", False), ("newton", True), ("newton", False)]


def _wrap(x):
    return np.angle(np.exp(1j * np.asarray(x, dtype=float)))


def _solve(lk, rel, method, compiled, monkeypatch):
    from mechcirc import _jit

    monkeypatch.setattr(_jit, "COMPILED", compiled)
    return lk.motion(rel, method=method)


# The crossing is 135° of crank rotation from the pose (absolute 180°).
PARA_GRIDS = [np.radians(np.arange(0.0, 361.0, 1.0)), np.radians(np.arange(0.0, 361.0, 45.0)),
              np.radians([135.0]), np.radians(135.0) + np.array([-1e-12, 1e-12]) * math.pi / 180,
              np.radians(np.linspace(134.0, 136.0, 81)), np.radians([400.0, 135.0, -90.0])]


@pytest.mark.parametrize("grid", range(len(PARA_GRIDS)))
@pytest.mark.parametrize("method,compiled", SOLVERS)
def test_parallelogram_stays_a_parallelogram_through_its_crossing(grid, method, compiled,
                                                                  monkeypatch):
    lk = parse_linkage(PARALLELOGRAM)
    rel = PARA_GRIDS[grid]
    m = _solve(lk, rel, method, compiled, monkeypatch)
    phi, w, al = m.q[:, 2::3], m.angular_velocities, m.angular_accelerations
    crank, coupler, rocker = range(3)
    # positions: coupler angle constant (0 from the pose), rocker turned as the crank
    assert np.max(np.abs(_wrap(phi[:, coupler]))) < 1e-12
    assert np.max(np.abs(_wrap(phi[:, rocker] - rel))) < 1e-12
    B = m.points[:, m.point_names.index("B")]
    C = m.points[:, m.point_names.index("C")]
    assert np.max(np.abs(C - B - [60.0, 0.0])) < 1e-11                  # mm
    # rates: coupler 0, rocker ω = 1 rad/s; accelerations 0 (measured on these grids:
    # ≤ 3.4e-11 rad/s and 1.3e-8 rad/s², the largest just outside the crossing's zone,
    # where the closed form and Newton lose about eps/sin³)
    assert np.max(np.abs(w[:, coupler])) < 1e-10
    assert np.max(np.abs(w[:, rocker] - 1.0)) < 1e-10
    assert np.max(np.abs(al[:, 1:])) < 5e-8
    assert np.max(np.abs(m.accelerations[:, m.point_names.index("C")]
                         - m.accelerations[:, m.point_names.index("B")])) < 3e-6   # mm/s²


def _reference(dims, theta, sigma, w):
    """(φ3, φ4, ω3, ω4, α3, α4) of the four-bar on assembly ``sigma`` at crank angle
    ``theta``, mpmath at 60 digits (not at a crossing itself)."""
    with mp.workdps(60):
        a, b, c, d = (mp.mpf(x) for x in dims)
        th = mp.mpf(theta)
        z = a * mp.expj(th) - d                       # D → B
        bd = abs(z)
        psi = mp.acos((bd * bd + c * c - b * b) / (2 * bd * c))
        phi4 = mp.arg(z) - sigma * psi
        C = d + c * mp.expj(phi4)
        phi3 = mp.arg(C - a * mp.expj(th))
        s43, c43 = mp.sin(phi4 - phi3), mp.cos(phi4 - phi3)
        mu = a * mp.sin(th - phi3) / (c * s43)
        mu3 = a * mp.sin(th - phi4) / (b * s43)
        nu = (a * mp.cos(th - phi3) + b * mu3 ** 2 - c * mu ** 2 * c43) / (c * s43)
        nu3 = (a * mp.cos(th - phi4) + b * mu3 ** 2 * c43 - c * mu ** 2) / (b * s43)
        return tuple(float(x) for x in (phi3, phi4, mu3 * w, mu * w, nu3 * w * w, nu * w * w))


def _fourbar(dims, th0, w):
    """The four-bar ``dims`` as a linkage file posed at crank angle ``th0`` on assembly +1."""
    a, b, c, d = dims
    phi4 = _reference(dims, th0, 1, w)[1]
    return parse_linkage(FOURBAR_FILE.format(bx=a * math.cos(th0), by=a * math.sin(th0),
                                             cx=d + c * math.cos(phi4), cy=c * math.sin(phi4),
                                             d=d, omega=w))


@pytest.mark.parametrize("dims,crossings", [
    ((20.0, 30.0, 40.0, 50.0), (180.0,)),
    ((20.0, 60.0, 50.0, 30.0), (0.0,)),
    ((30.0, 30.0, 100.0, 100.0), (0.0, 180.0)),       # deltoid (kite): crank = coupler
])
def test_general_change_points_follow_the_smooth_branch(dims, crossings, monkeypatch):
    w = 3.0
    a, b, c, d = dims
    th0 = math.radians(crossings[0] - 60.0)
    lk = _fourbar(dims, th0, w)
    rel = np.radians(np.concatenate([np.arange(0.0, 721.0, 1.0),
                                     60.0 + np.linspace(-1.0, 1.0, 41),
                                     60.0 + np.array([-1e-12, 0.0, 1e-12])]))
    th = th0 + rel
    # the assembly side changes at every crossing passed (the smooth branch)
    cross = np.sort(np.concatenate([math.radians(x) + 2 * math.pi * np.arange(-1, 3)
                                    for x in crossings]))
    # on a crossing: the limit from before it (the smooth branch's rates are continuous)
    at = np.array([np.any(np.isclose(x, cross, rtol=0, atol=1e-9)) for x in th])
    th_ref = np.where(at, th - 1e-14, th)
    passed = np.array([np.count_nonzero((cross > th0) & (cross < x)) for x in th_ref])
    ref = np.array([_reference(dims, x, (-1.0) ** k, w) for x, k in zip(th_ref, passed)])
    got = {}
    for method, compiled in SOLVERS:
        m = got[method, compiled] = _solve(lk, rel, method, compiled, monkeypatch)
        phi = m.q[:, 2::3]
        # angles from the pose against the reference's
        assert np.max(np.abs(_wrap(phi[:, 1] - phi[0, 1] - (ref[:, 0] - ref[0, 0])))) < 1e-11
        assert np.max(np.abs(_wrap(phi[:, 2] - phi[0, 2] - (ref[:, 1] - ref[0, 1])))) < 1e-11
        # angles measured ≤ 1.4e-13 rad; rates relative to ω, ω² measured ≤ 4.2e-11 and
        # 1.2e-8 (the accelerations inside the crossing's zone, interpolated)
        assert np.max(np.abs(m.angular_velocities[:, 1:] - ref[:, 2:4])) / w < 2e-10
        assert np.max(np.abs(m.angular_accelerations[:, 1:] - ref[:, 4:])) / w ** 2 < 4e-8
    # the solvers agree (measured: ≤ 1.2e-13 rad, 1.1e-12 and 4.4e-10 of the largest rate)
    base = got["dyads", False]
    for m in got.values():
        assert np.max(np.abs(_wrap(m.q[:, 2::3] - base.q[:, 2::3]))) < 1e-12
        assert np.max(np.abs(m.qdot - base.qdot)) / np.max(np.abs(base.qdot)) < 1e-11
        assert np.max(np.abs(m.qddot - base.qddot)) / np.max(np.abs(base.qddot)) < 2e-9


def test_velocity_is_continuous_across_the_crossing(monkeypatch):
    """Central differences of the positions (steps of 1e-4 rad, error ~ h² q‴/6 ≈ 2e-9 ω)
    match the solver's rates on both sides of the crossing and on it."""
    dims, w = (20.0, 30.0, 40.0, 50.0), 3.0
    th0 = math.radians(120.0)
    lk = _fourbar(dims, th0, w)
    h = 1e-4
    centre = np.radians([59.0, 59.9, 60.0, 60.1, 61.0])
    rel = np.concatenate([centre - h, centre, centre + h])
    for method, compiled in SOLVERS:
        m = _solve(lk, rel, method, compiled, monkeypatch)
        phi = np.unwrap(m.q[:, 2::3], axis=0)
        n = len(centre)
        fd = (phi[2 * n:] - phi[:n]) / (2 * h) * w
        assert np.max(np.abs(fd - m.angular_velocities[n:2 * n])) / w < 2e-9   # 2.8e-10 measured
        # and no jump: the rocker's rate 0.1° before and after the crossing agree
        # (measured 6e-12 ω apart)
        assert abs(m.angular_velocities[n + 1, 2] - m.angular_velocities[n + 3, 2]) < 1e-3 * w


@pytest.mark.parametrize("method,compiled", SOLVERS)
def test_a_triple_rocker_driven_past_its_limit_still_locks(method, compiled, monkeypatch):
    # non-Grashof (s + l > p + q): the crank cannot pass where coupler and rocker line up,
    # |B − D| = b + c: cos θ = (a² + d² − (b + c)²) / (2ad), posed at θ = 90°
    dims, w = (30.0, 10.0, 30.0, 25.0), 1.0
    lk = _fourbar(dims, math.pi / 2, w)
    lock = math.degrees(math.acos((30.0 ** 2 + 25.0 ** 2 - 40.0 ** 2) / (2 * 30.0 * 25.0))) - 90
    with pytest.raises(GeometryError, match=rf"locks near θ = {lock:.6g}°"):
        _solve(lk, np.radians(np.arange(0.0, 361.0, 1.0)), method, compiled, monkeypatch)


# test_sliders' slider-crank (crank 40 mm) with the rod 40 mm and no offset, posed at θ = 0
ISOSCELES = SLIDER_CRANK.format(omega=2.0)
for old, new in (("C = [178.5357, -10.0]", "C = [80.0, 0.0]"),
                 ("G1 = [0.0, -10.0]", "G1 = [-50.0, 0.0]"), ("G2 = [100.0, -10.0]", "G2 = [100.0, 0.0]")):
    assert old in ISOSCELES
    ISOSCELES = ISOSCELES.replace(old, new)


@pytest.mark.parametrize("method,compiled", SOLVERS)
def test_isosceles_slider_crank_passes_its_crossing(method, compiled, monkeypatch):
    # the rod lines up across the guide at θ = 90° and 270° (the block on the crank
    # pivot); on the smooth branch the rod mirrors the crank, x_C = 80 cos θ
    lk = parse_linkage(ISOSCELES)
    w = 2.0
    th = np.radians(np.concatenate([np.arange(0.0, 721.0, 1.0), [90.0, 270.0],
                                    90.0 + np.array([-1e-12, 1e-12])]))
    m = _solve(lk, th, method, compiled, monkeypatch)
    k = m.point_names.index("C")
    # measured: ≤ 1.7e-12 mm, 2.9e-10 mm/s, 2.5e-7 mm/s² (of 80, 160, 320), rod 7e-12 rad/s
    assert np.max(np.abs(m.points[:, k, 0] - 80 * np.cos(th))) < 1e-11
    assert np.max(np.abs(m.velocities[:, k, 0] + 80 * w * np.sin(th))) < 2e-9
    assert np.max(np.abs(m.accelerations[:, k, 0] + 80 * w * w * np.cos(th))) < 1e-6
    assert np.max(np.abs(m.angular_velocities[:, 1] + w)) < 1e-10      # the rod: −ω
