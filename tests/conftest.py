"""Shared test configuration.

Property tests (hypothesis) are derandomized by default, so a run of the suite
is reproducible: CI and a developer see the same examples.  Set
``HYPOTHESIS_PROFILE=explore`` to draw fresh random examples (and keep a
database of failures) when hunting for new cases.
"""

import os

from hypothesis import settings

settings.register_profile("ci", derandomize=True, database=None)
settings.register_profile("explore", derandomize=False)
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "ci"))
