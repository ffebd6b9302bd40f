"""The --cycle map (issue 7 §3) against the sley's own linear model and rebuilt crossings."""

import math
from pathlib import Path

import numpy as np
import pytest

import _scene_helpers as helpers
from mechcirc.scene import build, load_scene, parse_scene
from mechcirc.scene.cycle import cycle_map

ROOT = Path(__file__).resolve().parents[2]


def test_sley_cycle_matches_the_linearised_sley_model():
    from mechcirc.sley import eigenfrequencies, linearise, preset

    p = preset("one-side", 3)
    theta_pose = 0.5
    scene = parse_scene(helpers.sley_scene_text(p, theta_pose))
    cmap = cycle_map(scene, points=8, harmonics=3)
    assert not cmap.skipped
    assert cmap.omega_shaft == p.omega
    for i, th in enumerate(cmap.theta):
        modes = eigenfrequencies(p, theta_pose + th)
        ours = sorted(r.omega for r in cmap.resonances[i])
        ref = sorted(abs(m.eigenvalue) for m in modes)
        assert ours[:len(ref)] == pytest.approx(ref, rel=1e-8)
        w = cmap.harmonics * p.omega
        Q_ref = linearise(p, theta_pose + th).drive_moment(w) * p.omega   # V0 = ω [rad/s]
        np.testing.assert_allclose(cmap.Q0[i], Q_ref, rtol=1e-8)


def test_heald_crossings_are_where_a_resonance_meets_a_harmonic():
    scene = load_scene(ROOT / "examples" / "heald_scene.toml")
    cmap = cycle_map(scene, points=24, harmonics=8)
    cross = cmap.crossings()
    assert cross, "the illustrative scene is built so its first resonance meets 6·Ω"
    for c in cross:
        model = build(scene, math.radians(c["theta_deg"]))
        lowest = min(r.omega for r in model.circuit.resonances()
                     if r.kind == "resonance" and r.zeta < 1)
        # linear interpolation between grid points 15° apart: within 0.5 %
        assert lowest == pytest.approx(c["harmonic"] * cmap.omega_shaft, rel=5e-3)
    # away from every crossing the first resonance stays on one side of each harmonic
    W = cmap.natural_frequencies()[:, 0]
    for h in cmap.harmonics:
        sign = np.sign(W - h * cmap.omega_shaft)
        changes = int(np.count_nonzero(sign != np.roll(sign, 1)))
        assert changes == sum(1 for c in cross if c["harmonic"] == h and c["mode"] == 0)


def test_cycle_through_a_dead_centre_skips_it_and_says_why():
    from mechcirc.sley import preset

    p = preset("one-side", 1)
    front = p.fourbar().dead_centres()[0].theta
    scene = parse_scene(helpers.sley_scene_text(p, front))     # θ = 0 is a dead centre
    cmap = cycle_map(scene, points=6, harmonics=2)
    assert list(cmap.skipped) == [0]
    assert "dead centre" in cmap.skipped[0]
    assert np.all(np.isnan(cmap.Q0[0])) and np.all(np.isfinite(cmap.Q0[1:]))
    assert cmap.resonances[0] == () and all(cmap.resonances[1:])


def test_cycle_arguments_are_checked():
    scene = load_scene(ROOT / "examples" / "heald_scene.toml")
    with pytest.raises(ValueError, match="points"):
        cycle_map(scene, points=1)
    with pytest.raises(ValueError, match="harmonics"):
        cycle_map(scene, harmonics=0)


def test_cycle_batch_forms_every_angle_as_build_does():
    # The circuits of the batched cycle map (the η of every element at every angle)
    # against scene.build at each angle, on the heald scene (no angle left to build)
    # on the geared FNF six-bar (its rigid gear mesh in the parts' rank check; the
    # cycle two revolutions) and on a sley scene whose θ = 0 is a dead centre (that
    # angle left to build, which refuses it; the others batched).
    from mechcirc.scene.cycle import _cycle_designs
    from mechcirc.sley import preset

    root = ROOT
    p = preset("one-side", 1)
    front = p.fourbar().dead_centres()[0].theta
    scenes = [(load_scene(root / "examples" / "heald_scene.toml"), 72, []),
              (load_scene(root / "examples" / "fnf_sixbar_scene.toml"), 24, []),
              (parse_scene(helpers.sley_scene_text(p, front)), 12, [0])]
    for scene, n, left in scenes:
        theta = np.linspace(0.0, scene.cycle, n, endpoint=False)
        motion = scene.linkage.motion(theta)
        (ds, where), alone = _cycle_designs(scene, motion, "eta")
        assert list(alone) == left and sorted(where.tolist() + left) == list(range(n))
        states = motion.states()
        for d, i in enumerate(where):
            c = build(scene, theta[i], state=states[i]).circuit
            assert [e.name for e in c.elements] == [e.name for e in ds.circuit.elements]
            np.testing.assert_allclose(ds.eta[:, d], [e.eta for e in c.elements],
                                       rtol=1e-13, atol=0)
            np.testing.assert_array_equal(ds.values[:, d], [e.value for e in c.elements])

