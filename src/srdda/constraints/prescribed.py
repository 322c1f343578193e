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
from ..term import LEDGER, StepContext, Term
from .data import ConstraintArrays
from .lagrange import prescribed_target

if TYPE_CHECKING:
    from ..assembly.system import BlockSystem
    from ..modeldata.arrays import ModelArrays
    from ..state import State

__all__ = ["PrescribedPenaltyTerm", "BaseAccelerationTerm", "penalty_stiffness"]


def penalty_stiffness(links: ConstraintArrays, penalty: float) -> np.ndarray:
    """Stiffness (n,) of every prescribed point (the run's penalty where none is given)."""
    return np.where(np.isnan(links.prescribed_stiffness), penalty, links.prescribed_stiffness)


class PrescribedPenaltyTerm(Term):
    """Points driven by penalty springs to their moving targets."""

    energy_kind = "spring"

    def __init__(self, links: ConstraintArrays, penalty: float) -> None:
        self.links = links
        self.pen = np.flatnonzero(~links.prescribed_multiplier)
        self.stiffness = penalty_stiffness(links, penalty)[self.pen]

    @property
    def at_points(self) -> bool:
        return True

    def _gap(self, initial_points: np.ndarray, points: np.ndarray, t: float) -> np.ndarray:
        links = self.links
        rows = links.prescribed_rows[self.pen]
        target = prescribed_target(links, initial_points, t)[self.pen]
        return (points[rows] - target) * links.prescribed_mask[self.pen]

    def add_to(self, system: BlockSystem, ctx: StepContext) -> None:
        rows = self.links.prescribed_rows[self.pen]
        blocks = ctx.arrays.attached.point_block[rows]
        mask = self.links.prescribed_mask[self.pen].astype(float)
        t = ctx.shape_at(blocks, ctx.state.points[rows]) * mask[:, :, None]
        gap = self._gap(ctx.arrays.attached.point_position, ctx.state.points, ctx.t_load)
        add_penalty_pairs(system, PenaltyPairs(blocks, t, np.full(len(rows), -1), None, gap, self.stiffness),
                          ctx.coeffs.c_p)

    def energy(self, arrays: ModelArrays, state: State) -> float:
        """½p|gap|² in the prescribed components."""
        gap = self._gap(arrays.attached.point_position, state.points, state.time)
        return 0.5 * float(np.sum(self.stiffness * np.sum(gap**2, axis=1)))

    def work(self, ctx: StepContext, new: State, dd: np.ndarray, multipliers: np.ndarray) -> np.ndarray | None:
        """Work of the moving anchors on their springs: -p·g_mid·Δx_target, g_mid the mean gap."""
        links, pen = self.links, self.pen
        a0 = prescribed_target(links, ctx.arrays.attached.point_position, ctx.state.time)[pen]
        a1 = prescribed_target(links, ctx.arrays.attached.point_position, new.time)[pen]
        rows = links.prescribed_rows[pen]
        g_mid = 0.5 * ((ctx.state.points[rows] - a0) + (new.points[rows] - a1)) * links.prescribed_mask[pen]
        out = np.zeros(len(LEDGER))
        out[LEDGER.index("work_prescribed")] -= float(np.sum(self.stiffness[:, None] * g_mid * (a1 - a0)))
        return out


class BaseAccelerationTerm(Term):
    """Body force -m·a_g(t) on the translation of every block; its work goes to ``work_loads``."""

    same_every_solve = True

    def __init__(self, links: ConstraintArrays) -> None:
        assert links.base_acceleration is not None  # the term of a model with a base acceleration
        self.history = links.base_acceleration

    def add_to(self, system: BlockSystem, ctx: StepContext) -> None:
        mass = ctx.arrays.block_mass
        system.rhs[:, ctx.block_type.translation] -= mass[:, None] * self.history(ctx.t_load)

    def work(self, ctx: StepContext, new: State, dd: np.ndarray, multipliers: np.ndarray) -> np.ndarray | None:
        mass = ctx.arrays.block_mass
        out = np.zeros(len(LEDGER))
        shift = dd[:, ctx.block_type.translation]
        out[LEDGER.index("work_loads")] -= float(np.sum(mass[:, None] * self.history(ctx.t_load)[None, :] * shift))
        return out
