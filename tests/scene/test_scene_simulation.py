"""mechcirc.scene.simulation: a crank speed profile (``omega_ripple``) against an independent
solution, the scipy methods on a scene, and the run options' one check (with the sley's)."""

import math
import warnings

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import _scene_helpers as helpers
import mechcirc.sley.simulation as sley_simulation
from mechcirc.errors import MechcircError, ParameterError
from mechcirc.scene import parse_scene
from mechcirc.scene.simulation import METHODS, SceneAccuracyWarning, simulate_scene
from mechcirc.sley import preset, simulate_params

J, K, D, OMEGA, A, H = 0.01, 1000.0, 0.5, 50.0, 0.1, 2

FLYWHEEL = f"""
name = "flywheel"
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
omega = {OMEGA}
[[torsion]]
name = "rod"
link = "crank"
body = "shaft"
stiffness = {K}
damping = {D}
[[masses]]
name = "J"
link = "crank"
inertia = {J}
[drive]
link = "shaft"
velocity = {OMEGA}
[simulate]
revolutions = 3
points = 720
omega_ripple = {{amplitude = {A}, harmonic = {H}}}
"""


def reference(t_out):
    """The crank on a torsion rod from a shaft turning at Ω (1 + a cos(k Ω t)), written out:
    x = q − θ, J ẍ + D ẋ + K x = −J θ̈, θ̈ = −a k Ω² sin(k Ω t); from rest in x (the rigid
    start).  Returns the crank's acceleration q̈ = ẍ + θ̈ and the rod's moment −(K x + D ẋ)."""
    nu = H * OMEGA

    def thdd(t):
        return -A * OMEGA * nu * np.sin(nu * t)

    def f(t, y):
        return [y[1], (-J * thdd(t) - D * y[1] - K * y[0]) / J]

    sol = solve_ivp(f, (0, t_out.max()), [0.0, 0.0], method="DOP853", rtol=1e-12,
                    atol=[1e-15, 1e-12], dense_output=True)
    x, xd = sol.sol(t_out)
    xdd = (-J * thdd(t_out) - D * xd - K * x) / J
    return xdd + thdd(t_out), -(K * x + D * xd)


def crank_motion(t_out):
    """q, q̇, q̈ of the crank (independent, as :func:`reference`)."""
    nu = H * OMEGA
    acc, moment = reference(t_out)
    th = OMEGA * t_out + A / H * np.sin(nu * t_out)
    thd = OMEGA * (1 + A * np.cos(nu * t_out))
    # x = q − θ from the rod's moment −(K x + D ẋ) and J(ẍ + θ̈) = moment: integrate again
    sol_x = solve_ivp(lambda t, y: [y[1], (A * OMEGA * nu * np.sin(nu * t) * J - D * y[1]
                                           - K * y[0]) / J],
                      (0, t_out.max()), [0.0, 0.0], method="DOP853", rtol=1e-12,
                      atol=[1e-15, 1e-12], dense_output=True)
    x, xd = sol_x.sol(t_out)
    return th + x, thd + xd, acc


@pytest.mark.parametrize("method, kw, tol", [("rk4", {"steps_per_period": 200}, 1e-7),
                                             ("DOP853", {"rtol": 1e-11}, 1e-9)])
def test_speed_ripple_against_written_out_equation(method, kw, tol):
    scene = parse_scene(FLYWHEEL, "<flywheel>")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", SceneAccuracyWarning)
        m = simulate_scene(scene, method=method, error_estimate=False, **kw)
    acc, moment = reference(m.time)
    # measured: rk4 (200 steps/period) 1.2e-8, DOP853 (rtol 1e-11) 2.3e-11 of the largest
    # value (rk4 at the default 50: 3.0e-6); tolerances ~9x and ~40x above
    for got, want in ((m.values["crank.acceleration"], acc), (m.values["rod.force"], moment)):
        assert np.max(np.abs(got - want)) <= tol * np.max(np.abs(want))
    # the shaft follows the profile exactly: θ̈ = −a k Ω² sin(k Ω t)
    want = -A * H * OMEGA ** 2 * np.sin(H * OMEGA * m.time)
    np.testing.assert_allclose(m.values["shaft.acceleration"], want, atol=1e-9 * A * H * OMEGA ** 2)
    # crank angle: θ = Ω t + (a/k) sin(k Ω t), mod 2π, ascending
    th = (OMEGA * m.time + A / H * np.sin(H * OMEGA * m.time)) % (2 * math.pi)
    np.testing.assert_allclose(m.crank_angle, th, atol=1e-12)
    assert np.all(np.diff(m.crank_angle) > 0)


def test_no_ripple_is_constant_speed():
    scene = parse_scene(FLYWHEEL, "<flywheel>")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", SceneAccuracyWarning)
        m = simulate_scene(scene, omega_ripple=(0.0, 1), error_estimate=False)
    # a rigid crank at constant speed: nothing deforms
    assert max(map(abs, m.extrema["rod.force"])) < 1e-9


@pytest.mark.parametrize("ripple, text", [((1.0, 1), "amplitude must be in"),
                                          ((0.1, 1.5), "whole number"),
                                          ((0.1, 0), "whole number")])
def test_bad_ripple_options(ripple, text):
    from mechcirc.errors import MechcircError

    with pytest.raises(MechcircError, match=text):
        simulate_scene(parse_scene(FLYWHEEL, "<flywheel>"), omega_ripple=ripple)


@pytest.mark.parametrize("value, text", [
    ("0.1", "must be an inline table"),
    ("{amplitude = 1.5}", "amplitude must be a number in"),
    ("{amplitude = 0.1, harmonic = 0}", "harmonic must be a whole number"),
    ("{amplitude = 0.1, harmonic = 1.5}", "harmonic must be a whole number"),
    ("{amplitude = 0.1, phase = 2}", "unknown key 'phase'"),
    ("{harmonic = 2}", "missing amplitude"),
])
def test_ripple_grammar_errors_are_located(value, text):
    from mechcirc.errors import NetlistError

    src = FLYWHEEL.replace("omega_ripple = {amplitude = 0.1, harmonic = 2}",
                           f"omega_ripple = {value}")
    line = next(i for i, ln in enumerate(src.splitlines(), 1) if ln.startswith("omega_ripple"))
    with pytest.raises(NetlistError, match=text) as info:
        parse_scene(src, "s.toml")
    assert info.value.line == line


def test_set_overrides_the_ripple():
    from mechcirc.scene.files import apply_overrides

    scene = apply_overrides(parse_scene(FLYWHEEL, "<f>"), {"omega_ripple.amplitude": 0.2,
                                                            "omega_ripple.harmonic": 3.0})
    assert scene.simulate.omega_ripple == (0.2, 3)


def test_point_acceleration_of_a_crank_pin():
    """B on the crank, 0.1 m from the pivot: a = 0.1 (−q̇² cos q − q̈ sin q, −q̇² sin q + q̈ cos q)
    with q from the equation written out (measured 1.8e-9 of the largest |a| at 200 steps per
    period; tolerance 1e-7)."""
    scene = parse_scene(FLYWHEEL, "<flywheel>")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", SceneAccuracyWarning)
        m = simulate_scene(scene, steps_per_period=200, error_estimate=False)
    q, qd, qdd = crank_motion(m.time)
    ax = 0.1 * (-qd ** 2 * np.cos(q) - qdd * np.sin(q))
    ay = 0.1 * (-qd ** 2 * np.sin(q) + qdd * np.cos(q))
    scale = np.max(np.hypot(ax, ay))
    assert np.max(np.abs(m.values["B.acceleration_x"] - ax)) <= 1e-7 * scale
    assert np.max(np.abs(m.values["B.acceleration_y"] - ay)) <= 1e-7 * scale
    assert np.max(np.abs(m.values["B.acceleration"] - np.hypot(ax, ay))) <= 1e-7 * scale
    assert "A.acceleration" not in m.values          # a frame point does not move


def test_without_point_accelerations_the_rest_is_unchanged():
    """``point_accelerations=False`` (what the sley asks for) leaves out exactly the points'
    ``.acceleration``, ``_x``, ``_y``; every other output, extremum, the estimate and the
    periodicity are those of the full call, bit for bit."""
    scene = parse_scene(FLYWHEEL, "<flywheel>")
    kw = dict(revolutions=2, points=360)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", SceneAccuracyWarning)
        full = simulate_scene(scene, **kw)
        lean = simulate_scene(scene, point_accelerations=False, **kw)
    points = {"B.acceleration", "B.acceleration_x", "B.acceleration_y"}
    assert set(full.values) - set(lean.values) == points == set(full.extrema) - set(lean.extrema)
    assert set(lean.values) < set(full.values)
    for k, v in lean.values.items():
        assert np.array_equal(v, full.values[k]), k
        assert lean.extrema[k] == full.extrema[k], k
    assert (lean.error_estimate, lean.periodicity) == (full.error_estimate, full.periodicity)
    assert np.array_equal(lean.states, full.states)


@pytest.mark.parametrize("name", ["slider_crank_scene", "fnf_sixbar_scene", "cam_heald_scene"])
def test_rk4_error_estimate_bounds_the_returned_runs_error_on_shipped_scenes(name):
    """The RK4 result is the half-step run; its error_estimate (change from the run at
    the step) must be >= its true error, measured against DOP853 at rtol 1e-12 on the
    same equations (an independent integrator).  Measured estimate / true at 6 and 20
    steps per period: slider-crank 15.4, 15.2; geared six-bar 15.7, 15.4; cam 5.7, 7.8."""
    from mechcirc.scene.simulation import _rel_change

    scene, ref = helpers.shipped_and_reference(name)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for spp in (6, 20):
            r = simulate_scene(scene, revolutions=2, points=720, steps_per_period=spp)
            true = _rel_change(r.extrema, ref.extrema)
            assert 0 < true <= r.error_estimate, (spp, r.error_estimate, true)


@pytest.mark.parametrize("python", [True, False])
def test_output_extrema_are_the_extrema_of_the_outputs(python):
    """The kernel's running extrema (the error estimate's and periodicity's runs) equal
    numpy's min/max of the tabulated outputs, compiled and as Python; a NaN stays NaN."""
    from mechcirc._jit import load
    from mechcirc.scene import _motion_kernels, motion_model

    kern = load("mechcirc.scene._motion_kernels", _FORCE_PYTHON=True) if python \
        else _motion_kernels
    model = motion_model(parse_scene(FLYWHEEL, "flywheel.toml"))
    n = model.n_free
    ts = np.linspace(0.0, 0.1, 40)
    rng = np.random.default_rng(3)
    ys = np.array([model.rigid_state(0.0)] * ts.size) + 1e-3 * rng.standard_normal((ts.size, 2 * n))
    args = model.kernel_args(0.0, 1e300, outputs=True)
    out = np.empty((model.naux(), ts.size))               # an output per row
    kern.outputs(ts, ys, out, *args)
    ext = np.empty((2, model.naux()))
    kern.output_extrema(ts, ys, ext, *args)
    assert np.array_equal(ext[0], out.min(axis=1)) and np.array_equal(ext[1], out.max(axis=1))
    assert np.ptp(out[:-1], axis=1).max() > 0             # the outputs do vary
    ys[7, n] = np.nan
    kern.output_extrema(ts, ys, ext, *args)
    kern.outputs(ts, ys, out, *args)
    nan = np.isnan(out).any(axis=1)
    assert nan.any() and np.array_equal(np.isnan(ext[0]), nan) and np.array_equal(np.isnan(ext[1]), nan)


@pytest.mark.parametrize("name", ["slider_crank_scene", "fnf_sixbar_scene", "cam_heald_scene"])
def test_rk8_is_accurate_and_its_error_estimate_bounds_its_error(name):
    """method="rk8" (the 8th-order DOP853 formula at a fixed step, cut at the force laws'
    kinks, quintic output in the positions) against DOP853 at rtol 1e-12 on the same
    equations: its error_estimate is >= its true error, and at 16 steps per period it is
    within 1e-7 (measured, 2 revolutions, at 8 / 16 steps: slider-crank 5.1e-9 / 3.1e-11,
    six-bar 3.5e-8 / 1.3e-9, cam 1.7e-6 / 7.9e-9; estimate / true 233, 165; 349, 11.4;
    19, 148.  With cubic output, as RK4's, the cam was 6.3e-6 at 16 steps)."""
    from mechcirc.scene.simulation import _rel_change

    scene, ref = helpers.shipped_and_reference(name)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for spp in (8, 16):
            r = simulate_scene(scene, revolutions=2, points=720, steps_per_period=spp,
                               method="rk8")
            true = _rel_change(r.extrema, ref.extrema)
            assert 0 < true <= r.error_estimate, (spp, r.error_estimate, true)
    assert true <= 1e-7
    assert any(n.startswith("RK8 step") for n in r.notes)


def test_hermite_point_reproduces_polynomials_and_converges_at_its_order():
    """The shared step interpolant (mechcirc._ode.hermite_point): for y = [q, q̇] and
    f = [q̇, q̈], the quintic form (m = 1) reproduces q(t) of degree 5 and its q̇ exactly,
    the cubic form (m = 0) degree 3; on q = sin t their errors fall as h⁶ (q) and h⁵
    (q̇) against h⁴ for the cubic (observed orders from h = 0.2 and 0.1)."""
    from mechcirc._ode import hermite_point

    def state(c, t):            # q = Σ c_k t^k: [q, q̇], [q̇, q̈]
        p = np.polynomial.Polynomial(c)
        return np.array([p(t), p.deriv()(t)]), np.array([p.deriv()(t), p.deriv(2)(t)])

    t0, h = 0.3, 0.7
    out = np.empty(2)
    for m, deg in ((1, 5), (0, 3)):
        c = np.arange(1.0, deg + 2.0) * (-1.0) ** np.arange(deg + 1)
        y0, f0 = state(c, t0)
        y1, f1 = state(c, t0 + h)
        for s in (0.0, 0.17, 0.5, 0.93, 1.0):
            hermite_point(out, s, h, y0, f0, y1, f1, 2, m)
            want = state(c, t0 + s * h)[0]
            np.testing.assert_allclose(out, want, rtol=1e-13, atol=1e-13)

    def worst(m, h):
        y0, f0 = np.array([np.sin(t0), np.cos(t0)]), np.array([np.cos(t0), -np.sin(t0)])
        t1 = t0 + h
        y1, f1 = np.array([np.sin(t1), np.cos(t1)]), np.array([np.cos(t1), -np.sin(t1)])
        err = np.zeros(2)
        for s in np.linspace(0.0, 1.0, 41):
            hermite_point(out, s, h, y0, f0, y1, f1, 2, m)
            t = t0 + s * h
            err = np.maximum(err, np.abs(out - [np.sin(t), np.cos(t)]))
        return err

    p5 = np.log2(worst(1, 0.2) / worst(1, 0.1))
    p3 = np.log2(worst(0, 0.2) / worst(0, 0.1))
    # observed orders, measured: quintic 6.18 (q), 5.19 (q̇); cubic 4.18, 3.97
    assert abs(p5[0] - 6) < 0.35 and abs(p5[1] - 5) < 0.35, p5
    assert abs(p3[0] - 4) < 0.35 and abs(p3[1] - 4) < 0.35, p3


def test_simulate_scene_warns_of_a_follower_flying_across_its_gap_at_the_callers_line():
    """A weak follower spring (100 N/m, 0.5 N preload) thrown off the cam at 300 rad/s: the
    library call itself warns (FollowerFlightWarning, attributed to this line), with the
    message ``flight`` returns; the shipped scene (600 rpm) does not."""
    from pathlib import Path

    from mechcirc.errors import FollowerFlightWarning
    from mechcirc.scene.simulation import flight

    path = Path(__file__).resolve().parents[2] / "examples" / "cam_jump_scene.toml"
    text = path.read_text(encoding="utf-8")
    weak = text.replace("spring = 5.0e3 ", "spring = 100.0 ").replace("preload = 50.0 ",
                                                                        "preload = 0.5 ")
    assert weak != text
    scene = parse_scene(weak, str(path))
    with pytest.warns(FollowerFlightWarning) as caught:
        sm = simulate_scene(scene, omega=300.0, revolutions=1, error_estimate=False)
    (w,) = [c for c in caught if issubclass(c.category, FollowerFlightWarning)]
    assert w.filename == __file__
    assert str(w.message) == flight(scene, sm) and "left the cam by" in str(w.message)
    with warnings.catch_warnings():
        warnings.simplefilter("error", FollowerFlightWarning)
        simulate_scene(parse_scene(text, str(path)), revolutions=1, error_estimate=False,
                       points=720)


def test_the_default_estimate_on_a_subgrid_after_a_coarse_spin_up_bounds_the_true_error():
    """The sley scene (one-side, variant 3), 3 revolutions, 3600 points (80 a period of the
    fastest mode: the checks compare every 2nd): the estimate's run at 12.5 steps per
    period covers the 3 revolutions, the returned run at 25 the last 2.  Its true error,
    against DOP853 at rtol 1e-10 (about 1e-8 off, docs/sley.md), is within the estimate,
    and the estimate is the change from that coarse run made on its own, compared on
    every 2nd point in time."""
    from mechcirc.scene.simulation import _rel_change
    from mechcirc.sley.scenes import preset_scene

    scene = preset_scene("one-side", 3)
    kw = dict(revolutions=3, points=3600)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        r = simulate_scene(scene, **kw)
        coarse = simulate_scene(scene, steps_per_period=12.5, error_estimate=False, **kw)
        ref = simulate_scene(scene, method="DOP853", rtol=1e-10, error_estimate=False, **kw)
    per_rev = r.steps_per_revolution
    assert coarse.steps_per_revolution == per_rev // 2
    assert r.n_steps == per_rev // 2 * 3 + per_rev * 2
    true = _rel_change(r.extrema, ref.extrema)
    assert 0 < true <= 1e-4 and true <= r.error_estimate <= 1e-3, (true, r.error_estimate)

    def every_2nd(res):
        sub = np.argsort(res.time, kind="stable")[::2]
        return {k: (float(v[sub].min()), float(v[sub].max())) for k, v in res.values.items()
                if k.endswith((".acceleration", ".force", ".deformation", ".moment"))
                and "." in k and k.split(".")[0] not in ("B", "C")}

    change = _rel_change(every_2nd(r), every_2nd(coarse))
    assert abs(change - r.error_estimate) <= 1e-9 * change, (change, r.error_estimate)


def test_output_pass_skips_the_points_functions():
    """The kernel's output pass evaluates the functions of the dynamics and of the bodies
    (``n_out``), not the points' (computed apart): every output is the same as with every
    function evaluated, at perturbed states of a scene whose points have functions of their
    own (the heald scene: 6 of its 34)."""
    from pathlib import Path

    from mechcirc.scene import load_scene
    from mechcirc.scene.motion import motion_model
    from mechcirc.scene.simulation import kernels_for

    ex = Path(__file__).resolve().parents[2] / "examples"
    model = motion_model(load_scene(ex / "heald_scene.toml"))
    a = model.arrays
    assert a["n_dyn"] <= a["n_out"] < a["FI"].shape[0]
    rng = np.random.default_rng(3)
    ts = np.linspace(0.0, 0.05, 40)
    ys = np.array([model.rigid_state(model.omega * t) for t in ts])
    ys *= 1.0 + 1e-3 * rng.standard_normal(ys.shape)
    args = model.kernel_args(0.0, 1e300, outputs=True)
    every = (args[0].copy(), *args[1:])
    every[0][3] = a["FI"].shape[0]
    kern = kernels_for("rk4")[0]
    got, full = (np.empty((model.naux(), ts.size)) for _ in range(2))
    kern.outputs(ts, ys, got, *args)
    kern.outputs(ts, ys, full, *every)
    np.testing.assert_array_equal(got, full)


# The run options of ``simulate_scene`` and of the sley's ``simulate_params`` are checked by
# one function (``check_run``, issue 24): the same rules, each message naming the option as
# its caller's user wrote it (the sley's ``points_per_revolution``, the scene's ``points``),
# in the caller's error class.  Before, the scene took ``revolutions=2.5`` (or ``True``, or
# ``points=720.5``) and int()'d it, and ignored a ``steps_per_period`` given with a scipy
# method; the sley int()'d a non-integer ``points_per_revolution``.

#: (scene keywords, sley keywords, the scene's message, the sley's message)
CASES = [
    (dict(revolutions=2.5), dict(revolutions=2.5),
     "revolutions must be an integer ≥ 1, got 2.5",
     "revolutions must be an integer ≥ 1, got 2.5"),
    (dict(revolutions=True), dict(revolutions=True),
     "revolutions must be an integer ≥ 1, got True",
     "revolutions must be an integer ≥ 1, got True"),
    (dict(revolutions=0), dict(revolutions=0),
     "revolutions must be an integer ≥ 1, got 0", "revolutions must be an integer ≥ 1, got 0"),
    (dict(revolutions=2, revolution=True), dict(revolutions=2, revolution=True),
     "revolution must be an integer in 1..2, got True",
     "revolution must be an integer in 1..2, got True"),
    (dict(revolutions=2, revolution=3), dict(revolutions=2, revolution=3),
     "revolution must be an integer in 1..2, got 3",
     "revolution must be an integer in 1..2, got 3"),
    (dict(points=720.5), dict(points_per_revolution=720.5),
     "points must be an integer ≥ 16, got 720.5",
     "points_per_revolution must be an integer ≥ 16, got 720.5"),
    (dict(points=np.bool_(True)), dict(points_per_revolution=np.bool_(True)),
     "points must be an integer ≥ 16, got ", "points_per_revolution must be an integer ≥ 16"),
    (dict(points=8), dict(points_per_revolution=8),
     "points must be an integer ≥ 16, got 8",
     "points_per_revolution must be an integer ≥ 16, got 8"),
    (dict(method="DOP853", steps_per_period=50), dict(method="DOP853", steps_per_period=50),
     "steps_per_period applies to rk4 and rk8, not DOP853; use rtol",
     "steps_per_period applies to rk4 and rk8, not DOP853; use rtol"),
    (dict(rtol=1e-6), dict(rtol=1e-6),
     "rtol applies to the scipy methods, not rk4; use steps_per_period",
     "rtol applies to the scipy methods, not rk4; use steps_per_period"),
    (dict(method="LSODA", rtol=1.0), dict(method="LSODA", rtol=1.0),
     "rtol must be in [1e-14, 1), got 1.0", "rtol must be in [1e-14, 1), got 1.0"),
    (dict(steps_per_period=0.5), dict(steps_per_period=0.5),
     "steps_per_period must be ≥ 1, got 0.5", "steps_per_period must be ≥ 1, got 0.5"),
    (dict(method="LSODA", rtol="1e-6"), dict(method="LSODA", rtol="1e-6"),
     "rtol must be in [1e-14, 1), got '1e-6'", "rtol must be in [1e-14, 1), got '1e-6'"),
    (dict(steps_per_period="200"), dict(steps_per_period="200"),
     "steps_per_period must be ≥ 1, got '200'", "steps_per_period must be ≥ 1, got '200'"),
    (dict(method="Euler"), dict(method="Euler"),
     "unknown method 'Euler'; choose one of rk4, rk4-python, rk8, DOP853, RK45, LSODA",
     "unknown method 'Euler'; choose one of rk4, rk4-python, rk8, DOP853, RK45, LSODA"),
]


@pytest.mark.parametrize("scene_kw, sley_kw, scene_msg, sley_msg", CASES)
def test_one_rule_two_names(scene_kw, sley_kw, scene_msg, sley_msg, monkeypatch):
    scene = parse_scene(FLYWHEEL, "<flywheel>")
    with pytest.raises(MechcircError) as info:
        simulate_scene(scene, **scene_kw)
    assert str(info.value).startswith(scene_msg)
    assert not isinstance(info.value, ParameterError)       # the scene's class

    def no_model(*args):
        raise AssertionError("the model was built before the options were checked")

    monkeypatch.setattr(sley_simulation, "_model", no_model)
    with pytest.raises(ParameterError) as info:
        simulate_params(preset("one-side", 1), **sley_kw)
    assert str(info.value).startswith(sley_msg)


def test_numpy_integers_still_taken():
    """np.int64 counts (a value from an array) pass the check as ints do."""
    from mechcirc.scene.simulation import check_run

    check_run("rk4", np.int64(3), np.int64(2), np.int64(720), np.float64(25.0), None)
    check_run("DOP853", 3, None, 720, None, np.float32(1e-8), ParameterError,
              "points_per_revolution")


def test_file_steps_per_period_is_not_refused_with_a_scipy_method():
    """The file's ``steps_per_period`` is the fixed-step methods' default: a scipy method
    asked for in the call runs (only a steps_per_period in the call itself is refused)."""
    text = FLYWHEEL.replace("[simulate]\n", "[simulate]\nsteps_per_period = 50\n")
    m = simulate_scene(parse_scene(text, "<flywheel>"), method="RK45", rtol=1e-6,
                       error_estimate=False)
    assert m.method == "RK45" and m.revolution == 3 and m.crank_angle.size == 720


def test_methods_spelt_alike():
    """The sley's public METHODS and the CLI's choices are the scene's, which the check
    uses: one tuple (mechcirc.limits, which ``import mechcirc.sley`` loads without the
    scene package)."""
    from mechcirc import limits
    from mechcirc.cli import sley_commands

    assert sley_simulation.METHODS is METHODS is sley_commands.METHODS is limits.METHODS


def test_the_shipped_sley_scene_is_in_metres():
    """New-user pass, session 28: docs/examples/sley_scene.toml said units = "mm" with its
    coordinates in metres (a 29 µm crank), so B's acceleration came out 0.29 m/s² where
    a 29 mm crank at 100 rad/s has ω² r = 290 m/s² (the crank's speed ripple aside)."""
    from pathlib import Path

    from mechcirc.scene import load_scene

    scene = load_scene(Path(__file__).resolve().parents[2] / "docs/examples/sley_scene.toml")
    with warnings.catch_warnings(action="ignore", category=SceneAccuracyWarning):
        m = simulate_scene(scene, revolutions=1, points=36, error_estimate=False)
    lo, hi = m.extrema["B.acceleration"]
    assert 0.95 * 290.0 < lo <= hi < 1.05 * 290.0, (lo, hi)
