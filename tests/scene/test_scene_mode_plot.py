"""A mode drawn on a scene's linkage (mechcirc.scene.plots.plot_mode) against the mode
computed here: a four-bar whose coupler is elastic, driven through a torsion spring on the
crank, its 2-DOF equations (crank, rocker) written from the closed-form velocity ratios,
their eigenvector by scipy's state-space eig, each point's dP/dθ from the closed form."""

import math

import numpy as np
import pytest
import scipy.linalg
from matplotlib.figure import Figure
from mechcirc.errors import MechcircError
from mechcirc.scene import parse_scene
from mechcirc.scene.plots import plot_mode
from test_scene_periodic import A_, C_, fourbar

from reference.inputs import FOURBAR_SCENE

K2, C2, KC, CC, I2P, I4 = 8000.0, 1.5, 2.0e5, 3.0, 0.01, 0.02
TEXT = f'''name = "elastic coupler"
{FOURBAR_SCENE}[[torsion]]
name = "C2"
link = "crank"
body = "shaft"
stiffness = {K2!r}
damping = {C2!r}
[[elastic]]
name = "kc"
link = "coupler"
stiffness = {KC!r}
damping = {CC!r}
[[masses]]
name = "I2P"
link = "crank"
inertia = {I2P!r}
[[masses]]
name = "I4"
link = "rocker"
inertia = {I4!r}
[drive]
link = "shaft"
velocity = 1.0
'''


def reference_mode(theta, n):
    """(ξ crank, ξ rocker), largest real 1, of resonance n (drive held): the coupler's
    elongation rate is c·(ξ_rocker − ξ_crank), c = u·dB/dθ [m], u along B→C."""
    C, _, _, g = fourbar(theta)                           # g = ω4/ω2
    B = A_ * np.array([math.cos(theta), math.sin(theta)])
    u = (C - B) / np.hypot(*(C - B))
    c = float(u @ (A_ * np.array([-math.sin(theta), math.cos(theta)]))) * 1e-3
    M = np.diag([I2P, I4 * g * g])
    K = np.array([[K2 + KC * c * c, -KC * c * c], [-KC * c * c, KC * c * c]])
    D = np.array([[C2 + CC * c * c, -CC * c * c], [-CC * c * c, CC * c * c]])
    Z, I = np.zeros((2, 2)), np.eye(2)
    w, V = scipy.linalg.eig(np.block([[Z, I], [-np.linalg.solve(M, K), -np.linalg.solve(M, D)]]))
    up = np.argsort(np.where(w.imag > 0, np.abs(w), np.inf))
    v = V[2:, up[n - 1]]                                    # the velocity half
    return v / v[np.argmax(np.abs(v))]


@pytest.mark.parametrize("theta_deg,n", [(30.0, 1), (30.0, 2), (250.0, 1)])
def test_drawn_deflection_is_the_mode_through_the_velocity_ratios(theta_deg, n):
    th = math.radians(theta_deg)
    ax = plot_mode(parse_scene(TEXT), th, n, ax=Figure().add_subplot(), exaggeration=0.1)
    lines = {ln.get_gid(): ln.get_xydata() for ln in ax.lines}
    xi = reference_mode(th, n).real
    C, _, phi4, w4 = fourbar(th)
    dB = A_ * np.array([-math.sin(th), math.cos(th)])      # dB/dθ [mm] (drive ratio 1)
    dC = C_ * w4 * np.array([-math.sin(phi4), math.cos(phi4)])
    B = A_ * np.array([math.cos(th), math.sin(th)])
    # the rigid drawing is the linkage at θ
    assert np.allclose(lines["rigid:coupler"], [B, C], atol=1e-9)
    drawn = {"B": lines["mode:coupler"][0] - B, "C": lines["mode:coupler"][1] - C}
    assert np.array_equal(lines["mode:crank"][1] - B, drawn["B"])
    assert np.array_equal(lines["mode:rocker"][1] - C, drawn["C"])
    expect = {"B": xi[0] * dB, "C": xi[1] * dC}
    # one scale for every point: the largest drawn is 10 % of the linkage (200 mm)
    k = 0.1 * 200.0 / max(np.hypot(*e) for e in expect.values())
    for p in ("B", "C"):
        assert np.max(np.abs(drawn[p] - k * expect[p])) <= 1e-12 * 20.0   # achieved 8e-14 mm
    assert np.allclose(lines["mode:rocker"][0], [200.0, 0.0], atol=0)     # D on the ground
    assert np.allclose(lines["mode:crank"][0], [0.0, 0.0], atol=0)       # A on the ground


def test_no_such_mode_is_said():
    with pytest.raises(MechcircError, match="has 2"):
        plot_mode(parse_scene(TEXT), 0.5, 3)


def test_cli_draws_the_mode_or_says_why_not(tmp_path, capsys):
    from cli_helpers import assert_user_error, run

    scene = tmp_path / "coupler.toml"
    scene.write_text(TEXT)
    out = tmp_path / "mode.png"
    status, text, _ = run(["scene", scene, "--theta", "30", "--mode", "2", "--plot", out],
                          capsys)
    assert status == 0 and out.stat().st_size > 0
    assert f"resonance 2 drawn on the linkage into {out}" in text
    bad = tmp_path / "bad.png"
    assert_user_error(["scene", scene, "--theta", "30", "--mode", "3", "--plot", bad], capsys,
                      "no resonance 3", "has 2")
    assert_user_error(["scene", scene, "--theta", "30", "--mode", "1"], capsys, "--plot")
    assert not bad.exists()
