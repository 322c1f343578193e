"""Point springs: fixed points, zero-length point springs and linear springs with dashpots.

All three are penalty springs between two block points (or a block point and
the ground), added by one route (:func:`srdda.assembly.system.add_penalty_pairs`)
and with one energy:

* fixed point: energy ½k|x - x(0)|², a point pulled back to where it started
  (k: the point's stiffness, else the run's penalty; Shi 1988);
* point spring: ½k|x_a - x_b|², two points tied together (Shi's point spring);
* axial spring (``kind="axial"``): ½k(ℓ - ℓ0)², ℓ = |x_a - x_b|, linearised
  about the configuration at t like every DDA spring: stiffness k·n nᵀ along the
  unit direction n plus the geometric stiffness (N/ℓ)(I - n nᵀ) of the current
  force N = k(ℓ - ℓ0) (kept only in tension, N ≥ 0, so the step matrix stays
  positive definite);
* offset spring (``kind="offset"``): ½k|x_a - x_b - r0|², linear in the
  relative displacement;
* dashpot: force c·Δx_rel/Δt (the mean relative velocity over the step, along
  n for an axial spring), matrix (c/Δt)·TᵀT; it dissipates c|Δx_rel|²/Δt per
  step, which the energy ledger records.

Shape functions are ``ctx.shape_at`` (T at t or the secant T_sec), with the
scheme's penalty weight c_p.
"""
from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from ..assembly.system import PenaltyPairs, add_penalty_pairs
from ..term import LEDGER, StepContext, Term
from .data import ConstraintArrays

if TYPE_CHECKING:
    from ..assembly.system import BlockSystem
    from ..modeldata.arrays import ModelArrays
    from ..state import State

__all__ = ["SpringTerm", "spring_geometry", "spring_energy", "fixed_point_stiffness"]


def spring_geometry(links: ConstraintArrays, points: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Separation d = x_a - x_b (n, dim), length ℓ (n,) and unit direction n (n, dim) of every spring."""
    d = points[links.spring_rows_a] - points[links.spring_rows_b]
    length = np.linalg.norm(d, axis=1)
    unit = d / np.where(length > 0, length, 1.0)[:, None]
    return d, length, unit


def fixed_point_stiffness(arrays: ModelArrays, penalty: float) -> np.ndarray:
    """Stiffness (nf,) of every fixed point: its own, else the run's penalty."""
    return np.where(np.isnan(arrays.attached.fixed_stiffness), penalty, arrays.attached.fixed_stiffness)


def spring_energy(arrays: ModelArrays, points: np.ndarray, penalty: float) -> float:
    """Strain energy of the fixed points, point springs and springs at ``points``."""
    energy = 0.0
    attached = arrays.attached
    fr = attached.fixed_rows
    if len(fr):
        k = fixed_point_stiffness(arrays, penalty)
        energy += 0.5 * float(np.sum(k * np.sum((points[fr] - attached.point_position[fr]) ** 2, axis=1)))
    if len(attached.point_spring_rows_a):
        gap = points[attached.point_spring_rows_a] - points[attached.point_spring_rows_b]
        energy += 0.5 * float(np.sum(attached.point_spring_stiffness * np.sum(gap**2, axis=1)))
    links = arrays.links
    if len(links.spring_rows_a):
        d, length, _ = spring_geometry(links, points)
        stretch = np.where(links.spring_axial, length - links.spring_rest,
                           np.linalg.norm(d - links.spring_offset, axis=1))
        energy += 0.5 * float(np.sum(links.spring_stiffness * stretch**2))
    return energy


class SpringTerm(Term):
    """Every fixed point, point spring, spring and dashpot of the model."""

    energy_kind = "spring"

    def __init__(self, penalty: float) -> None:
        self.penalty = penalty  # stiffness of fixed points that give none

    @property
    def at_points(self) -> bool:
        return True

    def add_to(self, system: BlockSystem, ctx: StepContext) -> None:
        arrays, attached, points, c_p = ctx.arrays, ctx.arrays.attached, ctx.state.points, ctx.coeffs.c_p
        pb = attached.point_block
        fr = attached.fixed_rows
        if len(fr):
            gap = points[fr] - attached.point_position[fr]  # pull back to the original position
            add_penalty_pairs(system, PenaltyPairs(pb[fr], ctx.shape_at(pb[fr], points[fr]), np.full(len(fr), -1),
                                                   None, gap, fixed_point_stiffness(arrays, self.penalty)), c_p)
        ra, rb = attached.point_spring_rows_a, attached.point_spring_rows_b
        if len(ra):
            add_penalty_pairs(system, PenaltyPairs(pb[ra], ctx.shape_at(pb[ra], points[ra]), pb[rb],
                                                   ctx.shape_at(pb[rb], points[rb]), points[ra] - points[rb],
                                                   attached.point_spring_stiffness), c_p)
        if len(arrays.links.spring_rows_a):
            self._add_springs(system, ctx)

    @staticmethod
    def _add_springs(system: BlockSystem, ctx: StepContext) -> None:
        links = ctx.arrays.links
        ra, rb = links.spring_rows_a, links.spring_rows_b
        points = ctx.state.points
        ba, bb = ctx.arrays.attached.point_block[ra], ctx.arrays.attached.point_block[rb]
        ta, tb = ctx.shape_at(ba, points[ra]), ctx.shape_at(bb, points[rb])
        d, length, unit = spring_geometry(links, points)
        k, c = links.spring_stiffness, links.spring_damping
        axial = links.spring_axial
        along = np.einsum("ni,nj->nij", unit, unit)
        eye = np.broadcast_to(np.eye(unit.shape[1]), along.shape)
        across = eye - along
        force = k * (length - links.spring_rest)
        geometric = np.where(axial & (force > 0), force / np.where(length > 0, length, 1.0), 0.0)
        # axial: k along n with gap (ℓ - ℓ0) n, geometric stiffness across n; offset: k in every direction
        proj = np.where(axial[:, None, None], along, eye)
        gap = np.where(axial[:, None], (length - links.spring_rest)[:, None] * unit, d - links.spring_offset)
        c_p = ctx.coeffs.c_p
        add_penalty_pairs(system, PenaltyPairs(ba, proj @ ta, bb, proj @ tb, gap, k), c_p)
        if np.any(geometric > 0):
            add_penalty_pairs(system, PenaltyPairs(ba, across @ ta, bb, across @ tb, np.zeros_like(gap), geometric),
                              c_p)
        if np.any(c > 0):
            add_penalty_pairs(system, PenaltyPairs(ba, proj @ ta, bb, proj @ tb, np.zeros_like(gap), c / ctx.dt),
                              1.0)

    def energy(self, arrays: ModelArrays, state: State) -> float:
        return spring_energy(arrays, state.points, self.penalty)

    def work(self, ctx: StepContext, new: State, dd: np.ndarray, multipliers: np.ndarray) -> np.ndarray | None:
        """Dashpots' dissipation (``dissipated``) and what the springs' step force took out (``dissipated_springs``).

        The springs act on the blocks with -k(g + c_p·Δg), Δg the linearised
        change T·Δd of their stretch: their work minus the change of their stored
        energy is what the step's spring force took out, ½k|Δg|² per step with
        c_p = 1 (the schemes of the paper), or what a point update that differs
        from T·Δd (dda1's post-adjusted rotations) put into them (negative).
        """
        arrays, attached, links = ctx.arrays, ctx.arrays.attached, ctx.arrays.links
        if not (len(attached.fixed_rows) or len(attached.point_spring_rows_a) or len(links.spring_rows_a)):
            return None
        out = np.zeros(len(LEDGER))
        points, pb, c_p = ctx.state.points, attached.point_block, ctx.coeffs.c_p

        def moved(rows: np.ndarray) -> np.ndarray:  # T·Δd of the points ``rows`` (n, dim)
            return np.einsum("nki,ni->nk", ctx.shape_at(pb[rows], points[rows]), dd[pb[rows]])

        def step_work(k: np.ndarray, gap: np.ndarray, dg: np.ndarray) -> float:
            return -float(np.sum(k[:, None] * (gap + c_p * dg) * dg))

        work = 0.0
        fr = attached.fixed_rows
        if len(fr):
            work += step_work(fixed_point_stiffness(arrays, self.penalty), points[fr] - attached.point_position[fr],
                              moved(fr))
        ra, rb = attached.point_spring_rows_a, attached.point_spring_rows_b
        if len(ra):
            work += step_work(attached.point_spring_stiffness, points[ra] - points[rb], moved(ra) - moved(rb))
        if len(links.spring_rows_a):
            d, length, unit = spring_geometry(links, points)
            rel = moved(links.spring_rows_a) - moved(links.spring_rows_b)
            axial = links.spring_axial[:, None]
            along = np.einsum("ni,ni->n", rel, unit)[:, None] * unit
            dg = np.where(axial, along, rel)
            gap = np.where(axial, (length - links.spring_rest)[:, None] * unit, d - links.spring_offset)
            work += step_work(links.spring_stiffness, gap, dg)
            force = links.spring_stiffness * (length - links.spring_rest)
            geometric = np.where(links.spring_axial & (force > 0), force / np.where(length > 0, length, 1.0), 0.0)
            work -= c_p * float(np.sum(geometric * np.sum((rel - along) ** 2, axis=1)))
            dx = new.points - points
            actual = dx[links.spring_rows_a] - dx[links.spring_rows_b]
            sq = np.where(links.spring_axial, np.einsum("ni,ni->n", actual, unit) ** 2, np.sum(actual**2, axis=1))
            out[LEDGER.index("dissipated")] = float(np.sum(links.spring_damping * sq) / ctx.dt)
        stored = spring_energy(arrays, new.points, self.penalty) - spring_energy(arrays, points, self.penalty)
        out[LEDGER.index("dissipated_springs")] = -work - stored
        return out
