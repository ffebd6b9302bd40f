"""Disc cams against independent references: closed forms, SymPy, finite differences.

The references never call mechcirc.kinematics.cam: the pitch curve is built in
SymPy from the law written out here (not from mechcirc.motion_laws), rotated
into the cam's frame and differentiated symbolically; pressure angles come from
that curve's normal and from the closed forms (the translating one the
textbook's); curvature from the parametric formula κ = (x'y'' − y'x'')/(x'² + y'²)^{3/2}.
"""

import dataclasses
import math
import pickle

import mpmath
import numpy as np
import pytest
import sympy as sp

from mechcirc.errors import InputError
from mechcirc.kinematics.cam import cam_profile, profile_csv, profile_svg, save_profile
from mechcirc.motion_laws import Motion, cam_cycle

TH = sp.Symbol("theta", real=True)


def _zero_motion():
    return Motion("zero", (0.0,), ((0.0,) * 6,), ((0.0, 0.0, 0.0),))


def _cycloidal_rise(h, beta):
    """s(θ) of a cycloidal rise of h over β, written out (valid for 0 ≤ θ ≤ β)."""
    u = TH / beta
    return h * (u - sp.sin(2 * sp.pi * u) / (2 * sp.pi))


def _clear_of_junctions(theta, starts, k):
    """Grid points whose ±k-point stencil does not straddle a junction of the law's pieces
    (where a derivative of the lift jumps and a difference quotient loses its order)."""
    dt = theta[1] - theta[0]
    near = np.zeros(theta.size, bool)
    for t0 in list(starts) + [2 * np.pi]:
        near |= np.abs(theta - t0) < (k + 0.5) * dt
    return ~near


def _reference(B, v, theta):
    """Pitch point, pressure angle and signed curvature (+ convex) of the cam-frame curve
    R(−θ)·B(θ), B and the follower direction v given in the fixed frame (SymPy)."""
    c, s = sp.cos(TH), sp.sin(TH)
    x = B[0] * c + B[1] * s
    y = -B[0] * s + B[1] * c
    vx = v[0] * c + v[1] * s
    vy = -v[0] * s + v[1] * c
    x1, y1 = sp.diff(x, TH), sp.diff(y, TH)
    x2, y2 = sp.diff(x1, TH), sp.diff(y1, TH)
    kappa = -(x1 * y2 - y1 * x2) / (x1 ** 2 + y1 ** 2) ** sp.Rational(3, 2)  # runs clockwise
    nx, ny = -y1, x1                                   # outward normal (unnormalised)
    phi = sp.atan2(vx * ny - vy * nx, vx * nx + vy * ny)
    # cse: the four expressions' common subexpressions (the derivatives repeat the
    # lift's terms) evaluated once per point: the same 30-digit values, bit for bit
    # as floats, in about a seventh of the CPU (0.05 against 0.33 s for the oscillating
    # roller's 120 points).
    f = sp.lambdify(TH, [x, y, phi, kappa], "mpmath", cse=True)
    with mpmath.workdps(30):
        return np.array([[float(val) for val in f(mpmath.mpf(float(t)))] for t in theta]).T


@pytest.mark.parametrize("e", [0.0, 7.5, -12.0])
def test_translating_roller_against_sympy(e):
    h, beta, rb, rf = 20.0, math.radians(120), 40.0, 10.0
    cam = cam_profile(cam_cycle("cycloidal", 120, 60, 120, h), rb, roller_radius=rf,
                      offset=e, points=361)
    inside = (cam.theta > 0.01) & (cam.theta < beta - 0.01)       # the rise, written above
    theta = cam.theta[inside]
    d = math.sqrt((rb + rf) ** 2 - e ** 2)
    s = _cycloidal_rise(h, sp.Float(beta, 30))
    x, y, phi, kappa = _reference((sp.Float(e), d + s), (0, 1), theta)
    assert np.max(np.abs(cam.pitch_x[inside] - x)) < 1e-12 * rb
    assert np.max(np.abs(cam.pitch_y[inside] - y)) < 1e-12 * rb
    assert np.max(np.abs(cam.pressure_angle[inside] - phi)) < 1e-13
    assert np.max(np.abs(1 / cam.rho_pitch[inside] - kappa) * rb) < 1e-12
    # The textbook form tan φ = (s' − e)/(s + √((r_b + r_f)² − e²)) (Norton, ch. 8).
    textbook = np.arctan2(cam.dlift - e, cam.lift + d)
    assert np.max(np.abs(cam.pressure_angle - textbook)) < 1e-14


def test_oscillating_roller_against_sympy():
    h, beta, rb, rf, arm, pivot = math.radians(20), math.radians(120), 40.0, 10.0, 60.0, 80.0
    cam = cam_profile(cam_cycle("cycloidal", 120, 60, 120, h), rb, "oscillating",
                      roller_radius=rf, arm=arm, pivot=pivot, points=361)
    inside = (cam.theta > 0.01) & (cam.theta < beta - 0.01)
    theta = cam.theta[inside]
    psi0 = sp.acos(sp.Float((pivot ** 2 + arm ** 2 - (rb + rf) ** 2) / (2 * pivot * arm), 30))
    psi = psi0 + _cycloidal_rise(sp.Float(h, 30), sp.Float(beta, 30))
    B = (pivot - arm * sp.cos(psi), arm * sp.sin(psi))
    v = (sp.sin(psi), sp.cos(psi))                     # the roller centre's velocity direction
    x, y, phi, kappa = _reference(B, v, theta)
    assert np.max(np.abs(cam.pitch_x[inside] - x)) < 1e-12 * pivot
    assert np.max(np.abs(cam.pitch_y[inside] - y)) < 1e-12 * pivot
    assert np.max(np.abs(cam.pressure_angle[inside] - phi)) < 1e-13
    assert np.max(np.abs(1 / cam.rho_pitch[inside] - kappa) * rb) < 1e-12
    # Closed form: tan φ = (L(1 + ψ') − D cos ψ)/(D sin ψ) (derived in cam.py), over the whole turn.
    ps = float(psi0) + cam.lift
    closed = np.arctan2(arm * (1 + cam.dlift) - pivot * np.cos(ps), pivot * np.sin(ps))
    assert np.max(np.abs(cam.pressure_angle - closed)) < 1e-14
    # The roller centre is L from the pivot, which turns with −θ in the cam frame.
    ax, ay = pivot * np.cos(cam.theta), -pivot * np.sin(cam.theta)
    assert np.max(np.abs(np.hypot(cam.pitch_x - ax, cam.pitch_y - ay) - arm)) < 1e-12 * pivot


@pytest.mark.parametrize("law", ["harmonic", "modified_sine", "modified_trapezoid",
                                 "polynomial_345"])
def test_roller_profile_is_the_envelope(law):
    """Each profile point is r_f from its pitch point along the pitch curve's normal, whose
    direction is checked against 4th-order finite differences of the pitch points."""
    rf = 12.0
    motion = cam_cycle(law, 100, 40, 80, 25.0)
    cam = cam_profile(motion, 50.0, roller_radius=rf, offset=5.0, points=20001)
    P = cam.pitch_x + 1j * cam.pitch_y
    C = cam.x + 1j * cam.y
    assert np.max(np.abs(np.abs(P - C) - rf)) < 1e-12 * rf
    dt = cam.theta[1] - cam.theta[0]
    tangent = (-P[4:] + 8 * P[3:-1] - 8 * P[1:-3] + P[:-4]) / (12 * dt)
    cos = ((P - C)[2:-2] * np.conj(tangent)).real / (rf * np.abs(tangent))
    smooth = _clear_of_junctions(cam.theta, motion.start, 2)[2:-2]
    assert np.max(np.abs(cos[smooth])) < 1e-10
    # The profile is on the cam's side of the pitch curve (outward normal).
    assert np.all(np.abs(C) < np.abs(P))


def test_curvature_against_finite_differences_of_the_pitch_curve():
    motion = cam_cycle("polynomial_345", 90, 30, 90, 15.0)
    cam = cam_profile(motion, 30.0, roller_radius=8.0, offset=-4.0, points=36001)
    P = cam.pitch_x + 1j * cam.pitch_y
    dt = cam.theta[1] - cam.theta[0]
    d1 = (P[2:] - P[:-2]) / (2 * dt)
    d2 = (P[2:] - 2 * P[1:-1] + P[:-2]) / dt ** 2
    kappa = -(d1.real * d2.imag - d1.imag * d2.real) / np.abs(d1) ** 3
    smooth = _clear_of_junctions(cam.theta, motion.start, 1)[1:-1]
    assert np.max(np.abs(kappa - 1 / cam.rho_pitch[1:-1])[smooth]) * 30.0 < 1e-6


@pytest.mark.parametrize("follower,kw", [("roller", {"roller_radius": 10.0, "offset": 6.0}),
                                         ("roller", {"roller_radius": 0.0}),
                                         ("flat", {}),
                                         ("oscillating",
                                          {"roller_radius": 10.0, "arm": 60.0, "pivot": 80.0})])
def test_zero_stroke_is_the_base_circle(follower, kw):
    rb = 40.0
    cam = cam_profile(_zero_motion(), rb, follower, points=73, **kw)
    assert np.max(np.abs(np.hypot(cam.x, cam.y) - rb)) < 1e-13 * rb
    assert np.max(np.abs(cam.rho - rb)) < 1e-12 * rb
    if follower != "flat":
        rp = rb + kw["roller_radius"]
        assert np.max(np.abs(np.hypot(cam.pitch_x, cam.pitch_y) - rp)) < 1e-13 * rp
    if follower == "roller":      # the force along the radius: φ = −asin(e/(r_b + r_f))
        phi = -math.asin(kw.get("offset", 0.0) / (rb + kw["roller_radius"]))
        assert np.max(np.abs(cam.pressure_angle - phi)) < 1e-15
    assert cam.check("undercut").ok and cam.check("pressure_angle").ok


def test_eccentric_circle_with_a_flat_face():
    """Harmonic rise and return of h over 180° each: s = h(1 − cos θ)/2, the lift of an
    eccentric circle of radius r_b + h/2 whose centre is h/2 from the cam's axis."""
    rb, h = 30.0, 20.0
    cam = cam_profile(cam_cycle("harmonic", 180, 0, 180, h), rb, "flat", offset=3.0,
                      points=1001)
    assert np.max(np.abs(cam.lift - h * (1 - np.cos(cam.theta)) / 2)) < 1e-13 * h
    r = np.abs(cam.x + 1j * (cam.y + h / 2))
    assert np.max(np.abs(r - (rb + h / 2))) < 1e-13 * rb
    assert np.max(np.abs(cam.rho - (rb + h / 2))) < 1e-13 * rb
    assert np.all(cam.pressure_angle == 0.0)


def test_undercut_fires_for_a_small_base_circle_only():
    motion = cam_cycle("cycloidal", 60, 30, 60, 40.0)
    small = cam_profile(motion, 10.0, roller_radius=20.0, points=721)
    large = cam_profile(motion, 60.0, roller_radius=20.0, points=721)
    cut = small.check("undercut")
    assert not cut.ok and cut.value < 0
    assert large.check("undercut").ok
    # The reported value is the smallest convex ρ − r_f: no grid point of 10⁵ has less.
    fine = cam_profile(motion, 10.0, roller_radius=20.0, points=100001)
    convex = fine.rho_pitch > 0
    assert cut.value <= np.min(fine.rho[convex]) + 1e-12
    assert cut.value == pytest.approx(np.min(fine.rho[convex]), abs=1e-7)
    # Flat face: ρ = r_b + s + s'' ≤ 0 is the undercut.  On a cycloidal rise of h over β,
    # dρ/dθ = s' + s''' = 0 where cos 2πu = 1/(1 − (2π/β)²), u = θ/β in (1/2, 1).
    flat = cam_profile(motion, 10.0, "flat", points=721)
    h, beta = 40.0, math.pi / 3
    u = (2 * math.pi - math.acos(1 / (1 - (2 * math.pi / beta) ** 2))) / (2 * math.pi)
    rho_min = 10.0 + h * (u - math.sin(2 * math.pi * u) / (2 * math.pi)) \
        + h * 2 * math.pi * math.sin(2 * math.pi * u) / beta ** 2
    assert not flat.check("undercut").ok
    assert flat.check("undercut").value == pytest.approx(rho_min, abs=1e-11)
    assert cam_profile(motion, 200.0, "flat").check("undercut").ok


def test_pressure_angle_check_and_its_refined_extreme():
    motion = cam_cycle("modified_sine", 70, 50, 90, 30.0)
    cam = cam_profile(motion, 25.0, roller_radius=8.0, offset=3.0, points=361)
    check = cam.check("pressure_angle")
    fine = cam_profile(motion, 25.0, roller_radius=8.0, offset=3.0, points=200001)
    worst = np.max(np.abs(fine.pressure_angle))
    assert worst - 1e-13 <= check.value <= worst + 1e-9
    assert not check.ok and check.limit == pytest.approx(math.radians(30))
    assert cam_profile(motion, 25.0, roller_radius=8.0, offset=3.0,
                       pressure_limit_deg=80).check("pressure_angle").ok


@pytest.mark.parametrize("kw,needle", [
    ({"base_radius": -1.0}, "base radius must be > 0"),
    ({"base_radius": 40.0, "roller_radius": -2.0}, "roller radius must be ≥ 0"),
    ({"base_radius": 40.0, "roller_radius": 10.0, "offset": 50.0}, "offset |e| = 50"),
    ({"base_radius": 40.0, "follower": "oscillating", "roller_radius": 10.0, "arm": 10.0, "pivot": 100.0},
     "cannot put its roller centre"),
    ({"base_radius": 40.0, "follower": "knife"}, "unknown follower"),
    ({"base_radius": 40.0, "points": 3}, "points must be at least 8"),
    ({"base_radius": 40.0, "pressure_limit_deg": 90.0}, "between 0 and 90 degrees"),
])
def test_bad_geometry_is_named(kw, needle):
    with pytest.raises(InputError, match=None) as info:
        cam_profile(cam_cycle("cycloidal", 120, 60, 120, 20.0), **kw)
    assert needle in str(info.value)


def test_the_lift_is_measured_from_its_lowest_point():
    """A negative stroke (or a table of absolute positions): the lowest point touches the
    base circle, and the cam is the positive-stroke cam turned by the rise and dwell."""
    down = cam_profile(cam_cycle("cycloidal", 120, 60, 120, -20.0), 40.0, roller_radius=10.0,
                       points=361)
    up = cam_profile(cam_cycle("cycloidal", 120, 60, 120, 20.0), 40.0, roller_radius=10.0,
                     points=361)
    assert np.min(down.lift) == 0.0 and np.min(np.hypot(down.x, down.y)) == pytest.approx(40)
    # s_down(θ) = 20 − s_up(θ): the down cam dwells at the top where the up cam dwells low.
    assert np.max(np.abs(down.lift - (20.0 - up.lift))) < 1e-13
    m = cam_cycle("cycloidal", 120, 60, 120, 20.0)
    raised = dataclasses.replace(m, poly=tuple((p[0] + 7.0, *p[1:]) for p in m.poly))
    shifted = cam_profile(raised, 40.0, roller_radius=10.0, points=361)
    assert np.max(np.abs(shifted.x - up.x)) < 1e-13 and np.max(np.abs(shifted.y - up.y)) < 1e-13


def test_a_motion_of_another_period_is_refused():
    m = dataclasses.replace(cam_cycle("cycloidal", 120, 60, 120, 20.0), period=1.0)
    with pytest.raises(InputError, match="period 2π"):
        cam_profile(m, 40.0, roller_radius=10.0)


def test_arm_through_the_pivot_line():
    with pytest.raises(InputError, match="leaves"):
        cam_profile(cam_cycle("cycloidal", 120, 60, 120, math.radians(150)), 40.0,
                    "oscillating", roller_radius=10.0, arm=60.0, pivot=80.0)


def test_pickles_and_exports(tmp_path):
    cam = cam_profile(cam_cycle("cycloidal", 120, 60, 120, 20.0), 40.0, roller_radius=10.0,
                      points=97)
    back = pickle.loads(pickle.dumps(cam))
    assert np.array_equal(back.x, cam.x) and back.checks == cam.checks
    csv, svg = tmp_path / "p.csv", tmp_path / "p.svg"
    save_profile(cam, csv, svg)
    assert csv.read_text() == profile_csv(cam) and svg.read_text() == profile_svg(cam)
    lines = csv.read_text().splitlines()
    assert lines[0].startswith("#")
    assert lines[1] == "theta_deg,x,y,pressure_angle_deg,radius_of_curvature"
    data = np.array([[float(v) for v in row.split(",")] for row in lines[2:]])
    assert np.array_equal(data[:, 1], cam.x) and np.array_equal(data[:, 4], cam.rho)
    assert np.array_equal(data[:, 3], np.degrees(cam.pressure_angle))
    import xml.etree.ElementTree as ET
    root = ET.fromstring(svg.read_text())
    ns = "{http://www.w3.org/2000/svg}"
    assert root.get("width").endswith("mm") and root.get("height").endswith("mm")
    pts = root.find(f"{ns}polygon").get("points").split()
    assert len(pts) == 96                           # closed: the last angle repeats the first
    xy = np.array([[float(v) for v in p.split(",")] for p in pts])
    assert np.max(np.abs(xy[:, 0] - cam.x[:-1])) < 1e-6
    assert np.max(np.abs(xy[:, 1] + cam.y[:-1])) < 1e-6    # SVG's y points down
    circle = root.find(f"{ns}circle")
    assert float(circle.get("r")) == 40.0 and circle.get("stroke-dasharray")


def test_a_failed_export_leaves_no_file(tmp_path):
    cam = cam_profile(cam_cycle("cycloidal", 120, 60, 120, 20.0), 40.0, roller_radius=10.0,
                      points=9)
    csv = tmp_path / "p.csv"
    with pytest.raises(InputError, match="does not exist"):   # the output layer's user error
        save_profile(cam, csv, tmp_path / "missing" / "p.svg")
    assert list(tmp_path.iterdir()) == []


def test_motion_scaled():
    m = cam_cycle("modified_trapezoid", 100, 20, 120, 3.0)
    t = np.linspace(0, 2 * np.pi, 50)
    for a, b in zip(m.scaled(0.25).evaluate(t), m.evaluate(t)):
        assert np.array_equal(a, 0.25 * b)


def test_flat_face_profile_is_the_envelope_of_the_face():
    """Each profile point lies on the face line (C·u = r_b + s, u the face normal turned into
    the cam's frame), the profile's tangent runs along the face (finite differences), and its
    curvature from SymPy's parametric derivatives of the written-out rise is 1/(r_b + s + s'')."""
    h, beta, rb = 20.0, math.radians(120), 60.0
    cam = cam_profile(cam_cycle("cycloidal", 120, 60, 120, h), rb, "flat", points=20001)
    ux, uy = np.sin(cam.theta), np.cos(cam.theta)             # R(−θ)·(0, 1)
    assert np.max(np.abs(cam.x * ux + cam.y * uy - (rb + cam.lift))) < 1e-12 * rb
    C = cam.x + 1j * cam.y
    dt = cam.theta[1] - cam.theta[0]
    tangent = (-C[4:] + 8 * C[3:-1] - 8 * C[1:-3] + C[:-4]) / (12 * dt)
    along = (tangent.real * ux[2:-2] + tangent.imag * uy[2:-2]) / np.abs(tangent)
    motion = cam_cycle("cycloidal", 120, 60, 120, h)
    smooth = _clear_of_junctions(cam.theta, motion.start, 2)[2:-2]
    assert np.max(np.abs(along[smooth])) < 1e-9
    # The profile as the envelope of the lines X·u(θ) = p(θ), solved by SymPy: X·u = p and
    # X·u' = p' (no formula of the module), then its curvature.
    s = _cycloidal_rise(h, sp.Float(beta, 30))
    p = rb + s
    X, Y = sp.symbols("X Y")
    u = (sp.sin(TH), sp.cos(TH))
    sol = sp.solve([X * u[0] + Y * u[1] - p,
                    X * sp.diff(u[0], TH) + Y * sp.diff(u[1], TH) - sp.diff(p, TH)], [X, Y])
    x, y = sol[X], sol[Y]
    x1, y1 = sp.diff(x, TH), sp.diff(y, TH)
    kappa = -(x1 * sp.diff(y1, TH) - y1 * sp.diff(x1, TH)) / (x1 ** 2 + y1 ** 2) ** 1.5
    f = sp.lambdify(TH, [x, y, kappa], "mpmath")
    inside = np.flatnonzero((cam.theta > 0.01) & (cam.theta < beta - 0.01))[::500]
    with mpmath.workdps(30):
        ref = np.array([[float(v) for v in f(mpmath.mpf(float(cam.theta[i])))]
                        for i in inside]).T
    assert np.max(np.abs(cam.x[inside] - ref[0])) < 1e-12 * rb
    assert np.max(np.abs(cam.y[inside] - ref[1])) < 1e-12 * rb
    assert np.max(np.abs(1 / cam.rho[inside] - ref[2]) * rb) < 1e-12
