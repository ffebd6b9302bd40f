"""Inputs the fuzz campaign found (scene seeds widened to every example scene): each is a
located error, not a traceback."""

from pathlib import Path

import pytest

from mechcirc.errors import MechcircError
from mechcirc.scene import load_scene

SCENE = Path(__file__).resolve().parents[1] / "examples" / "mrazek_one_side.toml"


@pytest.mark.parametrize("value", ["[-12]", "{a = 1}", "3"])
def test_moment_body_not_a_name(tmp_path, value):
    # fuzz seeds 1008832, 1027652: body = [-12] raised TypeError (unhashable list)
    head, sep, tail = SCENE.read_text().partition("[[moments]]")
    assert sep and 'body = "sley"' in tail
    path = tmp_path / "bad.toml"
    path.write_text(head + sep + tail.replace('body = "sley"', f"body = {value}", 1))
    line = (head + sep + tail[:tail.index('body = "sley"')]).count("\n") + 1
    with pytest.raises(MechcircError, match=r"\[\[moments\]\] #1: body .* is not a rigid link") \
            as exc:
        load_scene(path)
    assert f"bad.toml:{line}:" in str(exc.value)
