"""``tests/cpu_report.py``: the per-test CPU files summed by test, file and function."""

from __future__ import annotations

import cpu_report


def test_files_and_functions_sum_their_tests_without_compiling(tmp_path, capsys):
    path = tmp_path / "cpu"
    # node id, worker CPU, subprocess CPU, compiling (tests/conftest.py's columns)
    (tmp_path / "cpu.gw0").write_text(
        "tests/a.py::test_x[1]\t2.000\t0.500\t1.000\n"
        "tests/a.py::test_x[2]\t1.000\t0.000\t0.000\n", encoding="utf-8")
    (tmp_path / "cpu.gw1").write_text(
        "tests/a.py::test_y\t0.250\t0.000\t0.000\n"
        "tests/b.py::test_z\t3.000\t0.000\t0.000\n", encoding="utf-8")
    cpu_report.main(str(path), 5)
    out = capsys.readouterr().out
    assert out.startswith("4 tests, 6.8 s CPU (6.2 s in the workers, 0.5 s in subprocesses)")
    files = out.split("top 5 test files without compiling (seconds, tests):\n")[1]
    functions = files.split("top 5 test functions without compiling (seconds, tests):\n")[1]
    # a.py: 2.5 - 1.0 + 1.0 + 0.25 = 2.75 over 3 tests; b.py: 3.0 over 1
    assert files.splitlines()[:2] == ["    3.00     1  tests/b.py", "    2.75     3  tests/a.py"]
    assert functions.splitlines()[:3] == ["    3.00     1  tests/b.py::test_z",
                                          "    2.50     2  tests/a.py::test_x",
                                          "    0.25     1  tests/a.py::test_y"]
