"""``.ci/run``: the tests' exit status and mypy's both decide CI; no tests is a failure.

The script is run with stand-ins for ``python3``, ``python`` and ``pip`` first on
PATH (nothing is installed): the stand-in ``python -m pytest`` and ``python -m mypy``
exit with the statuses under test (mypy's arguments are logged).
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
  "-m pytest"*) exit "$PYTEST_STATUS" ;;
  "-m mypy "*) echo "$*" >> "$TMPDIR/mypy_args"; exit "$MYPY_STATUS" ;;
esac
exit 0
"""


@pytest.mark.parametrize("pytest_status, mypy_status, ci_status", [
    (0, 0, 0), (1, 0, 1), (5, 0, 5), (0, 1, 1), (0, 2, 2), (1, 1, 1), (5, 1, 5)])
def test_ci_status_follows_pytest_and_mypy_and_no_tests_collected_fails(
        tmp_path, pytest_status, mypy_status, ci_status):
    bin_dir = tmp_path / "bin"
    bin_dir.mkdir()
    for name in ("python3", "python", "pip"):
        (bin_dir / name).write_text(STAND_IN)
        (bin_dir / name).chmod(0o755)
    env = {**os.environ, "PATH": f"{bin_dir}{os.pathsep}{os.environ['PATH']}",
           "PYTEST_STATUS": str(pytest_status), "MYPY_STATUS": str(mypy_status),
           "TMPDIR": str(tmp_path)}
    proc = subprocess.run(["bash", str(ROOT / ".ci" / "run")], env=env, capture_output=True,
                          text=True, timeout=SUBPROCESS_TIMEOUT, check=False)
    assert proc.returncode == ci_status, proc.stderr
    assert ("collected no tests" in proc.stderr) == (pytest_status == 5)
    assert ("mypy found type errors" in proc.stderr) == (mypy_status != 0)
    # mypy checks the package, after the tests, with a fresh cache in the run's temp dir
    args = (tmp_path / "mypy_args").read_text().split()
    assert args[:2] == ["-m", "mypy"] and args[-1] == "mechcirc"
    cache = Path(args[args.index("--cache-dir") + 1])
    assert cache.parent.parent == tmp_path and not cache.exists()
    assert not cache.parent.exists()        # the run's temp dir (its virtualenv) removed


def test_no_two_test_files_share_a_name():
    """The test folders are not packages, so pytest imports each file by its base name: two
    test_x.py in different folders make the second an 'import file mismatch' error, which
    fails the run (it happened once after two branches each added one)."""
    from collections import Counter

    tests = Path(__file__).resolve().parent
    names = Counter(p.name for p in tests.rglob("test_*.py"))
    assert not [n for n, c in names.items() if c > 1], names.most_common(3)


def test_ci_runs_the_readmes_test_command():
    """.ci/run installs and tests as the README's test command does (the install and the
    pytest line after the virtualenv is made and activated, word for word)."""
    import re

    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    block = re.search(r"Install with the test extra and run the tests:\s*```\n(.*?)\n```",
                      readme, re.S)
    assert block, "README.md: the test command's block was not found"
    steps = [s.strip() for s in block.group(1).split("&&")]
    assert steps[0].startswith("python3.11 -m venv ") and steps[1].startswith(". ")
    command = " && ".join(steps[2:])              # e.g. pip install ".[test]" && python -m pytest -q
    assert command.startswith("pip install ") and command.endswith("python -m pytest -q")
    ci = (ROOT / ".ci" / "run").read_text(encoding="utf-8")
    # each step may be timed by bash's `time` keyword, which changes nothing it runs
    untimed = [" && ".join(re.sub(r"^time ", "", s.strip()) for s in line.split("&&"))
               for line in ci.splitlines()]
    assert command in untimed, (command, ci)
