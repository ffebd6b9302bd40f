"""Rotational quantities in rotary units (issue 26): angular accelerations in rad/s², crank
speeds in rad/s beside rpm, a sweep's DataFrame carrying its units."""

from __future__ import annotations

import math
import warnings
from pathlib import Path

import numpy as np
import pytest

import mechcirc
from cli_helpers import run

REPO = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def sley():
    from mechcirc.sley import simulate

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return simulate("one-side", 4, revolutions=1, points_per_revolution=90,
                        error_estimate=False)


def test_every_angular_acceleration_axis_says_rad_per_s2(sley):
    pytest.importorskip("matplotlib")
    from mechcirc.kinematics import FourBar
    from mechcirc.kinematics.plots import plot_fourbar
    from mechcirc.scene import load_scene
    from mechcirc.scene.plots import plot_motion
    from mechcirc.scene.simulation import simulate_scene
    from mechcirc.sley.plots import plot_result

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        motion = simulate_scene(load_scene(REPO / "examples" / "mrazek_one_side.toml"),
                                revolutions=1, points=90, error_estimate=False)
    figs = {"sley": plot_result(sley), "scene": plot_motion(motion),
            "fourbar": plot_fourbar(FourBar(29, 37, 188, 189), 100.0)}
    labels = {k: [ax.get_ylabel() for ax in f.axes] for k, f in figs.items()}
    assert labels["sley"] == ["crank acceleration [rad/s²]", "sley acceleration [rad/s²]",
                              "driving moment [N·m]"]
    assert labels["scene"][0] == "angular acceleration [rad/s²]"
    assert labels["fourbar"][2] == "ε4T = ν·ω² [rad/s²]"
    title = figs["sley"]._suptitle.get_text()
    assert "ω = 100 rad/s" in title
    texts = [title, *(ax.get_title() for f in figs.values() for ax in f.axes),
             *(t for ts in labels.values() for t in ts)]
    assert not [t for t in texts if "1/s" in t], texts


def test_the_sley_table_gives_rad_per_s2(sley):
    from mechcirc.cli.sley_commands import _table

    rows = _table(sley).splitlines()[1:7]
    units = {ln[:9].strip(): ln[10:17].strip() for ln in rows}
    assert units == {"quantity": "unit", "eps4T": "rad/s^2", "eps2P": "rad/s^2",
                     "eps4P": "rad/s^2", "M2V": "N m", "-M2V*": "N m"}
    assert [ln.split()[-4:] for ln in rows[1:]] == [ln[17:].split() for ln in rows[1:]]


def test_fourbar_takes_rpm_and_prints_rad_per_s_beside_rpm(capsys):
    status, out, err = run(["fourbar", "--crank", "29", "--coupler", "37", "--rocker", "188",
                            "--frame", "189", "--omega", "955 rpm"], capsys)
    assert status == 0, err
    omega = 955 * 2 * math.pi / 60                              # 100.007 rad/s
    line = out.splitlines()[-1]
    assert line.startswith(f"  ε4T = ν·ω² at ω = {omega:g} rad/s (955 rpm): [")
    assert line.endswith("] rad/s²") and out.count("rad/s²") == 3
    assert "1/s²" not in out


def test_linkage_gives_each_cranks_speed_in_rpm_too(capsys):
    status, out, err = run(["linkage", REPO / "examples" / "fnf_sixbar.toml", "--theta", "30"],
                           capsys)
    assert status == 0, err
    rpm = [f"{w * 60 / (2 * math.pi):.6g}" for w in (20, -30)]
    assert f"crank1 (ω = 20 rad/s, {rpm[0]} rpm), crank2 (ω = -30 rad/s, {rpm[1]} rpm)" in out
    assert rpm == ["190.986", "-286.479"]


@pytest.mark.parametrize("text, units", [
    ("drive F a 0 force=2\nmass m a 0 1\nspring k a 0 100\n",
     {"omega": "rad/s", "K": "m/(N·s)", "|K|": "m/(N·s)", "Q0": "N", "|Q0|": "N",
      "v0": "m/s", "|v0|": "m/s", "flag": "", "error": "1"}),
    ("drive W a 0 velocity=1 rad/s\nmass J a 0 0.2 kg*m^2\nspring k a 0 4e3 N*m/rad\n",
     {"omega": "rad/s", "K": "rad/(N·m·s)", "|K|": "rad/(N·m·s)", "Q0": "N·m", "|Q0|": "N·m",
      "flag": "", "error": "1"})])
def test_to_dataframe_carries_the_units_of_its_columns(text, units):
    pytest.importorskip("pandas")
    s = mechcirc.parse(text).sweep(np.array([10.0, 100.0]))
    df = s.to_dataframe()
    assert df.attrs["units"] == units and list(df.columns) == list(units)


def test_a_rotary_stage_behind_a_lever_is_labelled_rotary(capsys):
    """New-user pass, session 28: in docs/examples/units.mcir (a translational drive, a
    lever of 8 rad/m to a rotary stage) check showed J = 4e-05 kg·m² as '4e-05 kg' and
    kt as '12 N/m', and forces and resonances --modes gave J's moment (0.0032 N·m =
    100 · 4e-5 · 0.8, by hand) under '|Q| [N]' and its 0.8 rad/s under '|v| [m/s]'."""
    units = REPO / "docs" / "examples" / "units.mcir"
    c = mechcirc.load(units)
    assert {e.name: c.rotational(e) for e in c.elements} == {
        "m": False, "k": False, "c": False, "J": True, "kt": True}
    status, out, _ = run(["check", units], capsys)
    assert status == 0 and "4e-05 kg·m²" in out and "12 N·m/rad" in out and "0.25 kg" in out
    status, out, _ = run(["forces", units, "--omega", 100], capsys)
    rows = {line.split()[0]: line for line in out.splitlines()[2:]}
    assert rows["J"].split()[2] == "0.0032" and rows["J"].endswith("[N·m, rad/s]")
    assert rows["kt"].endswith("[N·m, rad/s]") and not rows["m"].endswith("]")
    status, out, _ = run(["resonances", units, "--modes"], capsys)
    tables = out.count("zeta part")             # one element table per mode with a shape
    assert tables >= 1 and [line.split()[0] for line in out.splitlines()
                            if line.endswith("[N·m, rad/s]")] == ["J", "kt"] * tables
