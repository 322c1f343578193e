"""Constraints and driven boundaries: hinges and pins by Lagrange multipliers, springs with dashpots,
prescribed motion (penalty or multipliers), base acceleration, and the energy ledger.

``step_terms(arrays)`` gives the :class:`~srdda.simulation.StepTerm` objects a
model needs; the time loop adds them to every step. See docs/constraints.md.
"""
from __future__ import annotations

from typing import TYPE_CHECKING

from .data import ConstraintArrays, HingeSpec, PrescribedSpec, SpringSpec
from .energy import LEDGER, hinge_forces, link_energy, step_work
from ..history import HistoryError, MotionHistory
from .lagrange import LagrangeTerm
from .prescribed import BaseAccelerationTerm, PrescribedPenaltyTerm
from .springs import SpringTerm

if TYPE_CHECKING:
    from ..model import ModelArrays

__all__ = ["ConstraintArrays", "HingeSpec", "PrescribedSpec", "SpringSpec", "MotionHistory", "HistoryError",
           "LagrangeTerm", "SpringTerm", "PrescribedPenaltyTerm", "BaseAccelerationTerm", "LEDGER",
           "hinge_forces", "link_energy", "step_work", "step_terms"]


def step_terms(arrays: ModelArrays) -> list:
    """The step terms of the model's hinges, pins, springs, prescribed points and base acceleration."""
    links = arrays.links
    terms: list = []
    if links.n_hinges or links.prescribed_multiplier.any():
        terms.append(LagrangeTerm(links))
    if len(links.spring_rows_a):
        terms.append(SpringTerm(links))
    if (~links.prescribed_multiplier).any():
        terms.append(PrescribedPenaltyTerm(links))
    if links.base_acceleration is not None:
        terms.append(BaseAccelerationTerm(links))
    return terms
