"""Fuzz harness of mechcirc (see docs/reliability.md).

``harness.py`` holds the generators and the properties; the short in-suite run
is ``tests/test_reliability_fuzz.py`` and the long run ``long_run.py`` (not
collected by pytest).
"""
