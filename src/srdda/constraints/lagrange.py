"""Exact point constraints by Lagrange multipliers (paper Eqs. 72-75).

A hinge keeps point a of one block on point b of another:
x_a(t+Δt) = x_b(t+Δt), i.e. T_a·Δd_a - T_b·Δd_b = -(x_a - x_b)(t) (Eq. 72 with
a drift-closing right-hand side; the paper's right-hand side 0 is kept with
``correct_drift=False``). A pin is a hinge to the ground. A point driven by
multipliers asks T·Δd = x_target(t+Δt) - x(t) in its prescribed components.

The rows are added to the step's :class:`~srdda.assembly.BlockSystem`, which
is then solved as the saddle point [[A, Cᵀ], [C, 0]]·[Δd; μ] = [F; g]
(Eq. 73). T is ``ctx.shape_at``: Shi's T at t (dda0, dda1) or the secant
T_sec at the converged rotation increment (srdda), so under srdda and dda0 the
updated points satisfy the constraint to round-off, while dda1 (T at t,
exact-rotation update) leaves the separation of the paper's Table 5.

Multiplier layout in the step's μ: two rows (x, y) per hinge or pin, in
model order, then one row per prescribed component of the points driven by
multipliers. The constraint force on point a (on the block of the hinge's
first point, or on the driven block) is -μ, in N per metre of thickness.
"""
from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from .data import ConstraintArrays

if TYPE_CHECKING:
    from ..assembly.system import BlockSystem
    from ..simulation import StepContext

__all__ = ["LagrangeTerm", "prescribed_target"]


def prescribed_target(links: ConstraintArrays, initial_points: np.ndarray, t: float) -> np.ndarray:
    """Target positions (n, 2) of the prescribed points at time t."""
    return initial_points[links.prescribed_rows] + links.prescribed_displacement(t)


class LagrangeTerm:
    """Hinges, pins and multiplier-driven points as constraint rows of each step."""

    cuts_step = False  # linear in the step: converged after one solve

    def __init__(self, links: ConstraintArrays) -> None:
        self.links = links
        self.driven = np.flatnonzero(links.prescribed_multiplier)

    def add_to(self, system: BlockSystem, ctx: StepContext) -> None:
        links, arrays, points = self.links, ctx.arrays, ctx.state.points
        point_block = arrays.point_block
        if links.n_hinges:
            ra, rb = links.hinge_rows_a, links.hinge_rows_b
            bb = links.hinge_block_b
            linked = bb >= 0
            ta = ctx.shape_at(point_block[ra], points[ra])
            tb = ctx.shape_at(point_block[rb], points[rb])
            other = np.where(linked[:, None], points[rb], arrays.points[ra])  # pins: the point's start position
            rhs = np.where(links.hinge_correct[:, None], other - points[ra], 0.0)
            system.add_point_constraints(point_block[ra], ta, bb, tb, rhs)
        if len(self.driven):
            rows = links.prescribed_rows[self.driven]
            blocks = point_block[rows]
            target = prescribed_target(links, arrays.points, ctx.state.time + ctx.dt)[self.driven]
            t = ctx.shape_at(blocks, points[rows])
            system.add_point_constraints(blocks, t, np.full(len(rows), -1), None, target - points[rows],
                                         links.prescribed_mask[self.driven])

    def converged(self, dd: np.ndarray, ctx: StepContext) -> bool:
        return True
