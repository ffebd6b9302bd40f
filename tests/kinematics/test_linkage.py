"""Tests of the planar multi-crank linkage solver (Koshel & Koshel 2014).

References: finite differences of positions (in time, and with one crank
stopped), the closed-form FourBar, and hand-placed errors in TOML text.
"""

import math
from pathlib import Path

import numpy as np
import pytest
from cli_helpers import assert_user_error

from mechcirc.errors import GeometryError, NetlistError
from mechcirc.kinematics import FourBar
from mechcirc.kinematics.linkage import load_linkage, parse_linkage

ROOT = Path(__file__).resolve().parents[2]
FNF = ROOT / "examples" / "fnf_sixbar.toml"


@pytest.fixture(scope="module")
def fnf():
    return load_linkage(FNF)


def test_fnf_structure(fnf):
    assert len(fnf.links) == 6
    assert fnf.revolute_pairs == 8
    assert fnf.mobility == 2 == len(fnf.cranks)
    assert len(fnf.links["link4"]) == 3           # the ternary base link
    w = [c.omega for c in fnf.cranks]
    assert w[0] * w[1] < 0 and abs(w[0]) != abs(w[1])   # different speed and direction


def test_velocity_is_the_sum_of_conditional_stop_contributions(fnf):
    for state in fnf.solve(np.radians([0.0, 37.0, 141.0, 250.0, 333.0])):
        for p, v in state.velocities.items():
            total = sum(c[p] for c in state.contributions.values())
            scale = max(1.0, np.max(np.abs(v)))
            np.testing.assert_allclose(total, v, rtol=0, atol=1e-12 * scale)


def test_conditional_stop_against_positions_with_one_crank_stopped(fnf):
    """Contribution of crank c = ω_c · ∂(position)/∂(angle of c), the other crank held."""
    state = fnf.solve(math.radians(100.0))
    base = {c.link: c.omega * state.t for c in fnf.cranks}
    h = 1e-5
    for crank in fnf.cranks:
        plus = dict(base, **{crank.link: base[crank.link] + h})
        minus = dict(base, **{crank.link: base[crank.link] - h})
        pp = fnf.assemble(plus, near=state.q)["points"]
        pm = fnf.assemble(minus, near=state.q)["points"]
        for p in fnf.pose:
            fd = crank.omega * (pp[p] - pm[p]) / (2 * h)
            np.testing.assert_allclose(state.contributions[crank.link][p], fd,
                                       rtol=1e-6, atol=1e-6 * abs(crank.omega) * 100)
    # each crank alone moves K: both contributions matter
    k1, k2 = (np.linalg.norm(state.contributions[c.link]["K"]) for c in fnf.cranks)
    assert k1 > 1 and k2 > 1


def test_velocities_and_accelerations_against_finite_differences(fnf):
    w1 = fnf.cranks[0].omega
    h = 1e-4                                     # in θ [rad]
    for theta in np.radians([10.0, 95.0, 200.0, 290.0]):
        s = fnf.solve(np.array([theta - 2 * h, theta - h, theta, theta + h, theta + 2 * h]))
        dt = h / w1
        for p in fnf.pose:
            x = [st.points[p] for st in s]
            v = [st.velocities[p] for st in s]
            fd_v = (x[0] - 8 * x[1] + 8 * x[3] - x[4]) / (12 * dt)
            fd_a = (v[0] - 8 * v[1] + 8 * v[3] - v[4]) / (12 * dt)
            sv = max(1.0, np.max(np.abs(s[2].velocities[p])))
            sa = max(1.0, np.max(np.abs(s[2].accelerations[p])))
            np.testing.assert_allclose(s[2].velocities[p], fd_v, rtol=0, atol=1e-7 * sv)
            np.testing.assert_allclose(s[2].accelerations[p], fd_a, rtol=0, atol=1e-7 * sa)


def test_fnf_full_cycle_is_periodic(fnf):
    # crank 1 turns 2×, crank 2 turns 3× (ω = 20, −30): both back at the pose
    states = fnf.solve(np.radians(np.arange(0.0, 720.0 + 1e-9, 4.0)))
    for p, x in fnf.pose.items():
        np.testing.assert_allclose(states[-1].points[p], x, atol=1e-9)


FOURBAR_TOML = """
name = "Mrázek beat-up four-bar"
[points]
A = [0.0, 0.0]
B = [{bx!r}, {by!r}]
C = [{cx!r}, {cy!r}]
D = [189.0, 0.0]

[ground]
points = ["A", "D"]

[links]
crank = ["A", "B"]
coupler = ["B", "C"]
rocker = ["D", "C"]

[[cranks]]
link = "crank"
omega = {omega!r}
"""


def _fourbar_text(theta0, omega=100.0):
    fb = FourBar(29.0, 37.0, 188.0, 189.0)
    phi4 = fb.rocker_angle(theta0)
    return FOURBAR_TOML.format(bx=29 * math.cos(theta0), by=29 * math.sin(theta0),
                               cx=189 + 188 * math.cos(phi4), cy=188 * math.sin(phi4),
                               omega=omega), fb


def test_fourbar_in_file_agrees_with_fourbar():
    theta0 = 0.3
    text, fb = _fourbar_text(theta0)
    lk = parse_linkage(text)
    assert lk.mobility == 1
    thetas = np.radians(np.arange(0.0, 360.0, 15.0))
    omega = 100.0
    for th, st in zip(thetas, lk.solve(thetas)):
        crank_angle = theta0 + th
        C = st.points["C"]
        phi4 = math.atan2(C[1], C[0] - 189.0)
        assert (phi4 - fb.rocker_angle(crank_angle) + math.pi) % (2 * math.pi) - math.pi \
            == pytest.approx(0.0, abs=1e-11)
        assert st.angular_velocities["rocker"] == pytest.approx(
            fb.mu(crank_angle) * omega, rel=1e-9, abs=1e-9)
        # rocker angular acceleration from C's acceleration: a_C = α k×r − ω² r
        r = C - np.array([189.0, 0.0])
        w4 = st.angular_velocities["rocker"]
        t = st.accelerations["C"] + w4 ** 2 * r
        alpha = (r[0] * t[1] - r[1] * t[0]) / np.dot(r, r)
        assert alpha == pytest.approx(fb.nu(crank_angle) * omega ** 2, rel=1e-8, abs=1e-6)


# ------------------------------------------------------------------ bad input
def test_unknown_point_in_link_is_located():
    text = FNF.read_text().replace('coupler5 = ["B", "E"]', 'coupler5 = ["B", "Q"]')
    with pytest.raises(NetlistError) as info:
        parse_linkage(text, "fnf.toml")
    err = info.value
    line = text.splitlines()[err.line - 1]
    assert line.startswith("coupler5") and line[err.col - 1:err.col + 2] == '"Q"'
    assert "unknown point 'Q'" in str(err) and str(err).startswith(f"fnf.toml:{err.line}:")


def test_unknown_link_in_crank_is_located():
    text = FNF.read_text().replace('link = "crank2"', 'link = "crank9"')
    with pytest.raises(NetlistError, match="unknown link 'crank9'") as info:
        parse_linkage(text, "fnf.toml")
    assert 'link = "crank9"' in text.splitlines()[info.value.line - 1]


def test_toml_syntax_error_is_located():
    text = FNF.read_text().replace("K  = [100.0, 130.0]", "K  = [100.0, 130.0")
    with pytest.raises(NetlistError, match="TOML syntax") as info:
        parse_linkage(text, "fnf.toml")
    assert info.value.line > 0


def test_mobility_mismatch_says_W():
    # drop crank 2's drive: W = 2 but one crank
    text = FNF.read_text()
    text = text[:text.rindex("[[cranks]]")]
    with pytest.raises(GeometryError, match=r"W = 3·6 − 2·8 = 2.*1 crank"):
        parse_linkage(text)
    # weld the output to the ground: W = 1 with two cranks
    text = FNF.read_text().replace('points = ["O1", "O2", "O6"]', 'points = ["O1", "O2", "O6", "K"]')
    with pytest.raises(GeometryError, match="W = .* = 0"):
        parse_linkage(text)


def test_locking_names_theta(tmp_path, capsys):
    # a double-rocker written as a crank: it cannot turn fully
    fb = FourBar(30.0, 10.0, 30.0, 25.0)
    lo, hi = fb.crank_range()
    th0 = 0.5 * (lo + hi)
    phi4 = fb.rocker_angle(th0)
    text = FOURBAR_TOML.format(bx=30 * math.cos(th0), by=30 * math.sin(th0),
                               cx=25 + 30 * math.cos(phi4), cy=30 * math.sin(phi4),
                               omega=1.0).replace("189.0", "25.0")
    lk = parse_linkage(text)
    lk.solve(0.5 * (hi - th0))                          # inside the range: fine
    with pytest.raises(GeometryError, match=r"locks near θ = ([\d.]+)°") as info:
        lk.solve(math.pi)
    import re
    got = float(re.search(r"θ = ([\d.]+)°", str(info.value)).group(1))
    assert got == pytest.approx(math.degrees(hi - th0), abs=1e-3)
    # assemble (one Newton solve, no continuation): the closed-form rocker angle inside the
    # range; beyond it (θ = π from the pose, past hi) no assembly, said with what would do
    C = lk.assemble({"crank": 0.5 * (hi - th0)})["points"]["C"]
    assert math.atan2(C[1], C[0] - 25.0) == pytest.approx(fb.rocker_angle(0.5 * (th0 + hi)),
                                                          abs=1e-12)
    assert hi < th0 + math.pi < lo + 2 * math.pi       # outside [lo, hi] modulo 2π
    with pytest.raises(GeometryError, match=r"no assembly for crank angles .*'crank': 3\.14159"
                                            r".* give angles the linkage reaches, or near= "
                                            r"closer"):
        lk.assemble({"crank": math.pi})
    # the CLI solves by continuation (it calls no assemble): the lock is a user error, exit 2
    (tmp_path / "rocker.toml").write_text(text)
    assert_user_error(["linkage", tmp_path / "rocker.toml", "--theta", "180"], capsys,
                      "rocker.toml", f"locks near θ = {math.degrees(hi - th0):.1f}")


def test_branch_jump_is_reported():
    # with a huge step the Newton predictor lands nearer the mirror assembly
    text, fb = _fourbar_text(0.3)
    lk = parse_linkage(text)
    with pytest.raises(GeometryError, match="branch jump"):
        lk.solve(math.radians(180.0), max_step_deg=180.0, method="newton")
    # the closed-form dyad keeps its assembly mode whatever the step
    C = lk.solve(math.radians(180.0), max_step_deg=180.0).points["C"]
    assert math.atan2(C[1], C[0] - 189.0) == pytest.approx(fb.rocker_angle(0.3 + math.pi),
                                                           abs=1e-12)


def test_the_format_example_in_the_docs_runs():
    text = (ROOT / "docs" / "kinematics.md").read_text()
    block = text.split("```toml\n", 1)[1].split("```", 1)[0]
    lk = parse_linkage(block, "docs/kinematics.md")
    assert lk.mobility == 1
    st = lk.solve(math.radians(90.0))
    C = st.points["C"]
    phi4 = math.atan2(C[1], C[0] - 189.0)
    # the pose is rounded to 1e-6 mm, so agreement is to that order
    assert phi4 == pytest.approx(FourBar(29, 37, 188, 189).rocker_angle(math.pi / 2), abs=1e-6)


def test_structure_fnf_is_one_class_III_group_of_order_3(fnf):
    (group,) = fnf.assur_groups()
    assert group.group_class == 3 and group.base == "link4" and group.order == 3
    assert set(group.links) == {"coupler3", "link4", "coupler5", "output6"}
    assert set(group.external_pairs) == {"A", "B", "O6"}


def test_structure_of_a_six_bar_of_two_dyads():
    text = """
[points]
A = [0.0, 0.0]
B = [10.0, 0.0]
C = [40.0, 60.0]
D = [100.0, 0.0]
E = [90.0, 70.0]
F = [140.0, 90.0]
G = [160.0, 20.0]
[ground]
points = ["A", "D", "G"]
[links]
crank = ["A", "B"]
coupler = ["B", "C"]
rocker = ["D", "C", "E"]
link5 = ["E", "F"]
link6 = ["F", "G"]
[[cranks]]
link = "crank"
omega = 1.0
"""
    lk = parse_linkage(text)
    groups = lk.assur_groups()
    assert [g.group_class for g in groups] == [2, 2]
    assert set(groups[0].links) == {"coupler", "rocker"}
    assert set(groups[1].links) == {"link5", "link6"}
    assert set(groups[1].external_pairs) == {"E", "G"}


def test_unknown_key_in_crank_is_located():
    text = FNF.read_text().replace("omega = -30.0", "omgea = -30.0")
    with pytest.raises(NetlistError, match="unknown key 'omgea'") as info:
        parse_linkage(text, "fnf.toml")
    assert text.splitlines()[info.value.line - 1].startswith("omgea")
    assert info.value.col == 1


def test_unknown_key_in_ground_is_located():
    # [ground] is declared (kinematics.linkage.TABLES): a typo there is refused, not ignored
    text = FNF.read_text().replace("[ground]\n", "[ground]\npivot = \"A\"\n", 1)
    assert text != FNF.read_text()
    with pytest.raises(NetlistError, match=r"unknown key 'pivot' in \[ground\]") as info:
        parse_linkage(text, "fnf.toml")
    assert text.splitlines()[info.value.line - 1].startswith("pivot")
    assert info.value.expected == "points"


def test_a_scene_table_in_a_linkage_file_is_located_at_its_header():
    text = FNF.read_text() + "\n[drive]\nlink = \"crank\"\n"
    with pytest.raises(NetlistError, match="unknown top-level key 'drive'") as info:
        parse_linkage(text, "fnf.toml")
    assert text.splitlines()[info.value.line - 1] == "[drive]"
