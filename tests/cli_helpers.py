"""Running the command line in-process, for tests (``from cli_helpers import run``)."""

from __future__ import annotations

from mechcirc.cli import main


def run(argv, capsys):
    """(status, stdout, stderr) of the CLI in-process; argparse's exits count as statuses."""
    try:
        status = main([str(a) for a in argv])
    except SystemExit as exc:
        status = exc.code
    out, err = capsys.readouterr()
    return status, out, err


def assert_user_error(argv, capsys, *needles):
    """The command exits 2 with one line on stderr holding every needle; returns the line."""
    status, out, err = run(argv, capsys)
    assert status == 2, (status, err)
    lines = err.strip().splitlines()
    assert len(lines) == 1, err                        # one line, no warnings before it
    assert "internal error" not in err and "Traceback" not in err
    for needle in needles:
        assert needle in err, err
    return err


def assert_cam_key_error(text, key, needles, tmp_path, capsys):
    """A scene whose ``[cam]`` table is bad at ``key``: ``parse_scene`` raises a located
    NetlistError at that key's line inside ``[cam]`` holding every needle, and
    ``mechcirc scene`` on the file exits 2 saying the same."""
    import pytest

    from mechcirc.errors import NetlistError
    from mechcirc.scene import parse_scene

    with pytest.raises(NetlistError) as exc:
        parse_scene(text, "bad.toml")
    lines = text.splitlines()
    cam = lines.index("[cam]")
    line = next(i for i, ln in enumerate(lines[cam:], cam + 1) if ln.startswith(key + " ="))
    assert exc.value.line == line, str(exc.value)
    for n in needles:
        assert n in str(exc.value), str(exc.value)
    f = tmp_path / "bad.toml"
    f.write_text(text)
    assert_user_error(["scene", f, "--theta", "60"], capsys, "bad.toml:", *needles)


def run_script(path, argv, capsys, monkeypatch, cwd=None):
    """(status, stdout, stderr) of ``python PATH ARGV`` run in this process.

    The script runs as ``__main__`` from ``cwd`` (by default the repository
    root, its working directory in the tests), with ``sys.argv`` set: what the interpreter does,
    without its start-up and the imports of numpy, scipy and the numba cache
    (about 0.5-1 s of CPU per script).  Warnings the script raises are printed
    to stderr as the interpreter would show them (deprecations only from the
    script itself), so a test can still require an empty stderr.
    """
    import runpy
    import sys
    import warnings
    from pathlib import Path

    path = Path(path)
    monkeypatch.chdir(path.resolve().parents[1] if cwd is None else cwd)
    monkeypatch.setattr(sys, "argv", [str(path), *map(str, argv)])
    monkeypatch.syspath_prepend(str(path.parent))        # as the interpreter puts it first
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            runpy.run_path(str(path), run_name="__main__")
            status = 0
        except SystemExit as exc:
            status = 0 if exc.code is None else exc.code
    out, err = capsys.readouterr()
    for w in caught:
        if (issubclass(w.category, (DeprecationWarning, PendingDeprecationWarning))
                and Path(w.filename).resolve() != path.resolve()):
            continue
        err += warnings.formatwarning(w.message, w.category, w.filename, w.lineno)
    return status, out, err
