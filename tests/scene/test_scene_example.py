"""examples/heald_scene.py runs, and what it prints holds."""

import re
from pathlib import Path

import pytest
from cli_helpers import run_script

ROOT = Path(__file__).resolve().parents[2]


def test_heald_example_prints_consistent_numbers(capsys, monkeypatch):
    status, out, err = run_script(ROOT / "examples" / "heald_scene.py", [], capsys, monkeypatch)
    assert status == 0, out + err
    assert err == ""
    m = re.search(r"circuit (\S+) kg·m², finite differences (\S+) kg·m²", out)
    assert m and float(m.group(1)) == pytest.approx(float(m.group(2)), rel=1e-8)
    crossings = re.findall(r"meets (\d+)·Ω = (\S+) rad/s at θ ≈ (\S+)°", out)
    assert crossings and all(int(h) * 60.0 == float(w) for h, w, _ in crossings)
    rng = re.search(r"resonance 1:\s+(\S+) …\s+(\S+) rad/s", out)
    lo, hi = float(rng.group(1)), float(rng.group(2))
    assert all(lo <= float(w) <= hi for _, w, _ in crossings)
    for e in re.findall(r"measured worst relative error (\S+)", out):
        assert float(e) <= 1e-2
