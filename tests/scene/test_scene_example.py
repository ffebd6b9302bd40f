"""examples/heald_scene.py runs, and what it prints holds."""

import re
import subprocess
import sys
from pathlib import Path

import pytest
from bounds import SUBPROCESS_TIMEOUT

ROOT = Path(__file__).resolve().parents[2]


def test_heald_example_prints_consistent_numbers():
    proc = subprocess.run([sys.executable, str(ROOT / "examples" / "heald_scene.py")], cwd=ROOT,
                          capture_output=True, text=True, timeout=SUBPROCESS_TIMEOUT)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert proc.stderr == ""
    out = proc.stdout
    m = re.search(r"circuit (\S+) kg·m², finite differences (\S+) kg·m²", out)
    assert m and float(m.group(1)) == pytest.approx(float(m.group(2)), rel=1e-8)
    crossings = re.findall(r"meets (\d+)·Ω = (\S+) rad/s at θ ≈ (\S+)°", out)
    assert crossings and all(int(h) * 60.0 == float(w) for h, w, _ in crossings)
    rng = re.search(r"resonance 1:\s+(\S+) …\s+(\S+) rad/s", out)
    lo, hi = float(rng.group(1)), float(rng.group(2))
    assert all(lo <= float(w) <= hi for _, w, _ in crossings)
    for e in re.findall(r"measured worst relative error (\S+)", out):
        assert float(e) <= 1e-2
