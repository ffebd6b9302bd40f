"""Units in the scene tables of ``mechcirc simulate`` (with and without ``--shaft``)."""

from __future__ import annotations

from pathlib import Path

import pytest

from mechcirc.scene import load_scene
from mechcirc.scene.simulation import output_units

ROOT = Path(__file__).resolve().parents[1]


# The tables of ``mechcirc simulate`` print the units the results carry (output_units; the
# CLI decided them itself until the fifteenth session, a second source that could differ).
@pytest.mark.parametrize("key, unit", [
    ("sley.acceleration", "rad/s²"), ("C2.force", "N·m"), ("C2.deformation", "rad"),
    ("drive.moment", "N·m"), ("M4.moment", "N·m"), ("B.acceleration", "m/s²"),
    ("B.acceleration_x", "m/s²"), ("eps2P", "rad/s²"), ("eps4T", "rad/s²"), ("M2V", "N·m")])
def test_torsion_scene(key, unit):
    # Mrázek's sley: torsion rods C2, C4 (N·m, rad), a point B, aliases of both kinds.
    scene = load_scene(ROOT / "examples" / "mrazek_one_side.toml")
    assert output_units(scene, [key]) == {key: unit}


@pytest.mark.parametrize("key, unit", [("kCD.force", "N"), ("kCD.deformation", "m"),
                                       ("crank.acceleration", "rad/s²")])
def test_spring_scene(key, unit):
    scene = load_scene(ROOT / "examples" / "heald_scene.toml")
    assert output_units(scene, [key]) == {key: unit}


def test_the_simulate_table_prints_the_results_units(capsys):
    from cli_helpers import run

    status, out, err = run(["simulate", "examples/mrazek_one_side.toml", "--revolutions", "1"],
                           capsys)
    assert status == 0, err
    rows = {ln.split()[0]: ln.split()[-1] for ln in out.splitlines() if ln.split()}
    assert rows["eps2P"] == "rad/s²" and rows["M2V"] == "N·m" and rows["C2.force"] == "N·m"


ROTARY = """drive W T 0 velocity=2 rad/s
mass J1 T 0 0.02 kg*m^2
spring k1 T A 2e4 N*m/rad
mass J2 A 0 0.1 kg*m^2
damper c2 A 0 3 N*m*s/rad
"""


def test_mode_table_of_a_rotary_drive_in_rad_per_s_and_newton_metres(tmp_path, capsys):
    from cli_helpers import run

    path = tmp_path / "rotary.mcir"
    path.write_text(ROTARY)
    status, out, err = run(["resonances", path, "--modes"], capsys)
    assert status == 0, err
    assert "|v| [rad/s]" in out and "|Q| [N·m]" in out and "[m/s]" not in out
