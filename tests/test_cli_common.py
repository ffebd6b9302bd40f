"""mechcirc.cli (the contract in ``cli/_common.py``), checked for every registered sub-command.

Exit status 0 success, 1 internal failure (one line, a hint to report it, the
traceback only with ``--debug``), 2 user error; ``--help`` of every command
shows an example, and the example is a valid command line.  Every number an
option takes goes through one validator (bad values: exit 2, one line naming
the option); Ctrl-C during start-up prints no traceback (a real process).
"""

from __future__ import annotations

import shlex
import subprocess
import sys
import time
from pathlib import Path

import pytest

from fuzz.harness import cli_commands
from mechcirc.cli import build_parser, main
import signal
from cli_helpers import assert_user_error, run
from bounds import SUBPROCESS_TIMEOUT
from reference.inputs import STB

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


@pytest.mark.parametrize("argv", [["--debug", "check", "x.mcir"],
                                  ["check", "x.mcir", "--debug"]])   # where the hint puts it
def test_internal_error_traceback_only_with_debug(monkeypatch, argv):
    from mechcirc.cli import circuit_commands

    monkeypatch.setattr(circuit_commands, "cmd_check", _boom("boom"))
    with pytest.raises(RuntimeError, match="boom"):
        main(argv)


@pytest.mark.parametrize("name", COMMANDS)
def test_every_command_takes_debug_after_it(name):
    parser = build_parser()
    command = next(a for a in parser._subparsers._group_actions).choices[name]
    assert "--debug" in command._option_string_actions


def test_internal_error_in_a_real_process_has_no_traceback(tmp_path):
    """python -m mechcirc with a handler that fails: exit 1, no traceback on stderr."""
    code = ("import sys, mechcirc.cli.circuit_commands as c\n"
            "def bad(args): raise KeyError('x')\n"
            "c.cmd_check = bad\n"
            "from mechcirc.cli import main\n"
            "sys.exit(main(['check', 'any.mcir']))\n")
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          timeout=SUBPROCESS_TIMEOUT)
    assert proc.returncode == 1
    assert "Traceback" not in proc.stderr
    assert proc.stderr.startswith("mechcirc: internal error: KeyError: 'x'\n")


def test_broken_pipe_is_not_an_error(monkeypatch):
    from mechcirc.cli import circuit_commands

    def pipe(args):
        raise BrokenPipeError

    monkeypatch.setattr(circuit_commands, "cmd_check", pipe)
    assert main(["check", "x.mcir"]) == 0


@pytest.mark.parametrize("value", ["0", "-1", "inf", "nan", "1e400"])
def test_forces_omega_out_of_domain_is_a_user_error(value, capsys):
    assert_user_error(["forces", STB, f"--omega={value}"], capsys, "--omega")


@pytest.mark.parametrize("argv, needle", [
    (["--omega", "1e300"], "--omega"),
    (["--omega", "nan"], "--omega"),
    (["--omega", "inf"], "--omega"),
])
def test_fourbar_omega_must_be_finite_and_bounded(argv, needle, capsys):
    assert_user_error(["fourbar", "--crank", "29", "--coupler", "37", "--rocker", "188",
                       "--frame", "189", *argv], capsys, needle)


@pytest.mark.parametrize("lengths", [("1e308", "37", "188", "189"),
                                     ("1e50", "37", "188", "189"),
                                     ("1e-300", "37", "188", "189"),
                                     ("1e308", "1e308", "1e308", "1e308")])
def test_fourbar_extreme_lengths_are_refused_before_any_work(lengths, capsys):
    a, b, c, d = lengths
    assert_user_error(["fourbar", "--crank", a, "--coupler", b, "--rocker", c, "--frame", d],
                      capsys, "--")


@pytest.mark.parametrize("option", ["--omega-min", "--omega-max"])
@pytest.mark.parametrize("value", ["nan", "-1", "inf"])
def test_compare_band_must_be_finite_and_non_negative(option, value, tmp_path, capsys):
    s1p = tmp_path / "m.s1p"
    s1p.write_text("# Hz Z RI R 1\n1 0.001 0.002\n2 0.001 0.003\n")
    assert_user_error(["compare", STB, s1p, f"{option}={value}"], capsys, option)


@pytest.mark.parametrize("value", ["nan", "-1", "0", "inf"])
def test_resonances_omega_max_must_be_positive_and_finite(value, capsys):
    assert_user_error(["resonances", STB, f"--omega-max={value}"], capsys, "--omega-max")


def test_simulate_set_value_is_checked(capsys):
    assert_user_error(["simulate", "--set", "C2=1e308"], capsys, "--set C2")
    assert_user_error(["simulate", "--set", "C2=nan"], capsys, "--set C2")
    assert_user_error(["simulate", "--set", "=5"], capsys, "--set expects NAME=VALUE, got '=5'")


def test_import_mechcirc_installs_no_signal_handler(light_imports):
    """Only the command line's entry point handles signals; a library user keeps their own
    (the process is even named ``mechcirc`` here, which once sufficed to install one):
    SIGINT's and SIGTERM's handlers before ``import mechcirc`` and after every public
    name and the parser (one process with the other light-import checks: tests/conftest.py, light_imports)."""
    before, after = light_imports["signals"]
    assert after == before


#: A Ctrl-C delivered exactly while a module is being imported (no clock: a meta-path
#: finder sends SIGINT to its own process when the module is asked for), then the
#: command line started as ``python -m mechcirc`` or as the console script does.
_INTERRUPTED_START = """\
import os, signal, sys
class Interrupt:
    def find_spec(self, name, path=None, target=None):
        if name == {module!r}:
            sys.meta_path.remove(self)
            os.kill(os.getpid(), signal.SIGINT)
        return None
sys.meta_path.insert(0, Interrupt())
sys.argv = ["mechcirc", "check", {netlist!r}]
if {as_module!r}:
    import runpy
    runpy.run_module("mechcirc", run_name="__main__", alter_sys=True)
else:
    from mechcirc.cli import main
    sys.exit(main())
"""


@pytest.mark.parametrize("as_module", [True, False], ids=["python-m", "script"])
@pytest.mark.parametrize("module", ["mechcirc.cli", "mechcirc.cli._common",
                                    "mechcirc.netlist", "numpy"])
def test_ctrl_c_during_start_up_exits_130_without_traceback(module, as_module):
    if module == "mechcirc.cli" and not as_module:
        pytest.skip("the console script imports mechcirc.cli before its entry point runs")
    code = _INTERRUPTED_START.format(module=module, netlist=str(STB), as_module=as_module)
    # SIGINT as a terminal leaves it (a test runner may have it ignored in children).
    proc = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True,
                          text=True, timeout=SUBPROCESS_TIMEOUT,
                          preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    assert (proc.returncode, proc.stderr) == (130, "mechcirc: interrupted\n")


@pytest.mark.parametrize("argv", [
    ["synth", "--plot", "{d}/x.s1p"],
    ["fourbar", "--crank", "1", "--coupler", "3", "--rocker", "3", "--frame", "3",
     "--plot", "{d}/x.xyz"],
    ["linkage", "examples/fnf_sixbar.toml", "--plot", "{d}/x.csv"],
    ["simulate", "--revolutions", "1", "--points", "36", "--plot", "{d}/x.txt"],
])
def test_unsupported_plot_format_is_a_user_error_before_any_work(tmp_path, capsys, argv,
                                                                  monkeypatch):
    import pathlib

    monkeypatch.chdir(pathlib.Path(__file__).resolve().parents[1])
    argv = [a.replace("{d}", str(tmp_path)) for a in argv]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert "unsupported plot format" in err and "internal error" not in err
    assert list(tmp_path.iterdir()) == []


def test_synth_limit_below_one_is_refused(capsys):
    with pytest.raises(SystemExit) as exit_:      # a usage error: argparse exits
        main(["synth", "--limit", "0"])
    assert exit_.value.code == 2
    assert "--limit: must be at least 1, got 0" in capsys.readouterr().err


def test_crosscheck_reports_unmeasurable_ringing_instead_of_crashing(cli_once):
    """Variant 6 of Table 1 rings too little to count crossings: (b) cannot be measured
    (said, with why), (a), (c) stand.  (Variant 2 did too with its clearance open; the
    ringing check now closes it, and measures 1.9e-3.)"""
    status, out, _ = cli_once(["crosscheck", "--variant", "6"])
    assert status == 0
    assert "(b) ringing after beat-up: cannot be measured" in out
    assert "zero crossing(s) of the pulse response" in out
    assert "(c) harmonic forcing" in out


@pytest.mark.parametrize("theta", ["inf", "1e400", "nan", "-inf"])
def test_crosscheck_refuses_a_non_finite_theta(theta, capsys):
    """Long-run CLI fuzz (17 of 3,000 command lines): --theta inf was a math domain error."""
    with pytest.raises(SystemExit) as exit_:      # a usage error: argparse exits
        main(["crosscheck", f"--theta={theta}"])
    assert exit_.value.code == 2
    assert "--theta: " in (err := capsys.readouterr().err) and "is not a finite number" in err


# ------------------------------------------------- the formula's limit counts CPU time (issue 23 §8)
def test_time_limit_ignores_time_spent_waiting():
    """Wall-clock time without CPU use (a loaded machine, here a sleep) does not count."""
    from mechcirc.cli._common import time_limit

    with time_limit(0.05, "the test", "nothing"):
        time.sleep(0.3)             # 6× the limit of wall time, ~0 CPU time


def test_time_limit_stops_cpu_work_and_says_so():
    from mechcirc.cli._common import time_limit
    from mechcirc.errors import MechcircError

    start = time.process_time()
    with pytest.raises(MechcircError, match=r"the test used more than the limit of 0\.1 s of "
                                            r"CPU time; do less"), \
            time_limit(0.1, "the test", "do less"):
        while time.process_time() - start < 5.0:        # CPU work, bounded by CPU time
            pass
    assert time.process_time() - start < 5.0            # stopped by the limit, not the loop


def test_a_package_warning_raised_again_during_a_command_is_not_printed_twice(capsys,
                                                                              monkeypatch):
    """msl_backlash's unloaded elements are reported when the netlist is read; the exact
    peak's resonance search raises the same warning again, which used to reach stderr as a
    raw Python warning line (file:line: UnloadedElementWarning: ...) after the output."""
    import warnings

    def show(message, category, filename, lineno, file=None, line=None):
        # What Python does outside pytest (which records warnings instead of printing).
        sys.stderr.write(warnings.formatwarning(message, category, filename, lineno, line))

    monkeypatch.setattr(warnings, "showwarning", show)

    status, out, err = run(["sweep", "examples/msl_backlash.mcir", "--omega-min", "1",
                            "--omega-max", "100", "--points", "20"], capsys)
    assert status == 0
    lines = [line for line in err.splitlines() if "lie on no path" in line]
    assert len(lines) == 1 and lines[0].startswith("warning: "), err
    assert "UnloadedElementWarning" not in err and ".py:" not in err, err


@pytest.mark.parametrize("argv, what", [
    (["check", "{}"], "a .mcir netlist"),
    (["linkage", "{}"], "a linkage .toml"),
    (["scene", "{}", "--theta", "10"], "a scene .toml"),
    (["study", "{}", "-o", "{out}"], "a study .toml"),
    (["transient", STB, "--t-end", "1", "--waveform", "csv:{}", "-o", "{out}"],
     "a drive CSV (time,value)"),
])
@pytest.mark.parametrize("kind", ["missing", "folder"])
def test_an_input_file_missing_or_a_folder_exits_2_naming_it(argv, what, kind, tmp_path, capsys):
    """Each kind of input file missing, or a folder: exit 2, one line 'PATH: error: no such
    file (expected the path of …)' / 'is a directory (expected … file)', nothing written
    (the drive CSV's expectation read '… (time,value) file file' before)."""
    path = tmp_path / ("nope.txt" if kind == "missing" else "folder")
    if kind == "folder":
        path.mkdir()
    out = tmp_path / "out.csv"
    argv = [str(a).replace("{}", str(path)).replace("{out}", str(out)) for a in argv]
    expected = (f"no such file (expected the path of {what})" if kind == "missing"
                else f"is a directory (expected {what} file)")
    assert_user_error(argv, capsys, f"{path}: error: {expected}")
    assert not out.exists()


@pytest.mark.parametrize("exc, line", [
    (FileNotFoundError(2, "No such file or directory", "/p/x.png"), "/p/x.png: error: no such file"),
    (IsADirectoryError(21, "Is a directory", "/p/d"), "/p/d: error: is a directory, expected a file"),
])
def test_a_file_error_a_command_lets_through_is_a_user_error(exc, line, monkeypatch, capsys):
    """The last guard (cli/_common._run): an OSError naming a file that a command did not
    turn into a located error still exits 2 with one line naming the file, no traceback."""
    from mechcirc.cli import circuit_commands

    def handler(args):
        raise exc

    monkeypatch.setattr(circuit_commands, "cmd_check", handler)
    assert_user_error(["check", "x.mcir"], capsys, line)


def test_set_with_an_unknown_unit_names_the_parameter_and_the_units(capsys):
    assert_user_error(["simulate", "--set", "omega=3furlong"], capsys,
                      "--set omega: unknown unit 'furlong' (expected one of kg,")


@pytest.mark.parametrize("argv", [
    ["sweep", STB, "--omega-min", "1", "--omega-max", "10", "-o", ""],
    ["scene", "examples/mrazek_one_side.toml", "--cycle", "--plot", ""],
    ["simulate", "examples/mrazek_one_side.toml", "--plot", ""],
])
def test_an_empty_output_name_is_refused(argv, capsys):
    """-o "$OUT" with OUT unset: exit 2 before any work (it wrote nothing and exited 0)."""
    assert_user_error(argv, capsys, "an output file name is empty; give a file name")


@pytest.mark.skipif(not Path("/dev/full").exists(), reason="no /dev/full (a device that is full)")
def test_an_output_with_no_room_is_the_environments_refusal(capsys):
    """A write the system refuses for room (ENOSPC: a full disk; /dev/full) carries no file
    name: exit 2 naming the cause, not 'internal error ... a bug in mechcirc' (exit 1)."""
    assert_user_error(["sweep", STB, "--omega-min", "1", "--omega-max", "10", "-o", "/dev/full"],
                      capsys, "mechcirc: error: no space left on device")
