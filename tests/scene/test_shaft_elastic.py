"""The dynamic main shaft coupled to an ELASTIC scene (mechcirc.scene.shaft) against an
independent Lagrange derivation in SymPy, and its two limits: infinitely stiff links (the
rigid shaft) and an infinite flywheel (the constant-speed elastic simulation)."""

import math

import numpy as np
import pytest

from mechcirc.scene import parse_scene
from mechcirc.scene.shaft import simulate_shaft

# The shipped elastic slider-crank (crank 40 mm, elastic rod 150 mm, 2.5 kg block on a
# guide 10 mm below the crank pivot) with a crank inertia, a process moment on the crank
# and a Kloss motor on a flywheel.
R, Y_G, X_C0, L0 = 0.04, -0.01, 0.189666295470958, 0.15
M_BLOCK, J_CRANK, JF = 2.5, 0.002, 0.01
WS, TB, SB = 42.0, 30.0, 0.25
AMP, WIN, CENTRE = -6.0, 90.0, 120.0
START = 10.0
EXTRA = f"""
[[masses]]
name = "J_crank"
link = "crank"
inertia = {J_CRANK}

[[moments]]
name = "M_proc"
body = "crank"
amplitude = {AMP}
window_deg = {WIN}
sigma_deg = {WIN}
centre = {CENTRE}

[shaft]
flywheel = {JF}
motor = "kloss"
sync_speed = {WS}
breakdown_torque = {TB}
breakdown_slip = {SB}
start_deg = {START}
"""


def scene(stiffness=3.0e6, damping=300.0, flywheel=JF):
    text = open("examples/slider_crank_scene.toml", encoding="utf-8").read()
    text = text.replace("stiffness = 3.0e6", f"stiffness = {stiffness!r}").replace(
        "damping = 300.0", f"damping = {damping!r}")
    return parse_scene(text + EXTRA.replace(f"flywheel = {JF}", f"flywheel = {flywheel!r}"))


def sympy_reference(k=3.0e6, d=300.0):
    """f(θ, [θ̇, s, ṡ]) → (θ̈, ṡ, s̈) of crank + flywheel + elastic rod + block, derived from
    T = ½ (J_f + J_c) θ̇² + ½ m ṡ², V = ½ k δ², the Rayleigh function ½ d δ̇² with
    δ = |C − B| − ℓ0, B = r (cos θ, sin θ), C = (x_C0 + s, y_g), and the generalised forces
    T_motor(θ̇) + M(θ) on θ (Kloss; the half-sine process window)."""
    sp = pytest.importorskip("sympy")
    th, s, thd, sd = sp.symbols("theta s thetadot sdot")
    q, qd = [th, s], [thd, sd]
    T = sp.Rational(1, 2) * (JF + J_CRANK) * thd ** 2 + sp.Rational(1, 2) * M_BLOCK * sd ** 2
    delta = sp.sqrt((X_C0 + s - R * sp.cos(th)) ** 2 + (Y_G - R * sp.sin(th)) ** 2) - L0
    V = k * delta ** 2 / 2
    ddot = sum(sp.diff(delta, a) * b for a, b in zip(q, qd))
    Ray = d * ddot ** 2 / 2
    acc = sp.symbols("a0 a1")
    Qm, Mw = sp.symbols("Q_motor M_window")
    eqs = []
    for i, (a, b) in enumerate(zip(q, qd)):
        dT = sp.diff(T, b)
        ddt = sum(sp.diff(dT, x) * y for x, y in zip(qd, acc)) + \
            sum(sp.diff(dT, x) * y for x, y in zip(q, qd))
        gen = (Qm + Mw) if i == 0 else 0
        eqs.append(sp.Eq(ddt - sp.diff(T, a) + sp.diff(V, a) + sp.diff(Ray, b), gen))
    # The equations are linear in the accelerations, M(q) a = b(q, q̇): M and b are
    # lambdified (common subexpressions shared) and the 2 × 2 system solved numerically,
    # the same accelerations as a symbolic solve without its minute-long expression swell.
    M, b = sp.linear_eq_to_matrix([e.lhs - e.rhs for e in eqs], acc)
    mass = sp.lambdify((th, s), M, "numpy", cse=True)
    rest = sp.lambdify((th, s, thd, sd, Qm, Mw), b, "numpy", cse=True)

    def f(theta, s_, thetadot, sdot, q_motor, m_window):
        a = np.linalg.solve(np.asarray(mass(theta, s_), float),
                            np.asarray(rest(theta, s_, thetadot, sdot, q_motor, m_window),
                                       float).ravel())
        return float(a[0]), float(a[1])
    force = sp.lambdify((th, s, thd, sd), k * delta + d * ddot, "math", cse=True)

    def motor(w):
        slip = (WS - w) / WS
        return 2 * TB * slip * SB / (slip * slip + SB * SB)

    def window(phi):
        x = (phi - math.radians(CENTRE) + 0.5 * math.radians(WIN)) % (2 * math.pi)
        return AMP * math.sin(math.pi * x / math.radians(WIN)) if x < math.radians(WIN) \
            else 0.0

    def rhs(theta, y):
        a0, a1 = f(theta, y[1], y[0], y[2], motor(y[0]), window(theta))
        return a0, y[2], a1
    return rhs, force


def rigid_travel(theta):
    """The block's travel s in the rigid slider-crank (closed form)."""
    return R * math.cos(theta) + math.sqrt(L0 ** 2 - (Y_G - R * math.sin(theta)) ** 2) - X_C0


@pytest.mark.slow
def reference_cycle(rhs, r):
    """The steady cycle ``r`` of :func:`simulate_shaft` checked in the SymPy equations ``rhs``:
    one revolution in θ from the state the code found, by DOP853 at rtol 1e-12, stopping at
    the moment window's edges (kinks: the half sine's slope jumps there).  Returns (the
    state after the revolution, that state [θ̇, s, ṡ, t] at its start, the solution at
    ``r.theta``)."""
    from scipy.integrate import solve_ivp

    th0 = math.radians(START)
    x0 = [r.speed[0], r.states[0, 0], r.states[0, 1], 0.0]
    ends = [th0] + sorted((math.radians(CENTRE + k * WIN / 2) - th0) % (2 * math.pi) + th0
                          for k in (-1, 1)) + [th0 + 2 * math.pi]

    def in_theta(theta, z):
        a0, v, a1 = rhs(theta, z)
        return [a0 / z[0], v / z[0], a1 / z[0], 1.0 / z[0]]
    th = th0 + r.theta
    Y = np.empty((4, th.size))
    y = x0
    for a, b in zip(ends, ends[1:]):
        ref = solve_ivp(in_theta, (a, b), y, method="DOP853", rtol=1e-12, atol=1e-14,
                        dense_output=True)
        on = (th >= a) & ((th < b) | (b == ends[-1]))
        Y[:, on] = ref.sol(th[on])
        y = ref.y[:, -1]
    return y, x0, Y


def test_elastic_shaft_matches_an_independent_sympy_derivation():
    """Steady cycle (speed, rod force, periodicity) and start-up against the SymPy
    equations integrated by DOP853 at rtol 1e-12: ≤ 1e-6 over the revolution."""
    from scipy.integrate import solve_ivp

    rhs, force = sympy_reference()
    r = simulate_shaft(scene(), points=180)
    th0 = math.radians(START)
    end, x0, Y = reference_cycle(rhs, r)
    assert np.max(np.abs(Y[0] - r.speed)) <= 1e-6 * WS
    assert np.max(np.abs(Y[3] - r.time)) <= 1e-6 * r.period
    # the state the code found repeats after the revolution in the reference equations
    assert abs(end[0] - x0[0]) <= 1e-6 * WS
    assert abs(end[1] - x0[1]) <= 1e-6 * 1e-4     # of the rod's largest deformation
    assert abs(end[3] - r.period) <= 1e-6 * r.period
    fref = np.array([force(t, s, w, sd) for t, s, w, sd in zip(th0 + r.theta, Y[1], Y[0],
                                                                 Y[2])])
    fmax = np.max(np.abs(fref))
    assert np.max(np.abs(fref - r.values["k_rod.force"])) <= 1e-6 * fmax
    # the start-up from rest (rigid position, nothing moving, nothing deformed)
    keep = r.startup_t > 0
    s0 = rigid_travel(th0)
    up = solve_ivp(lambda t, y: [y[1], *rhs(y[0], y[1:])],
                   (0.0, r.startup_t[-1]), [th0, 0.0, s0, 0.0], method="DOP853", rtol=1e-12,
                   atol=1e-14, t_eval=r.startup_t[keep])
    assert np.max(np.abs(up.y[1] - r.startup_speed[keep])) <= 1e-6 * WS


def _speed_gap(a, b):
    return float(np.max(np.abs(a.speed - b.speed))) / WS


@pytest.mark.slow
def test_stiff_links_tend_to_the_rigid_shaft():
    """With the rod 10× stiffer the steady cycle's speed approaches the rigid shaft's (θ the
    only degree of freedom) about as 1/k: measured 1.56e-4 and 9.97e-6 of ω_s at k = 3e6
    and 3e7 N/m (ratio 0.064; at 3e8, 1.98e-6: the rigid tables' own interpolation)."""
    rigid = simulate_shaft(scene(), points=90, startup=False, rigid=True)
    gaps = [_speed_gap(simulate_shaft(scene(k), points=90, startup=False), rigid)
            for k in (3.0e6, 3.0e7)]
    assert gaps[1] <= 0.1 * gaps[0] and gaps[1] <= 2e-5, gaps


@pytest.mark.slow
def test_a_large_flywheel_tends_to_the_constant_speed_simulation():
    """With J_f = 1e3 and 1e4 kg·m² the rod force over the cycle approaches that of the
    constant-speed simulation (simulate_scene at Ω = ω_mean, DOP853) as 1/J_f."""
    from mechcirc.scene.simulation import simulate_scene

    gaps = []
    for jf in (1.0e3, 1.0e4):
        r = simulate_shaft(scene(flywheel=jf), points=90, startup=False)
        c = simulate_scene(scene(flywheel=jf), omega=r.omega_mean, start_deg=START, points=90,
                           method="DOP853", rtol=1e-10, revolutions=4, error_estimate=False)
        order = np.argsort((math.radians(START) + r.theta) % (2 * math.pi), kind="stable")
        f = r.values["k_rod.force"][order]
        want = c.values["k_rod.force"]
        gaps.append(float(np.max(np.abs(f - want)) / np.max(np.abs(want))))
    # measured 3.217e-6 and 3.217e-7 of the peak force (δ = 2.9e-6, 2.9e-7)
    assert gaps[1] <= 0.15 * gaps[0] and gaps[1] <= 1e-6, gaps


@pytest.mark.slow
def test_cli_prints_the_elastic_forces_with_units(tmp_path, capsys):
    from cli_helpers import assert_user_error, run

    path = tmp_path / "slider_shaft.toml"
    path.write_text(open("examples/slider_crank_scene.toml", encoding="utf-8").read() + EXTRA,
                    encoding="utf-8")
    status, out, err = run(["simulate", str(path), "--shaft", "--points", "90"], capsys)
    assert status == 0, err
    rows = {ln.split()[0]: ln.split() for ln in out.splitlines() if ln.split()}
    assert rows["k_rod.force"][-1] == "N" and rows["k_rod.deformation"][-1] == "m"
    assert rows["speed"][-1] == "rad/s" and rows["motor_torque"][-1] == "N·m"
    assert rows["block.travel.acceleration"][-1] == "m/s²"
    assert 0 < float(rows["k_rod.force"][2]) < 300          # about 227 N (docs)
    assert_user_error(["simulate", str(path), "--rigid"], capsys, "--rigid applies to --shaft")


@pytest.mark.slow
def test_a_stroke_is_checked_at_every_sample_of_the_shaft_cycle():
    """The block's rigid travel stays below 189.7367 mm (closed form) but the elastic rod on
    the shaft lets it reach about 189.80 mm: a stroke [100, 189.77] is left at a sample of
    the steady cycle, reported (located at the stroke) where the unbounded run says."""
    import re

    from mechcirc.errors import NetlistError

    th = np.linspace(0, 2 * math.pi, 200001)
    assert (R * np.cos(th) + np.sqrt(L0 ** 2 - (Y_G - R * np.sin(th)) ** 2)).max() < 0.18976
    free = simulate_shaft(scene(), points=180, startup=False)
    x = 189.666295470958 + free.states[:, 0] * 1000           # the block's place [mm]
    first = int(np.argmax(x > 189.77))
    assert x[first] > 189.77
    text = open("examples/slider_crank_scene.toml", encoding="utf-8").read() + EXTRA
    text = text.replace('line = ["G1", "G2"]\n', 'line = ["G1", "G2"]\nstroke = [100.0, 189.77]\n')
    with pytest.raises(NetlistError, match="sample of the shaft's steady cycle") as exc:
        simulate_shaft(parse_scene(text, "stroke.toml"), points=180, startup=False)
    msg = str(exc.value)
    assert msg.startswith("stroke.toml:33:") and "slider 'block'" in msg
    deg, along = (float(v) for v in re.search(r"θ = ([\d.]+)°.* at ([\d.]+) along", msg)
                  .groups())
    assert deg == pytest.approx(START + math.degrees(free.theta[first]), abs=1e-3)
    assert along == pytest.approx(x[first], abs=1e-3)
