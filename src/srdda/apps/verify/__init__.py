"""``srdda verify``: the verification cases, each against an independent reference (docs/verification.md).

A case is one function registered with :func:`case`; importing this package
registers every case (:mod:`.at_rest`, :mod:`.cases2d`, :mod:`.cases3d`, :mod:`.cases_quake`, :mod:`.cases_stages`,
:mod:`.contacts3d`, :mod:`.impacts`, :mod:`.fos`, :mod:`.water`).
"""
from .registry import (CASES, EXPECTED_SECONDS, Case, Row, UnknownCaseError, case, expected_seconds, get_case, row,
                       run_case)
from . import at_rest, cases2d, cases3d, cases_quake, cases_stages, contacts3d, fos, impacts, water  # noqa: F401  (registers every case)

__all__ = ["CASES", "Case", "Row", "UnknownCaseError", "case", "get_case", "row", "run_case", "expected_seconds",
           "EXPECTED_SECONDS"]
