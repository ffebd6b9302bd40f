"""The package is clean under the ruff rule set written in pyproject.toml (a gate: bugs, not style)."""

import subprocess
import sys
from pathlib import Path

import pytest

from bounds import SUBPROCESS_TIMEOUT

REPO = Path(__file__).resolve().parents[1]


def test_ruff_finds_nothing_in_the_package():
    pytest.importorskip("ruff", reason="ruff is in the test extra")
    proc = subprocess.run([sys.executable, "-m", "ruff", "check", "--no-cache", "mechcirc"],
                          cwd=REPO, capture_output=True, text=True, timeout=SUBPROCESS_TIMEOUT)
    assert proc.returncode == 0, proc.stdout[-3000:] + proc.stderr[-1000:]
