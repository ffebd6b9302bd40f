"""``.ci/run``: the exit status of the test run is the CI's, and no tests is a failure.

The script is run with stand-ins for ``python3``, ``python`` and ``pip`` first on
PATH (nothing is installed): the stand-in ``python -m pytest`` exits with the
status under test.
"""

from __future__ import annotations

import os
import subprocess
from pathlib import Path

import pytest

from bounds import SUBPROCESS_TIMEOUT

ROOT = Path(__file__).resolve().parents[1]

STAND_IN = """#!/bin/sh
case "$*" in
  "-m venv "*) mkdir -p "$3/bin" && : > "$3/bin/activate" ;;
  *pytest*) exit "$PYTEST_STATUS" ;;
esac
exit 0
"""


@pytest.mark.parametrize("pytest_status, ci_status", [(0, 0), (1, 1), (5, 5)])
def test_ci_status_follows_pytest_and_no_tests_collected_fails(tmp_path, pytest_status,
                                                               ci_status):
    bin_dir = tmp_path / "bin"
    bin_dir.mkdir()
    for name in ("python3", "python", "pip"):
        (bin_dir / name).write_text(STAND_IN)
        (bin_dir / name).chmod(0o755)
    env = {**os.environ, "PATH": f"{bin_dir}{os.pathsep}{os.environ['PATH']}",
           "PYTEST_STATUS": str(pytest_status), "TMPDIR": str(tmp_path)}
    proc = subprocess.run(["bash", str(ROOT / ".ci" / "run")], env=env, capture_output=True,
                          text=True, timeout=SUBPROCESS_TIMEOUT, check=False)
    assert proc.returncode == ci_status, proc.stderr
    if pytest_status == 5:
        assert "collected no tests" in proc.stderr
