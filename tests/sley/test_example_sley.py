"""examples/sley_table1.py runs and its claims hold."""

import re
from pathlib import Path

from cli_helpers import run_script

REPO = Path(__file__).resolve().parents[2]


def test_table1_example(capsys, monkeypatch):
    status, out, err = run_script(REPO / "examples" / "sley_table1.py", ["--revolutions", "3"],
                                  capsys, monkeypatch)
    assert status == 0, err
    assert "eps4T reproduced exactly (rounded to integers) in every variant: True" in out
    assert len(re.findall(r"^variant \d$", out, flags=re.M)) == 7
    m = re.search(r"^  -M2V\s+median\s+(\S+) %", out, flags=re.M)
    assert m and float(m.group(1)) < 10.0
