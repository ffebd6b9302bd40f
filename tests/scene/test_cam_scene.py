"""A cam scene (``[cam]``: a disc cam swings the lever that drives a heald frame) against
references written here independently of mechcirc.

* The lever follows the cycloidal law written out by hand (rise, top dwell, return,
  bottom dwell): x = h (u − sin 2πu / 2π), x' = (h/β)(1 − cos 2πu),
  x'' = (2π h/β²) sin 2πu; its angle, rate and acceleration and its end point A
  over a turn, ≤ 1e-12.
* The circuit at θ against a SymPy linearisation of the same mechanism: lever
  angle ψ (the drive), heald height y on its guide x = 310 mm through the rod of
  fixed length |AH|: y(ψ) = A_y − sqrt(l² − (x_H − A_x)²), A = L (cos ψ, sin ψ);
  the heald's mass is reflected through y'(ψ)², the rod through its elongation
  rate u·(0, y'), the load through y'; the drive ratio is x'(θ); the resonance
  with the lever held, sqrt((k_rod η_r + k_warp η_w)/(m η_m)).
"""

import functools
import math
import warnings
from pathlib import Path

import numpy as np
import pytest
import sympy as sp

from cli_helpers import assert_user_error
from mechcirc.errors import GeometryError, MechcircWarning, NetlistError
from mechcirc.scene import build, load_scene, parse_scene
from mechcirc.scene.motion import motion_model

ROOT = Path(__file__).resolve().parents[2]
EXAMPLE = ROOT / "examples" / "cam_heald_scene.toml"
TEXT = EXAMPLE.read_text()
#: The same scene with a flat face on the arm (follower_type = "oscillating_flat", the face
#: through the pivot 130 mm from the cam's centre): the arm moves by the same law.
FLAT = TEXT.replace("roller_radius = 12.0\narm = 100.0\n", "").replace(
    "[cam]\n", '[cam]\nfollower_type = "oscillating_flat"\n')
SCENES = {"roller": TEXT, "oscillating_flat": FLAT}
L_ARM, XH, YH0 = 0.300, 0.310, -0.400             # the example's geometry [m]
H, W = math.radians(8.0), 26.0                    # the lever's swing [rad], cam shaft [rad/s]
B1, D1, B2 = (math.radians(v) for v in (120.0, 60.0, 120.0))
M_H, K_ROD, K_W = 3.0, 5.0e5, 2.0e4


def cycloidal(theta):
    """x, x', x'' of the example's cam cycle, by hand."""
    theta = np.mod(np.asarray(theta, float), 2 * math.pi)
    x, x1, x2 = (np.zeros_like(theta) for _ in range(3))
    up = theta < B1
    u = theta[up] / B1
    x[up] = H * (u - np.sin(2 * np.pi * u) / (2 * np.pi))
    x1[up] = H / B1 * (1 - np.cos(2 * np.pi * u))
    x2[up] = 2 * np.pi * H / B1 ** 2 * np.sin(2 * np.pi * u)
    top = (theta >= B1) & (theta < B1 + D1)
    x[top] = H
    down = (theta >= B1 + D1) & (theta < B1 + D1 + B2)
    u = (theta[down] - B1 - D1) / B2
    x[down] = H * (1 - u + np.sin(2 * np.pi * u) / (2 * np.pi))
    x1[down] = -H / B2 * (1 - np.cos(2 * np.pi * u))
    x2[down] = -2 * np.pi * H / B2 ** 2 * np.sin(2 * np.pi * u)
    return x, x1, x2


def test_the_lever_and_its_end_follow_the_law_exactly():
    scene = load_scene(EXAMPLE)
    lk = scene.linkage
    theta = np.linspace(0.0, 2 * math.pi, 721)
    m = lk.motion(theta)
    j = lk.link_index()["lever"]
    x, x1, x2 = cycloidal(theta)
    assert np.max(np.abs(np.unwrap(m.q[:, 3 * j + 2]) - x)) <= 1e-12 * H
    assert np.max(np.abs(m.qdot[:, 3 * j + 2] - x1 * W)) <= 1e-12 * H * W
    assert np.max(np.abs(m.qddot[:, 3 * j + 2] - x2 * W * W)) <= 1e-12 * H * W * W
    a = list(lk.pose).index("A")
    L = L_ARM * 1e3                                   # the linkage is in mm
    c, s = np.cos(x), np.sin(x)
    pos = L * np.column_stack([c, s])
    vel = L * (x1 * W)[:, None] * np.column_stack([-s, c])
    acc = L * ((x2 * W * W)[:, None] * np.column_stack([-s, c])
               - ((x1 * W) ** 2)[:, None] * np.column_stack([c, s]))
    assert np.max(np.abs(m.points[:, a] - pos)) <= 1e-12 * L
    assert np.max(np.abs(m.velocities[:, a] - vel)) <= 1e-12 * L * H * W
    assert np.max(np.abs(m.accelerations[:, a] - acc)) <= 1e-12 * L * H * W * W


psi = sp.symbols("psi", real=True)
_AX, _AY = L_ARM * sp.cos(psi), L_ARM * sp.sin(psi)
_L2 = (sp.Float(XH, 30) - L_ARM) ** 2 + sp.Float(YH0, 30) ** 2
Y = _AY - sp.sqrt(_L2 - (XH - _AX) ** 2)            # the heald on its guide, rigid rod


@pytest.mark.parametrize("face", SCENES)
@pytest.mark.parametrize("deg", [30.0, 60.0, 100.0, 200.0, 250.0])
def test_circuit_at_theta_against_the_sympy_linearisation(deg, face):
    theta = math.radians(deg)
    x, x1, _ = (float(v[0]) for v in cycloidal([theta]))
    at = {psi: sp.Float(x, 30)}
    y1 = float(sp.diff(Y, psi).subs(at).evalf(30))
    ux, uy = XH - float(_AX.subs(at).evalf(30)), float(Y.subs(at).evalf(30) - _AY.subs(at))
    c_rod = uy * y1 / math.hypot(ux, uy)              # u·v_H per unit lever speed
    sc = build(parse_scene(SCENES[face], str(EXAMPLE)), theta)
    assert abs(sc.drive_ratio - x1) <= 1e-12 * H / B1 * 2
    el = {e.name: e for e in sc.circuit.elements}
    # achieved ≤ 1.1e-15 relative on the ratios, 2.2e-16 on the resonance (goal 1e-8)
    assert abs(el["m_heald"].eta - y1 * y1) <= 1e-12 * y1 * y1
    assert abs(el["k_rod"].eta - c_rod * c_rod) <= 1e-12 * c_rod * c_rod
    assert abs(el["k_warp"].eta - y1 * y1) <= 1e-12 * y1 * y1
    assert el["J_lever"].eta == 1.0
    wn = math.sqrt((K_ROD * c_rod ** 2 + K_W * y1 ** 2) / (M_H * y1 ** 2))
    (r,) = [r for r in sc.circuit.resonances() if r.kind == "resonance"]
    assert abs(r.omega - wn) <= 1e-12 * wn


def test_a_dwell_is_refused_with_the_cam_named(capsys):
    scene = load_scene(EXAMPLE)
    for deg in (0.0, 150.0, 330.0):
        with pytest.raises(GeometryError, match="the cam dwells"):
            build(scene, math.radians(deg))
    assert_user_error(["scene", EXAMPLE, "--theta", "150"], capsys, "cam_heald_scene.toml",
                      "the cam dwells", "150°")


def test_time_domain_tables_follow_the_cam():
    """The heald's travel and its rate in the rigid motion (the model's quintic tables)."""
    model = motion_model(load_scene(EXAMPLE), table_points=256)
    for deg in (17.0, 60.0, 233.0):
        theta = math.radians(deg)
        x, x1, _ = (float(v[0]) for v in cycloidal([theta]))
        at = {psi: sp.Float(x, 30)}
        # the travel is along the guide G1 → G2, pointing down: s = −(y − y0)
        s_ref = -float((Y.subs(at) - YH0).evalf(30))
        v_ref = -float(sp.diff(Y, psi).subs(at).evalf(30)) * x1 * W
        q, qd = model.rigid_state(theta)
        # achieved 6e-15 m and 3.4e-11 m/s (of ~1 m/s) at 256 table intervals
        assert abs(q - s_ref) <= 1e-13
        assert abs(qd - v_ref) <= 1e-9


def _bad(old, new):
    assert old in TEXT
    return TEXT.replace(old, new)


@pytest.mark.parametrize("old, new, key, needles", [
    ('follower = "lever"', 'follower = "rod"', "follower", ["follower 'rod'", "only crank"]),
    ("dwell = 60.0", "dwell = 160.0", "rise", ["400 degrees, more than one revolution"]),
    ('law = "cycloidal"', 'law = "sinus"', "law", ["not a motion law", "cycloidal"]),
    ("stroke_deg = 8.0", "stroke_deg = 0", "stroke_deg", ["stroke"]),
    ("pivot = 130.0", "pivot = 300.0", "base_radius",
     ["cannot be built", "cannot put its roller", "200 < r_b + r_f < 400"]),
    ("omega = 26.0", "omega = -26.0", "follower", ["omega = -26", "omega > 0"]),
])
def test_bad_cam_tables_are_located(old, new, key, needles, tmp_path, capsys):
    text = _bad(old, new)
    with pytest.raises(NetlistError) as exc:
        parse_scene(text, "bad.toml")
    cam = text.splitlines().index("[cam]")
    line = next(i for i, ln in enumerate(text.splitlines()[cam:], cam + 1)
                if ln.startswith(key + " ="))
    assert exc.value.line == line, str(exc.value)
    for n in needles:
        assert n in str(exc.value)
    f = tmp_path / "bad.toml"
    f.write_text(_bad(old, new))
    assert_user_error(["scene", f, "--theta", "60"], capsys, "bad.toml:", *needles)


def test_pressure_angle_beyond_the_limit_warns_with_the_value():
    text = _bad("pivot = 130.0", "pivot = 130.0\npressure_limit_deg = 5.0")
    with warnings.catch_warnings(record=True) as got:
        warnings.simplefilter("always")
        scene = parse_scene(text, "tight.toml")
    msgs = [str(w.message) for w in got if issubclass(w.category, MechcircWarning)]
    assert len(msgs) == 1 and "pressure angle" in msgs[0] and "limit 5°" in msgs[0], msgs
    build(scene, math.radians(60.0))                  # a warning: the scene still computes


def _lagrange_reference(times):
    """The frame's height y(t), ÿ(t) and the rod's force, from its equation of motion written
    here: M ÿ = −(k (ℓ − l₀) + c ℓ̇) ∂ℓ/∂y − k_w (y − y_rigid(ψ)), the lever at ψ = x(Ω t)
    (the load's deformation is the frame's departure from its rigid motion)."""
    sol, parts = _lagrange_solution(float(times.max()))
    y = sol.sol(times)
    acc, force = parts(times, y[0], y[1])
    return y[0], acc, force


@functools.cache
def _lagrange_solution(t_end):
    """The reference's dense solution to ``t_end`` and its right-hand side, solved once
    (both follower faces move the frame by the same law: the same equation, same span)."""
    from scipy.integrate import solve_ivp

    l0 = math.hypot(XH - L_ARM, YH0)
    C_ROD = 50.0

    def parts(tt, y, yd):
        x, x1, _ = cycloidal(np.atleast_1d(W * tt))
        ax, ay = L_ARM * np.cos(x), L_ARM * np.sin(x)
        dx, dy = XH - ax, y - ay
        ell = np.hypot(dx, dy)
        ell_y, ell_psi = dy / ell, (dx * ay - dy * ax) / ell
        ell_dot = ell_y * yd + ell_psi * x1 * W
        force = K_ROD * (ell - l0) + C_ROD * ell_dot
        y_rigid = ay - np.sqrt(l0 * l0 - dx * dx)
        return (-force * ell_y - K_W * (y - y_rigid)) / M_H, force

    sol = solve_ivp(lambda tt, s: [s[1], parts(tt, s[0], s[1])[0][0]],
                    (0.0, t_end), [YH0, 0.0], method="DOP853", rtol=1e-12,
                    atol=1e-15, dense_output=True, max_step=2 * math.pi / W / 720)
    return sol, parts


@pytest.mark.parametrize("face", SCENES)
def test_simulation_over_a_revolution_against_the_equation_of_motion(face):
    from mechcirc.scene import simulate_scene

    sm = simulate_scene(parse_scene(SCENES[face], str(EXAMPLE)), revolutions=1, steps_per_period=400, points=720,
                        error_estimate=False)
    y, ydd, F = _lagrange_reference(sm.time)
    # the frame's travel is along the guide, pointing down: s = −(y − y0)
    assert np.max(np.abs(sm.states[:, 0] + (y - YH0))) <= 1e-11
    # achieved 6.6e-13 m; the force and the acceleration 2.5e-9 of their largest values,
    # the RK4 step's error (1.6e-10 at 800 steps a period); the kinematic tables have a
    # node on each joint of the law (1026 intervals; at 1024, where the third derivative
    # jumps between two nodes, 1.6e-7); the goal was 1e-6
    fmax = np.max(np.abs(F))
    assert np.max(np.abs(sm.values["k_rod.force"] - F)) <= 1e-8 * fmax
    amax = np.max(np.abs(ydd))
    assert np.max(np.abs(sm.values["H.acceleration_y"] - ydd)) <= 1e-8 * amax


def test_a_lift_table_drives_the_lever_through_its_rows(tmp_path):
    """table = "FILE.csv" (the arm's angle [deg]): the spline passes through every row."""
    deg = np.arange(0.0, 361.0, 5.0)
    lift = 4.0 * (1 - np.cos(np.radians(deg)))         # [deg], meets itself at 360
    (tmp_path / "lift.csv").write_text("angle_deg,displacement\n" + "".join(
        f"{float(a)!r},{float(v)!r}\n" for a, v in zip(deg, lift)))
    text = _bad('law = "cycloidal"\nrise = 120.0', 'table = "lift.csv"\n#')
    for key in ("dwell", "return", "stroke_deg"):
        text = "\n".join(ln for ln in text.splitlines() if not ln.startswith(key + " ="))
    (tmp_path / "s.toml").write_text(text)
    lk = load_scene(tmp_path / "s.toml").linkage
    m = lk.motion(np.radians(deg))
    j = lk.link_index()["lever"]
    assert np.max(np.abs(np.unwrap(m.q[:, 3 * j + 2]) - np.radians(lift))) <= 1e-13


def test_a_dynamic_shaft_with_a_cam_is_read():
    """A [shaft] beside a [cam] with elastic parts is no longer refused at the table (the
    simulation against hand equations is tests/scene/test_shaft_cam.py)."""
    text = TEXT + ('\n[shaft]\nflywheel = 1.0\nmotor = "kloss"\nsync_speed = 21.0\n'
                   'breakdown_torque = 2.0\nbreakdown_slip = 0.2\n')
    scene = parse_scene(text, "s.toml")
    assert scene.shaft is not None and scene.shaft.flywheel == 1.0


def test_a_moment_window_is_in_cam_angle():
    """A moment M on the lever, windowed at cam angle 60° ± 10°: the drive supplies −M x'(θ)
    more (the moment's generalised force on θ is M ∂φ_lever/∂θ = M x'), zero elsewhere."""
    from mechcirc.scene import simulate_scene

    M0 = 7.0
    moment = ('\n[[moments]]\nname = "push"\nbody = "lever"\namplitude = 7.0\n'
              'window_deg = 20.0\ncentre = 60.0\n')
    runs = [simulate_scene(parse_scene(TEXT + extra, "m.toml"), revolutions=1, points=720,
                           error_estimate=False) for extra in ("", moment)]
    th = runs[0].crank_angle
    diff = runs[1].values["drive.moment"] - runs[0].values["drive.moment"]
    xw = np.degrees(th) - 60.0 + 10.0                 # the window's x [deg], in [0, 20)
    m = np.where((xw >= 0) & (xw < 20.0), M0 * np.sin(np.pi * xw / 20.0), 0.0)
    ref = -m * cycloidal(th)[1]
    # the lever is prescribed, so the moment changes nothing else: exact to round-off
    assert np.max(np.abs(diff - ref)) <= 1e-9 * M0
    assert np.max(np.abs(ref)) > 0.5 * M0 * 2 * H / B1   # the window was reached
