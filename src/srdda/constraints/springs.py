"""Linear springs between two block points, with an optional dashpot.

Axial spring (``kind="axial"``): energy ½k(ℓ - ℓ0)², ℓ = |x_a - x_b|. It is
linearised about the configuration at t like every DDA spring (Shi 1988): the
stiffness k·n nᵀ along the unit direction n plus the geometric stiffness
(N/ℓ)(I - n nᵀ) of the current force N = k(ℓ - ℓ0) (kept only when N ≥ 0, in
tension, so the step matrix stays positive definite), force -N n.
Offset spring (``kind="offset"``): energy ½k|x_a - x_b - r0|², linear in the
relative displacement (the DDA point spring when r0 = 0).
Dashpot: force c·Δx_rel/Δt (the mean relative velocity over the step, along
n for an axial spring), matrix (c/Δt)·TᵀT; it dissipates c|Δx_rel|²/Δt per
step, which the energy ledger records.

Both use ``ctx.shape_at`` (T at t or the secant T_sec) and the scheme's
penalty weight c_p, like the other penalty-type terms.
"""
from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from ..assembly.system import PenaltyPairs, add_penalty_pairs
from .data import ConstraintArrays

if TYPE_CHECKING:
    from ..assembly.system import BlockSystem
    from ..simulation import StepContext

__all__ = ["SpringTerm", "spring_geometry", "spring_energy"]


def spring_geometry(links: ConstraintArrays, points: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Separation d = x_a - x_b (n, 2), length ℓ (n,) and unit direction n (n, 2) of every spring."""
    d = points[links.spring_rows_a] - points[links.spring_rows_b]
    length = np.linalg.norm(d, axis=1)
    unit = d / np.where(length > 0, length, 1.0)[:, None]
    return d, length, unit


def spring_energy(links: ConstraintArrays, points: np.ndarray) -> float:
    """Strain energy of all springs (J per m thickness)."""
    if not len(links.spring_rows_a):
        return 0.0
    d, length, _ = spring_geometry(links, points)
    stretch = np.where(links.spring_axial, length - links.spring_rest,
                       np.linalg.norm(d - links.spring_offset, axis=1))
    return 0.5 * float(np.sum(links.spring_stiffness * stretch**2))


class SpringTerm:
    """Adds every spring and dashpot to the step's system."""

    cuts_step = False  # linear in the step: converged after one solve

    def __init__(self, links: ConstraintArrays) -> None:
        self.links = links

    def add_to(self, system: BlockSystem, ctx: StepContext) -> None:
        links = self.links
        ra, rb = links.spring_rows_a, links.spring_rows_b
        points = ctx.state.points
        ba, bb = ctx.arrays.point_block[ra], ctx.arrays.point_block[rb]
        ta, tb = ctx.shape_at(ba, points[ra]), ctx.shape_at(bb, points[rb])
        d, length, unit = spring_geometry(links, points)
        k, c = links.spring_stiffness, links.spring_damping
        axial = links.spring_axial
        along = np.einsum("ni,nj->nij", unit, unit)
        across = np.eye(2) - along
        force = k * (length - links.spring_rest)
        geometric = np.where(axial & (force > 0), force / np.where(length > 0, length, 1.0), 0.0)
        eye = np.broadcast_to(np.eye(2), along.shape)
        # axial: k along n with gap (ℓ - ℓ0) n, geometric stiffness across n; offset: k in both directions
        proj = np.where(axial[:, None, None], along, eye)
        gap = np.where(axial[:, None], (length - links.spring_rest)[:, None] * unit, d - links.spring_offset)
        self._add(system, ba, proj @ ta, bb, proj @ tb, gap, k, ctx.coeffs.c_p)
        if np.any(geometric > 0):
            self._add(system, ba, across @ ta, bb, across @ tb, np.zeros_like(gap), geometric, ctx.coeffs.c_p)
        if np.any(c > 0):
            self._add(system, ba, proj @ ta, bb, proj @ tb, np.zeros_like(gap), c / ctx.dt, 1.0)

    @staticmethod
    def _add(system: BlockSystem, ba: np.ndarray, ta: np.ndarray, bb: np.ndarray, tb: np.ndarray,
             gap: np.ndarray, k: np.ndarray, factor: float) -> None:
        add_penalty_pairs(system, PenaltyPairs(ba, ta, bb, tb, gap, k), factor)

    def converged(self, dd: np.ndarray, ctx: StepContext) -> bool:
        return True
