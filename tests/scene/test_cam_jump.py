"""A cam scene whose contact can open (``[cam] contact``: follower jump) against references
written here independently of the scene code.

* The jump speed: the speed at which the simulated least contact force reaches 0
  (:func:`scene_jump_speed`, a stiff contact of 1e11 N/m, bracketed, then a secant in Ω²)
  against the closed form of a rigid follower, min over θ of sqrt((F₀ + k s)/(−m s″))
  (``transient.follower.jump_speed``, itself tested against the law written out by
  hand): 8.1e-5 below it at 100 RK4 steps per period (the step's error near N = 0).
* Above the jump (800 rpm, a contact of 1e8 N/m, damping ratio 0.5): the follower's
  own equation m ÿ = N − F₀ − k y, N the contact's push k_c c + d_c ċ on its squeeze
  c = s + F₀/k_c − y > 0 (the damping part at most the spring part, never pulling:
  the ElastoBacklash law written out), with the cycloidal lift s(θ) written out here,
  integrated by scipy's DOP853 (rtol 1e-12, atol 1e-15): the follower's travel over
  the turn ≤ 1e-8 m (6.7e-9 at 400 RK4 steps per period of the contact), and the
  angle at which the contact first opens, to a sample.
* Bad input (negative preload, spring 0, a contact that is not an [[elastic]] link)
  is refused at its key, exit 2 from the CLI.
"""

import json
import math
from pathlib import Path

import numpy as np
import pytest
from mechcirc.errors import MechcircError, NetlistError
from mechcirc.motion_laws import cam_cycle
from mechcirc.scene import parse_scene, simulate_scene
from mechcirc.scene.jump import contact_report, scene_jump_speed
from mechcirc.transient.follower import jump_speed
from scipy.integrate import solve_ivp

from cli_helpers import assert_user_error, run
from reference.cam_lift import cycloidal_cycle

ROOT = Path(__file__).resolve().parents[2]
EXAMPLE = ROOT / "examples" / "cam_jump_scene.toml"
TEXT = EXAMPLE.read_text(encoding="utf-8")
M, K, F0, H = 0.5, 5e3, 50.0, 0.020
RISE, DWELL, RET = (math.radians(d) for d in (100.0, 80.0, 80.0))


def scene(text=TEXT):
    return parse_scene(text, str(EXAMPLE))


def lift(theta):
    """s, s', s'' of the cycloidal rise 100°, dwell 80°, return 80°, dwell (by hand)."""
    th = np.mod(np.atleast_1d(np.asarray(theta, dtype=float)), 2 * math.pi)
    s, s1, s2 = (np.zeros_like(th) for _ in range(3))
    for lo, beta, sign in ((0.0, RISE, 1.0), (RISE + DWELL, RET, -1.0)):
        on = (th >= lo) & (th < lo + beta)
        u = (th[on] - lo) / beta
        s[on] = H * (u - np.sin(2 * np.pi * u) / (2 * np.pi)) if sign > 0 else \
            H * (1 - u + np.sin(2 * np.pi * u) / (2 * np.pi))
        s1[on] = sign * H / beta * (1 - np.cos(2 * np.pi * u))
        s2[on] = sign * 2 * np.pi * H / beta ** 2 * np.sin(2 * np.pi * u)
    s[(th >= RISE) & (th < RISE + DWELL)] = H
    return s, s1, s2


def test_closed_form_jump_speed_by_hand():
    """The closed form used below against a fine grid of the hand-written law."""
    th = np.linspace(0, 2 * math.pi, 2_000_001)
    s, _, s2 = lift(th)
    neg = s2 < 0
    w = math.sqrt(np.min((F0 + K * s[neg]) / (-M * s2[neg])))
    rpm, _ = jump_speed(cam_cycle("cycloidal", 100, 80, 80, H), M, K, F0)
    assert abs(rpm / (w * 30 / math.pi) - 1) <= 1e-9


@pytest.mark.slow
def test_jump_speed_of_the_scene_against_the_closed_form():
    """The search brackets the jump from the scene's 600 rpm (steps of 5 %) without the
    closed form, then runs the secant in Omega^2 on the side where the contact holds
    (5 one-turn runs).  Measured: 1.08e-7 below the closed form at 100 steps per period
    (1.04e-7 at 200); the goal is 1e-6."""
    rpm, angle = jump_speed(cam_cycle("cycloidal", 100, 80, 80, H), M, K, F0)
    w = rpm * math.pi / 30
    got = scene_jump_speed(scene(), steps_per_period=100)
    assert abs(got.omega / w - 1) <= 1e-6, got             # measured -1.08e-7
    lo, hi = got.bracket
    assert lo < got.omega < hi and got.least[0] > 0 >= got.least[1], got
    assert got.runs <= 12, got


@pytest.mark.parametrize("bracket, kw, needle", [
    ((70.0, 60.0), {}, "does not hold the jump"),
    (None, {"rtol": 0.0}, "rtol = 0.0 must be"),
    (None, {"grow": 1.0}, "grow = 1.0 > 1"),
])
def test_a_bad_jump_search_is_refused(bracket, kw, needle):
    with pytest.raises(MechcircError, match=needle):
        scene_jump_speed(scene(), bracket, **kw)


def _lift1(th):
    """s, s' of the same law at one angle (scalar, for the reference's right-hand side)."""
    return cycloidal_cycle(th, H, RISE, DWELL, RET)


def _reference(omega, kc, dc, t):
    """The follower's own equation by DOP853: the contact pushes k_c c + d_c ċ (c its
    squeeze s + F0/k_c − y), its damping part at most its spring part, never pulling."""
    def push(t, y):
        s, s1 = _lift1(omega * t)
        c, cdot = s + F0 / kc - y[0], omega * s1 - y[1]
        if c <= 0:
            return 0.0
        fc, fd = kc * c, dc * cdot
        return 0.0 if fc + fd <= 0 else fc + min(fc, fd)

    def rhs(t, y):
        return [y[1], (push(t, y) - F0 - K * y[0]) / M]

    r = solve_ivp(rhs, (0.0, t[-1]), [0.0, 0.0], method="DOP853", rtol=1e-12, atol=1e-15,
                  t_eval=t)
    assert r.success
    return r.y[0], np.array([push(a, b) for a, b in zip(t, r.y.T)])


def test_follower_flies_as_its_own_equation_says():
    kc, rpm = 1e8, 800.0
    dc = 2 * 0.5 * math.sqrt(kc * M)                     # damping ratio 0.5
    text = TEXT.replace("stiffness = 1.0e11", f"stiffness = {kc!r}").replace(
        "damping = 2.236e5", f"damping = {dc!r}")
    sc = scene(text)
    w = rpm * math.pi / 30
    sm = simulate_scene(sc, omega=w, revolutions=1, error_estimate=False,
                        steps_per_period=400, points=3600)
    rep = contact_report(sc, sm)
    t = sm.crank_angle / w
    ref, push = _reference(w, kc, dc, t)
    assert np.max(np.abs(rep.travel - ref)) <= 1e-8             # measured 6.7e-9
    assert rep.min_contact < 0 and len(rep.separations) >= 1
    # the first opening: where the reference's push first falls to 0, to a sample
    first = np.degrees(w * t[np.argmax(push <= 0)])
    assert abs(rep.separations[0][0] - first) <= 360.0 / t.size + 1e-9


@pytest.mark.parametrize("old, new, needles", [
    ("preload = 50.0 ", "preload = -5.0 ", ["preload", "-5", ":57:"]),
    ("spring = 5.0e3 ", "spring = 0.0 ", ["spring", "> 0", ":56:"]),
    ('contact = "contact" ', 'contact = "nope" ', ["'nope'", "not an [[elastic]]",
                                                    "one of contact"]),
])
def test_bad_contact_input_is_located(tmp_path, capsys, old, new, needles):
    assert old in TEXT
    bad = tmp_path / "bad.toml"
    bad.write_text(TEXT.replace(old, new), encoding="utf-8")
    with pytest.raises(NetlistError):
        scene(TEXT.replace(old, new))
    assert_user_error(["simulate", str(bad)], capsys, "bad.toml:", *needles)


def test_keys_of_the_spring_need_a_contact():
    with pytest.raises(NetlistError, match="contact"):
        scene(TEXT.replace('contact = "contact" ', "#"))


def test_the_cli_prints_the_contact_report(capsys):
    """``mechcirc simulate`` of a cam scene whose follower can jump: the contact report
    (text and --json) holds what :func:`contact_report` gives for the same run."""
    w = 800 * math.pi / 30
    argv = ["simulate", EXAMPLE, "--omega", repr(w), "--revolutions", "1",
            "--no-error-estimate", "--json"]
    status, out, err = run(argv, capsys)
    assert status == 0, err
    doc = json.loads(out)["cam_contact"]
    sc = scene()
    rep = contact_report(sc, simulate_scene(sc, omega=w, revolutions=1, error_estimate=False))
    assert doc["min_contact_N"] == pytest.approx(rep.min_contact, rel=1e-12)
    assert [tuple(s.values()) for s in doc["separations"]] == list(rep.separations)
    assert doc["travel"] == pytest.approx([rep.travel.min() * 1e3, rep.travel.max() * 1e3],
                                          rel=1e-12, abs=1e-12)
    assert doc["min_contact_N"] < 0 and len(doc["separations"]) >= 1
    status, out, err = run(argv[:-1], capsys)
    assert status == 0, err
    a, d = rep.separations[0]
    assert f"least contact force {rep.min_contact:.6g} N" in out
    assert f"opens at {a:7.2f}° for {d:6.2f}°" in out


def test_a_follower_flying_across_the_whole_gap_is_warned_with_the_value(tmp_path, capsys):
    """A weak spring (100 N/m, 0.5 N preload: the model's gap 2 × (20 + 5) = 50 mm) at
    300 rad/s: the follower is thrown off the rise far beyond the gap.  The warning names
    its largest departure from the cam, checked against the follower's travel minus the
    cycloidal lift written out here (to the 6 digits shown)."""
    text = TEXT.replace("spring = 5.0e3 ", "spring = 100.0 ").replace(
        "preload = 50.0 ", "preload = 0.5 ")
    f = tmp_path / "weak.toml"
    f.write_text(text, encoding="utf-8")
    status, out, err = run(["simulate", f, "--omega", "300", "--revolutions", "1",
                            "--no-error-estimate"], capsys)
    assert status == 0, err
    assert "cam contact: no report" in out
    (msg,) = [line for line in err.splitlines() if "left the cam" in line]
    assert msg.startswith("warning: "), err          # the CLI's own warning line, once
    assert "more than the model's gap 50 mm" in msg and "far flank" in msg, msg
    sc = parse_scene(text, str(f))
    sm = simulate_scene(sc, omega=300.0, revolutions=1, error_estimate=False)
    y = -sm.values["follower_spring.deformation"] - 0.5 / 100.0     # its rise [m]
    away = y - lift(sm.crank_angle)[0]
    e = sm.values["contact.deformation"]
    k = int(np.argmax(e))
    assert f"left the cam by {away[k] * 1e3:.6g} mm" in msg, (msg, away[k])
    with pytest.raises(MechcircError, match="more than the model's gap"):
        contact_report(sc, sm)
