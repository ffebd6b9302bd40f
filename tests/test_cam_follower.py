"""Cam drives in the time domain: the motion= drive, the follower on its cam, its jump.

References are independent of the code under test: the periodic steady state
by harmonics (mechcirc.periodic, K(kΩ) of the frequency domain) against time
integration; a closed form of the SDOF under the cycloidal rise and dwell,
derived by hand (particular solutions + homogeneous e^{λt}, 30-digit mpmath;
it agrees with sympy's dsolve of the same equation to 1.4e-16 m); the jump
speed of a rigid follower from the contact force it needs,
N = F₀ + k s + cΩ s' + mΩ² s'' (with k = 0 the textbook Ω*² = F₀/(m max|s''|)).
"""

import json
import math

import mpmath as mp
import numpy as np
import pytest
from cli_helpers import assert_user_error, run

import mechcirc
from mechcirc.motion_laws import cam_cycle
from mechcirc.periodic import periodic
from mechcirc.transient import transient
from mechcirc.transient.follower import follower, follower_circuit, jump_speed

CAM = "drive V T 0 motion=cycloidal rise=120 dwell=60 return=120 stroke=0.05\n"


def cycloidal_sdof(m, C, K, a, b, h, T1, t):
    """y(t) of m y'' + C y' + K y = a s + b s' from rest, s = h (t/T1 − sin(2πt/T1)/2π)
    for t ≤ T1, then s = h (the dwell)."""
    mp.mp.dps = 30
    m, C, K, a, b, h, T1 = (mp.mpf(v) for v in (m, C, K, a, b, h, T1))
    w = 2 * mp.pi / T1
    disc = mp.sqrt(mp.mpc(C * C - 4 * m * K))
    l1, l2 = (-C + disc) / (2 * m), (-C - disc) / (2 * m)
    A1 = a * h / (T1 * K)                           # y_p = A1 t + A0 + Re(Y e^{jwt})
    A0 = (b * h / T1 - C * A1) / K
    Y = (1j * a * h / (2 * mp.pi) - b * h / T1) / (K - m * w * w + 1j * C * w)

    def homog(y0, v0):                              # D1 e^{l1 τ} + D2 e^{l2 τ}
        D2 = (v0 - l1 * y0) / (l2 - l1)
        return y0 - D2, D2

    def yp(t):
        return A1 * t + A0 + (Y * mp.exp(1j * w * t)).real

    def vp(t):
        return A1 + (1j * w * Y * mp.exp(1j * w * t)).real

    D1, D2 = homog(-yp(0), -vp(0))

    def rise(t):
        return yp(t) + (D1 * mp.exp(l1 * t) + D2 * mp.exp(l2 * t)).real

    def rise_v(t):
        return vp(t) + (l1 * D1 * mp.exp(l1 * t) + l2 * D2 * mp.exp(l2 * t)).real

    ys = a * h / K
    E1, E2 = homog(rise(T1) - ys, rise_v(T1))
    out = []
    for x in t:
        x = mp.mpf(float(x))
        if x <= T1:
            out.append(rise(x))
        else:
            out.append(ys + (E1 * mp.exp(l1 * (x - T1)) + E2 * mp.exp(l2 * (x - T1))).real)
    return np.array([float(v) for v in out])


def test_transient_steady_state_of_a_motion_drive_matches_periodic():
    # Time integration from rest (ring-down e^{-67 t}: 1e-17 after 10 turns) vs the
    # harmonic sum through K(kΩ).  Achieved 1.6e-7 of the peak (first-order hold,
    # 14,400 samples per turn; h² convergence: 6.4e-7 at 7,200, 4.0e-8 at 28,800).
    c = mechcirc.parse(CAM + "spring k T a 2e5\nmass m a 0 1.5\ndamper c a 0 200\n")
    p = periodic(c, 600, tol=1e-9, points=720)
    n = 14400
    r = transient(c, 10 * 0.1, 0.1 / n, rpm=600, elements=False)
    last = r.drive_force[-n - 1:-1][::n // 720]
    assert np.abs(last - p.Q).max() <= 1e-6 * p.peak
    assert abs(p.peak - 1095.8) < 0.1                        # it is a real force


def test_sdof_under_cycloidal_rise_and_dwell_matches_closed_form():
    # base excitation: m ÿ + c (ẏ − ṡ) + k (y − s) = 0; achieved 1.7e-10 of the stroke
    c = mechcirc.parse(CAM + "spring k T a 2e5\ndamper c T a 200\nmass m a 0 1.5\n")
    r = transient(c, 0.05, 5e-7, rpm=600, elements=False)       # rise 1/30 s, then dwell
    every = 200
    ya = cycloidal_sdof(1.5, 200, 2e5, 2e5, 200, 0.05, 1 / 30, r.time[::every])
    assert np.abs(r.node("a")[0][::every] - ya).max() <= 1e-8 * 0.05


def test_follower_in_closed_contact_matches_closed_form():
    # through the clearance law (contact held shut by a large preload): m ÿ + (c + d_c) ẏ
    # + (k + k_c) y = k_c s + d_c ṡ about the preloaded rest.  Achieved 2.1e-11 of the stroke.
    m, k, F0, c, kc, dc = 1.5, 2e4, 1e5, 20.0, 2e5, 50.0
    motion = cam_cycle("cycloidal", 120, 60, 120, 0.05)
    r = follower(motion, 600, m, k, F0, c, contact=kc, contact_damping=dc,
                 revolutions=0.5, dt=1e-6)
    assert r.separations == [] and r.contact_force.min() > 0
    every = 500
    ya = cycloidal_sdof(m, c + dc, k + kc, kc, dc, 0.05, 1 / 30, r.transient.time[::every])
    assert np.abs(r.rise[::every] - ya).max() <= 1e-8 * 0.05


def test_jump_speed_minimisation_vs_textbook_closed_form():
    # k = 0, c = 0: Ω*² = F₀ / (m max|s''|), max|s''| = 2π h / β² on the return (β = 80°)
    motion = cam_cycle("cycloidal", 100, 80, 80, 0.02)
    rpm, angle = jump_speed(motion, 0.5, 0.0, 50.0)
    beta = math.radians(80)
    omega = math.sqrt(50.0 / (0.5 * 2 * math.pi * 0.02 / beta ** 2))
    assert rpm == pytest.approx(omega * 60 / (2 * math.pi), rel=1e-12)
    assert angle == pytest.approx(180 + 80 / 4, abs=1e-6)       # peak deceleration


def test_simulated_separation_sets_in_at_the_closed_form_jump_speed():
    # A stiff contact (k_c = 1e11 N/m, ζ = 0.5): the follower stays on the cam at
    # (1 − 1e-6)·rpm* and leaves it at (1 + 1e-6)·rpm*, so the simulated onset is
    # within 1e-6 of the closed form (brentq on the simulation: 1.1e-7 of it, the
    # onset's resolution; 3.4e-9 in an earlier round).
    motion = cam_cycle("cycloidal", 100, 80, 80, 0.02)
    m, k, F0, c, kc = 0.5, 5e3, 50.0, 5.0, 1e11
    dc = 2 * 0.5 * math.sqrt(kc * m)
    rpm, angle = jump_speed(motion, m, k, F0, c)
    below = follower(motion, rpm * (1 - 1e-6), m, k, F0, c, contact=kc, contact_damping=dc,
                     revolutions=0.6)
    above = follower(motion, rpm * (1 + 1e-6), m, k, F0, c, contact=kc, contact_damping=dc,
                     revolutions=0.6)
    assert below.min_contact > 0 and below.separations == []
    assert above.min_contact < 0 and len(above.separations) == 1
    sep = above.separations[0]
    assert sep.angle_deg == pytest.approx(angle, abs=0.1)
    assert below.min_contact_angle_deg == pytest.approx(angle, abs=0.1)


def test_jump_reported_with_angle_duration_and_impact(capsys, tmp_path):
    motion = cam_cycle("cycloidal", 100, 80, 80, 0.02)
    c = follower_circuit(motion, 0.5, 5e3, 50.0, 5.0, contact=1e9, contact_damping=2e4)
    rpm, angle = jump_speed(motion, 0.5, 5e3, 50.0, 5.0)
    r = transient(c, 60 / (1.2 * rpm), 60 / (1.2 * rpm) / 7200, rpm=1.2 * rpm)
    first = r.separations[0]
    assert first.element == "kc" and first.revolution == 0
    assert 170 < first.angle_deg < angle and first.duration_deg > 0   # earlier when faster
    # converged in the output step (the instants are refined between samples):
    # dt/10 moves the angle by 0.0017 deg, the duration by 0.0021 deg and the impact
    # velocity by 4e-5 of it
    fine = transient(c, r.time[-1], (r.time[1] - r.time[0]) / 10, rpm=1.2 * rpm).separations[0]
    assert first.angle_deg == pytest.approx(fine.angle_deg, abs=0.01)
    assert first.duration_deg == pytest.approx(fine.duration_deg, abs=0.01)
    assert first.impact_velocity == pytest.approx(fine.impact_velocity, rel=5e-4)
    assert first.impact_velocity > 0
    assert json.loads(json.dumps(r.to_json(), default=list))["separations"][0]["element"] == "kc"


NETLIST = """# follower on a cycloidal cam
drive cam T 0 motion=cycloidal rise=100 dwell=80 return=80 stroke=0.02
spring kc T f 1e9 backlash=0.06 damping=2e4
mass m f 0 0.5
spring k f 0 5e3
damper c f 0 5
.ic T x=0.04000005
.ic f x=0.01
"""


def test_cli_reports_the_jump(tmp_path, capsys):
    path = tmp_path / "f.mcir"
    path.write_text(NETLIST)
    status, out, err = run(["transient", path, "--t-end", "0.08", "--rpm", "800"], capsys)
    assert status == 0, err
    assert "contact kc: opened" in out and "impact velocity" in out
    # counted from 0 as --json and Separation.revolution count (the text said 1 for 0)
    status, js, err = run(["transient", path, "--t-end", "0.08", "--rpm", "800", "--json"],
                          capsys)
    first = __import__("json").loads(js)["separations"][0]
    assert f"(revolution {first['revolution']})" in out
    status, out, err = run(["transient", path, "--t-end", "0.08", "--rpm", "500"], capsys)
    assert status == 0, err
    assert "contact kc: never opened" in out


def test_a_switch_at_a_steps_start_is_not_cut_over_and_over(tmp_path, capsys, monkeypatch):
    # At 800 rpm the contact kc left the wall with e − b/2 at 1 ulp after a cut (t =
    # 0.0394 s): the edge's root stayed ~4e-9 of each next step ahead, and 53,914 trial
    # steps in a row were cut to 4.3e-14 s (134,396 steps in the CLI's three runs; 26,549
    # since, 33,574 before kinks were located on the continuous extension)
    from mechcirc.transient import simulate

    kern = simulate.kernels()
    steps = []
    dopri_run = kern.dopri_run

    def counted(*args):
        steps.append(dopri_run(*args))
        return steps[-1]

    monkeypatch.setattr(simulate, "kernels", lambda: kern)
    monkeypatch.setattr(kern, "dopri_run", counted)
    path = tmp_path / "f.mcir"
    path.write_text(NETLIST)
    status, out, err = run(["transient", path, "--t-end", "0.075", "--rpm", "800"], capsys)
    assert status == 0, err
    assert len(steps) == 3 and 0 < sum(steps) <= 40_000, steps


def test_bad_cam_input_is_a_located_user_error(tmp_path, capsys):
    path = tmp_path / "f.mcir"
    path.write_text(NETLIST)
    assert_user_error(["transient", path, "--t-end", "0.08"], capsys,
                      f"{path}:2:1:", "no shaft speed", "--rpm")
    big = tmp_path / "big.mcir"
    big.write_text(NETLIST.replace("stroke=0.02", "stroke=1e308"))
    col = NETLIST.splitlines()[1].index("stroke=") + len("stroke=") + 1    # at the value
    for argv in (["periodic", big, "--rpm", "600"],
                 ["periodic", big, "--rpm", "600", "--plot", tmp_path / "p.png"],
                 ["transient", big, "--t-end", "0.08", "--rpm", "600"]):
        assert_user_error(argv, capsys, f"{big}:2:{col}:", "<= 1e+100")
    assert not (tmp_path / "p.png").exists()
    over = tmp_path / "over.mcir"
    over.write_text(NETLIST.replace("dwell=80", "dwell=200"))
    assert_user_error(["transient", over, "--t-end", "0.08", "--rpm", "600"], capsys,
                      f"{over}:2:", "more than one revolution")
    lin = tmp_path / "lin.mcir"
    lin.write_text("drive F a 0 force=1\nmass m a 0 1\nspring k a 0 1\n")
    assert_user_error(["transient", lin, "--t-end", "1", "--rpm", "600"], capsys,
                      "--rpm", "has none")


def test_example_prints_the_jump_speed_both_ways(capsys, monkeypatch):
    import re
    from pathlib import Path

    from cli_helpers import run_script

    repo = Path(__file__).resolve().parents[1]
    status, out, err = run_script(repo / "examples" / "cam_follower_jump.py", [], capsys,
                                  monkeypatch)
    assert status == 0 and err == "", err
    closed = float(re.search(r"closed form \(rigid follower\): (\S+) rpm", out).group(1))
    simulated = float(re.search(r"simulated onset of separation: (\S+) rpm", out).group(1))
    # The example's bracket is ±0.01 % about the closed form (9 runs, 0.5 s; ±0.1 % took
    # 29 runs, 3.6 s): a simulated onset outside it fails the example's bracket check,
    # one inside must still be within 1e-6 of the closed form.
    assert abs(simulated / closed - 1) <= 1e-6                 # achieved 5.7e-8
    assert re.search(r"at 800 rpm the contact opens [1-9]\d* time", out)


def test_a_table_beyond_the_lift_bound_is_located(tmp_path, capsys):
    rows = ["angle_deg,displacement"] + [f"{a},0.0" for a in range(0, 361, 30)]
    rows[4] = "90,1e200"                                   # finite slopes, beyond 1e100
    (tmp_path / "lift.csv").write_text("\n".join(rows) + "\n")
    net = tmp_path / "t.mcir"
    net.write_text("drive V T 0 motion=lift.csv\nspring k T a 1e5\nmass m a 0 1\n"
                   "damper c a 0 10\n")
    for argv in (["periodic", net, "--rpm", "600"],
                 ["transient", net, "--t-end", "0.1", "--rpm", "600"]):
        assert_user_error(argv, capsys, "lift.csv:5:4:", "beyond the bound 1e+100")


@pytest.mark.parametrize("bad", [dict(spring=-1.0), dict(mass=0.0), dict(preload=-5.0),
                                 dict(damping=math.nan), dict(contact=0.0)])
def test_follower_refuses_bad_parameters(bad):
    args = dict(mass=0.5, spring=5e3, preload=50.0, damping=5.0, contact=1e9) | bad
    motion = cam_cycle("cycloidal", 100, 80, 80, 0.02)
    with pytest.raises(mechcirc.MechcircError, match=next(iter(bad))):
        follower_circuit(motion, args["mass"], args["spring"], args["preload"],
                         args["damping"], contact=args["contact"])


def test_ic_on_the_drive_node_sets_where_the_drive_starts():
    c = mechcirc.parse("drive V T 0 velocity=1\nspring k T a 100\nmass m a 0 1\n"
                       ".ic T x=0.1\n.ic a x=0.1\n")
    r = transient(c, 1.0, 1e-2)                  # drive at rest: nothing moves
    assert not any("not attainable" in n for n in r.notes)
    assert np.allclose(r.node("T")[0], 0.1, rtol=0, atol=1e-15)
    assert np.allclose(r.node("a")[0], 0.1, rtol=0, atol=1e-15)
    free = mechcirc.parse("drive V T 0 velocity=1\nspring k T a 100\nmass m a 0 1\n"
                          ".ic a x=0.1\n")
    x = transient(free, 1.0, 1e-2).node("a")[0]   # drive held at 0: a oscillates about 0
    assert np.allclose(x, 0.1 * np.cos(10 * np.arange(101) * 1e-2), rtol=0, atol=1e-12)
