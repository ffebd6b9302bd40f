"""Every fenced example in README.md and docs/*.md runs as written, with its inputs shipped.

How a block is treated (the markers are HTML comments, invisible on GitHub,
on the line right before the opening fence; they are listed in
docs/tutorial.md under "Examples in these docs"):

* ``python`` blocks are executed, in order, in one namespace per document;
  blocks written as a session (``>>>`` prompts) are run as doctests, so the
  output shown must be the output produced (``...`` elides, whitespace is
  normalised).
* Any other block whose lines start with ``$ `` is a shell session: its
  ``$`` commands run in order; a plain ``mechcirc ...`` line (no pipe,
  redirection or expansion; or piped only into ``head -N``/``tail -N``, whose
  lines are then kept here) runs in this process with the same argv and
  working directory (``mechcirc.cli.main``, as ``python -m mechcirc`` does;
  it saves the interpreter start-up of every line), and so does a plain
  ``python examples/NAME.py ...`` line (``run_script`` of ``tests/cli_helpers.py``:
  ``runpy`` in the page's folder); any other line in
  ``bash -o pipefail``, which sees the previous status as ``$?`` (``echo $?``;
  each line is its own ``bash``, so ``cd`` or a variable does not carry over);
  each ``mechcirc`` command must exit 0, or the status of an
  ``<!-- exit: N -->`` marker; other commands (``cat``, ``head``) must exit 0.
  Real start-up, exit codes and signals of the ``mechcirc`` script are
  tested by subprocess in ``tests/test_cli.py``, ``tests/test_cli_common.py``
  and ``tests/test_outputs.py``.
  The lines after a command are its output as shown, and they are compared
  with what the command printed (stdout, then stderr; :func:`output_mismatch`):
  text word for word (runs of spaces are one space), every number to the
  digits shown, within one unit of the last digit shown or 1e-10 relative,
  whichever is wider (a library's last bit may move it); a line ``...`` stands for any number of lines, and
  ``...`` inside a line for any text there (the rest of that line is then
  compared as text).  An
  ``<!-- output-varies: REASON -->`` marker skips the comparison for a block
  whose output cannot repeat (times, load, a random start).
* ``<!-- file: PATH -->`` writes the block to PATH before the next blocks
  run, so a netlist shown in a page is the netlist its commands read; when
  PATH is shipped (``docs/examples/...``) the block must equal the file.
* ``<!-- not-run: REASON -->`` skips a block (a synopsis, a long run);
  ``$ python benchmarks/...`` commands are never run (they measure, and take
  minutes).
* Blocks without ``$`` lines (netlists, TOML, output, grammars) are text.

Each document runs in a fresh temporary folder holding links to
``netlists/``, ``examples/``, ``benchmarks/`` and ``docs/`` of the checkout,
with ``mechcirc`` on the PATH running this checkout.  New pages are collected
automatically.
"""

from __future__ import annotations

import doctest
import os
import re
import shlex
import subprocess
import sys
from pathlib import Path

import pytest

from bounds import SUBPROCESS_TIMEOUT
from cli_helpers import run_script

REPO = Path(__file__).resolve().parents[1]
PAGES = [REPO / "README.md"] + sorted((REPO / "docs").glob("*.md"))
_FENCE = re.compile(r"^(```+|~~~+)\s*([\w+-]*)")
_MARK = re.compile(r"^<!--\s*([\w-]+)\s*(?::\s*(.*?))?\s*-->\s*$")


def blocks(path: Path):
    """``(line, info, text, marks)`` of each fenced block of ``path``."""
    lines = path.read_text(encoding="utf-8").splitlines()
    out, i = [], 0
    while i < len(lines):
        m = _FENCE.match(lines[i])
        if not m:
            i += 1
            continue
        fence, info, start = m.group(1), m.group(2).lower(), i + 1
        marks = {}
        j = i - 1
        while j >= 0 and _MARK.match(lines[j]):
            mm = _MARK.match(lines[j])
            marks[mm.group(1)] = mm.group(2) or ""
            j -= 1
        i += 1
        body = []
        while i < len(lines) and not lines[i].startswith(fence):
            body.append(lines[i])
            i += 1
        i += 1
        out.append((start, info, "\n".join(body) + "\n", marks))
    return out


def _kind(info: str, text: str, marks: dict) -> str:
    if "not-run" in marks:
        return "skip"
    if "file" in marks:
        return "file"
    if info in ("python", "py", "pycon"):
        return "doctest" if re.search(r"^\s*>>> ", text, re.M) else "python"
    if re.search(r"^\$ ", text, re.M):
        return "shell"
    return "text"


def _workdir(tmp: Path) -> Path:
    import shutil

    for name in ("netlists", "examples", "benchmarks", "mechcirc"):
        (tmp / name).symlink_to(REPO / name)
    for item in (REPO / "docs").iterdir():      # docs/examples copied: pages may write there
        if item.name == "examples":
            shutil.copytree(item, tmp / "docs" / "examples")
        else:
            (tmp / "docs").mkdir(exist_ok=True)
            (tmp / "docs" / item.name).symlink_to(item)
    bin_dir = tmp / ".bin"
    bin_dir.mkdir()
    shim = bin_dir / "mechcirc"
    shim.write_text(f"#!/bin/sh\nexec {sys.executable} -m mechcirc \"$@\"\n")
    shim.chmod(0o755)
    # ``python`` in a shell line is this interpreter (the one with mechcirc's
    # dependencies, numba among them), not the first ``python`` on the PATH.
    python = bin_dir / "python"
    python.write_text(f"#!/bin/sh\nexec {sys.executable} \"$@\"\n")
    python.chmod(0o755)
    return bin_dir


def _commands(text: str):
    """The ``$`` commands of a shell block (a trailing ``\\`` continues a command)."""
    cmds, cur = [], None
    for line in text.splitlines():
        if cur is not None:
            cur += "\n" + line
            if not line.rstrip().endswith("\\"):
                cmds.append(cur)
                cur = None
        elif line.startswith("$ "):
            cur = line[2:]
            if not cur.rstrip().endswith("\\"):
                cmds.append(cur)
                cur = None
    return cmds


#: Characters that make a command line need a real shell (pipes, redirections,
#: expansions, several commands); a ``mechcirc`` line without them runs in-process.
_SHELL_SYNTAX = set("|&;<>()$`*?[]{}~!\\'\"")


#: ``mechcirc ... | head -N`` or ``| tail -N`` (N lines of its output): run in-process too.
_HEAD_TAIL = re.compile(r"^(?P<cmd>[^|]*)\|\s*(?P<which>head|tail)\s+-(?P<n>\d+)\s*$")


def _in_process_argv(cmd: str):
    """The argv of a plain ``mechcirc ...`` line, or None when it needs a shell."""
    line = cmd.replace("\\\n", " ")
    try:
        words = shlex.split(line, comments=True)
    except ValueError:
        return None
    code = re.split(r"(?:^|\s)#", line, maxsplit=1)[0]     # without its comment
    if not words or words[0] != "mechcirc" or _SHELL_SYNTAX & set(code) or "#" in code:
        return None
    return words[1:]


def _in_process(cmd: str):
    """``(argv, keep)`` of a line run in this process, or None when it needs a shell.

    ``keep`` is None, or ``("head"|"tail", N)`` for a plain ``mechcirc`` line
    piped into ``head -N``/``tail -N``: what the pipeline prints is those lines
    of its standard output (standard error passes by the pipe) and, under
    ``pipefail``, its status is mechcirc's (head and tail exit 0), so the line
    runs in-process and the lines are kept here.
    """
    m = _HEAD_TAIL.match(cmd.replace("\\\n", " "))
    if m:
        argv = _in_process_argv(m.group("cmd"))
        return None if argv is None else (argv, (m.group("which"), int(m.group("n"))))
    argv = _in_process_argv(cmd)
    return None if argv is None else (argv, None)


def _keep_lines(text: str, keep) -> str:
    if keep is None:
        return text
    lines = text.splitlines(keepends=True)
    which, n = keep
    return "".join(lines[:n] if which == "head" else lines[-n:] if n else [])


def _example_argv(cmd: str):
    """``[script, args...]`` of a plain ``python examples/NAME.py ...`` line, or None."""
    argv = _in_process_argv(re.sub(r"^\s*python(?=\s)", "mechcirc", cmd))
    if argv and argv[0].startswith("examples/") and argv[0].endswith(".py"):
        return argv
    return None


def run_mechcirc(argv: list[str]) -> tuple[int, str, str]:
    """``mechcirc ARGV`` in this process: ``(exit status, stdout, stderr)``.

    What ``python -m mechcirc`` does (``mechcirc.cli.main``), without the ~1 s
    of interpreter, numpy/scipy/matplotlib and numba-cache start-up per line.
    A ``SystemExit`` (argparse's usage errors, ``--help``) gives its code; any
    other exception escaping ``main`` is what a real run would show as a
    traceback, so it is a failure (status 1, the traceback on stderr).
    """
    import contextlib
    import io
    import traceback

    from mechcirc.cli import main

    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        try:
            status = main(list(argv))
        except SystemExit as exc:
            status = exc.code if isinstance(exc.code, int) else (0 if exc.code is None else 1)
            if exc.code is not None and not isinstance(exc.code, int):
                print(exc.code, file=sys.stderr)
        except BaseException:               # noqa: BLE001 - a traceback is a failure here
            traceback.print_exc()
            status = 1
    return status, out.getvalue(), err.getvalue()


def _shown_outputs(text: str) -> list[list[str]]:
    """The lines shown after each ``$`` command of a shell block, in order."""
    shown: list[list[str]] = []
    cont = False
    for line in text.splitlines():
        if cont:
            cont = line.rstrip().endswith("\\")
            continue
        if line.startswith("$ "):
            shown.append([])
            cont = line.rstrip().endswith("\\")
        elif shown:
            shown[-1].append(line)
    return shown


_NUMBER = re.compile(r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?")


def _number_matches(shown: str, actual: str) -> bool:
    """``actual`` is ``shown`` to the digits shown, within one unit of the last."""
    if shown == actual:
        return True
    mantissa, _, exponent = shown.lower().partition("e")
    decimals = len(mantissa.partition(".")[2])
    unit = 10.0 ** (int(exponent or 0) - decimals)
    try:
        # One unit of the last digit shown, and never tighter than 1e-10
        # relative (a 17-digit CSV value may move in its last bits with the
        # CPU or the library; 1e-10 is still far below any drift a reader sees).
        return abs(float(actual) - float(shown)) <= max(unit, 1e-10 * abs(float(shown))) * (1 + 1e-9)
    except ValueError:
        return False


def _line_matches(shown: str, actual: str) -> bool:
    if "..." in shown and shown.strip() != "...":   # elided inside the line: the rest as text
        parts = [re.escape(" ".join(p.split())) for p in shown.split("...")]
        return re.fullmatch(".*?".join(parts), " ".join(actual.split())) is not None
    s_words, a_words = _NUMBER.split(" ".join(shown.split())), _NUMBER.split(" ".join(actual.split()))
    s_nums, a_nums = _NUMBER.findall(" ".join(shown.split())), _NUMBER.findall(" ".join(actual.split()))
    return (s_words == a_words and len(s_nums) == len(a_nums)
            and all(_number_matches(s, a) for s, a in zip(s_nums, a_nums)))


def output_mismatch(shown: list[str], actual: str) -> str | None:
    """None when ``actual`` (a command's output) is what ``shown`` shows, else why not.

    Blank lines are ignored on both sides; a shown line ``...`` matches any
    number of lines (the shortest run that lets the rest match).
    """
    want = [line for line in shown if line.strip()]
    have = [line for line in actual.splitlines() if line.strip()]
    if not want:
        return None

    def match(i: int, j: int) -> bool:
        if i == len(want):
            return j == len(have)
        if want[i].strip() == "...":
            return any(match(i + 1, k) for k in range(j, len(have) + 1))
        return j < len(have) and _line_matches(want[i], have[j]) and match(i + 1, j + 1)

    if match(0, 0):
        return None
    first = next((f"shown:   {w!r}\nprinted: {h!r}" for w, h in zip(want, have)
                  if w.strip() != "..." and not _line_matches(w, h)), "")
    return (f"the output shown ({len(want)} lines) is not what it printed "
            f"({len(have)} lines)\n{first}\n--- printed ---\n" + "\n".join(have[:40]))


def _run_shell(text, marks, where, tmp, env, fixtures):
    """Run a block's ``$`` commands in order, as one shell session would.

    A plain ``mechcirc ...`` line (no pipe, redirection or expansion) runs
    in-process with the same argv and working directory (:func:`run_mechcirc`);
    any other line runs in ``bash`` (``set -o pipefail``), which sees the last
    status as ``$?`` (``echo $?``).
    """
    expected = int(marks.get("exit", "0") or 0)
    # Benchmarks measure time, they do not check anything, and take minutes: the
    # pages show their command and output, the test does not run them.
    compare = "output-varies" not in marks
    failures, last = [], 0
    for cmd, shown in zip(_commands(text), _shown_outputs(text)):
        if cmd.lstrip().startswith("python benchmarks/"):
            continue
        plain, example = _in_process(cmd), _example_argv(cmd)
        if plain is not None:
            last, stdout, stderr = run_mechcirc(plain[0])
            stdout = _keep_lines(stdout, plain[1])
        elif example is not None:
            fixtures[0].readouterr()                # what earlier blocks printed is not its output
            last, stdout, stderr = run_script(tmp / example[0], example[1:], *fixtures, cwd=tmp)
        else:
            proc = subprocess.run(["bash", "-c", f"set -o pipefail\n(exit {last})\n{cmd}"],
                                  cwd=tmp, env=env, capture_output=True, text=True,
                                  timeout=SUBPROCESS_TIMEOUT)
            last, stdout, stderr = proc.returncode, proc.stdout, proc.stderr
        want = expected if cmd.lstrip().startswith("mechcirc") else 0
        if last != want:
            failures.append(f"{where}: `{cmd}` exited {last}, expected {want}\n"
                            f"{stderr[-1500:]}")
        elif compare:
            why = output_mismatch(shown, stdout + stderr)
            if why:
                failures.append(f"{where}: `{cmd}`: {why}")
    return failures


def _run_page(page: Path, tmp: Path, fixtures):
    bin_dir = _workdir(tmp)
    env = dict(os.environ, PYTHONPATH=str(REPO), MPLBACKEND="Agg",
               PATH=f"{bin_dir}{os.pathsep}{os.environ.get('PATH', '')}")
    namespace: dict = {"__name__": "__doc_example__"}
    failures = []
    # The test's monkeypatch owns the working directory: the example scripts run by
    # run_script chdir through it too, and it restores the original one at teardown
    # (an os.chdir back here would be undone by that teardown, leaving the worker in tmp).
    fixtures[1].chdir(tmp)
    try:
        for line, info, text, marks in blocks(page):
            kind = _kind(info, text, marks)
            where = f"{page.relative_to(REPO)}:{line}"
            if kind == "file":
                target = tmp / marks["file"]
                target.parent.mkdir(parents=True, exist_ok=True)
                target.write_text(text, encoding="utf-8")
                shipped = REPO / marks["file"]
                if shipped.exists() and shipped.read_text(encoding="utf-8") != text:
                    failures.append(f"{where}: the block differs from the shipped "
                                    f"{marks['file']}")
            elif kind == "python":
                try:
                    exec(compile(text, where, "exec"), namespace)
                except Exception as exc:   # noqa: BLE001 - reported per block
                    failures.append(f"{where}: {type(exc).__name__}: {exc}")
            elif kind == "doctest":
                test = doctest.DocTestParser().get_doctest(text, namespace, where, where, line)
                runner = doctest.DocTestRunner(optionflags=doctest.ELLIPSIS |
                                               doctest.NORMALIZE_WHITESPACE)
                report = []
                runner.run(test, out=report.append, clear_globs=False)
                namespace.update(test.globs)        # later blocks see its names
                if runner.failures:
                    failures.append(f"{where}: doctest failed\n" + "".join(report))
            elif kind == "shell":
                failures += _run_shell(text, marks, where, tmp, env, fixtures)
    finally:
        fixtures[1].undo()
    return failures


@pytest.mark.slow
@pytest.mark.parametrize("page", PAGES, ids=[p.name for p in PAGES])
def test_every_fenced_example_runs(page, tmp_path, capsys, monkeypatch):
    failures = _run_page(page, tmp_path, (capsys, monkeypatch))
    assert not failures, "\n\n".join(failures)


#: What a user of a clone reads besides the pages: the package's docstrings (the API
#: reference and help()), the examples, the bundled netlists and the docs' inputs.
READ_BY_USERS = PAGES + sorted(
    path
    for folder in ("mechcirc", "examples", "netlists", "docs/examples")
    for path in (REPO / folder).rglob("*")
    if path.suffix in (".py", ".mcir", ".toml", ".md")
)


def test_docs_stand_alone():
    """No link to ../shared or its digest (a clone has neither), no 'issue N' references."""
    for page in READ_BY_USERS:
        text = page.read_text(encoding="utf-8")
        assert "../shared" not in text and "DIGEST" not in text, page
        assert not re.search(r"\bissues? \d", text, re.I), (page, re.search(
            r".{0,40}\bissues? \d.{0,40}", text, re.I).group())


def test_relative_links_resolve():
    for page in PAGES:
        for target in re.findall(r"\]\(([^)#\s]+)(?:#[^)]*)?\)", page.read_text("utf-8")):
            if "://" in target:
                continue
            assert (page.parent / target).exists(), f"{page.name}: broken link {target}"


def _heading_anchors(text: str) -> set[str]:
    """The anchors GitHub gives a page's headings: lower case, characters other
    than letters, digits, ``_``, ``-`` and spaces dropped, spaces as ``-``; a
    repeated heading gets ``-1``, ``-2``, …  Headings inside fenced blocks are not
    headings."""
    seen: dict[str, int] = {}
    anchors = set()
    fenced = False
    for line in text.splitlines():
        if line.startswith("```"):
            fenced = not fenced
        m = None if fenced else re.match(r"#{1,6}\s+(.*?)\s*#*\s*$", line)
        if m:
            title = re.sub(r"\[([^\]]*)\]\([^)]*\)", r"\1", m.group(1)).replace("`", "")
            slug = re.sub(r"[^\w\- ]", "", title.replace("*", "").lower()).replace(" ", "-")
            n = seen.get(slug, 0)
            seen[slug] = n + 1
            anchors.add(slug if n == 0 else f"{slug}-{n}")
    return anchors


def test_links_reach_their_anchors():
    """A link ``page.md#anchor`` (or ``#anchor`` on the same page) names a heading
    that exists: a renamed heading must not leave links to nowhere."""
    checked = 0
    anchors: dict[Path, set[str]] = {}          # each page's headings read once
    for page in PAGES:
        text = page.read_text("utf-8")
        for target, anchor in re.findall(r"\]\(([^)#\s]*)#([^)\s]+)\)", text):
            dest = page if not target else page.parent / target
            if "://" in target or dest.suffix != ".md" or not dest.exists():
                continue
            checked += 1
            if dest not in anchors:
                anchors[dest] = _heading_anchors(dest.read_text("utf-8"))
            assert anchor in anchors[dest], (
                f"{page.name}: link to {target or page.name}#{anchor}, no such heading")
    assert checked > 50, checked       # the pattern still finds the docs' anchored links


def test_the_markers_are_known():
    for page in PAGES:
        for line in page.read_text("utf-8").splitlines():
            m = _MARK.match(line)
            if m:
                assert m.group(1) in ("file", "not-run", "exit", "output-varies"), (page, line)


@pytest.mark.parametrize("cmd, want", [
    ("mechcirc check a.mcir", (["check", "a.mcir"], None)),
    ("mechcirc check a.mcir | tail -1", (["check", "a.mcir"], ("tail", 1))),
    ("mechcirc check a.mcir | head -3", (["check", "a.mcir"], ("head", 3))),
    ("mechcirc check a.mcir | grep x", None),
    ("mechcirc check a.mcir | tail -1 | head -1", None),
    ("mechcirc check *.mcir | tail -1", None),
    ("cat a.mcir | tail -1", None),
])
def test_which_lines_run_in_process(cmd, want):
    assert _in_process(cmd) == want


@pytest.mark.parametrize("cmd, want", [
    ("python examples/heald_design.py", ["examples/heald_design.py"]),
    ("python examples/a.py --x 1", ["examples/a.py", "--x", "1"]),
    ("python benchmarks/bench_batch.py", None),
    ("python examples/a.py > out.txt", None),
    ("python -c 'print(1)'", None),
    ("mechcirc check a.mcir", None),
])
def test_which_example_lines_run_in_process(cmd, want):
    assert _example_argv(cmd) == want


def test_an_example_runs_in_process_in_the_pages_folder(tmp_path, capsys, monkeypatch):
    script = tmp_path / "examples" / "x.py"
    script.parent.mkdir()
    script.write_text("import os, sys\nprint('args', sys.argv[1:], os.getcwd())\n"
                      "print('note', file=sys.stderr)\nsys.exit(int(sys.argv[1]))\n")
    print("printed before")
    capsys.readouterr()
    status, out, err = run_script(script, ["3"], capsys, monkeypatch, cwd=tmp_path)
    assert (status, out, err) == (3, f"args ['3'] {tmp_path}\n", "note\n")


def test_head_and_tail_keep_the_lines_the_commands_keep():
    text = "a\nb\nc\n"
    for which, n in (("head", 2), ("tail", 2), ("tail", 1), ("head", 5), ("tail", 0)):
        shell = subprocess.run(["bash", "-c", f"printf 'a\\nb\\nc\\n' | {which} -{n}"],
                               capture_output=True, text=True, check=True).stdout
        assert _keep_lines(text, (which, n)) == shell, (which, n)


@pytest.mark.parametrize("shown, printed, ok", [
    (["K = 1.25 m/(N·s)"], "K = 1.2501 m/(N·s)\n", True),      # within one unit of 0.01
    (["K = 1.25 m/(N·s)"], "K = 1.27 m/(N·s)\n", False),
    (["K = 1.25 m/(N·s)"], "K = 1.25 N\n", False),             # the words differ
    (["3.4e-13"], "3.5e-13", True),
    (["0.6360572198528941"], "0.6360572198528951", True),     # 1.6e-15 relative
    (["0.6360572198528941"], "0.6360572208528941", False),    # 1.6e-9 relative
    (["3.4e-13"], "3.4e-12", False),
    (["a", "...", "z"], "a\nb\nc\nz\n", True),
    (["a", "z"], "a\nb\nz\n", False),
    (["dead centre ... so"], "dead centre -1e-17, so\n", True),
    (["dead centre ... so"], "dead center -1e-17, so\n", False),                         # a line missing from the shown
    (["a", "b", "c"], "a\nb\n", False),
    ([], "anything\n", True),                                  # nothing shown: nothing compared
])
def test_output_comparison(shown, printed, ok):
    assert (output_mismatch(shown, printed) is None) == ok
