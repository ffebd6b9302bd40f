"""A call does not change the objects it is given: the pickle of a circuit, a linkage or
a scene is the same bytes before and after each analysis run on it.  Memos (a circuit's
reduction tree and state-space model, a linkage's solver plan, a motor's table) stay on
the object but are never pickled (:class:`mechcirc._memo.Memos`); no field changes."""

import math
import pickle
from pathlib import Path

import numpy as np
import pytest

import mechcirc
from mechcirc import scene as S
from mechcirc.kinematics import load_linkage
from mechcirc.periodic import periodic
from mechcirc.scene.shaft import simulate_shaft
from mechcirc.transient import crosscheck, transient
from reference.inputs import STB

ROOT = Path(__file__).resolve().parents[1]
OMEGA = np.geomspace(10.0, 1e4, 40)

CASES = {
    "sweep": (STB, lambda c: c.sweep(OMEGA)),
    "sweep nodal": (STB, lambda c: c.sweep(OMEGA, method="nodal")),
    "resonances": (STB, lambda c: c.resonances()),
    "modes": (STB, lambda c: c.modes()),
    "formula": (STB, lambda c: c.formula()),
    "designs": (STB, lambda c: mechcirc.designs(c, {"eta1": [0.7, 0.8]}).sweep(OMEGA)),
    "transient": (STB, lambda c: transient(c, 0.02)),
    "transient, clearance": (ROOT / "examples" / "msl_backlash.mcir",
                             lambda c: transient(c, 0.02)),
    "periodic": (ROOT / "docs" / "examples" / "cam_drive.mcir",
                 lambda c: periodic(c, 600.0, harmonics=20)),
    "crosscheck": (STB, lambda c: crosscheck(c)),
}


@pytest.mark.parametrize("case", sorted(CASES))
def test_a_parsed_circuit_is_unchanged_by_its_analyses(case):
    path, call = CASES[case]
    c = mechcirc.load(path)
    before = pickle.dumps(c)
    call(c)
    assert pickle.dumps(c) == before
    # and the memos it keeps give the same answer as a fresh copy's
    fresh = pickle.loads(before)
    np.testing.assert_array_equal(c.sweep(OMEGA[:5]).K, fresh.sweep(OMEGA[:5]).K)


def test_a_linkage_is_unchanged_by_its_motion():
    lk = load_linkage(ROOT / "examples" / "fnf_sixbar.toml")
    before = pickle.dumps(lk)
    m = lk.motion(np.radians([0.0, 10.0, 20.0]))
    assert pickle.dumps(lk) == before
    np.testing.assert_array_equal(pickle.loads(before).motion(np.radians([0.0, 10.0, 20.0])).q,
                                  m.q)


@pytest.mark.parametrize("name", ["heald_scene.toml", "cam_heald_scene.toml"])
def test_a_scene_is_unchanged_by_build_and_simulation(name):
    sc = S.load_scene(ROOT / "examples" / name)
    before = pickle.dumps(sc)
    S.build(sc, math.radians(40.0))
    S.simulate_scene(sc, revolutions=1, error_estimate=False)
    assert pickle.dumps(sc) == before


def test_a_scene_with_a_shaft_is_unchanged_by_simulate_shaft():
    sc = S.load_scene(ROOT / "examples" / "fnf_sixbar_scene.toml")    # a [shaft] with a motor
    before = pickle.dumps(sc)
    simulate_shaft(sc, startup=False, points=90)
    assert pickle.dumps(sc) == before
