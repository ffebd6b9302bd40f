"""Results shown in a notebook (issue 26): a result's repr is a summary, each array as its
shape, not the thousands of numbers it holds (on main PeriodicResult printed 96,880
characters, CamProfile 138,338, FrameLoading 49,856, SweepSensitivity 44,706, a Motion
read from a table 67,135)."""

from pathlib import Path

import numpy as np
import pytest

import mechcirc
from mechcirc.kinematics import FourBar, cam_profile, frame_loading
from mechcirc.modes import modes, sweep_sensitivity
from mechcirc.motion_laws import cam_cycle, read_motion_table
from mechcirc.periodic import periodic, speed_map
from mechcirc.sley import linearise, preset

HEALD = Path(__file__).resolve().parents[1] / "netlists" / "heald_damped.mcir"


def _results():
    c = mechcirc.load(HEALD)
    ds = mechcirc.designs(HEALD.read_text(), {"eta1": np.linspace(0.7, 0.9, 40)})
    fb = FourBar(35, 62.8, 170.1, 170.65)
    return {
        "PeriodicResult": (periodic(c, 600), "angle_deg=<array 360>"),
        "SpeedMap": (speed_map(c, 300, 900, 30), "rpm=<array 30>"),
        "SweepSensitivity": (sweep_sensitivity(c, np.linspace(1, 2000, 300)),
                             "omega=<array 300>"),
        "Mode": (modes(c)[0], "resonance=Resonance("),
        "Designs": (ds, "values=<array 18×40>"),
        "DesignSweep": (ds.sweep(np.linspace(1, 2000, 200)), "K=<array 40×200>"),
        "DesignResonances": (ds.resonances(3000), "omega=<array 40×"),
        "DesignExtremes": (ds.extremes([1, 2000]), "K_max=<array 40>"),
        "CamProfile": (cam_profile(cam_cycle("cycloidal", 100, 80, 80, 0.02), 40.0,
                                   roller_radius=10.0), "lift=<array 721>"),
        "FrameLoading": (frame_loading(fb, np.linspace(0, 6.28, 361), 20.0),
                         "F_A=<array 361×2>"),
        "LinearModel": (linearise(preset(), 0.3), "M=<array 2×2>"),
        # a motion read from a table: 67,135 characters of coefficients on main
        "Motion": (read_motion_table(HEALD.parents[1] / "docs" / "examples" / "lift.csv"),
                   "poly=<tuple of 360>"),
    }


@pytest.fixture(scope="module")
def results():
    return _results()


@pytest.mark.parametrize("name", ["PeriodicResult", "SpeedMap", "SweepSensitivity", "Mode",
                                  "Designs", "DesignSweep", "DesignResonances",
                                  "DesignExtremes", "CamProfile", "FrameLoading",
                                  "LinearModel", "Motion"])
def test_repr_is_a_short_summary_with_array_shapes(results, name):
    result, shown = results[name]
    text = repr(result)
    assert text.startswith(f"{name}(") and shown in text
    assert len(text) < 700 and "\n" not in text      # one line, no array dumped


def test_modes_show_as_the_table_of_their_roots():
    # on main: a list of Mode dataclass reprs, 3,360 characters for the heald's six roots
    c = mechcirc.load(HEALD)
    found = modes(c)
    assert repr(found) == repr(c.resonances())
    assert found._repr_html_() == c.resonances()._repr_html_()
    assert isinstance(found, list) and found[0].resonance == c.resonances()[0]


def test_a_crosscheck_shows_its_verdict_first():
    """A cross-check's repr opens with the verdict line the CLI prints last, so a notebook
    shows whether the domains agree (the summary repr alone hid it among the rows)."""
    from mechcirc.scene.crosscheck import SceneCrosscheck
    from mechcirc.transient import CrossCheck
    from mechcirc.verdict import judge

    rows = [judge({"omega": 10.0}, 1e-12, 1e-9), judge({"omega": 20.0}, 0.5, 1e-9),
            judge({"omega": 30.0}, None, 1e-9, "no ringing")]
    for result in (SceneCrosscheck("x.toml", 40.0, rows[:2], forced=rows[2:]),
                   CrossCheck("net", "velocity", rows[:1], rows[1:])):
        first, rest = repr(result).split("\n")
        assert first == ("verdict: DISAGREES — 1 of 3 checks agree, 1 disagree beyond their "
                         "tolerance, 1 cannot be measured")
        assert rest.startswith(type(result).__name__ + "(") and len(rest) < 600
