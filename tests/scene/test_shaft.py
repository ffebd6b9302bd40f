"""The dynamic main shaft (mechcirc.scene.shaft) against closed forms and an independent
SymPy derivation of the sley four-bar on a flywheel and a Kloss motor."""

import math
import warnings

import numpy as np
import pytest

from mechcirc.errors import MechcircError, NetlistError, ShaftWarning
from mechcirc.scene import parse_scene
from mechcirc.scene.shaft import kloss_motor, simulate_shaft

J0, JF = 0.004, 0.016

DISC = f"""
name = "disc"
units = "m"
[points]
A = [0.0, 0.0]
B = [0.1, 0.0]
[ground]
points = ["A"]
[links]
crank = ["A", "B"]
[[cranks]]
link = "crank"
omega = 100.0
[[masses]]
link = "crank"
inertia = {J0}
[drive]
link = "crank"
velocity = 1.0
"""


def test_linear_motor_starts_up_exponentially():
    """Constant J_red, T = T0 (1 − ω/ω0): ω(t) = ω0 (1 − exp(−T0 t / (ω0 J)))."""
    T0, W0 = 20.0, 80.0
    scene = parse_scene(DISC + f"""[shaft]
flywheel = {JF}
motor = "table"
speeds = [0.0, {W0}]
torques = [{T0}, 0.0]
""")
    r = simulate_shaft(scene)
    want = W0 * (1 - np.exp(-T0 * r.startup_t / (W0 * (J0 + JF))))
    assert np.max(np.abs(r.startup_speed - want)) <= 1e-8 * W0
    assert abs(r.omega_mean - W0) <= 1e-9 * W0 and r.delta <= 1e-9
    # the speed is within 1 % of ω0 after τ ln 100, τ = J ω0 / T0
    tau = (J0 + JF) * W0 / T0
    assert abs(r.startup_time - tau * math.log(100)) <= 1e-8 * tau


def test_kloss_start_up_matches_the_closed_form():
    """Kloss with constant J: t(s) = J ω_s/(2 T_b) [(1 − s²)/(2 s_b) − s_b ln s]."""
    ws, tb, sb = 100.0, 20.0, 0.25
    scene = parse_scene(DISC + f"""[shaft]
flywheel = {JF}
motor = "kloss"
sync_speed = {ws}
breakdown_torque = {tb}
breakdown_slip = {sb}
""")
    r = simulate_shaft(scene)
    keep = (r.startup_speed > 0) & (r.startup_speed < 0.99 * ws)
    s = 1 - r.startup_speed[keep] / ws
    t = (J0 + JF) * ws / (2 * tb) * ((1 - s * s) / (2 * sb) - sb * np.log(s))
    assert keep.sum() > 50
    assert np.max(np.abs(t - r.startup_t[keep])) <= 1e-8 * r.startup_t[keep].max()


def test_kloss_from_the_rated_point():
    """s_b = s_n (λ + √(λ² − 1)) puts the rated point on Kloss's curve."""
    m = kloss_motor(sync_speed=104.72, breakdown_torque=37.5, rated_power=1500.0,
                    rated_speed=100.0)
    assert abs(float(m.torque(100.0)) - 15.0) <= 1e-12 * 15.0
    assert abs(float(m.torque(104.72 * (1 - m.breakdown_slip))) - 37.5) <= 1e-12 * 37.5
    with pytest.raises(MechcircError, match="must exceed the rated torque"):
        kloss_motor(sync_speed=104.72, breakdown_torque=10.0, rated_power=1500.0,
                    rated_speed=100.0)


FOURBAR = """
name = "sley rigid"
units = "m"
[points]
A = [0.0, 0.0]
B = [0.029, 0.0]
C = [0.0028281250000000147, 0.02615402376278609]
D = [0.189, 0.0]
[ground]
points = ["A", "D"]
[links]
crank = ["A", "B"]
coupler = ["B", "C"]
rocker = ["D", "C"]
[[cranks]]
link = "crank"
omega = 100.0
[[torsion]]
name = "C4"
link = "rocker"
body = "sley"
stiffness = 50000.0
[[masses]]
link = "crank"
inertia = 0.005
[[masses]]
link = "rocker"
inertia = 0.025
[[masses]]
link = "sley"
inertia = 0.35
[[moments]]
name = "M4"
body = "sley"
amplitude = -300.0
window_deg = 40.0
centre = 150.0
[drive]
link = "crank"
velocity = 1.0
[shaft]
flywheel = 0.05
motor = "kloss"
sync_speed = 104.72
breakdown_torque = 60.0
breakdown_slip = 0.2
start_deg = 10.0
"""


def sympy_reference(tb=60.0):
    """θ̈(θ, θ̇) of the rigid sley four-bar (Kloss motor of breakdown torque ``tb``), derived in SymPy: the rocker angle φ4(θ) in
    closed form (two circles), μ = dφ4/dθ and μ' by SymPy; Lagrange II applied in SymPy
    to T = ½ (J_f + I2) θ̇² + ½ (I4 + I4P) (μ(θ) θ̇)² with the motor torque and the
    beat-up moment's generalised force M4 μ."""
    sp = pytest.importorskip("sympy")
    th, thd, thdd, tm, m4 = sp.symbols("theta thetad thetadd Tm M4")
    Cx, Cy = 0.0028281250000000147, 0.02615402376278609
    a, d = 0.029, 0.189
    b, c = math.hypot(Cx - a, Cy), math.hypot(Cx - d, Cy)
    Bx, By = a * sp.cos(th), a * sp.sin(th)
    L = sp.sqrt((d - Bx) ** 2 + By ** 2)
    base = sp.atan2(By, Bx - d)                      # direction D → B
    gam = sp.acos((c * c + L * L - b * b) / (2 * c * L))
    pose = math.atan2(Cy, Cx - d)
    phi4 = min((base + gam, base - gam), key=lambda e: abs(float(e.subs(th, 0)) - pose))
    mu_e = sp.diff(phi4, th)
    mu_f = sp.lambdify(th, [mu_e, sp.diff(mu_e, th)], "math")
    mu = sp.Function("mu")
    T = (0.05 + 0.005) * thd ** 2 / 2 + (0.025 + 0.35) * (mu(th) * thd) ** 2 / 2
    dT = sp.diff(T, thd)
    lag = sp.diff(dT, th) * thd + sp.diff(dT, thd) * thdd - sp.diff(T, th)
    m, m1 = sp.symbols("m m1")
    acc = sp.solve(sp.Eq(lag, tm + m4 * mu(th)), thdd)[0]
    acc = acc.subs(sp.Derivative(mu(th), th), m1).subs(mu(th), m)
    f = sp.lambdify((thd, tm, m4, m, m1), acc, "math")
    ws, sb = 104.72, 0.2
    centre, alpha = math.radians(150.0), math.radians(40.0)

    def rhs(t, y):
        s = (ws - y[1]) / ws
        torque = 2 * tb / (s / sb + sb / s) if s != 0 else 0.0
        x = (y[0] - centre + alpha / 2) % (2 * math.pi)
        moment = -300.0 * math.sin(math.pi * x / alpha) if x < alpha else 0.0
        return [y[1], f(y[1], torque, moment, *mu_f(y[0]))]
    return rhs


@pytest.mark.slow
def test_sley_shaft_matches_an_independent_sympy_derivation():
    """Start-up from rest and the steady cycle against the SymPy equations integrated by
    DOP853 at rtol 1e-12: speed to 1e-6 of ω_s."""
    from scipy.integrate import solve_ivp

    rhs = sympy_reference()
    scene = parse_scene(FOURBAR)
    r = simulate_shaft(scene, points=180, rigid=True)      # the torsion rod C4 rigid
    th0 = math.radians(10.0)
    keep = r.startup_t <= 0.3
    sol = solve_ivp(rhs, (0, 0.3), [th0, 0.0], method="DOP853", rtol=1e-12, atol=1e-12,
                    t_eval=r.startup_t[keep])
    err = np.max(np.abs(sol.y[1] - r.startup_speed[keep]))
    assert err <= 1e-6 * 104.72, err
    # the steady cycle: run the reference until it has settled, then one cycle in θ
    end = lambda t, y: y[0] - (th0 + 2 * math.pi * 12)      # noqa: E731
    end.terminal = True
    s1 = solve_ivp(rhs, (0, 100), [th0, 0.0], method="DOP853", rtol=1e-12, atol=1e-12,
                   events=end)
    y = s1.y[:, -1]
    s2 = solve_ivp(lambda th, z: [rhs(0, [th, z[0]])[1] / z[0], 1 / z[0]],
                   (y[0], y[0] + 2 * math.pi), [y[1], 0.0], method="DOP853", rtol=1e-12,
                   atol=1e-12, dense_output=True)
    want = s2.sol(y[0] + r.theta)[0]
    assert np.max(np.abs(want - r.speed)) <= 1e-6 * 104.72
    fine = s2.sol(np.linspace(y[0], y[0] + 2 * math.pi, 200001))[0]
    mean = 2 * math.pi / s2.y[1, -1]
    assert abs(mean - r.omega_mean) <= 1e-7 * mean
    assert abs((fine.max() - fine.min()) / mean - r.delta) <= 1e-6 * r.delta


def test_a_motor_that_cannot_start_the_load_is_refused():
    text = FOURBAR.replace('breakdown_torque = 60.0', 'breakdown_torque = 2.0').replace(
        "start_deg = 10.0", "start_deg = 150.0")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ShaftWarning)
        with pytest.raises(MechcircError, match="cannot start the mechanism: its starting "
                                                "torque T\\(0\\) = 0.769231 N·m does not exceed the load torque 57.3174 N·m"):
            simulate_shaft(parse_scene(text))


def test_breakdown_below_the_peak_load_warns_and_stalls_without_a_flywheel():
    text = FOURBAR.replace('breakdown_torque = 60.0', 'breakdown_torque = 12.0').replace(
        "flywheel = 0.05", "flywheel = 0.0")
    with pytest.warns(ShaftWarning, match="below the peak load torque"):
        with pytest.raises(MechcircError, match="no steady cycle|stalls"):
            simulate_shaft(parse_scene(text), rigid=True)


@pytest.mark.parametrize("line, message", [
    ('motor = "diesel"', 'motor must be "kloss" or "table"'),
    ("flywheel = -1.0", "flywheel must be a finite number ≥ 0"),
    ("speeds = [0.0, 1.0]", "speeds does not apply to motor = 'kloss'"),
])
def test_bad_shaft_tables_are_located(line, message):
    key = line.split(" =")[0]
    text = FOURBAR.replace("breakdown_slip = 0.2", "breakdown_slip = 0.2\n" + line) \
        if key == "speeds" else "\n".join(
            line if ln.startswith(key + " =") else ln for ln in FOURBAR.splitlines())
    with pytest.raises(NetlistError, match=message) as exc:
        parse_scene(text)
    assert exc.value.line > 0


def test_cli_prints_the_fluctuation_and_refuses_a_motor_that_cannot_start(tmp_path, capsys):
    import json

    from cli_helpers import assert_user_error, run

    status, out, err = run(["simulate", "examples/fnf_sixbar_scene.toml", "--shaft",
                            "--json"], capsys)
    assert status == 0, err
    doc = json.loads(out)
    assert 0 < doc["delta"] < 0.1 and doc["startup_time"] > 0
    assert doc["extrema"]["speed"][0] < doc["omega_mean"] < doc["extrema"]["speed"][1]
    bad = tmp_path / "weak.toml"
    bad.write_text(FOURBAR.replace("breakdown_torque = 60.0", "breakdown_torque = 2.0")
                   .replace("start_deg = 10.0", "start_deg = 150.0"), encoding="utf-8")
    out_csv = tmp_path / "out.csv"
    assert_user_error(["simulate", str(bad), "--shaft", "-o", str(out_csv)], capsys,
                      "cannot start the mechanism", "57.3174 N·m")
    assert not out_csv.exists()
    assert_user_error(["simulate", "examples/fnf_sixbar_scene.toml", "--flywheel", "0.1"],
                      capsys, "--flywheel applies to --shaft")


def test_the_sley_flywheel_example_gives_the_numbers_in_the_docs():
    """examples/sley_flywheel.py for two flywheels against its table in docs/sley.md."""
    import importlib.util
    import re

    spec = importlib.util.spec_from_file_location("sley_flywheel", "examples/sley_flywheel.py")
    ex = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(ex)
    text = open("docs/sley.md", encoding="utf-8").read()
    table = {}
    for line in text.splitlines():
        m = re.match(r"\|\s*([0-9.]+)\s*\|\s*([0-9.]+)\s*\|\s*([0-9.]+)\s*\|\s*(-?\d+)\s*\|"
                     r"\s*(-?\d+)\s*\|\s*(-?[0-9.]+)\s*\|\s*(-?[0-9.]+)\s*\|\s*([0-9.]+)\s*\|",
                     line)
        if m:
            table[float(m.group(1))] = [float(x) for x in m.groups()[1:]]
    assert {0.1, 1.0} <= set(table)
    for row in ex.rows((0.1,), startup=True) + ex.rows((1.0,), startup=False):
        want = table[row[0]]
        got = list(row[1:])
        digits = (0.01, 0.0001, 1, 1, 0.1, 0.1, 0.001)
        for g, w, d in zip(got, want, digits):
            if g is not None:
                assert abs(g - w) <= 0.51 * d, (row[0], got, want)


@pytest.mark.parametrize("max_time", [None, 0.05])
def test_dop853_start_up_is_the_closed_form_and_says_when_max_time_is_too_short(max_time):
    """method="DOP853" (scipy's solve_ivp, cycle by cycle): the linear motor's start-up
    ω(t) = ω0 (1 − exp(−T0 t / (ω0 J))) and its time into the 1 % band, τ ln 100; a
    max_time shorter than τ ln 100 (0.074 s here) is refused with the speed reached."""
    T0, W0 = 20.0, 80.0
    extra = "" if max_time is None else f"max_time = {max_time}\n"
    scene = parse_scene(DISC + f"""[shaft]
flywheel = {JF}
motor = "table"
speeds = [0.0, {W0}]
torques = [{T0}, 0.0]
{extra}""")
    tau = (J0 + JF) * W0 / T0
    if max_time is not None:
        with pytest.raises(MechcircError, match="did not reach the steady cycle within "
                                                "max_time = 0.05 s .speed ([0-9.]+) rad/s") as exc:
            simulate_shaft(scene, method="DOP853")
        speed = float(str(exc.value).split("(speed ")[1].split(" ")[0])
        assert abs(speed - W0 * (1 - math.exp(-max_time / tau))) <= 1e-5 * W0
        return
    r = simulate_shaft(scene, method="DOP853")
    want = W0 * (1 - np.exp(-r.startup_t / tau))
    assert np.max(np.abs(r.startup_speed - want)) <= 1e-8 * W0
    # the crossing's error is the speed's over the slope 0.01 ω0/τ there: 1.8e-8 τ achieved
    assert abs(r.startup_time - tau * math.log(100)) <= 1e-7 * tau


def test_dop853_start_up_that_stalls_says_where_as_the_sympy_equations():
    """A Kloss motor of breakdown torque 20 N·m (below the peak load, 57.3 N·m) and the
    flywheel 0.05 kg·m²: the steady cycle exists, but the start-up from rest by DOP853
    (scene/shaft._startup, whose stall no test ran) stops; the time and angle it prints
    are those at which the SymPy-derived equations (integrated by scipy, rtol 1e-12)
    come to rest, to their printed digits (4 and 5)."""
    import re

    from scipy.integrate import solve_ivp

    text = FOURBAR.replace("breakdown_torque = 60.0", "breakdown_torque = 20.0")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ShaftWarning)
        with pytest.raises(MechcircError, match="the start-up stalls at t = ") as info:
            simulate_shaft(parse_scene(text), rigid=True, method="DOP853", points=90)
    got = re.search(r"t = ([\d.]+) s, θ = ([\d.]+)°: the motor's largest torque 20 N·m is "
                    r"below the peak load torque 57.3174 N·m", str(info.value))
    assert got, str(info.value)
    rhs = sympy_reference(tb=20.0)
    rest = lambda t, y: y[1] + 1e-9 * 104.72      # noqa: E731 - as the code: ω below -1e-9 ω_s
    rest.terminal, rest.direction = True, -1
    ref = solve_ivp(rhs, (0, 5), [math.radians(10.0), 0.0], method="DOP853", rtol=1e-12,
                    atol=1e-12, events=rest)
    t_stop, th_stop = ref.t_events[0][0], ref.y_events[0][0][0]
    assert float(got.group(1)) == pytest.approx(t_stop, abs=5e-5 * 1.01)
    assert float(got.group(2)) == pytest.approx(math.degrees(th_stop), abs=5e-3 * 1.01)
