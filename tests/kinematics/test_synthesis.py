"""Tests of the patent CN104178888 synthesis.

References: direct four-bar computation (FourBar, checked separately against
finite differences), dense grids, and the law of cosines.
"""

import math

import numpy as np
import pytest

from mechcirc.errors import GeometryError
from mechcirc.kinematics import FourBar
from mechcirc.kinematics.synthesis import (LOAD_CRANK_MM, acceleration_ratio_eq5,
                                           dead_centre_angles,
                                           evaluate_design, solve_eq10, synthesize)


def _random_crank_rockers(n, seed=1):
    rng = np.random.default_rng(seed)
    out = []
    while len(out) < n:
        b, c, d = rng.uniform(1.2, 8.0, 3)
        fb = None
        try:
            fb = FourBar(1.0, b, c, d)
        except GeometryError:
            continue
        if fb.linkage_type == "crank-rocker" and fb.grashof_class == "Grashof":
            out.append(fb)
    return out


def test_eq5_identity_against_direct_dead_centre_accelerations():
    """|Φ1''/Φ2''| = ((b/a+1)/(b/a−1))·sin μ2/sin μ1, first power (patent CN104178888)."""
    for fb in _random_crank_rockers(40):
        front, back = fb.dead_centres()
        direct = abs(front.nu / back.nu)
        mu1, mu2 = dead_centre_angles(fb.coupler, fb.rocker, fb.frame)
        assert acceleration_ratio_eq5(fb.coupler, mu1, mu2) == pytest.approx(direct, rel=1e-9)
    # and not the squared reading the OCR could have meant
    fb = FourBar(1.0, 3.0, 4.5, 5.0)
    front, back = fb.dead_centres()
    mu1, mu2 = dead_centre_angles(3.0, 4.5, 5.0)
    squared = ((3.0 + 1) / (3.0 - 1)) * (math.sin(mu2) / math.sin(mu1)) ** 2
    assert abs(squared - abs(front.nu / back.nu)) > 1e-3


def test_eq1_is_the_interior_angle_at_the_dead_centres():
    for fb in _random_crank_rockers(20, seed=2):
        front, back = fb.dead_centres()
        mu1, mu2 = dead_centre_angles(fb.coupler, fb.rocker, fb.frame)
        assert float(mu1) == pytest.approx(fb.interior_angle(front.theta), abs=1e-9)
        assert float(mu2) == pytest.approx(fb.interior_angle(back.theta), abs=1e-9)


def eq10_residual(psi, b_a, c_a, d_a):
    """Left-hand side of the patent's eq. (10) exactly as it is written:
    (M − P)² + (N − P)² − 2 cos Ψ (M − P)(N − P) + cos² Ψ − 1 with
    M = (b/a − 1)²/(2(c/a)(d/a)), N = (b/a + 1)²/(2(c/a)(d/a)), P = (c² + d²)/(2cd)."""
    two_cd = 2 * c_a * d_a
    M, N, P = (b_a - 1) ** 2 / two_cd, (b_a + 1) ** 2 / two_cd, (c_a ** 2 + d_a ** 2) / two_cd
    cp = math.cos(psi)
    return (M - P) ** 2 + (N - P) ** 2 - 2 * cp * (M - P) * (N - P) + cp * cp - 1


def test_eq10_vanishes_at_the_linkage_swing_and_solves_back():
    for fb in _random_crank_rockers(30, seed=3):
        psi = fb.swing()
        b, c, d = fb.coupler, fb.rocker, fb.frame
        assert eq10_residual(psi, b, c, d) == pytest.approx(0.0, abs=1e-12)
        assert abs(eq10_residual(psi + 0.05, b, c, d)) > 1e-6
        assert any(math.isclose(r, c, rel_tol=1e-9) for r in solve_eq10(psi, b, d_a=d))
        assert any(math.isclose(r, d, rel_tol=1e-9) for r in solve_eq10(psi, b, c_a=c))
        for r in solve_eq10(psi, b, d_a=d):     # every returned root has the asked swing
            assert FourBar(1.0, b, r, d).swing() == pytest.approx(psi, abs=1e-9)


def test_eq10_rejects_roots_of_the_mirror_configuration():
    # quartic roots whose linkage swings across the frame line (α_f + α_b) are dropped
    psi, b, d = math.radians(60.0), 2.0, 3.0
    from mechcirc.kinematics.synthesis import _eq10_roots_squared
    all_roots = [math.sqrt(u) for u in _eq10_roots_squared(psi, b, d) if np.isfinite(u)]
    kept = solve_eq10(psi, b, d_a=d)
    assert len(all_roots) == 2
    for r in all_roots:
        swing = FourBar(1.0, b, r, d).swing()
        assert (r in kept) == math.isclose(swing, psi, abs_tol=1e-9)


def test_solve_eq10_bad_arguments():
    with pytest.raises(GeometryError, match="exactly one"):
        solve_eq10(0.4, 3.0)
    with pytest.raises(GeometryError, match="b/a > 1"):
        solve_eq10(0.4, 0.9, d_a=4.0)


def _independent_check(des, load):
    """Criteria recomputed from FourBar on dense grids and the law of cosines."""
    a, b, c, d = des.a, des.b, des.c, des.d
    fb = FourBar(a, b, c, d)
    th = np.linspace(0, 2 * math.pi, 100001)
    phi4 = fb.rocker_angle(th)
    swing = math.degrees(phi4.max() - phi4.min())
    gamma = fb.evaluate(th).gamma
    front, back = fb.dead_centres()
    cos_front = (c * c + (a + b) ** 2 - d * d) / (2 * c * (a + b))
    g1 = math.degrees(math.acos(abs(cos_front)))
    lo, hi = LOAD_CRANK_MM[load]
    assert lo <= a <= hi
    assert 23 - 1e-6 <= swing <= 26 + 1e-6
    assert g1 > 70
    assert math.degrees(gamma.min()) > 45
    assert abs(back.nu) / abs(front.nu) < 0.3
    assert d < 180
    assert c / a > (b / a) * (360 / swing) / (2 * math.pi)
    assert des.swing_deg == pytest.approx(swing, abs=1e-4)
    assert des.criteria["min_transmission"].value == pytest.approx(
        math.degrees(gamma.min()), abs=1e-6)


@pytest.mark.parametrize("load", ["light", "medium", "heavy"])
def test_synthesize_returns_designs_meeting_every_criterion(load):
    res = synthesize(load, limit=5)
    assert len(res.designs) == 5
    for des in res.designs:
        assert des.feasible
        _independent_check(des, load)
        assert des.binding and set(des.binding) <= set(des.criteria)
    scores = [des.objective for des in res.designs]
    # best (largest margin) first; similar linkages (same ratios) tie to rounding
    assert all(x >= y - 1e-12 for x, y in zip(scores, scores[1:]))
    for des in res.designs:   # the objective is the smallest shape margin
        shape = [des.criteria[n].margin for n in ("front_transmission", "min_transmission",
                                                  "acceleration_ratio", "frame_length",
                                                  "rocker_ratio")]
        assert des.objective == pytest.approx(min(shape))
        assert des.criteria[des.binding[0]].margin == pytest.approx(min(shape))


def test_synthesize_fixed_swing_and_ratio_objective():
    res = synthesize("medium", 24.0, objective="ratio", limit=4)
    assert res.designs
    for des in res.designs:
        _independent_check(des, "medium")
        assert des.swing_deg == pytest.approx(24.0, abs=1e-6)
    ratios = [des.criteria["acceleration_ratio"].value for des in res.designs]
    assert all(x <= y + 1e-12 for x, y in zip(ratios, ratios[1:]))


def test_no_feasible_design_names_the_conflicts():
    res = synthesize("medium", 20.0)
    assert res.designs == ()
    # at Ψ = 20° with a ≥ 35 mm no crank-rocker has d < 180 mm on the grid
    assert ("frame_length",) in res.conflicts and ("swing",) in res.conflicts
    assert "frame_length" in res.message
    res = synthesize("medium", 60.0)
    assert res.designs == ()
    assert ("front_transmission", "acceleration_ratio") in res.conflicts
    res = synthesize("medium", 10.0)
    assert res.designs == () and "no crank-rocker" in res.message


def test_evaluate_design_flags_mrazek():
    # Mrázek's 29/37/188/189 mm: crank too short, swing 17.75° too small, frame too long
    des = evaluate_design(29, 37, 188, 189)
    failed = {n for n, c in des.criteria.items() if not c.passed}
    assert failed >= {"crank_length", "swing", "frame_length"}
    assert des.swing_deg == pytest.approx(17.75, abs=0.01)


def test_bad_load():
    with pytest.raises(GeometryError, match="unknown load"):
        synthesize("enormous")


@pytest.mark.parametrize("kw, message", [
    (dict(objective="speed"), "unknown objective 'speed'; expected one of margin, ratio"),
    (dict(fixed={"link": 100.0}), "unknown fixed length 'link'; expected one of crank, "
                                      "coupler, rocker, frame"),
    (dict(fixed={"crank": -5.0}), "fixed crank length must be a positive number of mm, got -5.0"),
    (dict(fixed={"rocker": float("nan")}), "fixed rocker length must be a positive number"),
    (dict(swing_range=(10.0, 190.0)), "swing range must be 0 < low ≤ high < 180 degrees, got "
                                      "(10.0, 190.0)"),
    (dict(swing=180.0), "swing must be in (0°, 180°), got 180.0°"),
    (dict(b_a_range=(0.5, 3.0)), "b_a_range must be 1 < low ≤ high < 1000, got (0.5, 3.0)"),
    (dict(d_a_range=(2.0,)), "d_a_range must be 1 < low ≤ high < 1000, got (2.0,)"),
    (dict(crank_step=0.0), "step, crank_step and swing_step must be > 0"),
])
def test_bad_synthesis_arguments_are_refused_before_the_search(kw, message):
    """synthesis._checked (run by no test but for the load): each bad argument a
    GeometryError saying what is wrong and what is allowed, raised before any grid."""
    swing = kw.pop("swing", None)
    with pytest.raises(GeometryError) as info:
        synthesize("medium", swing, **kw)
    assert message in str(info.value)


def test_synth_cli_refuses_ranges_it_cannot_search(capsys):
    """`mechcirc synth` with a swing range beyond 180° or b/a below 1: exit 2, one line."""
    from cli_helpers import assert_user_error

    assert_user_error(["synth", "--swing-range", "10:190"], capsys,
                      "swing range must be 0 < low ≤ high < 180 degrees, got (10.0, 190.0)")
    assert_user_error(["synth", "--b-a-range", "0.5:3"], capsys,
                      "b_a_range must be 1 < low ≤ high < 1000, got (0.5, 3.0)")


# ----------------------------------------- refinement, shapes, fixed lengths, export
import itertools as _it


@pytest.fixture(scope="module")
def refined_and_grid():
    return (synthesize("medium", limit=8),
            synthesize("medium", limit=8, refine=False))


def test_refinement_is_never_worse_than_the_grid(refined_and_grid):
    ref, grid = refined_and_grid
    assert ref.refined and not grid.refined
    for des in ref.designs:
        assert des.feasible
        # the reported objective is re-evaluated directly (evaluate_design), not the screen's
        direct = min(des.criteria[n].margin for n in
                     ("front_transmission", "min_transmission", "acceleration_ratio",
                      "frame_length", "rocker_ratio"))
        assert des.objective == pytest.approx(direct, abs=1e-12)
        assert des.objective >= des.grid_objective
    assert ref.designs[0].objective >= grid.designs[0].objective
    # the continuous optimum is measurably better than the grid's best here (5 % or more)
    assert ref.designs[0].objective > 1.05 * grid.designs[0].objective


def test_no_two_designs_have_the_same_shape(refined_and_grid):
    for res in refined_and_grid:
        shapes = [(d.b / d.a, d.c / d.a, d.d / d.a) for d in res.designs]
        for s1, s2 in _it.combinations(shapes, 2):
            assert max(abs(x - y) / y for x, y in zip(s1, s2)) > 1e-3


def test_ratio_objective_refinement_never_worse():
    res = synthesize("light", limit=3, objective="ratio")
    for des in res.designs:
        assert des.feasible and des.objective <= des.grid_objective
        assert des.objective == des.criteria["acceleration_ratio"].value


@pytest.mark.parametrize("fixed", [{"frame": 165.0}, {"coupler": 60.0}, {"rocker": 158.0},
                                   {"crank": 34.2, "frame": 160.0}])
def test_fixed_lengths_are_held(fixed):
    res = synthesize("medium", limit=3, fixed=fixed, swing_range=(24.0, 26.0))
    assert res.designs, res.message
    names = {"crank": "a", "coupler": "b", "rocker": "c", "frame": "d"}
    for des in res.designs:
        assert des.feasible and 24.0 - 1e-9 <= des.swing_deg <= 26.0 + 1e-9
        for name, value in fixed.items():
            assert getattr(des, names[name]) == pytest.approx(value, rel=1e-9)


def test_fixing_rocker_and_frame_is_refused():
    with pytest.raises(GeometryError, match="not both"):
        synthesize("medium", fixed={"rocker": 150.0, "frame": 160.0})


def test_exported_files_load_and_build(tmp_path):
    from mechcirc.kinematics import load_linkage
    from mechcirc.kinematics.synthesis_export import SceneOptions, export_designs
    from mechcirc.scene import build, load_scene

    res = synthesize("heavy", limit=2)
    files = export_designs(res.designs, tmp_path, SceneOptions(omega=80.0, I4P=0.4))
    assert [p.name for pair in files for p in pair] == [
        "design_1.linkage.toml", "design_1.scene.toml",
        "design_2.linkage.toml", "design_2.scene.toml"]
    for des, (lk_path, sc_path) in zip(res.designs, files):
        lk = load_linkage(lk_path)
        fb = des.fourbar()
        for th in (0.3, 2.0, 4.0):
            C = lk.solve(th).points["C"]
            assert math.atan2(C[1], C[0] - fb.frame) == pytest.approx(
                float(fb.rocker_angle(th)), abs=1e-13)          # 9e-16 achieved
        scene = load_scene(sc_path)
        model = build(scene, 1.0)
        # the sley's inertia is reflected through the rocker's velocity ratio μ (closed form)
        assert model.ratios["I4P"] == pytest.approx(float(fb.mu(1.0)), rel=1e-13)  # 1e-15 achieved
        assert "C2" in model.ratios and "C4" in model.ratios


def test_beat_up_moment_is_a_moments_table_and_none_without_one():
    import tomllib

    from mechcirc.kinematics import synthesis_export as E

    des = synthesize("light", limit=1).designs[0]
    doc = tomllib.loads(E.scene_toml(des, 1, E.SceneOptions(M0=-500.0, alpha_deg=10.0)))
    assert doc["moments"] == [{"name": "beatup", "body": "sley", "amplitude": -500.0,
                               "window_deg": 10.0, "centre": "front-dead-centre"}]
    text = E.scene_toml(des, 1, E.SceneOptions(M0=0.0, alpha_deg=10.0))
    assert "moments" not in tomllib.loads(text) and "# No beat-up moment (M0 = 0)" in text


def test_a_grid_too_fine_is_refused_before_it_is_built():
    with pytest.raises(GeometryError, match="too large"):
        synthesize("medium", crank_step=1e-9)


def test_exported_design_simulates_and_cross_checks(tmp_path, capsys):
    """synth --export, simulate, crosscheck: the three commands of docs/kinematics.md."""
    import json

    from mechcirc.cli import main

    assert main(["synth", "--load", "heavy", "--frame", "170", "--swing-range", "24:26",
                 "--limit", "1", "--export", str(tmp_path), "--beat-moment=-500",
                 "--json"]) == 0
    capsys.readouterr()
    scene = tmp_path / "design_1.scene.toml"
    assert main(["simulate", str(scene), "--revolutions", "2", "--json"]) == 0
    sim = json.loads(capsys.readouterr().out)
    lo, hi = sim["extrema"]["beatup.moment"]
    # the half-sine beat-up moment reaches its amplitude (sampled: within 1e-3)
    assert lo == pytest.approx(-500.0, rel=1e-3) and hi == 0.0
    assert main(["crosscheck", str(scene), "--theta", "100", "--json"]) == 0
    cc = json.loads(capsys.readouterr().out)
    assert len(cc["resonances"]) >= 1
    # ringing measured from the motion against the circuit's resonances (2e-4 achieved)
    for r in cc["resonances"]:
        assert abs(r["ringing_omega"] - r["omega"]) / r["omega"] < 2e-3
