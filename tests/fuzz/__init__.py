"""Fuzz harness of mechcirc (see docs/reliability.md).

``harness.py`` holds the generators and the properties; the short in-suite run
is ``tests/fuzz/test_fuzz.py`` and the long run ``long_run.py`` (not
collected by pytest).
"""
