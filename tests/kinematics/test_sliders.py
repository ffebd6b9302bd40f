"""Prismatic joints (sliders) against closed forms written out independently (SymPy).

* offset slider-crank: x = r cos θ + sqrt(l² − (r sin θ + e)²), v and a by
  SymPy's exact derivatives of that formula;
* inverted slider-crank (crank-shaper quick return): the rocker angle
  ψ = atan2(y_A − y_O4, x_A − x_O4) and its end B = O4 + R (cos ψ, sin ψ),
  differentiated by SymPy.
"""

import functools
import math

import numpy as np
import pytest
import sympy as sp

from mechcirc.errors import GeometryError, NetlistError
from mechcirc.kinematics import parse_linkage

@pytest.fixture(params=["dyads", "newton-compiled", "newton-numpy"])
def backend(request, monkeypatch):
    """The solver, as ``motion(method=…)``: the closed-form RRP/RPR dyads (the default for
    these linkages), or Newton as one compiled loop (numba; plain Python without it) or
    batched numpy."""
    from mechcirc import _jit

    monkeypatch.setattr(_jit, "COMPILED", request.param != "newton-numpy")
    return request.param.split("-")[0]


R, E, XC = 40.0, 10.0, 178.5357          # crank, offset; the pose puts C here (any x works)

SLIDER_CRANK = f"""
[points]
A = [0.0, 0.0]
B = [{R!r}, 0.0]
C = [{XC!r}, {-E!r}]
G1 = [0.0, {-E!r}]
G2 = [100.0, {-E!r}]
[ground]
points = ["A", "G1", "G2"]
[links]
crank = ["A", "B"]
rod = ["B", "C"]
block = ["C"]
[[sliders]]
link = "block"
guide = "ground"
line = ["G1", "G2"]
[[cranks]]
link = "crank"
omega = {{omega}}
"""

TH = np.linspace(0.0, 2 * math.pi, 37)


@functools.lru_cache(maxsize=None)
def _slider_crank_reference(omega):
    """x(θ), ẋ, ẍ of the block from the closed form (l from the pose), θ = ω t."""
    th, t = sp.symbols("theta t", real=True)
    ll = sp.sqrt((sp.Float(XC, 30) - R) ** 2 + sp.Float(E, 30) ** 2)
    x = R * sp.cos(th) + sp.sqrt(ll ** 2 - (R * sp.sin(th) + E) ** 2)
    xt = x.subs(th, omega * t)
    T = TH / omega
    return [sp.lambdify(t, sp.diff(xt, t, k), "numpy")(T) for k in range(3)]


@pytest.mark.parametrize("omega", [10.0, -7.0])
def test_offset_slider_crank_against_the_closed_form(omega, backend):
    lk = parse_linkage(SLIDER_CRANK.format(omega=omega))
    assert lk.mobility == 1 and len(lk.sliders) == 1
    assert lk.solver == "dyads" and [d.kind for d in lk._plan.dyads] == ["RRP"]
    m = lk.motion(TH, method=backend)
    k = m.point_names.index("C")
    x, v, a = _slider_crank_reference(omega)
    stroke = 2 * R                        # achieved: 4e-16 of stroke·ω^k (goal 1e-12)
    assert np.max(np.abs(m.points[:, k, 0] - x)) <= 1e-14 * stroke
    assert np.max(np.abs(m.velocities[:, k, 0] - v)) <= 1e-14 * stroke * abs(omega)
    assert np.max(np.abs(m.accelerations[:, k, 0] - a)) <= 1e-14 * stroke * omega ** 2
    # the block stays on its guide and does not turn
    assert np.max(np.abs(m.points[:, k, 1] + E)) <= 1e-14 * stroke
    j = m.link_names.index("block")
    assert np.max(np.abs(m.q[:, 3 * j + 2])) <= 1e-13
    assert np.max(np.abs(m.qdot[:, 3 * j + 2])) <= 1e-14 * abs(omega)


O2Y, RC, RR = 50.0, 30.0, 120.0          # crank pivot above the rocker pivot, crank, rocker
TH0 = 0.3                                 # the crank's angle in the pose


def _shaper_text():
    ax, ay = RC * math.cos(TH0), O2Y + RC * math.sin(TH0)
    psi = math.atan2(ay, ax)
    return f"""
[points]
O2 = [0.0, {O2Y!r}]
A = [{ax!r}, {ay!r}]
O4 = [0.0, 0.0]
B = [{RR * math.cos(psi)!r}, {RR * math.sin(psi)!r}]
[ground]
points = ["O2", "O4"]
[links]
crank = ["O2", "A"]
block = ["A"]
rocker = ["O4", "B"]
[[sliders]]
link = "block"
guide = "rocker"
line = ["O4", "B"]
[[cranks]]
link = "crank"
omega = 12.0
"""


@functools.lru_cache(maxsize=None)
def _shaper_reference():
    """B and its two derivatives, ψ̇ and ψ̈, ṡ at TH (θ = θ0 + 12 t), by SymPy."""
    t = sp.symbols("t", real=True)
    th = TH0 + 12.0 * t
    psi = sp.atan2(O2Y + RC * sp.sin(th), RC * sp.cos(th))
    bx, by = RR * sp.cos(psi), RR * sp.sin(psi)
    s = sp.sqrt((RC * sp.cos(th)) ** 2 + (O2Y + RC * sp.sin(th)) ** 2)   # A along the rocker
    T = TH / 12.0

    def f(expr, order):
        return sp.lambdify(t, sp.diff(expr, t, order), "numpy")(T)

    return ([(f(bx, o), f(by, o)) for o in range(3)], [f(psi, o) for o in (1, 2)], f(s, 1))


def test_inverted_slider_crank_quick_return_against_the_closed_form(backend):
    lk = parse_linkage(_shaper_text())
    assert [d.kind for d in lk._plan.dyads] == ["RPR"]
    m = lk.motion(TH, method=backend)
    B, fpsi, fs = _shaper_reference()
    k = m.point_names.index("B")
    j = m.link_names.index("rocker")
    jb = m.link_names.index("block")
    for order, got in enumerate((m.points, m.velocities, m.accelerations)):
        for comp in (0, 1):
            assert np.max(np.abs(got[:, k, comp] - B[order][comp])) <= 1e-14 * RR * 12.0 ** order
    assert np.max(np.abs(m.qdot[:, 3 * j + 2] - fpsi[0])) <= 1e-14 * 12.0
    assert np.max(np.abs(m.qddot[:, 3 * j + 2] - fpsi[1])) <= 1e-14 * 144.0
    # the block turns with the rocker; its point slides along it by s(θ)
    assert np.max(np.abs(m.qdot[:, 3 * jb + 2] - m.qdot[:, 3 * j + 2])) <= 1e-14 * 12.0
    a_idx, o4 = m.point_names.index("A"), np.array([0.0, 0.0])
    u = (m.points[:, k] - o4) / RR
    rel = m.velocities[:, a_idx] - (m.points[:, a_idx] - o4)[:, ::-1] * [-1, 1] * \
        m.qdot[:, 3 * j + 2][:, None]
    assert np.max(np.abs(np.sum(rel * u, axis=1) - fs)) <= 1e-14 * RR * 12.0


def test_slider_off_its_guide_is_located():
    text = SLIDER_CRANK.format(omega=1.0).replace("G2 = [100.0, -10.0]", "G2 = [100.0, -9.0]")
    with pytest.raises(NetlistError) as e:
        parse_linkage(text, "sc.toml")
    msg = str(e.value)
    assert "off its guide" in msg and "sc.toml:" in msg and "'C'" in msg
    ref = XC * 1.0 / math.hypot(100.0, 1.0)      # C's distance from the tilted line
    assert f"{ref:.6g}" in msg


@pytest.mark.parametrize("change, words", [
    (('guide = "ground"', 'guide = "nowhere"'), "unknown guide 'nowhere'"),
    (('guide = "ground"', ''), "[[sliders]] #1 has no guide"),      # was "unknown guide None"
    (('line = ["G1", "G2"]', 'line = ["G1", "B"]'), "line must name two points"),
    (('link = "block"\nguide', 'link = ["block"]\nguide'), "link 'block' must list at least"),
    (('line = ["G1", "G2"]', 'line = ["G1", "G2"]\npoint = ["C"]'), "point must be one of"),
    (('link = "block"\nguide', 'link = "blok"\nguide'),
     "link 'block' must list at least two point names (one for a slider's link)"),
])
def test_bad_slider_tables_are_located(change, words):
    text = SLIDER_CRANK.format(omega=1.0).replace(*change)
    with pytest.raises(NetlistError) as e:
        parse_linkage(text, "sc.toml")
    assert words in str(e.value) and "sc.toml:" in str(e.value)


def test_sliders_not_a_table_is_located():
    table = '[[sliders]]\nlink = "block"\nguide = "ground"\nline = ["G1", "G2"]\n'
    text = "sliders = 3\n" + SLIDER_CRANK.format(omega=1.0).replace(table, "")
    with pytest.raises(NetlistError, match=r"sc.toml:1:1: .*'sliders' must be a \[\[sliders\]\]"):
        parse_linkage(text, "sc.toml")


def test_rod_too_short_for_the_offset_locks_with_the_angle(backend):
    """l < r + e: the crank cannot turn round; the lock angle is where r sin θ + e = l."""
    text = SLIDER_CRANK.format(omega=1.0).replace(f"C = [{XC!r}", "C = [70.0")
    lk = parse_linkage(text)
    with pytest.raises(GeometryError) as e:
        lk.motion(np.linspace(0, 2 * math.pi, 73), method=backend)
    ll = math.hypot(70.0 - R, E)
    ref = math.degrees(math.asin((ll - E) / R))
    got = float(str(e.value).split("θ = ")[1].split("°")[0])
    assert abs(got - ref) < 1e-3, (got, ref)


def test_shipped_quick_return_stroke_and_time_ratio():
    """examples/quick_return.toml: the ram's stroke 2·R_rocker·r/d = 144 mm (the rocker
    swings ±asin(r/d) and the ram's guide is level with the pivot-to-B line's top) — to the
    grid's resolution — and its return over 180° − 2 asin(r/d) of the crank."""
    from pathlib import Path

    from mechcirc.kinematics import load_linkage

    lk = load_linkage(Path(__file__).resolve().parents[2] / "examples" / "quick_return.toml")
    th = np.linspace(0.0, 2 * math.pi, 7201)
    m = lk.motion(th)
    k = m.point_names.index("D")
    assert np.max(np.abs(m.points[:, k, 1] - 125.0)) <= 1e-14 * 125
    # the ram's x at the rocker's extreme angles ±asin(0.6), from the closed form
    ref = [math.sqrt(60.0 ** 2 - (125.0 - 120.0 * 0.8) ** 2) + s * 120.0 * 0.6 for s in (-1, 1)]
    x = m.points[:, k, 0]
    assert abs(x.min() - ref[0]) < 1e-5 and abs(x.max() - ref[1]) < 1e-5
    v = m.velocities[:, k, 0]
    turns = th[np.flatnonzero(np.diff(np.sign(v)))]
    back = math.degrees(turns[1] - turns[0])
    ref = 180.0 - 2 * math.degrees(math.asin(0.6))
    assert min(abs(back - ref), abs(360 - back - ref)) < 0.05


W1, W2 = 10.0, -0.5                       # the crank and the slotted crank [rad/s]
O_SLOT, BETA0, SIG0 = (260.0, 30.0), math.radians(190.0), 80.0


def _slotted_text():
    """A rod from a crank drives a block along the slot of a second, slowly turning crank
    (an RRP dyad whose guide moves)."""
    ox, oy = O_SLOT
    cx, cy = ox + SIG0 * math.cos(BETA0), oy + SIG0 * math.sin(BETA0)
    sx, sy = ox + 50 * math.cos(BETA0), oy + 50 * math.sin(BETA0)
    return f"""
[points]
A = [0.0, 0.0]
B = [{R!r}, 0.0]
O = [{ox!r}, {oy!r}]
S = [{sx!r}, {sy!r}]
C = [{cx!r}, {cy!r}]
[ground]
points = ["A", "O"]
[links]
crank = ["A", "B"]
slot = ["O", "S"]
rod = ["B", "C"]
block = ["C"]
[[sliders]]
link = "block"
guide = "slot"
line = ["O", "S"]
[[cranks]]
link = "crank"
omega = {W1!r}
[[cranks]]
link = "slot"
omega = {W2!r}
"""


@functools.lru_cache(maxsize=None)
def _slotted_reference():
    """C and its two time derivatives at TH (θ = ω1 t), by SymPy."""
    t = sp.symbols("t", real=True)
    th, beta = W1 * t, BETA0 + W2 * t
    ux, uy = sp.cos(beta), sp.sin(beta)
    wx, wy = R * sp.cos(th) - O_SLOT[0], R * sp.sin(th) - O_SLOT[1]       # B − O
    c0 = (O_SLOT[0] + SIG0 * math.cos(BETA0) - R, O_SLOT[1] + SIG0 * math.sin(BETA0))
    ll = sp.sqrt(sp.Float(c0[0], 30) ** 2 + sp.Float(c0[1], 30) ** 2)
    sig = ux * wx + uy * wy - sp.sqrt(ll ** 2 - (ux * wy - uy * wx) ** 2)
    cx, cy = O_SLOT[0] + sig * ux, O_SLOT[1] + sig * uy
    return [tuple(sp.lambdify(t, sp.diff(e, t, o), "numpy")(TH / W1) for e in (cx, cy))
            for o in range(3)]


def _slot_slides_in_the_block(text):
    """The same motion with the roles swapped: the slotted crank's point O slides along a
    line C–K of the block (the known body carries the slider's point, the dyad's link the
    guide)."""
    kx = O_SLOT[0] + 30 * math.cos(BETA0)
    ky = O_SLOT[1] + 30 * math.sin(BETA0)
    return text.replace("C = [", f"K = [{kx!r}, {ky!r}]\nC = [").replace(
        'block = ["C"]', 'block = ["C", "K"]').replace(
        'link = "block"\nguide = "slot"\nline = ["O", "S"]',
        'link = "slot"\nguide = "block"\nline = ["C", "K"]\npoint = "O"')


@pytest.mark.parametrize("swap", [False, True])
def test_slider_on_a_turning_guide_against_the_closed_form(backend, swap):
    """C = O + σ u(β), β = β0 + ω2 t, |C − B| = l: σ = u·(B − O) − sqrt(l² − (u × (B − O))²)
    (the root of the pose), differentiated by SymPy; the conditional-stop parts add up."""
    text = _slotted_text()
    lk = parse_linkage(_slot_slides_in_the_block(text) if swap else text)
    assert "K" in lk.pose if swap else "K" not in lk.pose
    assert [d.kind for d in lk._plan.dyads] == ["RRP"]
    m = lk.motion(TH, method=backend)
    C = _slotted_reference()
    k = m.point_names.index("C")
    T = TH / W1
    for order, got in enumerate((m.points, m.velocities, m.accelerations)):
        for comp in (0, 1):
            ref = C[order][comp]
            # achieved 4.5e-15 of 2R·ω1^k (dyads and Newton); the goal is 1e-12
            assert np.max(np.abs(got[:, k, comp] - ref)) <= 1e-14 * 2 * R * W1 ** order
    j = m.link_names.index("block")
    assert np.max(np.abs(m.q[:, 3 * j + 2] - W2 * T)) <= 1e-14
    assert np.max(np.abs(m.qdot[:, 3 * j + 2] - W2)) <= 1e-14 * W1
    assert np.max(np.abs(m.qddot[:, 3 * j + 2])) <= 1e-14 * W1 ** 2
    assert np.max(np.abs(m.contributions.sum(axis=0) - m.velocities)) <= 1e-14 * 2 * R * W1


STROKE = 'line = ["G1", "G2"]\nstroke = [{lo}, {hi}]'


def _with_stroke(lo, hi):
    return SLIDER_CRANK.format(omega=10.0).replace('line = ["G1", "G2"]',
                                                  STROKE.format(lo=lo, hi=hi))


def test_slider_beyond_its_stroke_is_located_with_the_angle_and_excess():
    """The pose puts C at XC; at θ the block is at r cos θ + sqrt(l² − (r sin θ + e)²)."""
    lk = parse_linkage(_with_stroke(150.0, 189.7), "sc.toml")
    lk.motion(np.radians([0.0, 10.0, 30.0]))              # inside: no error
    th = np.radians([0.0, 30.0, 120.0, 150.0])
    with pytest.raises(NetlistError) as e:
        lk.motion(th)
    err = e.value
    ll = math.hypot(XC - R, E)
    x = R * math.cos(th[2]) + math.sqrt(ll ** 2 - (R * math.sin(th[2]) + E) ** 2)
    assert (err.source, err.line, err.col) == ("sc.toml", 18, 1)      # the stroke key
    msg = str(err)
    assert "slider 'block' leaves its guide at θ = 120°" in msg
    assert f"is at {x:.6g} along G1→G2, {150.0 - x:.6g} beyond the stroke's min 150" in msg


@pytest.mark.parametrize("lo, hi, words", [
    (190.0, 150.0, "stroke must be [min, max] with min < max, got [190.0, 150.0]"),
    ('"a"', 150.0, "stroke must be [min, max]"),
    (100.0, 150.0, f"starts off its stroke: its point is at {XC:.6g} along the line"),
])
def test_bad_strokes_are_located(lo, hi, words):
    with pytest.raises(NetlistError) as e:
        parse_linkage(_with_stroke(lo, hi), "sc.toml")
    assert words in str(e.value) and "sc.toml:18:1:" in str(e.value)
