"""A slider's ``stroke`` is checked wherever the scene is evaluated: at every angle of a
cycle map and at every output sample of a simulation (its elastic motion, not only the
rigid one), with the located error of the linkage (slider, θ, excess; CLI exit 2)."""

import math
import re
import warnings
from pathlib import Path

import numpy as np
import pytest
from cli_helpers import run

from mechcirc.errors import NetlistError
from mechcirc.scene import build, load_scene
from mechcirc.scene.motion import motion_model
from mechcirc.scene.simulation import simulate_scene

SCENE = Path(__file__).resolve().parents[1] / "examples" / "slider_crank_scene.toml"
SIM = {"revolutions": 2, "points": 720, "error_estimate": False}


def with_stroke(tmp_path, stroke, name="sc.toml"):
    text = SCENE.read_text().replace('line = ["G1", "G2"]\n',
                                     f'line = ["G1", "G2"]\nstroke = {stroke}\n')
    path = tmp_path / name
    path.write_text(text)
    return path


def rigid_x(theta):
    """Block C's place along G1→G2 [mm] in closed form: crank 40, rod 150, guide 10 below."""
    return 40 * np.cos(theta) + np.sqrt(150**2 - (40 * np.sin(theta) + 10) ** 2)


def test_rigid_excess_between_the_asked_angles(tmp_path, capsys):
    # C runs over [109.54, 189.74] mm; [130, 200] is left only around θ = 107..250°.
    path = with_stroke(tmp_path, "[130.0, 200.0]")
    th = np.radians([60.0, 300.0])
    assert np.all(rigid_x(th) > 130)
    build(load_scene(path), math.radians(60.0))           # the angle asked: fine
    status, _, err = run(["scene", path, "--theta", "60"], capsys)
    assert status == 0, err
    status, _, err = run(["scene", path, "--cycle", "--points", "8"], capsys)
    assert status == 2 and f"{path}:33:1:" in err and "slider 'block'" in err
    assert "θ = 135°" in err and "beyond the stroke's min 130" in err
    assert "Traceback" not in err
    with pytest.raises(NetlistError, match="slider 'block' leaves its guide"):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            simulate_scene(load_scene(path), **SIM)


def test_elastic_excess_at_an_output_sample(tmp_path, capsys):
    # The rigid maximum 189.7367 (closed form, below) stays inside 189.76; the elastic rod
    # lets the block overshoot it by about 0.1 mm in the simulation.
    theta = np.linspace(0, 2 * math.pi, 200001)
    assert rigid_x(theta).max() < 189.76 - 0.02 and rigid_x(theta).min() > 100
    path = with_stroke(tmp_path, "[100.0, 189.76]")
    status, _, err = run(["scene", path, "--cycle", "--points", "12"], capsys)
    assert status == 0, err                     # the map's angles are rigid: inside
    free = load_scene(SCENE)
    model = motion_model(free)                  # the same kinematics, the stroke aside
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        ref = simulate_scene(free, model=model, **SIM)
        with pytest.raises(NetlistError, match="output sample of the simulation") as exc:
            simulate_scene(load_scene(path), model=model, **SIM)
    msg = str(exc.value)
    assert f"{path}:33:1:" in msg
    # The reported place is the block's simulated travel there (unbounded run, same samples).
    x = 189.666295470958 + ref.states[:, 0] * 1000      # travel [m] from the pose → mm
    first = int(np.argmax(x > 189.76))
    deg, along = (float(v) for v in re.search(r"θ = ([\d.]+)°.* at ([\d.]+) along", msg)
                  .groups())
    assert deg == pytest.approx(math.degrees(ref.crank_angle[first]), abs=1e-3)
    assert along == pytest.approx(x[first], abs=1e-3)
    status, _, err = run(["simulate", path, "--revolutions", "2", "--points", "720",
                          "--no-error-estimate"], capsys)
    assert status == 2 and "output sample of the simulation" in err and "Traceback" not in err
