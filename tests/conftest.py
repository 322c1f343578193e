"""Test-suite configuration: hypothesis runs the same examples on every run.

``make test`` (and CI) uses the ``repeatable`` profile: derandomized, no
example database, so a pass or a failure is a property of the code and not of
the draw. ``HYPOTHESIS_PROFILE=explore`` searches fresh random examples (more
of them) for hunting new failures; any it finds is added to the test as an
explicit ``@example``.
"""
from __future__ import annotations

import os

from hypothesis import settings

settings.register_profile("repeatable", derandomize=True, database=None)
settings.register_profile("explore", max_examples=60, database=None)
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "repeatable"))
