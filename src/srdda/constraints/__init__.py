"""Constraints and driven boundaries: fixed points, point loads, springs with dashpots, hinges and pins by
Lagrange multipliers, prescribed motion (penalty or multipliers), base acceleration, rock bolts, the water in
the joints and tension cracks (:mod:`.water`).

``point_terms(arrays, penalty)`` gives the step terms (:class:`srdda.term.Term`)
a model's points need. See docs/constraints.md.
"""
from __future__ import annotations

from typing import TYPE_CHECKING

from ..history import HistoryError, MotionHistory
from ..term import Term
from .bolts import BoltTerm, bolt_forces
from .data import BoltSpec, ConstraintArrays, HingeSpec, PrescribedSpec, SpringSpec
from .lagrange import LagrangeTerm, hinge_forces
from .loads import PointLoadTerm
from .prescribed import BaseAccelerationTerm, PrescribedPenaltyTerm
from .springs import SpringTerm
from .water import WaterCrackTerm

if TYPE_CHECKING:
    from ..modeldata.arrays import ModelArrays

__all__ = ["ConstraintArrays", "HingeSpec", "PrescribedSpec", "SpringSpec", "BoltSpec", "BoltTerm", "bolt_forces", "MotionHistory", "HistoryError",
           "LagrangeTerm", "SpringTerm", "PointLoadTerm", "WaterCrackTerm", "PrescribedPenaltyTerm", "BaseAccelerationTerm",
           "hinge_forces", "point_terms"]


def point_terms(arrays: ModelArrays, penalty: float) -> list[Term]:
    """The terms of the model's fixed points, springs, loads, hinges, driven points, base acceleration, bolts and
    the water in its tension cracks."""
    links = arrays.links
    terms: list[Term] = []
    if len(arrays.attached.fixed_rows) or len(arrays.attached.point_spring_rows_a) or len(links.spring_rows_a):
        terms.append(SpringTerm(penalty))
    if len(arrays.attached.load_rows):
        terms.append(PointLoadTerm())
    if links.n_hinges or links.prescribed_multiplier.any():
        terms.append(LagrangeTerm(links))
    if (~links.prescribed_multiplier).any():
        terms.append(PrescribedPenaltyTerm(links, penalty))
    if links.base_acceleration is not None:
        terms.append(BaseAccelerationTerm(links))
    if links.n_bolts:
        terms.append(BoltTerm(links))
    if arrays.water is not None and arrays.water.cracks:
        terms.append(WaterCrackTerm(arrays))
    return terms
