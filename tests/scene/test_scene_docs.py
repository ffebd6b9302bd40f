"""docs/scenes.md: its Python example runs and its CLI excerpts are what the CLI prints."""

import doctest
from pathlib import Path

from cli_helpers import run

ROOT = Path(__file__).resolve().parents[2]
DOC = ROOT / "docs" / "scenes.md"


def test_python_example_runs(monkeypatch):
    monkeypatch.chdir(ROOT)
    failures, tried = doctest.testfile(str(DOC), module_relative=False,
                                       optionflags=doctest.ELLIPSIS)
    assert tried >= 5 and failures == 0


def test_cli_excerpts_match(capsys, monkeypatch):
    text = DOC.read_text()
    monkeypatch.chdir(ROOT)
    monkeypatch.setenv("COLUMNS", "200")
    for argv in (["scene", "examples/heald_scene.toml", "--cycle", "--points", "12",
                  "--harmonics", "6"],
                 ["reduce", "netlists/stb_heald.mcir", "--band", "10:300", "--tol", "0.01"]):
        status, out, err = run(argv, capsys)
        assert status == 0, err
        for line in out.splitlines():
            if line.startswith("wrote"):
                continue
            if "θ [deg]" in line or line.strip().startswith(("0.00", "90.00", "300.00")) \
                    or "meets" in line or "θ ≈" in line or "->" in line or "measured" in line:
                assert line in text, line
