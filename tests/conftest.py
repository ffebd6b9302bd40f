"""Shared test configuration.

Property tests (hypothesis) are derandomized by default, so a run of the suite
is reproducible: CI and a developer see the same examples.  Set
``HYPOTHESIS_PROFILE=explore`` to draw fresh random examples (and keep a
database of failures) when hunting for new cases.
"""

import os

import pytest
from hypothesis import settings

settings.register_profile("ci", derandomize=True, database=None)
settings.register_profile("explore", derandomize=False)
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "ci"))


@pytest.fixture(scope="session")
def cli_once():
    """``cli_once(argv)``: (status, stdout, stderr) of ``mechcirc ARGV`` in-process, run once.

    For long commands (a full ``crosscheck``) that several test files check
    with the same argv: the first caller runs it, the others read the same
    output.  Only for commands that read shipped inputs and nothing a test
    patches (no ``monkeypatch`` in effect while it runs).
    """
    import contextlib
    import io

    from mechcirc.cli import main

    done: dict[tuple[str, ...], tuple[int, str, str]] = {}

    def run(argv):
        key = tuple(map(str, argv))
        if key not in done:
            out, err = io.StringIO(), io.StringIO()
            with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
                try:
                    status = main(list(key))
                except SystemExit as exc:
                    status = exc.code
            done[key] = (status, out.getvalue(), err.getvalue())
        return done[key]

    return run
