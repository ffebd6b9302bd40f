"""The dynamic main shaft on the scene's one stepper: the 8th-order method against the
independent SymPy derivation, and the kinks inside the shaft's steps located (the order kept
across impacts of a clearance gap)."""


import math
import pickle

import numpy as np
import pytest

from mechcirc.errors import MechcircError
from mechcirc.scene import parse_scene
from mechcirc.scene.shaft import _prepare, simulate_shaft
from reference.located import at, located
from test_shaft_elastic import (CENTRE, EXTRA, L0, R, START, WIN, WS, X_C0, Y_G, reference_cycle,
                                scene, sympy_reference)


@pytest.mark.slow
def test_rk8_steady_cycle_matches_the_sympy_derivation():
    """The elastic slider-crank's steady cycle by rk8 (16 steps per period of the rod's mode,
    420 a cycle) against the SymPy equations integrated by DOP853 at rtol 1e-12 from the
    state the code found, stopping at the moment window's edges (its own error ≤ 3.2e-13 of
    ω_s against rtol 3e-14): the speed and time over the cycle, and that state repeating.
    Over 12 draws of the motion tables' coefficients moved by ±1 ulp at most 3.0e-13 of ω_s
    (speed), 1.1e-14 of the period (time), 4.2e-14 of ω_s (the state's repeat), 9.8e-15 of
    the period (its length); the reference not stopping at the window's edges gave
    0.7e-12 … 2.3e-11 for the speed on the same draws.  Asserted 2e-12, 1e-13, 2e-13, 1e-13
    (≥ 4.8x margins) — RK4 at 100 steps per period (2,625 steps) reaches 1.1e-9 here."""
    rhs, _ = sympy_reference()
    r = simulate_shaft(scene(), points=90, startup=False, method="rk8")
    assert any("RK8" in n for n in r.notes)
    end, x0, Y = reference_cycle(rhs, r)
    assert np.max(np.abs(Y[0] - r.speed)) <= 2e-12 * WS
    assert np.max(np.abs(Y[3] - r.time)) <= 1e-13 * r.period
    assert abs(end[0] - x0[0]) <= 2e-13 * WS
    assert abs(end[3] - r.period) <= 1e-13 * r.period


def gap_scene():
    """The elastic slider-crank with a 2 µm dead zone in the rod (Mrázek's law: the force's
    slope jumps at ±2 µm), crossed four times a cycle."""
    text = open("examples/slider_crank_scene.toml", encoding="utf-8").read().replace(
        "damping = 300.0", 'damping = 300.0\nclearance = 2e-6\nclearance_law = "dead-zone"')
    return parse_scene(text + EXTRA, "slider_crank_gap.toml")


def located_cycle(scene, theta, rigid=False, clearance=0.0, rtol=3e-14):
    """The steady cycle of :func:`simulate_shaft`'s equations (its kernel's right-hand side;
    not its steppers, which are under test) at θ0 + ``theta`` by :func:`located`: the
    integration stops at the moment window's edges (θ = 75°, 165°) and locates the edges of
    the rod's dead zone (|δ| = ``clearance``, δ from the closed-form geometry).  Three cycles
    from the rigid rest at ω_s settle the cycle (the map shrinks a start's error ~1e-6 a
    cycle with the elastic rod, to the noise in one rigid); the fourth is the reference.
    Returns (its [θ̇, t, z] at ``theta`` (rows), the change of θ̇ from its start to its end /
    ω_s)."""
    _, req, eq, *_ = _prepare(scene, None, None, 16, rigid)
    assert eq is req if rigid else eq.Jf == req.Jf == scene.shaft.flywheel
    th0 = math.radians(START)
    key = (pickle.dumps(scene), rigid, clearance, rtol)
    if key not in _CYCLES:
        _CYCLES[key] = _located_cycle(eq, clearance, rtol)
    pieces, repeat = _CYCLES[key]
    return at(pieces, th0 + np.asarray(theta)), repeat


#: located_cycle's cycles so far: (pickled scene, rigid, clearance, rtol) -> (the fourth
#: cycle's steps, its repeat): test_rk8_clearance.py asks for this file's cycle again (at
#: 360 points instead of 90), 0.5 s of CPU each.
_CYCLES: dict = {}


def _located_cycle(eq, clearance, rtol):
    """(the steps of :func:`located_cycle`'s fourth cycle, the change of θ̇ over it / ω_s)."""
    th0 = math.radians(START)
    ends = sorted((math.radians(CENTRE + k * WIN / 2) - th0) % (2 * math.pi) + th0
                  for k in (-1, 1)) + [th0 + 2 * math.pi]
    atol = 1e-3 * rtol * np.array([WS, 2 * math.pi / WS, R, R * WS])[:2 + 2 * eq.n]

    def f(th, Y):
        out = np.empty(Y.size)
        out[0], out[1] = eq.deriv(th, Y[0], Y[2:], out[2:]), 1.0
        return out / Y[0]

    def side(th, Y):        # the rod's piece of the dead zone: −1, 0, 1
        d = math.hypot(X_C0 + Y[2] - R * math.cos(th), Y_G - R * math.sin(th)) - L0 \
            if clearance else 0.0
        return (d > clearance) - (d < -clearance)

    def cycle(y):
        y, pieces = located(f, th0, y, ends, side, rtol, atol)
        return np.concatenate(([y[0], 0.0], y[2:])), pieces

    x = np.concatenate(([WS, 0.0], eq.rest(th0, 0.0)))
    for _ in range(3):
        x, _ = cycle(x)
    y, pieces = cycle(x)
    return pieces, abs(y[0] - x[0]) / WS


def test_the_kinks_of_a_clearance_are_located_inside_the_shaft_steps():
    """RK4 at 50 and 100 steps per period against :func:`located_cycle` (DOP853 at rtol
    3e-14, the kinks located): the error falls as h⁴ (measured 1.1e-8 → 7.1e-10 of ω_s,
    ×15.3) although each cycle crosses the gap's edges four times and the moment window's
    twice.  Over 16 draws of the motion tables' coefficients moved by ±1 ulp at most 7.1e-10,
    ×15.3 at least, as against the unlocated DOP853 at rtol 1e-12 used before, whose
    error can move by 1.2e-9 with such draws (the same call at 360 samples, one draw in 16,
    test_rk8_clearance); this reference is also cheaper (0.65 s of CPU, that one 1.0-2.0 s).
    A step that straddled a kink unlocated would lose the order there: the same runs (at
    90 samples, in the kernel's Python copy with ``regions`` replaced by one that reports no
    switch) gave 2.0e-7 → 1.0e-7, ×1.9.  Asserted ×12, i.e. order > 3.5, and 2e-9."""
    runs = [simulate_shaft(gap_scene(), points=90, startup=False, method="rk4",
                           steps_per_period=s) for s in (50, 100)]
    ref, _ = located_cycle(gap_scene(), runs[0].theta, clearance=2e-6)
    th = math.radians(START) + runs[0].theta
    d = np.hypot(X_C0 + ref[2] - R * np.cos(th), Y_G - R * np.sin(th)) - L0
    # the rod passes through its gap twice a cycle: four edges crossed (the impacts)
    assert np.sum(np.diff(np.sign(d)) != 0) >= 2
    err = [np.max(np.abs(r.speed - ref[0])) / WS for r in runs]
    assert err[0] / err[1] >= 12.0
    assert err[1] <= 2e-9


@pytest.mark.parametrize("kw, message", [
    (dict(method="rk2"), "method must be 'rk4', 'rk8' or 'DOP853'"),
    (dict(method="rk8", steps_per_period=2), "steps_per_period must be a number ≥ 4"),
    (dict(method="rk8", steps_per_period=True), "steps_per_period must be a number ≥ 4")])
def test_bad_methods_and_steps_are_refused(kw, message):
    with pytest.raises(MechcircError, match=message):
        simulate_shaft(scene(), **kw)


def test_cli_takes_the_method_and_refuses_what_does_not_apply(tmp_path, capsys):
    """`simulate --shaft --method rk8 --steps-per-period N` runs the rk8 stepper (its note);
    a scipy method other than DOP853 and a step count below 4 exit 2 with the reason."""
    import json

    from cli_helpers import assert_user_error, run

    scene = tmp_path / "heald.toml"
    scene.write_text(open("examples/cam_heald_scene.toml", encoding="utf-8").read()
                     + '\n[shaft]\nflywheel = 0.05\nmotor = "kloss"\nsync_speed = 21.0\n'
                     'breakdown_torque = 2.0\nbreakdown_slip = 0.2\n', encoding="utf-8")
    status, out, err = run(["simulate", str(scene), "--shaft", "--method", "rk8",
                            "--steps-per-period", "8", "--points", "90", "--json"], capsys)
    assert status == 0, err
    doc = json.loads(out)
    assert any("RK8 in θ" in n and "8 per period" in n for n in doc["notes"])
    assert 0 < doc["delta"] < 0.1
    assert_user_error(["simulate", str(scene), "--shaft", "--method", "RK45"], capsys,
                      "--method RK45 does not apply to --shaft")
    assert_user_error(["simulate", str(scene), "--shaft", "--method", "rk8",
                       "--steps-per-period", "2"], capsys, "steps_per_period must be a number ≥ 4")


def test_the_default_method_is_rk8_for_the_rigid_and_the_elastic_shaft():
    """Without ``method``: the rigid shaft runs rk8 (16 × 16 = 256 steps a cycle), the
    elastic one rk8 at 16 steps per period (its accuracy: the SymPy test above; across a
    clearance gap: test_rk8_clearance.py).  The rigid default's speed against DOP853 on the
    same equations (those are checked against SymPy in test_shaft.py) with the window's kinks
    at step ends (:func:`located_cycle`, rtol 3e-14): measured 8.2e-12 of ω_s (RK4 at 100
    steps per period, the default before: 4.6e-11); over 16 draws of the motion tables'
    coefficients moved by ±1 ulp at most 1.4e-11, a floor that moves the reference itself by
    1.3e-11 (rk8 moved 5e-16; the unlocated DOP853 at rtol 1e-12 used before moved 2.0e-10
    and gave 1.8e-11 to 2.1e-10).  Asserted at 5e-11 (3.6x margin), the reference's cycle
    repeating to 2e-12 (measured ≤ 4.5e-13)."""
    rigid = simulate_shaft(scene(), points=90, startup=False, rigid=True)
    assert any(n.startswith("steady cycle by shooting (RK8 in θ, 256 steps a cycle")
               for n in simulate_shaft(scene(), points=90, rigid=True).notes)
    ref, repeat = located_cycle(scene(), rigid.theta, rigid=True)
    assert repeat <= 2e-12
    assert np.max(np.abs(rigid.speed - ref[0])) <= 5e-11 * WS
    elastic = simulate_shaft(scene(), points=90, startup=False)
    assert any("RK8 in θ with the elastic parts" in n and "least 16 per period" in n
               for n in elastic.notes)


def test_cli_resolves_the_shaft_default_by_mode(tmp_path, capsys):
    """`simulate --shaft` without --method: rk8 for --rigid and with the elastic rod (the
    notes say which); --rtol with the default fixed-step method exits 2; a scene without
    --shaft keeps RK4 (its result's method)."""
    import json

    from cli_helpers import assert_user_error, run

    path = tmp_path / "crank.toml"
    path.write_text(open("examples/slider_crank_scene.toml", encoding="utf-8").read() + EXTRA,
                    encoding="utf-8")
    base = ["simulate", str(path), "--shaft", "--points", "90", "--json"]
    for extra, needle in (([], "RK8 in θ with the elastic parts"), (["--rigid"], "RK8 in θ")):
        status, out, err = run(base + extra, capsys)
        assert status == 0, err
        assert any(needle in n for n in json.loads(out)["notes"])
    assert_user_error(base + ["--rtol", "1e-8"], capsys, "--rtol applies to the scipy methods",
                      "not the default rk8")
    status, out, err = run(["simulate", str(path), "--revolutions", "1", "--points", "90",
                            "--no-error-estimate", "--json"], capsys)
    assert status == 0, err
    assert json.loads(out)["method"] == "rk4"


def test_a_small_flywheel_is_stepped_stably_and_agrees_with_lsoda(tmp_path, capsys):
    """A rigid slider-crank (2.5 kg block, crank 40 mm, rod 150.0 mm at 10 mm offset) on a
    table motor T = 10 (1 − ω/50) N·m and a flywheel of 1e-5 or 1e-7 kg·m²: near the dead
    centres the shaft's inertia falls to the flywheel's and its speed relaxes within
    J/|T'| = 5e-6 s, too fast for rk8's default 256 steps a cycle (the shaft stalled in
    NaNs, and the code said the 10 N·m motor could not beat the mean load of 0 N·m).  The
    steady cycle against J(θ) θ̈ + m x'x'' θ̇² = T(θ̇), J = J_f + m x'², x(θ) in closed form,
    its cycle map (which contracts within a cycle) iterated by LSODA in θ at rtol 1e-12:
    ω_mean to 1.2e-12 and 2.7e-12 (1e-5, 1e-7) and the speed at every sample to 1.2e-10
    and 6.4e-9 (DOP853's dense output at rtol 1e-10) measured; asserted 1e-10 and 3e-8.  At 1e-7 kg·m² fixed steps would need more
    than 2**16 a cycle, and DOP853 (adaptive) is said to integrate instead."""
    from scipy.integrate import solve_ivp

    text = open("examples/slider_crank_scene.toml", encoding="utf-8").read()
    text = text[:text.index("[[elastic]]")] + text[text.index("[drive]"):] + (
        '\n[shaft]\nflywheel = 0.002\nmotor = "table"\nspeeds = [0.0, 50.0]\n'
        'torques = [10.0, 0.0]\n')
    sc = parse_scene(text)
    r, e, m = 0.04, 0.01, 2.5
    ln = math.hypot(0.189666295470958 - r, e)

    def slopes(th):                         # x'(θ), x''(θ) of the block, by hand
        u, u1, u2 = r * math.sin(th) + e, r * math.cos(th), -r * math.sin(th)
        s = math.sqrt(ln * ln - u * u)
        return (-r * math.sin(th) - u * u1 / s,
                -r * math.cos(th) - (u1 * u1 + u * u2) / s - (u * u1) ** 2 / s ** 3)

    for jf in (1e-5, 1e-7):
        def f(th, y, jf=jf):
            x1, x2 = slopes(th)
            return [(10 * (1 - y[0] / 50) - m * x1 * x2 * y[0] ** 2) / ((jf + m * x1 * x1) * y[0]),
                    1 / y[0]]

        def cycle(w0, dense=False):
            return solve_ivp(f, (0, 2 * math.pi), [w0, 0.0], method="LSODA", rtol=1e-12,
                             atol=1e-12, dense_output=dense)
        w0 = cycle(cycle(50.0).y[0, -1]).y[0, -1]   # the cycle map contracts at once
        sol = cycle(w0, True)
        assert abs(sol.y[0, -1] - w0) <= 1e-10 * w0     # 2.2e-12 measured
        res = simulate_shaft(sc, flywheel=jf, startup=False, points=90)
        assert any("fixed steps would need over" in n for n in res.notes) == (jf < 1e-6)
        assert abs(2 * math.pi / sol.y[1, -1] / res.omega_mean - 1) <= 1e-10
        assert np.max(np.abs(sol.sol(res.theta)[0] / res.speed - 1)) <= 3e-8
    # the command line's table: no load, so 0, not "-0" (and the refusal printed "peak -0")
    from cli_helpers import run

    path = tmp_path / "rigid.toml"
    path.write_text(text, encoding="utf-8")
    status, out, err = run(["simulate", str(path), "--shaft", "--flywheel", "1e-5",
                            "--points", "16"], capsys)
    assert status == 0, err
    assert next(ln for ln in out.splitlines() if ln.startswith("load_torque")).split()[1:3] \
        == ["0", "0"]
