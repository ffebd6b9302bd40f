"""Units in the scene tables of ``mechcirc simulate`` (with and without ``--shaft``)."""

from __future__ import annotations

from pathlib import Path

import pytest

from mechcirc.cli.scene_commands import _quantity_unit
from mechcirc.scene import load_scene

ROOT = Path(__file__).resolve().parents[1]


@pytest.mark.parametrize("key, unit", [
    ("sley.acceleration", "rad/s²"), ("C2.force", "N·m"), ("C2.deformation", "rad"),
    ("drive.moment", "N·m"), ("M4.moment", "N·m"), ("B.acceleration", "m/s²"),
    ("B.acceleration_x", "m/s²"), ("eps2P", "rad/s²"), ("eps4T", "rad/s²"), ("M2V", "N·m"),
    ("speed", "rad/s"), ("acceleration", "rad/s²"), ("motor_torque", "N·m")])
def test_torsion_scene(key, unit):
    # Mrázek's sley: torsion rods C2, C4 (N·m, rad), a point B, aliases of both kinds.
    scene = load_scene(ROOT / "examples" / "mrazek_one_side.toml")
    keys = {"B.acceleration", "B.acceleration_x", "B.acceleration_y", key}
    assert _quantity_unit(scene, key, keys) == unit


@pytest.mark.parametrize("key, unit", [("kCD.force", "N"), ("kCD.deformation", "m"),
                                       ("crank.acceleration", "rad/s²")])
def test_spring_scene(key, unit):
    scene = load_scene(ROOT / "examples" / "heald_scene.toml")
    assert _quantity_unit(scene, key, {key}) == unit
