"""A scene's periodic drive (mechcirc.scene.drive_motion + mechcirc.periodic) against the
four-bar's closed form (positions by circle intersection, rates by the velocity-ratio
formula, written here) and against the time domain driven by that closed form."""

import math

import numpy as np
import pytest
from mechcirc.periodic import periodic, rpm_to_omega
from mechcirc.scene import build, parse_scene
from mechcirc.scene.cycle import drive_motion

from reference.inputs import FOURBAR_SCENE

A_, B_, C_, D_ = 40.0, math.hypot(20.0, 150.0), math.hypot(140.0, 150.0), 200.0   # mm
K4, C4, I4, I4P = 5000.0, 2.0, 0.02, 0.1


def scene_text(drive: str) -> str:
    return f'''name = "rocker drive"
{FOURBAR_SCENE}[[torsion]]
name = "C4"
link = "rocker"
body = "sley"
stiffness = {K4!r}
damping = {C4!r}
[[masses]]
name = "I4"
link = "rocker"
inertia = {I4!r}
[[masses]]
name = "I4P"
link = "sley"
inertia = {I4P!r}
[drive]
{drive}
velocity = 1.0
'''


def fourbar(theta):
    """C, the coupler angle φ3, the rocker angle φ4 and dφ4/dθ at crank angle θ (closed form)."""
    theta = np.asarray(theta, float)
    B = A_ * np.stack([np.cos(theta), np.sin(theta)], -1)
    D = np.array([D_, 0.0])
    e = D - B
    dist = np.hypot(e[..., 0], e[..., 1])
    a = (B_ ** 2 - C_ ** 2 + dist ** 2) / (2 * dist)
    h = np.sqrt(B_ ** 2 - a ** 2)
    u = e / dist[..., None]
    n = np.stack([-u[..., 1], u[..., 0]], -1)
    C = B + a[..., None] * u + h[..., None] * n            # the branch of the pose (C above BD)
    phi3 = np.arctan2(C[..., 1] - B[..., 1], C[..., 0] - B[..., 0])
    phi4 = np.arctan2(C[..., 1], C[..., 0] - D_)
    w4 = A_ * np.sin(theta - phi3) / (C_ * np.sin(phi4 - phi3))
    return C, phi3, phi4, w4


def test_the_pose_is_the_closed_forms_branch():
    C, *_ = fourbar(0.0)
    assert np.allclose(C, [60.0, 150.0], atol=1e-12)


@pytest.mark.parametrize("theta_deg", [30.0, 200.0])
def test_link_drive_motion_is_the_rocker_angle(theta_deg):
    m = drive_motion(parse_scene(scene_text('link = "rocker"')), math.radians(theta_deg))
    th = np.random.default_rng(1).uniform(0, 2 * math.pi, 400)
    x, dx, _ = m.evaluate(th)
    _, _, phi4, w4 = fourbar(th)
    _, _, phi40, _ = fourbar(0.0)
    assert np.max(np.abs(x - (phi4 - phi40))) <= 1e-8
    assert np.max(np.abs(dx - w4)) <= 1e-8 * np.max(np.abs(w4))
    assert m.error <= 1e-8                       # the stated interpolation estimate


def test_point_drive_motion_is_the_point_along_its_velocity_at_theta():
    theta0 = math.radians(75.0)
    m = drive_motion(parse_scene(scene_text('point = "C"')), theta0)
    C0, _, phi40, w40 = fourbar(theta0)
    u = np.array([-math.sin(phi40), math.cos(phi40)]) * np.sign(w40)   # C's velocity direction
    th = np.random.default_rng(2).uniform(0, 2 * math.pi, 400)
    C, _, phi4, w4 = fourbar(th)
    Cp, *_ = fourbar(0.0)
    x_ref = (C - Cp) @ u * 1e-3
    dx_ref = (C_ * w4[:, None] * np.stack([-np.sin(phi4), np.cos(phi4)], -1)) @ u * 1e-3
    x, dx, _ = m.evaluate(th)
    assert np.max(np.abs(x - x_ref)) <= 1e-8 * np.max(np.abs(x_ref))
    assert np.max(np.abs(dx - dx_ref)) <= 1e-8 * np.max(np.abs(dx_ref))


def test_a_crank_drive_has_no_harmonics_and_says_it_turns():
    text = scene_text('link = "rocker"').replace('link = "rocker"\nvelocity',
                                                   'link = "crank"\nvelocity')
    m = drive_motion(parse_scene(text), 0.5)
    assert "steady rotation (+1 turn" in m.spec and "nothing is left" in m.spec
    assert not np.any(m.fourier(20))             # not rounding noise turned into harmonics
    r = periodic(build(parse_scene(text), 0.5).circuit, 600, motion=m)
    assert r.peak == 0 and r.error == 0 and not np.any(r.Q)


def test_periodic_force_against_the_transient_driven_by_the_closed_form():
    # The circuit at θ = 30°: I4 at the rocker (the drive), C4 (k, c) to the sley I4P.
    # The time domain (mechcirc.transient, exact propagation, drive velocity sampled
    # 20,000 times a turn) driven by the closed-form ω4 for 12 turns from rest
    # (ζ = 0.045, ωn = 224 rad/s: the start decays to 4e-11); its 12th turn against Q(θ).
    from mechcirc.transient import transient

    sc = parse_scene(scene_text('link = "rocker"'))
    theta0 = math.radians(30.0)
    circuit = build(sc, theta0).circuit
    rpm = 300
    W = rpm_to_omega(rpm)
    T = 2 * math.pi / W
    r = periodic(circuit, rpm, motion=drive_motion(sc, theta0), tol=1e-9)
    assert r.error <= 1e-9
    # Run 10 steps past the 12th turn: the transient's drive force at its very last
    # sample takes I4·ω̇4 from a one-sided difference (1e-3 off here), not compared.
    dt = T / 20000
    tr = transient(circuit, 12 * T + 10 * dt, dt,
                   waveform=lambda t: W * fourbar(W * np.asarray(t))[3],
                   elements=False, velocities=False)
    last = (tr.time >= 11 * T - 1e-12) & (tr.time <= 12 * T + 1e-12)
    th = (W * tr.time[last]) % (2 * np.pi)
    Q = (np.exp(1j * np.outer(th, r.k)) @ r.amplitude).real
    assert np.max(np.abs(tr.drive_force[last] - Q)) <= 1e-6 * r.peak


def closed_form_Q(rpm, n=4096):
    """Q(θ) at θ = 2πi/n of the circuit by hand: Q = I4·ω̇4 + k(φ4 − ψ) + c(ω4 − ψ̇) with
    I4P ψ̈ = k(φ4 − ψ) + c(ω4 − ψ̇); per harmonic (jkΩ), the drive's velocity V_k from an
    FFT of the closed-form ω4 (4096 samples a turn: exact to rounding for the ~60
    harmonics that matter)."""
    W = rpm_to_omega(rpm)
    th = 2 * np.pi * np.arange(n) / n
    w4 = W * fourbar(th)[3]
    Vk = 2 * np.fft.rfft(w4)[1:200] / n                   # v = Σ Re(V_k e^{jkθ})
    s = 1j * W * np.arange(1, 200)
    z = K4 / s + C4                                        # the torsion's impedance (moment/rate)
    Qk = Vk * (I4 * s + z * I4P * s / (I4P * s + z))
    return np.fft.irfft(np.concatenate([[0], Qk, np.zeros(n // 2 + 1 - 200)]) * n / 2, n)


def test_periodic_force_against_the_closed_form():
    # For a rocker drive every ratio is 1 (I4, C4, I4P turn with the rocker): the same
    # circuit at any θ.
    sc = parse_scene(scene_text('link = "rocker"'))
    Q_ref = closed_form_Q(300)
    r = periodic(build(sc, 0.5).circuit, 300, motion=drive_motion(sc, 0.5), tol=1e-10,
                 points=Q_ref.size)
    assert np.max(np.abs(r.Q - Q_ref)) <= 1e-8 * np.max(np.abs(Q_ref))


def test_cli_on_a_scene_is_the_closed_form(capsys, tmp_path):
    # The shipped example is this file's scene: the CLI's Q(θ) against the closed form.
    import json
    from pathlib import Path

    from cli_helpers import assert_user_error, run

    path = Path(__file__).resolve().parents[2] / "docs" / "examples" / "rocker_drive.toml"
    body = [ln for ln in path.read_text().splitlines() if not ln.startswith("#")]
    assert body == scene_text('link = "rocker"').splitlines()
    status, out, _ = run(["periodic", path, "--theta", "30", "--rpm", "300", "--json",
                          "--tol", "1e-10", "--angles", "4096"], capsys)
    assert status == 0
    doc = json.loads(out)
    assert doc["unit"] == "N·m"
    Q_ref = closed_form_Q(300)
    assert np.max(np.abs(np.array(doc["Q"]) - Q_ref)) <= 1e-8 * np.max(np.abs(Q_ref))
    assert_user_error(["periodic", path, "--rpm", "300"], capsys, "give --theta DEG")
    assert_user_error(["periodic", "docs/examples/cam_drive.mcir", "--theta", "3", "--rpm",
                       "300"], capsys, "--theta applies to a scene")
