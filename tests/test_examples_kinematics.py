"""The kinematics example scripts run and what they print holds."""

import re
import subprocess
import sys
from pathlib import Path

from bounds import SUBPROCESS_TIMEOUT

REPO = Path(__file__).resolve().parents[1]


def _run(name):
    proc = subprocess.run([sys.executable, str(REPO / "examples" / name)], cwd=REPO,
                          capture_output=True, text=True, timeout=SUBPROCESS_TIMEOUT)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    return proc.stdout


def test_fourbar_mrazek_example():
    out = _run("fourbar_mrazek.py")
    diffs = [float(x) for x in re.findall(r"difference ([+-]\d+\.\d+) / ([+-]\d+\.\d+)", out)[0]
             + re.findall(r"difference ([+-]\d+\.\d+) / ([+-]\d+\.\d+)", out)[1]]
    assert len(diffs) == 4 and all(abs(d) <= 0.5 for d in diffs)     # paper prints integers
    assert "meets every criterion (checked on the linkage itself): True" in out


def test_fnf_sixbar_example():
    out = _run("fnf_sixbar.py")
    assert "mobility W = 2" in out and "class 3" in out
    rel = float(re.search(r"superposition, relative (\S+)\)", out).group(1))
    assert rel <= 1e-12
    rel_fd = float(re.search(r"finite difference of positions\| ≤ \S+ \(relative (\S+),", out)
                   .group(1))
    assert rel_fd <= 1e-8
