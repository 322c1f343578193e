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

from ..term import LEDGER, StepContext, Term
from .data import ConstraintArrays

if TYPE_CHECKING:
    from ..assembly.system import BlockSystem
    from ..state import State

__all__ = ["LagrangeTerm", "prescribed_target", "hinge_forces"]


def prescribed_target(links: ConstraintArrays, initial_points: np.ndarray, t: float) -> np.ndarray:
    """Target positions (n, 2) of the prescribed points at time t."""
    return initial_points[links.prescribed_rows] + links.prescribed_displacement(t)


def hinge_forces(links: ConstraintArrays, multipliers: np.ndarray) -> np.ndarray:
    """Force (n_hinges, dim) on the first point of every hinge or pin (N per m thickness in 2D)."""
    return -np.asarray(multipliers)[: links.n_hinges * links.dim].reshape(links.n_hinges, links.dim)


class LagrangeTerm(Term):
    """Hinges, pins and multiplier-driven points as constraint rows of each step (linear: one solve)."""

    def __init__(self, links: ConstraintArrays) -> None:
        self.links = links
        self.driven = np.flatnonzero(links.prescribed_multiplier)

    @property
    def at_points(self) -> bool:
        return True

    def add_to(self, system: BlockSystem, ctx: StepContext) -> None:
        links, arrays, points = self.links, ctx.arrays, ctx.state.points
        point_block = arrays.attached.point_block
        if links.n_hinges:
            ra, rb = links.hinge_rows_a, links.hinge_rows_b
            bb = links.hinge_block_b
            linked = bb >= 0
            ta = ctx.shape_at(point_block[ra], points[ra])
            tb = ctx.shape_at(point_block[rb], points[rb])
            start = arrays.attached.point_position[ra]
            other = np.where(linked[:, None], points[rb], start)  # pins: the point's start position
            rhs = np.where(links.hinge_correct[:, None], other - points[ra], 0.0)
            system.add_point_constraints(point_block[ra], ta, bb, tb, rhs)
        if len(self.driven):
            rows = links.prescribed_rows[self.driven]
            blocks = point_block[rows]
            target = prescribed_target(links, arrays.attached.point_position, ctx.state.time + ctx.dt)[self.driven]
            t = ctx.shape_at(blocks, points[rows])
            system.add_point_constraints(blocks, t, np.full(len(rows), -1), None, target - points[rows],
                                         links.prescribed_mask[self.driven])

    def work(self, ctx: StepContext, new: State, dd: np.ndarray, multipliers: np.ndarray) -> np.ndarray | None:
        """Hinge and pin forces (-μ·Δx_rel: zero for an exactly kept hinge); drivers (-μ·Δx)."""
        links = self.links
        dx = new.points - ctx.state.points
        out = np.zeros(len(LEDGER))
        nh, dim = links.n_hinges, links.dim
        if nh:
            mu = np.asarray(multipliers[: nh * dim]).reshape(nh, dim)
            rel = dx[links.hinge_rows_a] - np.where((links.hinge_block_b >= 0)[:, None], dx[links.hinge_rows_b], 0.0)
            out[LEDGER.index("work_constraints")] -= float(np.sum(mu * rel))
        if len(self.driven):
            mask = links.prescribed_mask[self.driven]
            mu = np.asarray(multipliers[nh * dim: nh * dim + int(mask.sum())])
            out[LEDGER.index("work_prescribed")] -= float(np.sum(mu * dx[links.prescribed_rows[self.driven]][mask]))
        return out
