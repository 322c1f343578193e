"""The energy ledger: stored energies and the work that enters or leaves, per step.

Balance (J per metre of thickness):

    E(t) = kinetic + gravitational + elastic strain + springs and penalties
    E(t) - E(0) = W_loads + W_prescribed + W_constraints - D_dashpots - D_numerical

W_loads: work of point loads and of the base-acceleration body force,
Σ F(t_load)·Δx per step with Δx the exact point (or centroid) displacement.
W_prescribed: work done by the drivers of prescribed points: -μ·Δx for
multiplier rows (μ the multiplier, -μ the force on the block), and
-p·g_mid·Δx_target for penalty drivers (g_mid the mean of the gaps at t and
t+Δt: the work the moving anchor does on its spring).
W_constraints: work of hinge and pin forces, -μ·(Δx_a - Δx_b); zero for an
exactly kept constraint (srdda, dda0), not for dda1's post-adjustment.
D_dashpots: c|Δx_rel|²/Δt per step. D_numerical is what is left: the time
scheme's and the linearisation's own dissipation or drift; ``balance`` =
E - W_loads - W_prescribed - W_constraints + D_dashpots stays at E(0) when it
is zero.
"""
from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from .data import ConstraintArrays
from .lagrange import prescribed_target
from .prescribed import penalty_stiffness, prescribed_penalty_energy
from .springs import spring_energy, spring_geometry

if TYPE_CHECKING:
    from ..model import ModelArrays
    from ..simulation import State

__all__ = ["LEDGER", "step_work", "link_energy", "hinge_forces"]

LEDGER = ("work_loads", "work_prescribed", "work_constraints", "dissipated")


def link_energy(arrays: ModelArrays, state: State, penalty: float) -> float:
    """Energy stored in springs and prescribed-motion penalties at ``state``."""
    links = arrays.links
    return spring_energy(links, state.points) + prescribed_penalty_energy(links, arrays.points, state.points,
                                                                          state.time, penalty)


def hinge_forces(links: ConstraintArrays, multipliers: np.ndarray) -> np.ndarray:
    """Force (n_hinges, 2) on the first point of every hinge or pin (N per m thickness)."""
    return -np.asarray(multipliers)[: 2 * links.n_hinges].reshape(-1, 2)


def step_work(arrays: ModelArrays, state: State, new_state: State, dd: np.ndarray, multipliers: np.ndarray,
              t_load: float, dt: float, penalty: float) -> np.ndarray:
    """Increments of the ledger (work_loads, work_prescribed, work_constraints, dissipated) over one step."""
    links = arrays.links
    dx = new_state.points - state.points
    out = np.zeros(len(LEDGER))
    lr = arrays.load_rows
    if len(lr):
        forces = np.array([ld(t_load) for ld in arrays.loads])
        out[0] += float(np.sum(forces * dx[lr]))
    if links.base_acceleration is not None:
        mass = arrays.density * state.moments.area
        out[0] -= float(np.sum(mass[:, None] * links.base_acceleration(t_load)[None, :] * dd[:, :2]))
    nh = links.n_hinges
    if nh:
        mu = np.asarray(multipliers[: 2 * nh]).reshape(nh, 2)
        rel = dx[links.hinge_rows_a] - np.where((links.hinge_block_b >= 0)[:, None], dx[links.hinge_rows_b], 0.0)
        out[2] -= float(np.sum(mu * rel))
    if len(links.prescribed_rows):
        driven = links.prescribed_multiplier
        mask = links.prescribed_mask
        rows = links.prescribed_rows
        if np.any(driven):
            mu = np.asarray(multipliers[2 * nh: 2 * nh + int(mask[driven].sum())])
            out[1] -= float(np.sum(mu * dx[rows[driven]][mask[driven]]))
        pen = ~driven
        if np.any(pen):
            a0 = prescribed_target(links, arrays.points, state.time)
            a1 = prescribed_target(links, arrays.points, new_state.time)
            g_mid = 0.5 * ((state.points[rows] - a0) + (new_state.points[rows] - a1)) * mask
            k = penalty_stiffness(links, penalty)
            out[1] -= float(np.sum((k[:, None] * g_mid * (a1 - a0))[pen]))
    if len(links.spring_rows_a) and np.any(links.spring_damping > 0):
        rel = dx[links.spring_rows_a] - dx[links.spring_rows_b]
        _, _, unit = spring_geometry(links, state.points)
        along = np.einsum("ni,ni->n", rel, unit)
        sq = np.where(links.spring_axial, along**2, np.sum(rel**2, axis=1))
        out[3] += float(np.sum(links.spring_damping * sq) / dt)
    return out
