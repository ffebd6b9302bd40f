"""Tests of the kineto-static frame loading (patent eq. (7)).

References: centre-of-mass and link-angle accelerations from finite
differences of positions, the kinetic energy's numerical derivative, and the
two-force-member property of a massless coupler.
"""

import math

import numpy as np
import pytest

from mechcirc.errors import GeometryError
from mechcirc.kinematics import FourBar, LinkMass, frame_loading

FB = FourBar(0.035, 0.0578, 0.1556, 0.16275)          # a beat-up crank-rocker [m]
OMEGA = 2 * math.pi * 600 / 60                         # 600 rpm
CRANK = LinkMass(2.0, (0.012, 0.003), 0.002)
COUPLER = LinkMass(1.5, (0.025, -0.004), 0.0009)
ROCKER = LinkMass(15.0, (0.11, 0.03), 0.08)
REED_POINT = (0.14, 0.05)
GRAVITY = (0.0, -9.81)


def _reed(theta):
    """A half-sine beat-up push of 500 N over 40° of crank around the front dead centre."""
    front, _ = FB.dead_centres()
    x = (theta - front.theta + math.pi) % (2 * math.pi) - math.pi
    mag = np.where(np.abs(x) < math.radians(20), 500 * np.cos(x / math.radians(40) * math.pi), 0)
    return np.stack([-0.1 * mag, -mag], axis=-1)      # mostly against the sley's forward push


def _positions(theta):
    """Link angles and centre-of-mass / reed positions from the closed-form positions."""
    a, b, d = FB.crank, FB.coupler, FB.frame
    phi3, phi4 = FB.evaluate(theta).phi3, FB.rocker_angle(theta)

    def place(origin, phi, uv):
        return origin + np.stack([np.cos(phi) * uv[0] - np.sin(phi) * uv[1],
                                  np.sin(phi) * uv[0] + np.cos(phi) * uv[1]], axis=-1)

    B = a * np.stack([np.cos(theta), np.sin(theta)], axis=-1)
    D = np.array([d, 0.0])
    return dict(phi2=theta, phi3=phi3, phi4=phi4, G2=place(0.0, theta, CRANK.com),
                G3=place(B, phi3, COUPLER.com), G4=place(D, phi4, ROCKER.com),
                P=place(D, phi4, REED_POINT), B=B, C=B + b * np.stack([np.cos(phi3),
                                                                     np.sin(phi3)], axis=-1))


def _fd(theta, key, order):
    """d^order/dt^order of a position at constant ω, 4th-order central differences."""
    h = 1e-3
    f = {k: _positions(theta + k * h)[key] for k in (-2, -1, 0, 1, 2)}
    if order == 1:
        return OMEGA * (f[-2] - 8 * f[-1] + 8 * f[1] - f[2]) / (12 * h)
    return OMEGA ** 2 * (-f[-2] + 16 * f[-1] - 30 * f[0] + 16 * f[1] - f[2]) / (12 * h * h)


def _cross(r, f):
    return r[..., 0] * f[..., 1] - r[..., 1] * f[..., 0]


@pytest.fixture(scope="module")
def loaded():
    theta = np.linspace(0, 2 * math.pi, 181)
    res = frame_loading(FB, theta, OMEGA, crank=CRANK, coupler=COUPLER, rocker=ROCKER,
                        reed_force=_reed, reed_point=REED_POINT, gravity=GRAVITY)
    return theta, res


def test_every_link_in_dynamic_equilibrium(loaded):
    theta, r = loaded
    p = _positions(theta)
    g = np.array(GRAVITY)
    A, D = np.zeros(2), np.array([FB.frame, 0.0])
    scale_f = np.max(np.abs(r.F_D))
    scale_m = scale_f * FB.rocker
    # crank: F_A − F_B + m g = m a_G ; moments about G2 with α2 = 0
    res = r.F_A - r.F_B + CRANK.mass * g - CRANK.mass * _fd(theta, "G2", 2)
    assert np.max(np.abs(res)) < 1e-6 * scale_f
    mom = _cross(A - p["G2"], r.F_A) - _cross(p["B"] - p["G2"], r.F_B) + r.torque
    assert np.max(np.abs(mom)) < 1e-6 * scale_m
    # coupler
    res = r.F_B - r.F_C + COUPLER.mass * g - COUPLER.mass * _fd(theta, "G3", 2)
    assert np.max(np.abs(res)) < 1e-6 * scale_f
    mom = (_cross(p["B"] - p["G3"], r.F_B) - _cross(p["C"] - p["G3"], r.F_C)
           - COUPLER.inertia * _fd(theta, "phi3", 2))
    assert np.max(np.abs(mom)) < 1e-6 * scale_m
    # rocker with the reed force
    res = r.F_C + r.F_D + r.reed_force + ROCKER.mass * g - ROCKER.mass * _fd(theta, "G4", 2)
    assert np.max(np.abs(res)) < 1e-6 * scale_f
    mom = (_cross(p["C"] - p["G4"], r.F_C) + _cross(D - p["G4"], r.F_D)
           + _cross(p["P"] - p["G4"], r.reed_force) - ROCKER.inertia * _fd(theta, "phi4", 2))
    assert np.max(np.abs(mom)) < 1e-6 * scale_m
    # the reed force really is applied (and in the rocker's frame)
    assert np.max(np.hypot(*r.reed_force.T)) == pytest.approx(500 * math.hypot(1, 0.1), rel=1e-2)


def test_power_balance(loaded):
    """T·ω + reed power + gravity power = dE_kin/dt, dE/dt by a numerical derivative."""
    theta, r = loaded
    h = 1e-4

    def energy(th):
        e = 0.0
        for key, link, phi in (("G2", CRANK, "phi2"), ("G3", COUPLER, "phi3"),
                               ("G4", ROCKER, "phi4")):
            v = _fd(th, key, 1)
            w = _fd(th, phi, 1)
            e = e + 0.5 * link.mass * np.sum(v * v, axis=-1) + 0.5 * link.inertia * w * w
        return e

    dE_dt = OMEGA * (energy(theta + h) - energy(theta - h)) / (2 * h)
    g = np.array(GRAVITY)
    p_reed = np.sum(r.reed_force * _fd(theta, "P", 1), axis=-1)
    p_grav = sum(m * np.sum(g * _fd(theta, key, 1), axis=-1)
                 for key, m in (("G2", CRANK.mass), ("G3", COUPLER.mass), ("G4", ROCKER.mass)))
    lhs = r.torque * OMEGA + p_reed + p_grav
    scale = np.max(np.abs(r.torque * OMEGA))
    np.testing.assert_allclose(lhs, dE_dt, rtol=0, atol=1e-5 * scale)
    assert np.max(np.abs(p_reed)) > 1e-2 * scale       # the reed term matters here


def test_shaking_force_is_momentum_change_minus_external(loaded):
    theta, r = loaded
    g = np.array(GRAVITY)
    total = sum(m * _fd(theta, key, 2) for key, m in
                (("G2", CRANK.mass), ("G3", COUPLER.mass), ("G4", ROCKER.mass)))
    mass = CRANK.mass + COUPLER.mass + ROCKER.mass
    expected = r.reed_force + mass * g - total
    np.testing.assert_allclose(r.shaking_force, expected, rtol=0,
                               atol=1e-6 * np.max(np.abs(expected)))
    np.testing.assert_allclose(r.shaking_force_magnitude, np.hypot(*expected.T),
                               rtol=0, atol=1e-6 * np.max(np.abs(expected)))


def test_shaking_moments_transfer(loaded):
    _, r = loaded
    AD = np.array([FB.frame, 0.0])
    np.testing.assert_allclose(r.T_a - r.T_d, _cross(AD, r.shaking_force),
                               rtol=0, atol=1e-9 * np.max(np.abs(r.T_a)))
    # eq. (7) letter for letter for T_a
    ad_x, ad_y = FB.frame, 0.0
    np.testing.assert_allclose(r.T_a, r.F_D[:, 0] * ad_y - r.F_D[:, 1] * ad_x - r.torque,
                               rtol=1e-12, atol=1e-12)


def test_massless_coupler_is_a_two_force_member():
    theta = np.linspace(0, 2 * math.pi, 73)
    r = frame_loading(FB, theta, OMEGA, crank=CRANK, rocker=ROCKER,
                      reed_force=_reed, reed_point=REED_POINT)
    phi3 = FB.evaluate(theta).phi3
    along = np.stack([np.cos(phi3), np.sin(phi3)], axis=-1)
    np.testing.assert_allclose(_cross(along, r.F_B), 0.0, atol=1e-9 * np.max(np.abs(r.F_B)))
    np.testing.assert_allclose(r.F_B, r.F_C, rtol=0, atol=1e-9 * np.max(np.abs(r.F_B)))


def test_bad_inputs():
    with pytest.raises(GeometryError, match="ω"):
        frame_loading(FB, [0.0], 0.0)
    with pytest.raises(GeometryError, match="shape"):
        frame_loading(FB, [0.0, 1.0], 10.0, reed_force=lambda th: np.zeros(2))
    with pytest.raises(GeometryError, match="mass"):
        LinkMass(-1.0)


def test_frame_loading_is_the_function_and_no_module_shadows_it():
    """``mechcirc.kinematics.frame_loading`` is the function (its module is private,
    ``_frame_loading``), imported either way; the API reference documents the function."""
    import importlib

    import mechcirc.kinematics as kin
    from mechcirc.kinematics import frame_loading as f

    assert f is frame_loading is kin.frame_loading and callable(f)
    assert "frame_loading" in kin.__all__ and f.__module__ == "mechcirc.kinematics._frame_loading"
    with pytest.raises(ModuleNotFoundError):
        importlib.import_module("mechcirc.kinematics.frame_loading")
