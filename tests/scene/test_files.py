"""mechcirc.scene.files: values of the wrong kind in a scene file are located user errors."""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from mechcirc.errors import MechcircError, NetlistError
from mechcirc.sources import split_lines
from cli_helpers import assert_user_error


ROOT = Path(__file__).resolve().parents[2]


SCENE = ROOT / "examples" / "heald_scene.toml"


def _scene(tmp_path, old, new, count=1):
    text = SCENE.read_text()
    assert text.count(old) >= count, old
    path = tmp_path / "s.toml"
    path.write_text(text.replace(old, new, count))
    return path, text.replace(old, new, count)


@pytest.mark.parametrize("old, new, key", [
    ('units = "mm"', "units = [-12]", "units"),
    ('link = "rodCD"', 'link = ["rodCD"]', "link"),                       # elastic.link
    ('direction = [0.0, 1.0]', 'direction = [0.0, 1.0]\npoint = ["M"]', None),
    ('[drive]\nname = "ripple"\nlink = "crank"', '[drive]\nname = "ripple"\nlink = ["crank"]',
     "link"),                                                             # drive.link
    ("stiffness = 2.0e6", "stiffness = " + "9" * 400, "stiffness"),
    ("mass = 3.0", "mass = " + "9" * 400, "mass"),
])
def test_scene_values_of_the_wrong_kind_are_located_user_errors(old, new, key, tmp_path,
                                                                  capsys):
    from mechcirc.scene import load_scene

    path, text = _scene(tmp_path, old, new)
    with pytest.raises(NetlistError) as info:
        load_scene(path)
    err = info.value
    assert 1 <= err.line <= len(split_lines(text)), err
    if key:
        assert split_lines(text)[err.line - 1].lstrip().startswith(key), err
    assert len(str(err)) < 400                       # a 400-digit integer is cut short
    assert_user_error(["scene", path, "--theta", "10"], capsys, f"{path}:{err.line}:")


def test_scene_loads_point_as_a_list(tmp_path):
    from mechcirc.scene import parse_scene

    text = SCENE.read_text()
    i = text.index("[[loads]]")
    j = text.index('point = "M"', i)
    text = text[:j] + 'point = ["M"]' + text[j + len('point = "M"'):]
    with pytest.raises(NetlistError, match="point"):
        parse_scene(text, "s.toml")


def test_scene_build_at_nan_is_a_mechcirc_error():
    from mechcirc.scene import build, load_scene

    scene = load_scene(SCENE)
    for theta in (math.nan, math.inf):
        with pytest.raises(MechcircError):
            build(scene, theta)
    with pytest.raises(ValueError):          # InputError is also a ValueError
        build(scene, math.nan)
