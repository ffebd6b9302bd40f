"""examples/sley_table1.py runs and its claims hold."""

import re
import subprocess
import sys
from pathlib import Path

from bounds import SUBPROCESS_TIMEOUT

REPO = Path(__file__).resolve().parents[2]


def test_table1_example():
    proc = subprocess.run([sys.executable, str(REPO / "examples" / "sley_table1.py"),
                           "--revolutions", "3"], cwd=REPO, capture_output=True, text=True,
                          timeout=SUBPROCESS_TIMEOUT)
    assert proc.returncode == 0, proc.stderr
    out = proc.stdout
    assert "eps4T reproduced exactly (rounded to integers) in every variant: True" in out
    assert len(re.findall(r"^variant \d$", out, flags=re.M)) == 7
    m = re.search(r"^  -M2V\s+median\s+(\S+) %", out, flags=re.M)
    assert m and float(m.group(1)) < 10.0
