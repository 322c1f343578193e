"""Prescribed motion of points by penalty, and base acceleration.

Prescribed motion: a point follows x_target(t) = x(0) + u(t) in its
prescribed components, u a displacement history or the time integral of a
velocity history (:class:`~srdda.history.TimeHistory`).
``by="multiplier"`` makes it exact through constraint rows
(:mod:`srdda.constraints.lagrange`); ``by="penalty"`` ties it to the moving
target by a spring of stiffness p in the prescribed components only (the
paper's way in 4.3: a penalty P on A and B). The penalty term is like a fixed
point whose position moves: matrix c_p·p·TᵀT, force -p·Tᵀ(x(t) - x_target(t_load)),
t_load the scheme's load time (the end of the step for shi and paper).

Base acceleration a_g(t) (a shaking table or an earthquake record, m/s²):
every block feels the body force -ρ·A·a_g(t_load) on its translation, the
d'Alembert force of a frame that moves with the ground; displacements are then
relative to the moving ground. Blocks marked fixed stay fixed (they are the
ground).
"""
from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from ..assembly.system import PenaltyPairs, add_penalty_pairs
from .data import ConstraintArrays
from .lagrange import prescribed_target

if TYPE_CHECKING:
    from ..assembly.system import BlockSystem
    from ..simulation import StepContext

__all__ = ["PrescribedPenaltyTerm", "BaseAccelerationTerm", "penalty_stiffness", "prescribed_penalty_energy"]


def penalty_stiffness(links: ConstraintArrays, penalty: float) -> np.ndarray:
    """Stiffness (n,) of every prescribed point (the run's penalty where none is given)."""
    return np.where(np.isnan(links.prescribed_stiffness), penalty, links.prescribed_stiffness)


def prescribed_penalty_energy(links: ConstraintArrays, initial_points: np.ndarray, points: np.ndarray,
                              t: float, penalty: float) -> float:
    """Energy ½p|gap|² of the penalty-driven points at time t (prescribed components only)."""
    pen = ~links.prescribed_multiplier
    if not np.any(pen):
        return 0.0
    gap = (points[links.prescribed_rows] - prescribed_target(links, initial_points, t)) * links.prescribed_mask
    k = penalty_stiffness(links, penalty)
    return 0.5 * float(np.sum(k[pen] * np.sum(gap[pen] ** 2, axis=1)))


class PrescribedPenaltyTerm:
    """Points driven by penalty springs to their moving targets."""

    cuts_step = False  # linear in the step: converged after one solve

    def __init__(self, links: ConstraintArrays) -> None:
        self.links = links
        self.pen = np.flatnonzero(~links.prescribed_multiplier)

    def add_to(self, system: BlockSystem, ctx: StepContext) -> None:
        links = self.links
        rows = links.prescribed_rows[self.pen]
        blocks = ctx.arrays.point_block[rows]
        mask = links.prescribed_mask[self.pen].astype(float)
        target = prescribed_target(links, ctx.arrays.points, ctx.t_load)[self.pen]
        t = ctx.shape_at(blocks, ctx.state.points[rows]) * mask[:, :, None]
        gap = (ctx.state.points[rows] - target) * mask
        k = penalty_stiffness(links, ctx.penalty)[self.pen]
        add_penalty_pairs(system, PenaltyPairs(blocks, t, np.full(len(rows), -1), None, gap, k), ctx.coeffs.c_p)

    def converged(self, dd: np.ndarray, ctx: StepContext) -> bool:
        return True


class BaseAccelerationTerm:
    """Body force -ρ·A·a_g(t) on the translation of every block."""

    cuts_step = False  # linear in the step: converged after one solve

    def __init__(self, links: ConstraintArrays) -> None:
        self.history = links.base_acceleration

    def add_to(self, system: BlockSystem, ctx: StepContext) -> None:
        mass = ctx.arrays.density * ctx.state.moments.area
        system.rhs[:, :2] -= mass[:, None] * self.history(ctx.t_load)

    def converged(self, dd: np.ndarray, ctx: StepContext) -> bool:
        return True
