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
