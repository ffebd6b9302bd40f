"""The oscillating flat-faced follower of ``cam_profile`` against an envelope built here.

The reference never calls mechcirc.kinematics.cam: the face is the line through the
pivot A = (D, 0) along the arm, direction (−cos ψ, sin ψ), ψ = asin(r_b/D) + s(θ)
with the cycloidal law written out; it is turned into the cam's frame by R(−θ), and
the profile is its envelope — the point on the line where the line's derivative in
θ vanishes too (n·X = p, n′·X = p′, the derivatives by mpmath.diff at 30 digits) —
with the radius of curvature from the parametric formula on that envelope
(|X′|³ / (X′ × X″), mpmath.diff again) and, signed, as the rate the contact point
runs along the face per turn of the face's normal.  Profile to 1e-9 of r_b, ρ to 1e-8
relative; the pressure angle is 0 (the contact point of a face through the pivot
moves perpendicular to the face) and the base circle and the top dwell are circles.
"""

import math

import mpmath
import numpy as np
import pytest

from mechcirc.errors import InputError
from mechcirc.kinematics.cam import cam_profile
from mechcirc.motion_laws import cam_cycle

RB, D, H = 40.0, 100.0, math.radians(12.0)
RISE, DWELL, RET = (math.radians(d) for d in (120.0, 60.0, 120.0))
mpmath.mp.dps = 30


def s_of(th):
    """The cycloidal rise / dwell / return / dwell of the arm [rad], by hand (mpmath)."""
    th = mpmath.mpf(th) % (2 * mpmath.pi)
    if th < RISE:
        u = th / RISE
        return H * (u - mpmath.sin(2 * mpmath.pi * u) / (2 * mpmath.pi))
    if th < RISE + DWELL:
        return mpmath.mpf(H)
    if th < RISE + DWELL + RET:
        u = (th - RISE - DWELL) / RET
        return H * (1 - u + mpmath.sin(2 * mpmath.pi * u) / (2 * mpmath.pi))
    return mpmath.mpf(0)


def line(th):
    """(n, p) of the face in the cam's frame at cam angle th: n·X = p."""
    psi = mpmath.asin(RB / mpmath.mpf(D)) + s_of(th)
    dx, dy = -mpmath.cos(psi), mpmath.sin(psi)                    # along the face
    nx, ny = dy, -dx                                              # a normal to it
    p = nx * D                                                    # n·A, A = (D, 0)
    c, s = mpmath.cos(th), mpmath.sin(th)
    return (nx * c + ny * s, -nx * s + ny * c), p                 # R(−θ) n, p unchanged


def envelope(th):
    (nx, ny), p = line(th)
    dnx = mpmath.diff(lambda t: line(t)[0][0], th)
    dny = mpmath.diff(lambda t: line(t)[0][1], th)
    dp = mpmath.diff(lambda t: line(t)[1], th)
    det = nx * dny - ny * dnx
    return (p * dny - ny * dp) / det, (nx * dp - p * dnx) / det


def radius(th):
    x1 = mpmath.diff(lambda t: envelope(t)[0], th)
    y1 = mpmath.diff(lambda t: envelope(t)[1], th)
    x2 = mpmath.diff(lambda t: envelope(t)[0], th, 2)
    y2 = mpmath.diff(lambda t: envelope(t)[1], th, 2)
    return -(x1 * x1 + y1 * y1) ** 1.5 / (x1 * y2 - y1 * x2)      # + convex (clockwise)


def signed_radius(th):
    """The rate at which the contact point runs along the face per turn of its normal,
    (X′·u)/φ′ (u the face's direction, φ the normal's angle): the radius, negative where
    the envelope runs back (an undercut)."""
    (nx, ny), _ = line(th)
    dnx = mpmath.diff(lambda t: line(t)[0][0], th)
    dny = mpmath.diff(lambda t: line(t)[0][1], th)
    x1 = mpmath.diff(lambda t: envelope(t)[0], th)
    y1 = mpmath.diff(lambda t: envelope(t)[1], th)
    return (-ny * x1 + nx * y1) / (nx * dny - ny * dnx)


@pytest.fixture(scope="module")
def cam():
    return cam_profile(cam_cycle("cycloidal", 120, 60, 120, H), RB, "oscillating_flat",
                       pivot=D, points=361)


@pytest.mark.parametrize("deg", [20.0, 55.0, 90.0, 110.0, 200.0, 250.0, 290.0])
def test_profile_and_curvature_against_the_envelope(cam, deg):
    i = int(round(deg))
    assert cam.theta[i] == pytest.approx(math.radians(deg), abs=1e-15)
    th = mpmath.mpf(cam.theta[i])
    x, y = envelope(th)
    assert abs(cam.x[i] - float(x)) <= 1e-9 * RB and abs(cam.y[i] - float(y)) <= 1e-9 * RB
    assert cam.rho[i] == pytest.approx(float(radius(th)), rel=1e-8)
    assert cam.rho[i] == pytest.approx(float(signed_radius(th)), rel=1e-8)
    assert cam.pressure_angle[i] == 0.0


def test_dwells_are_circles(cam):
    low = cam.theta > math.radians(305)
    top = (cam.theta > math.radians(125)) & (cam.theta < math.radians(175))
    assert np.allclose(np.hypot(cam.x[low], cam.y[low]), RB, rtol=0, atol=1e-12)
    assert np.allclose(cam.rho[low], RB, rtol=1e-14)
    r_top = D * math.sin(math.asin(RB / D) + H)
    assert np.allclose(np.hypot(cam.x[top], cam.y[top]), r_top, rtol=0, atol=1e-12)
    assert np.allclose(cam.rho[top], r_top, rtol=1e-14)


def test_undercut_where_the_radius_turns_negative():
    """A fast swing undercuts: the check's value is the least ρ, refined, against the
    reference's at its angle."""
    fast = cam_profile(cam_cycle("cycloidal", 60, 120, 60, math.radians(5.0)), RB,
                       "oscillating_flat", pivot=D, points=721)
    chk = fast.check("undercut")
    assert not chk.ok and chk.value < 0
    assert chk.value == pytest.approx(float(radius_fast(chk.theta)), rel=1e-7)
    assert cam_profile(cam_cycle("cycloidal", 120, 60, 120, H), RB, "oscillating_flat",
                       pivot=D).check("undercut").ok


def radius_fast(theta):
    global RISE, DWELL, RET, H
    saved = RISE, DWELL, RET, H
    RISE, DWELL, RET = (math.radians(d) for d in (60.0, 120.0, 60.0))
    H = math.radians(5.0)
    try:
        return signed_radius(mpmath.mpf(theta))
    finally:
        RISE, DWELL, RET, H = saved


def test_a_face_that_turns_back_has_no_least_radius():
    """Where 1 + s′ = 0 the face stops turning against the cam: the reference's ρ runs
    through ±∞ there (opposite signs, |ρ| > 1e8 r_b at 1e-6 rad either side), so the
    check reports −∞ at that angle (closed form of the cycloidal return), not a grid
    point's huge value (it reported −6.3e21 at 220° for a 40° swing)."""
    h, ret = math.radians(50.0), math.radians(60.0)
    cam = cam_profile(cam_cycle("cycloidal", 60, 120, 60, h), RB, "oscillating_flat",
                      pivot=D)
    chk = cam.check("undercut")
    # return from 180°: s′ = −(h/β)(1 − cos 2πu), u = (θ − 180°)/β; 1 + s′ = 0 first at
    u = math.acos(1.0 - ret / h) / (2 * math.pi)
    theta_star = math.pi + ret * u
    assert not chk.ok and chk.value == -math.inf
    assert chk.theta == pytest.approx(theta_star, abs=1e-12)
    global RISE, DWELL, RET, H
    saved = RISE, DWELL, RET, H
    RISE, DWELL, RET, H = math.radians(60.0), math.radians(120.0), ret, h
    try:
        before, after = (float(signed_radius(mpmath.mpf(theta_star) + d))
                         for d in (-1e-6, 1e-6))
    finally:
        RISE, DWELL, RET, H = saved
    assert before * after < 0 and min(abs(before), abs(after)) > 1e8 * RB


def test_a_face_that_turns_back_is_not_exported(tmp_path):
    """The cam above has no profile (its contact point at infinity at θ*, the grid's points
    near it 1e4 r_b out): the CSV, the SVG and save_profile refuse it with θ* (closed form)
    and write nothing; a cam whose face keeps turning exports as before."""
    from mechcirc.kinematics.cam import profile_csv, profile_svg, save_profile

    h, ret = math.radians(50.0), math.radians(60.0)
    cam = cam_profile(cam_cycle("cycloidal", 60, 120, 60, h), RB, "oscillating_flat",
                      pivot=D)
    theta_star = math.degrees(math.pi + ret * math.acos(1.0 - ret / h) / (2 * math.pi))
    needle = f"turns back at θ = {theta_star:.3f}°"
    for export in (profile_csv, profile_svg):
        with pytest.raises(InputError, match=needle):
            export(cam)
    csv, svg = tmp_path / "p.csv", tmp_path / "p.svg"
    with pytest.raises(InputError, match=f"p.csv and .*p.svg not written: .*{needle}"):
        save_profile(cam, str(csv), str(svg))
    assert list(tmp_path.iterdir()) == []
    fine = cam_profile(cam_cycle("cycloidal", 60, 120, 60, math.radians(5.0)), RB,
                       "oscillating_flat", pivot=D)
    save_profile(fine, str(csv))
    assert csv.read_text() == profile_csv(fine)


def test_pivot_inside_the_base_circle_is_refused():
    with pytest.raises(InputError, match="pivot distance D = 30 must be more than"):
        cam_profile(cam_cycle("cycloidal", 120, 60, 120, H), RB, "oscillating_flat",
                    pivot=30.0)
