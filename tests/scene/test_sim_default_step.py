"""The default RK4 step of simulate_scene / sley.simulate, chosen for the accuracy goal:
the run at 25 steps per period when its error estimate is within 1e-3, else the run at 50.

The returned run's true error is measured against DOP853 at rtol 1e-12 on the same
equations (the scene right-hand side is checked against the sley's eq. (4) written out
independently in tests/sley/test_simulation.py), never against the code's own estimate.
"""

import warnings

import pytest

import _scene_helpers as helpers
from mechcirc.scene import load_scene
from mechcirc.scene.simulation import ACCURACY_GOAL, _rel_change, simulate_scene
from mechcirc.sley import preset
from mechcirc.sley.simulation import simulate_params

PTS = 720


def test_sley_default_is_the_run_at_25_and_its_estimate_bounds_its_error():
    p = preset("one-side", 3)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")        # 2 revolutions: not yet periodic
        ref = simulate_params(p, 2, "DOP853", rtol=1e-12, points_per_revolution=PTS,
                              error_estimate=False)
        r = simulate_params(p, 2, points_per_revolution=PTS)
        at25 = simulate_params(p, 2, steps_per_period=25, points_per_revolution=PTS)
    true = _rel_change(r.scene_extrema, ref.scene_extrema)
    assert r.scene_extrema == at25.scene_extrema and r.n_steps == at25.n_steps
    assert r.error_estimate == at25.error_estimate
    assert 0 < true <= r.error_estimate <= ACCURACY_GOAL, (true, r.error_estimate)
    assert true <= 1e-4


@pytest.mark.filterwarnings("ignore::mechcirc.errors.SceneAccuracyWarning")
def test_default_takes_twice_the_steps_when_the_estimate_at_25_is_too_large():
    scene = load_scene("examples/fnf_sixbar_scene.toml")   # estimate at 25: ~5e-3
    kw = dict(revolutions=2, points=PTS)
    _, ref = helpers.shipped_and_reference("fnf_sixbar_scene")     # the same run, shared
    at25 = simulate_scene(scene, steps_per_period=25, **kw)
    assert at25.error_estimate > ACCURACY_GOAL
    r = simulate_scene(scene, **kw)
    at50 = simulate_scene(scene, steps_per_period=50, error_estimate=False, **kw)
    assert r.extrema == at50.extrema and r.steps_per_revolution == at50.steps_per_revolution
    assert any("run again at 50" in n for n in r.notes)
    true = _rel_change(r.extrema, ref.extrema)
    assert 0 < true <= r.error_estimate <= ACCURACY_GOAL, (true, r.error_estimate)
    # the estimate is the change from the run at 25 (twice the step)
    assert abs(_rel_change(r.extrema, at25.extrema) - r.error_estimate) <= 1e-12


def test_without_the_estimate_the_default_is_50_steps_per_period():
    scene = load_scene("examples/slider_crank_scene.toml")
    a = simulate_scene(scene, revolutions=1, points=PTS, error_estimate=False)
    b = simulate_scene(scene, revolutions=1, points=PTS, error_estimate=False,
                       steps_per_period=50)
    assert a.extrema == b.extrema and a.n_steps == b.n_steps


@pytest.mark.filterwarnings("ignore::mechcirc.errors.SceneAccuracyWarning")
def test_default_keeps_the_run_at_25_when_50_would_pass_the_step_limit(monkeypatch):
    import mechcirc.scene.simulation as sim

    scene = load_scene("examples/fnf_sixbar_scene.toml")
    kw = dict(revolutions=2, points=PTS)
    at25 = simulate_scene(scene, steps_per_period=25, **kw)
    assert at25.error_estimate > ACCURACY_GOAL
    monkeypatch.setattr(sim, "MAX_STEPS_PER_REV", at25.steps_per_revolution + 10)
    with pytest.warns(sim.SceneAccuracyWarning, match="error estimate"):
        r = simulate_scene(scene, **kw)
    assert r.extrema == at25.extrema and r.error_estimate == at25.error_estimate
    assert r.steps_per_revolution == at25.steps_per_revolution
