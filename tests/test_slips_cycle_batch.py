"""The batched cycle map takes scenes with blocks on fixed guides, the cam-driven heald
frame among them: each batched angle's circuit equals scene.build's there bit for bit,
the cam's dwells are left to build (which refuses them), and the whole map equals the
per-angle reference path exactly."""

from pathlib import Path

import numpy as np
import pytest

import mechcirc.scene.cycle as cy
from mechcirc.scene import build, load_scene

ROOT = Path(__file__).resolve().parents[1] / "examples"


@pytest.mark.parametrize("name, n, dwell", [
    ("cam_heald_scene.toml", 36, [(120, 180), (300, 360)]),   # rise 120, dwell 60, return 120
    ("slider_crank_scene.toml", 24, []),
])
def test_batched_angles_equal_build(name, n, dwell):
    scene = load_scene(ROOT / name)
    theta = np.linspace(0.0, scene.cycle, n, endpoint=False)
    motion = scene.linkage.motion(theta)
    (ds, where), alone = cy._cycle_designs(scene, motion, "eta")
    deg = np.degrees(theta)
    at_rest = [i for i in range(n) if any(a - 1e-9 <= deg[i] <= b for a, b in dwell) or
               (dwell and deg[i] == 0)]
    assert list(alone) == at_rest and sorted(where.tolist() + at_rest) == list(range(n))
    states = motion.states()
    for d, i in enumerate(where):
        c = build(scene, theta[i], state=states[i]).circuit
        assert [e.name for e in c.elements] == [e.name for e in ds.circuit.elements]
        assert np.array_equal(ds.eta[:, d], [e.eta for e in c.elements])
        assert np.array_equal(ds.values[:, d], [e.value for e in c.elements])


def test_cam_cycle_map_equals_the_per_angle_path(monkeypatch):
    scene = load_scene(ROOT / "cam_heald_scene.toml")
    batched = cy.cycle_map(scene, points=36, harmonics=3)
    monkeypatch.setattr(cy, "_BATCHED", False)
    ref = cy.cycle_map(scene, points=36, harmonics=3)
    assert batched.skipped == ref.skipped and len(ref.skipped) == 14
    assert np.array_equal(batched.Q0, ref.Q0, equal_nan=True)
    for a, b in zip(batched.resonances + batched.antiresonances,
                    ref.resonances + ref.antiresonances):
        assert [(r.omega, r.zeta) for r in a] == [(r.omega, r.zeta) for r in b]
