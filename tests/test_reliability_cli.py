"""The command-line contract (issue 8, §5), checked for every registered sub-command.

Exit status 0 success, 1 internal failure (one line, a hint to report it, the
traceback only with ``--debug``), 2 user error; ``--help`` of every command
shows an example, and the example is a valid command line.
"""

from __future__ import annotations

import shlex
import subprocess
import sys
from pathlib import Path

import pytest

from fuzz.harness import cli_commands
from mechcirc.cli import build_parser, main

ROOT = Path(__file__).resolve().parents[1]
COMMANDS = sorted(cli_commands())


def test_every_module_registers_commands():
    assert {"check", "sweep", "resonances", "fourbar", "synth", "linkage", "simulate",
            "crosscheck"} <= set(COMMANDS)


@pytest.mark.parametrize("name", COMMANDS)
def test_help_of_every_command_shows_an_example(name, capsys):
    with pytest.raises(SystemExit) as exit_:
        main([name, "--help"])
    assert exit_.value.code == 0
    out = capsys.readouterr().out
    assert "Example" in out and f"mechcirc {name}" in out


def _examples(text: str) -> list[list[str]]:
    """The command lines after 'mechcirc ' in a help epilog."""
    lines = []
    for line in text.splitlines():
        if "mechcirc " in line:
            lines.append(shlex.split(line.split("mechcirc ", 1)[1]))
    return lines


@pytest.mark.parametrize("name", COMMANDS)
def test_examples_in_help_are_valid_command_lines(name):
    """argparse accepts each example as written (it is not run: some need files)."""
    sub = cli_commands()[name]
    examples = _examples(sub.epilog or "")
    assert examples, f"{name}: no example in the epilog"
    parser = build_parser()
    for argv in examples:
        assert argv[0] == name
        args = parser.parse_args(argv)            # SystemExit(2) if invalid
        assert args.func is not None


def test_top_level_help_and_no_command(capsys):
    with pytest.raises(SystemExit) as exit_:
        main(["--help"])
    assert exit_.value.code == 0 and "Example" in capsys.readouterr().out
    assert main([]) == 2


@pytest.mark.parametrize("argv", [
    ["check", "no/such/file.mcir"],
    ["linkage", "no/such/file.toml"],
    ["sweep", str(ROOT / "netlists" / "stb_heald.mcir"), "--omega-min", "5",
     "--omega-max", "1"],
    ["fourbar", "--crank", "-1", "--coupler", "1", "--rocker", "1", "--frame", "1"],
    ["simulate", "--variant", "9"],
])
def test_user_errors_exit_2_with_one_line(argv, capsys):
    try:
        status = main(argv)
    except SystemExit as exc:       # a value refused by the option's type: a usage error
        status = exc.code
    assert status == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "error" in err and "Traceback" not in err


def test_usage_errors_exit_2():
    with pytest.raises(SystemExit) as exit_:
        main(["sweep", "--points", "many"])
    assert exit_.value.code == 2


def _boom(message):
    def handler(args):
        raise RuntimeError(message)
    return handler


@pytest.mark.parametrize("message", ["boom", "first line\nsecond line\nthird"])
def test_internal_error_is_one_line_and_a_hint(monkeypatch, capsys, message):
    from mechcirc.cli import circuit_commands

    monkeypatch.setattr(circuit_commands, "cmd_check", _boom(message))
    assert main(["check", "x.mcir"]) == 1
    lines = capsys.readouterr().err.strip().splitlines()
    assert lines[0] == "mechcirc: internal error: RuntimeError: " + message.splitlines()[0]
    assert len(lines) == 2 and "report" in lines[1] and "--debug" in lines[1]


def test_internal_error_traceback_only_with_debug(monkeypatch):
    from mechcirc.cli import circuit_commands

    monkeypatch.setattr(circuit_commands, "cmd_check", _boom("boom"))
    with pytest.raises(RuntimeError, match="boom"):
        main(["--debug", "check", "x.mcir"])


def test_internal_error_in_a_real_process_has_no_traceback(tmp_path):
    """python -m mechcirc with a handler that fails: exit 1, no traceback on stderr."""
    code = ("import sys, mechcirc.cli.circuit_commands as c\n"
            "def bad(args): raise KeyError('x')\n"
            "c.cmd_check = bad\n"
            "from mechcirc.cli import main\n"
            "sys.exit(main(['check', 'any.mcir']))\n")
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          timeout=60)
    assert proc.returncode == 1
    assert "Traceback" not in proc.stderr
    assert proc.stderr.startswith("mechcirc: internal error: KeyError: 'x'\n")


def test_broken_pipe_is_not_an_error(monkeypatch):
    from mechcirc.cli import circuit_commands

    def pipe(args):
        raise BrokenPipeError

    monkeypatch.setattr(circuit_commands, "cmd_check", pipe)
    assert main(["check", "x.mcir"]) == 0
