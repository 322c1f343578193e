"""srdda.threads: numba's OpenMP threads sleep after a short spin unless the user says otherwise.

Two large runs at once took 150 times longer with libgomp's default spin
(docs/performance.md, "Two runs at once"); the setting is an environment
variable, so it is checked in a fresh interpreter.
"""
from __future__ import annotations

import os
import subprocess
import sys

import pytest

from srdda.threads import GOMP_SPIN_COUNT


@pytest.mark.parametrize("preset, expected", [(None, GOMP_SPIN_COUNT), ("7", "7")], ids=["default", "user's"])
def test_importing_srdda_sets_the_openmp_spin_unless_the_user_has(preset, expected):
    env = {k: v for k, v in os.environ.items() if k != "GOMP_SPINCOUNT"}
    if preset is not None:
        env["GOMP_SPINCOUNT"] = preset
    out = subprocess.run([sys.executable, "-c", "import os, srdda; print(os.environ['GOMP_SPINCOUNT'])"], env=env,
                         capture_output=True, text=True, check=True)
    assert out.stdout.strip() == expected
