"""Point loads: a force F(t) (a :class:`~srdda.history.TimeHistory`) at a block point.

The force enters the step as Tᵀ·F(t_load) on its block's unknowns, t_load the
scheme's load time, with the method's shape function (T at t or the secant
T_sec). Its work over a step, F(t_load)·Δx with Δx the exact displacement of
the point, goes to the ledger's ``work_loads``.
"""
from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from ..assembly.system import scatter_add
from ..term import LEDGER, StepContext, Term

if TYPE_CHECKING:
    from ..assembly.system import BlockSystem
    from ..modeldata.arrays import ModelArrays
    from ..state import State

__all__ = ["PointLoadTerm", "point_load_forces"]


def point_load_forces(arrays: ModelArrays, t: float) -> np.ndarray:
    """Forces (n_loads, dim) of every point load at time t."""
    return np.array([load(t) for load in arrays.attached.load_force]).reshape(len(arrays.attached.load_force), -1)


class PointLoadTerm(Term):
    """Every point load of the model."""

    @property
    def at_points(self) -> bool:
        return True

    def add_to(self, system: BlockSystem, ctx: StepContext) -> None:
        lr = ctx.arrays.attached.load_rows
        blocks = ctx.arrays.attached.point_block[lr]
        T = ctx.shape_at(blocks, ctx.state.points[lr])
        scatter_add(system.rhs, blocks, np.einsum("nki,nk->ni", T, point_load_forces(ctx.arrays, ctx.t_load)))

    def work(self, ctx: StepContext, new: State, dd: np.ndarray, multipliers: np.ndarray) -> np.ndarray | None:
        lr = ctx.arrays.attached.load_rows
        out = np.zeros(len(LEDGER))
        dx = new.points[lr] - ctx.state.points[lr]
        out[LEDGER.index("work_loads")] = float(np.sum(point_load_forces(ctx.arrays, ctx.t_load) * dx))
        return out
