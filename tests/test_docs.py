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
  redirection or expansion) runs in this process with the same argv and
  working directory (``mechcirc.cli.main``, as ``python -m mechcirc`` does;
  it saves the interpreter start-up of every line), any other line in
  ``bash -o pipefail``, which sees the previous status as ``$?`` (``echo $?``;
  each line is its own ``bash``, so ``cd`` or a variable does not carry over);
  each ``mechcirc`` command must exit 0, or the status of an
  ``<!-- exit: N -->`` marker; other commands (``cat``, ``head``) must exit 0.
  Real start-up, exit codes and signals of the ``mechcirc`` script are
  tested by subprocess in ``tests/test_cli.py``, ``tests/test_cli_common.py``
  and ``tests/test_outputs.py``.
  The lines after a command are its output as shown and are not compared
  (numbers move with the last digit of a library).
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


def _run_shell(text, marks, where, tmp, env):
    """Run a block's ``$`` commands in order, as one shell session would.

    A plain ``mechcirc ...`` line (no pipe, redirection or expansion) runs
    in-process with the same argv and working directory (:func:`run_mechcirc`);
    any other line runs in ``bash`` (``set -o pipefail``), which sees the last
    status as ``$?`` (``echo $?``).
    """
    expected = int(marks.get("exit", "0") or 0)
    # Benchmarks measure time, they do not check anything, and take minutes: the
    # pages show their command and output, the test does not run them.
    cmds = [c for c in _commands(text) if not c.lstrip().startswith("python benchmarks/")]
    failures, last = [], 0
    for cmd in cmds:
        argv = _in_process_argv(cmd)
        if argv is not None:
            last, _, stderr = run_mechcirc(argv)
        else:
            proc = subprocess.run(["bash", "-c", f"set -o pipefail\n(exit {last})\n{cmd}"],
                                  cwd=tmp, env=env, capture_output=True, text=True,
                                  timeout=SUBPROCESS_TIMEOUT)
            last, stderr = proc.returncode, proc.stderr
        want = expected if cmd.lstrip().startswith("mechcirc") else 0
        if last != want:
            failures.append(f"{where}: `{cmd}` exited {last}, expected {want}\n"
                            f"{stderr[-1500:]}")
    return failures


def _run_page(page: Path, tmp: Path):
    bin_dir = _workdir(tmp)
    env = dict(os.environ, PYTHONPATH=str(REPO), MPLBACKEND="Agg",
               PATH=f"{bin_dir}{os.pathsep}{os.environ.get('PATH', '')}")
    namespace: dict = {"__name__": "__doc_example__"}
    failures = []
    old = Path.cwd()
    os.chdir(tmp)
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
                failures += _run_shell(text, marks, where, tmp, env)
    finally:
        os.chdir(old)
    return failures


@pytest.mark.slow
@pytest.mark.parametrize("page", PAGES, ids=[p.name for p in PAGES])
def test_every_fenced_example_runs(page, tmp_path):
    failures = _run_page(page, tmp_path)
    assert not failures, "\n\n".join(failures)


def test_docs_stand_alone():
    """No link to ../shared (a clone does not have it), no 'issue N' references."""
    for page in PAGES:
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


def test_the_markers_are_known():
    for page in PAGES:
        for line in page.read_text("utf-8").splitlines():
            m = _MARK.match(line)
            if m:
                assert m.group(1) in ("file", "not-run", "exit"), (page, line)
