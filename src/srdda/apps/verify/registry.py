"""The registry of verification cases and the rows they report.

A case runs models and compares what they give with an independent reference
(a closed form, or an ODE of the same body solved by scipy). It is one
decorated function::

    @case("free-spin-2d", dim=2, methods=("dda0", "dda1", "srdda"),
          description="a block spinning in free flight keeps ω and its area")
    def free_spin_2d(methods, quick):
        ...
        return [row("free-spin-2d", "omega", "srdda", ours, 1.0, tolerance=1e-10), ...]

The function receives the methods to run (those of the case, or fewer) and
``quick`` (True: a shorter run whose tolerances still hold; only for cases
registered with ``quick=True``, the others get False). Each tolerance is
defined beside its case with a comment saying what it measures.
"""
from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

from ...integrators.methods import METHODS, MethodName

__all__ = ["Case", "CASES", "Row", "case", "row", "run_case", "UnknownCaseError", "expected_seconds",
           "EXPECTED_SECONDS"]

Row = dict[str, Any]
CaseFunction = Callable[[tuple[MethodName, ...], bool], list[Row]]


@dataclass(frozen=True)
class Case:
    """One verification case: its name on the command line, its dimension, what it checks, how."""

    name: str
    dim: int
    description: str  # one line
    methods: tuple[MethodName, ...]  # the methods the case is meaningful for
    run: CaseFunction
    quick: bool  # True: ``--quick`` runs it shorter with the same tolerances


CASES: dict[str, Case] = {}


class UnknownCaseError(KeyError):
    """A case name that is not registered (the message lists the registered ones)."""

    def __str__(self) -> str:
        return str(self.args[0])


def case(name: str, dim: int, description: str, methods: Sequence[MethodName] = METHODS,
         quick: bool = False) -> Callable[[CaseFunction], CaseFunction]:
    """Register the decorated function as the verification case ``name``."""
    if name in CASES:
        raise ValueError(f"verification case {name!r} is registered twice")
    if dim not in (2, 3):
        raise ValueError(f"verification case {name!r}: dim must be 2 or 3, got {dim}")
    unknown = set(methods) - set(METHODS)
    if unknown:
        raise ValueError(f"verification case {name!r}: unknown methods {sorted(unknown)}")

    def register(function: CaseFunction) -> CaseFunction:
        CASES[name] = Case(name, dim, description, tuple(methods), function, quick)
        return function

    return register


def get_case(name: str) -> Case:
    if name not in CASES:
        raise UnknownCaseError(f"unknown verification case {name!r}; the cases are: {', '.join(CASES)}")
    return CASES[name]


def row(case_name: str, quantity: str, method: str, ours: float, reference: float,
        tolerance: float | None) -> Row:
    """A compared quantity: relative error |ours - reference| / |reference|, absolute where the reference is 0.

    ``tolerance`` None makes an information row (reported, never failed): ``passed`` is None.
    """
    ours, reference = float(ours), float(reference)
    measure = "absolute" if reference == 0.0 else "relative"
    error = abs(ours - reference) if measure == "absolute" else abs(ours - reference) / abs(reference)
    passed = None if tolerance is None else bool(math.isfinite(error) and error <= tolerance)
    return {"case": case_name, "quantity": quantity, "method": method, "ours": ours, "reference": reference,
            "rel_error": error, "measure": measure, "tolerance": tolerance, "passed": passed}


def run_case(name: str, quick: bool = False, methods: Sequence[str] | None = None) -> list[Row]:
    """Run the case ``name`` (all its methods, or ``methods``) and return its rows."""
    c = get_case(name)
    chosen = c.methods if methods is None else tuple(m for m in c.methods if m in methods)
    return c.run(chosen, quick and c.quick)


# Wall seconds of each case on the reference machine (the project's 2 shared cores, 2026-11-26, one
# `srdda verify --quick` and the quick cases alone without it), (with --quick, without): the estimate that
# `srdda verify`'s progress bar scales by this machine's speed. A case missing here (a new one) counts
# as the median of the others.
EXPECTED_SECONDS: dict[str, tuple[float, float]] = {
    "free-spin-2d": (3.0, 14.4),
    "free-fall-2d": (2.9, 15.9),
    "incline-2d": (17.5, 17.5),
    "pendulum-2d": (54.2, 54.2),
    "spring-mass-2d": (8.2, 8.2),
    "hinge-gap-2d": (5.1, 5.1),
    "uniaxial-2d": (0.4, 0.4),
    "spin-3d": (3.9, 18.2),
    "intermediate-axis-3d": (58.8, 58.8),
    "extruded-rod-3d": (35.9, 35.9),
    "extruded-pendulum-3d": (24.2, 24.2),
    "conical-pendulum-3d": (28.7, 28.7),
    "uniaxial-3d": (0.2, 0.2),
    "newmark": (33.2, 33.2),
    "bolted-block": (12.2, 12.2),
    "incline-3d": (26.2, 26.2),
    "corner-pairs-3d": (0.5, 0.5),
    "drop-3d": (7.4, 7.4),
    "extruded-incline-3d": (42.1, 42.1),
    "slide-topple-3d": (33.6, 33.6),
    "wedge-3d": (43.2, 43.2),
    "at-rest-2d": (50.0, 50.0),
    "stage-column-2d": (0.4, 0.4),  # measured 2026-11-26 (the machine otherwise idle)
    "stage-column-3d": (0.4, 0.4),
    "stage-excavation-2d": (0.2, 0.2),
    "stage-excavation-3d": (0.1, 0.1),
    "stage-wedge-cut-3d": (2.4, 2.4),
    "at-rest-3d": (45.0, 45.0),
    "impact-restitution-2d": (6.0, 26.2),
    "impact-restitution-3d": (7.4, 26.4),
    "fos-plane-2d": (4.1, 4.1),
    "fos-wedge-3d": (9.7, 9.7),
    "fos-plane-wet-2d": (3.4, 3.4),  # measured 2026-11-26 on the branch that added them (4 agents on 2 cores)
    "fos-wedge-wet-3d": (7.1, 7.1),
    "water-plane-2d": (10.0, 10.0),  # measured 2026-11-26 on the branch that added them (4 agents on 2 cores)
    "water-plane-3d": (21.8, 21.8),
    "water-uplift-2d": (1.4, 1.4),
    "water-uplift-3d": (1.2, 1.2),
}


def expected_seconds(name: str, quick: bool) -> float:
    """The wall seconds the case ``name`` took on the reference machine (:data:`EXPECTED_SECONDS`)."""
    if name in EXPECTED_SECONDS:
        return EXPECTED_SECONDS[name][0 if quick else 1]
    known = sorted(t[0 if quick else 1] for t in EXPECTED_SECONDS.values())
    return known[len(known) // 2] if known else 1.0
