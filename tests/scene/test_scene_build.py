"""mechcirc.scene.build against independent kinematics (issue 7 §2).

References: the four-bar closed form (FourBar.mu), arm lengths, central
differences of positions, a hand-written Lagrangian of a lever chain, and the
sley's own linearisation (mechcirc.sley.to_netlist).
"""

import math

import numpy as np
import pytest
import scipy.linalg as la

import _scene_helpers as helpers
import mechcirc
from mechcirc.kinematics.fourbar import FourBar
from mechcirc.scene import build, parse_scene


def _lever_scene(a, b, beta_deg, mass, reflect_point="T"):
    beta = math.radians(beta_deg)
    return parse_scene(f'''units = "m"
[points]
O = [0.0, 0.0]
T = [{-a!r}, 0.0]
A = [{b * math.cos(beta)!r}, {b * math.sin(beta)!r}]
[ground]
points = ["O"]
[links]
lever = ["O", "T", "A"]
[[cranks]]
link = "lever"
omega = 1.0
[[masses]]
name = "m"
point = "A"
mass = {mass!r}
[drive]
point = "{reflect_point}"
velocity = 0.1
''')


@pytest.mark.parametrize("a,b,beta", [(0.2, 0.5, 20.0), (0.35, 0.1, -130.0), (1.0, 1.0, 90.0)])
def test_two_arm_lever_gives_the_arm_ratio(a, b, beta):
    scene = _lever_scene(a, b, beta, 2.0)
    for theta in (0.0, 0.7, -2.0):
        eta_model = build(scene, theta)
        assert eta_model.ratios["m"] == pytest.approx(b / a, rel=1e-12)
        assert eta_model.circuit.element("m").eta == pytest.approx((b / a) ** 2, rel=1e-12)
        lever_model = build(scene, theta, reflect="lever")
        assert lever_model.circuit.element("L_m").ratio == pytest.approx(b / a, rel=1e-12)
        # K of a mass m seen through the arm ratio: -j / (ω m (b/a)²)
        w = np.array([3.0, 40.0])
        for model in (eta_model, lever_model):
            K = model.circuit.sweep(w).K
            np.testing.assert_allclose(K, -1j / (w * 2.0 * (b / a) ** 2), rtol=1e-12)


def _fourbar_scene(fb, theta_pose, inertia=0.03):
    P = helpers.fourbar_pose(fb, theta_pose)
    pts = "\n".join(f"{k} = [{x!r}, {y!r}]" for k, (x, y) in P.items())
    return parse_scene(f'''units = "mm"
[points]
{pts}
[ground]
points = ["A", "D"]
[links]
crank = ["A", "B"]
coupler = ["B", "C"]
rocker = ["D", "C"]
[[cranks]]
link = "crank"
omega = 10.0
[[masses]]
name = "J4"
link = "rocker"
inertia = {inertia!r}
[drive]
link = "crank"
velocity = 1.0
''')


@pytest.mark.parametrize("lengths,branch", [((29.0, 37.0, 188.0, 189.0), 1),
                                            ((40.0, 120.0, 90.0, 110.0), -1),
                                            ((30.0, 80.0, 70.0, 90.0), 1)])
def test_fourbar_gives_mu_exactly(lengths, branch):
    fb = FourBar(*lengths, branch=branch)
    theta_pose = 0.4
    scene = _fourbar_scene(fb, theta_pose)
    thetas = np.linspace(0.0, 2 * math.pi, 13, endpoint=False)[1:]
    states = scene.linkage.solve(thetas)
    for th, st in zip(thetas, states):
        mu = float(fb.mu(theta_pose + th))
        model = build(scene, th, state=st)
        assert model.ratios["J4"] == pytest.approx(mu, rel=1e-9, abs=1e-12)
        lever = build(scene, th, state=st, reflect="lever")
        assert lever.circuit.element("L_J4").ratio == pytest.approx(abs(mu), rel=1e-9)
        K = model.circuit.sweep([50.0]).K[0]
        assert K == pytest.approx(-1j / (50.0 * 0.03 * mu * mu), rel=1e-9)


SIXBAR = '''units = "mm"
[points]
O1 = [0.0, 0.0]
A  = [30.0, 10.0]
B  = [151.3026, 98.2365]
O2 = [170.0, 0.0]
C  = [218.0442, 109.9625]
D  = [350.0, 79.0]
O3 = [320.0, -40.0]
[ground]
points = ["O1", "O2", "O3"]
[links]
crank = ["O1", "A"]
coupler1 = ["A", "B"]
rocker2 = ["O2", "B", "C"]
coupler2 = ["C", "D"]
rocker3 = ["O3", "D"]
[[cranks]]
link = "crank"
omega = 12.0
[[masses]]
point = "A"
mass = 0.8
[[masses]]
point = "B"
mass = 1.3
[[masses]]
point = "C"
mass = 0.6
[[masses]]
point = "D"
mass = 2.1
[[masses]]
link = "rocker2"
inertia = 0.004
[[masses]]
link = "coupler2"
inertia = 0.002
[drive]
{drive}
velocity = 1.0
'''


@pytest.mark.parametrize("drive", ['link = "crank"', 'point = "A"', 'point = "D"'])
def test_reflected_inertia_equals_sum_of_m_v_squared(drive):
    scene = parse_scene(SIXBAR.format(drive=drive))
    lk = scene.linkage
    masses = {"A": 0.8, "B": 1.3, "C": 0.6, "D": 2.1}
    inertias = {"rocker2": (("O2", "C"), 0.004), "coupler2": (("C", "D"), 0.002)}
    h = 1e-5
    for th in (0.3, 2.0, 4.4):
        lo, hi = lk.solve(np.array([th - h, th + h]))
        dP = {p: (hi.points[p] - lo.points[p]) / (2 * h) * 1e-3 for p in lo.points}  # [m/rad]

        def angle(state, p, q):
            v = state.points[q] - state.points[p]
            return math.atan2(v[1], v[0])

        dphi = {l: (angle(hi, *pq) - angle(lo, *pq)) / (2 * h) for l, (pq, _) in inertias.items()}
        if drive == 'link = "crank"':
            r0 = 1.0
        else:
            r0 = float(np.hypot(*dP[drive.split('"')[1]]))
        M_ref = (sum(m * float(dP[p] @ dP[p]) for p, m in masses.items())
                 + sum(J * dphi[l] ** 2 for l, (_, J) in inertias.items())) / r0 ** 2
        model = build(scene, th)
        assert len(model.parts) == 1
        M = sum(e.value * e.eta for e in model.circuit.elements if e.kind == "mass")
        assert M == pytest.approx(M_ref, rel=1e-8)
        w = 20.0
        assert model.circuit.sweep([w]).K[0] == pytest.approx(-1j / (w * M_ref), rel=1e-8)


CHAIN = '''units = "m"
[points]
O1 = [0.0, 0.0]
A  = [0.1, 0.25]
B  = [0.55, 0.3]
O2 = [0.6, 0.0]
C  = [0.9, 0.2]
[ground]
points = ["O1", "O2"]
[links]
lever1 = ["O1", "A"]
rod = ["A", "B"]
lever2 = ["O2", "B", "C"]
[[cranks]]
link = "lever1"
omega = 5.0
[[elastic]]
name = "k"
link = "rod"
stiffness = 3.0e5
[[masses]]
name = "J1"
link = "lever1"
inertia = 0.02
[[masses]]
name = "mC"
point = "C"
mass = 4.0
[drive]
link = "lever1"
velocity = 1.0
'''


def _rot(phi, v):
    c, s = math.cos(phi), math.sin(phi)
    return np.array([c * v[0] - s * v[1], s * v[0] + c * v[1]])


def test_elastic_lever_chain_matches_a_hand_written_lagrangian():
    """Resonance (drive held) and anti-resonance (drive free) of lever1 -rod(k)- lever2."""
    from scipy.optimize import brentq

    O1, A0, B0 = np.zeros(2), np.array([0.1, 0.25]), np.array([0.55, 0.3])
    O2, C0 = np.array([0.6, 0.0]), np.array([0.9, 0.2])
    L0 = float(np.hypot(*(B0 - A0)))
    k, J1, m = 3.0e5, 0.02, 4.0
    scene = parse_scene(CHAIN)
    assert [sorted(p) for p in scene.parts] == [["lever1"], ["lever2"]]

    def A(p1):
        return O1 + _rot(p1, A0 - O1)

    def B(p2):
        return O2 + _rot(p2, B0 - O2)

    def C(p2):
        return O2 + _rot(p2, C0 - O2)

    for th in (0.15, -0.25):
        p2 = brentq(lambda x: float(np.hypot(*(B(x) - A(th)))) - L0, -0.8, 0.8)
        h = 1e-6

        def delta(x1, x2):
            return float(np.hypot(*(B(x2) - A(x1)))) - L0

        g1 = (delta(th + h, p2) - delta(th - h, p2)) / (2 * h)
        g2 = (delta(th, p2 + h) - delta(th, p2 - h)) / (2 * h)
        dC = (C(p2 + h) - C(p2 - h)) / (2 * h)
        m2 = m * float(dC @ dC)                          # [kg·m²] about O2
        held = math.sqrt(k * g2 * g2 / m2)
        Kmat = k * np.outer([g1, g2], [g1, g2])
        free = np.sqrt(np.abs(la.eigh(Kmat, np.diag([J1, m2]), eigvals_only=True)))
        free = free[free > 1e-6 * free.max()]
        got = build(scene, th).circuit.resonances()
        res = [r.omega for r in got if r.kind == "resonance"]
        anti = [r.omega for r in got if r.kind == "antiresonance"]
        assert res == pytest.approx([held], rel=1e-7)
        assert anti == pytest.approx(list(free), rel=1e-7)
        lever = build(scene, th, reflect="lever").circuit.resonances()
        assert [r.omega for r in lever] == pytest.approx([r.omega for r in got], rel=1e-9)


def test_sley_scene_has_the_resonances_of_sley_to_netlist():
    from mechcirc.sley import preset, to_netlist

    for variant in (1, 6):
        p = preset("one-side", variant)
        theta_pose = 0.3
        scene = parse_scene(helpers.sley_scene_text(p, theta_pose))
        assert [sorted(x) for x in scene.parts] == [["shaft"], ["coupler", "crank", "rocker"],
                                                    ["sley"]]
        for theta0 in (0.3, 1.0, 2.5, 4.0, 5.5):
            ours = build(scene, theta0 - theta_pose).circuit.resonances()
            ref = mechcirc.parse(to_netlist(p, theta0)).resonances()
            assert [r.kind for r in ours] == [r.kind for r in ref]
            for a, b in zip(ours, ref):
                assert a.omega == pytest.approx(b.omega, rel=1e-9)
                assert a.zeta == pytest.approx(b.zeta, rel=1e-8, abs=1e-12)


def test_netlist_text_round_trips_and_names_every_ratio():
    scene = parse_scene(CHAIN)
    model = build(scene, 0.1)
    again = mechcirc.parse(model.netlist)
    w = np.linspace(10.0, 5000.0, 7)
    np.testing.assert_allclose(again.sweep(w).K, model.circuit.sweep(w).K, rtol=1e-14)
    for name in ("J1", "mC", "k"):
        assert f"{model.ratios[name]!r}" in model.netlist


def test_build_needed_reduces_for_the_files_output_and_band():
    from mechcirc.scene import build_needed
    from mechcirc.errors import MechcircError

    text = CHAIN.replace("stiffness = 3.0e5", "stiffness = 3.0e5\ndamping = 20.0") + \
        '[[masses]]\nname = "tiny"\npoint = "A"\nmass = 1e-9\n' + \
        "[analysis]\ntheta_deg = 5.0\noutput = \"k\"\nband = [5.0, 500.0]\ntol = 1e-3\n"
    scene = parse_scene(text)
    model, reduced = build_needed(scene)
    assert model.theta == pytest.approx(math.radians(5.0))
    assert reduced.output == "k" and reduced.error <= 1e-3
    assert "tiny" not in {e.name for e in reduced.circuit.elements}     # 1e-9 kg: negligible
    w = np.geomspace(5.0, 500.0, 2000)
    full = model.circuit.sweep(w).force("k")
    red = mechcirc.parse(reduced.netlist).sweep(w).force("k")
    assert np.max(np.abs(red - full) / np.abs(full)) <= reduced.error * (1 + 1e-9) + 1e-15
    with pytest.raises(MechcircError, match="no crank angle"):
        build_needed(parse_scene(CHAIN))
    assert build_needed(parse_scene(CHAIN), 0.1)[1] is None


def test_heald_lever_form_equals_eta_form_and_force_drive_is_the_same_network():
    from pathlib import Path

    text = (Path(__file__).resolve().parents[2] / "examples" / "heald_scene.toml").read_text()
    scene = parse_scene(text)
    w = np.geomspace(20.0, 3000.0, 200)
    for th in (0.2, 2.9):
        eta = build(scene, th)
        lever = build(scene, th, reflect="lever")
        assert lever.circuit.levers and not eta.circuit.levers
        np.testing.assert_allclose(lever.circuit.sweep(w).K, eta.circuit.sweep(w).K, rtol=1e-9)
    forced = parse_scene(text.replace("velocity = 1.0", "force = 2.0"))
    f, v = build(forced, 0.2).circuit.sweep(w), build(scene, 0.2).circuit.sweep(w)
    np.testing.assert_allclose(f.v0, 2.0 * v.K, rtol=1e-12)


def test_load_anchor_and_direction_agree_when_on_one_line():
    base = CHAIN + '[[loads]]\nname = "w"\npoint = "C"\nstiffness = 5e3\n'
    with_dir = parse_scene(base + "direction = [0.0, 1.0]\n")
    with_anchor = parse_scene(base.replace("O2 = [0.6, 0.0]", "O2 = [0.6, 0.0]\nW = [0.9, 5.0]")
                              .replace('points = ["O1", "O2"]', 'points = ["O1", "O2", "W"]')
                              + 'anchor = "W"\n')
    # at θ = 0 the line C→W is vertical, as the direction
    a, b = build(with_dir, 0.0), build(with_anchor, 0.0)
    assert abs(a.ratios["w"]) == pytest.approx(abs(b.ratios["w"]), rel=1e-12)
    assert a.ratios["w"] != 0


def test_lever_names_never_clash_with_element_names():
    text = CHAIN.replace('name = "mC"', 'name = "L_J1"')
    model = build(parse_scene(text), 0.1, reflect="lever")
    names = [lv.name for lv in model.circuit.levers] + [e.name for e in model.circuit.elements]
    assert len(names) == len(set(names)) and "L_J1" in names and "LL_J1" in names


def test_random_crank_rockers_give_mu():
    rng = np.random.default_rng(7)
    done = 0
    while done < 12:
        a, b, c, d = rng.uniform(10, 40), rng.uniform(60, 200), rng.uniform(60, 200), \
            rng.uniform(60, 200)
        try:
            fb = FourBar(a, b, c, d, branch=int(rng.choice([-1, 1])))
        except Exception:
            continue
        if fb.linkage_type != "crank-rocker":
            continue
        pose = rng.uniform(0, 2 * math.pi)
        scene = _fourbar_scene(fb, pose)
        th = rng.uniform(-math.pi, math.pi)
        mu = float(fb.mu(pose + th))
        if abs(mu) < 1e-3:
            continue
        assert build(scene, th).ratios["J4"] == pytest.approx(mu, rel=1e-9)
        done += 1
