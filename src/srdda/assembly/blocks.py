"""The block terms of a step: inertia, elasticity, initial stress and body force (paper Eq. 60).

Each acts on every block's own unknowns (the diagonal sub-matrices) and is
written for any block type: translation, rotation and strain unknowns are
the block type's slices. With the scheme coefficients c (module doc of
:mod:`srdda.integrators.schemes`):

* inertia: c_m·M on the diagonal, M·(m_v V + m_a A) on the right, M = ρ∫TᵀT;
* elasticity: c_k·V_b·D on the strain block, V_b·D·(k_v V + k_a A) on the right
  (the paper's Δt·K·V(t+Δt-αf) term, zero for Shi's scheme);
* initial stress: -V_b·σ on the strain unknowns;
* body force: m·g on the translation, m = ρ·V_b of the block as built (mass is
  conserved when a method changes the volume).
"""
from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from ..kinematics.shape3d import rotation_matrix_3d
from ..state import mass_density
from ..term import StepContext, Term

if TYPE_CHECKING:
    from ..modeldata.arrays import ModelArrays
    from ..state import State
    from .system import BlockSystem

__all__ = ["InertiaTerm", "ElasticityTerm", "InitialStressTerm", "BodyForceTerm", "GyroscopicTerm", "block_terms",
           "mass_matrices"]


def mass_matrices(arrays: ModelArrays, state: State) -> np.ndarray:
    """M = ρ∫TᵀT (nb, ndof, ndof) of every block in the configuration of ``state``, ρ = m / V_b."""
    mom = state.moments
    density = mass_density(arrays, mom)
    return density[:, None, None] * arrays.block_type.mass_matrix(mom.volume, mom.second)


class InertiaTerm(Term):
    """c_m·M Δd = M (m_v V + m_a A) + ...: the inertia of the time scheme."""

    same_every_solve = True

    energy_kind = "kinetic"

    def begin(self, ctx: StepContext) -> None:
        self.mass = mass_matrices(ctx.arrays, ctx.state)
        c = ctx.coeffs
        self.rhs = np.einsum("nij,nj->ni", self.mass, c.m_v * ctx.state.velocity + c.m_a * ctx.state.acceleration)

    def add_to(self, system: BlockSystem, ctx: StepContext) -> None:
        system.diag += ctx.coeffs.c_m * self.mass
        system.rhs += self.rhs

    def energy(self, arrays: ModelArrays, state: State) -> float:
        V = state.velocity
        return 0.5 * float(np.einsum("ni,nij,nj->", V, mass_matrices(arrays, state), V))


class ElasticityTerm(Term):
    """c_k·V_b·D on the strain unknowns (Eq. 60) and the scheme's rate term; strain energy."""

    same_every_solve = True

    energy_kind = "elastic"

    def add_to(self, system: BlockSystem, ctx: StepContext) -> None:
        s = ctx.block_type.strain
        volume = ctx.state.moments.volume
        c = ctx.coeffs
        system.diag[:, s, s] += c.c_k * volume[:, None, None] * ctx.arrays.block_elasticity
        if c.k_v or c.k_a:
            rate = c.k_v * ctx.state.velocity[:, s] + c.k_a * ctx.state.acceleration[:, s]
            system.rhs[:, s] += volume[:, None] * np.einsum("nij,nj->ni", ctx.arrays.block_elasticity, rate)

    def energy(self, arrays: ModelArrays, state: State) -> float:
        ds = state.stress - arrays.block_stress
        return 0.5 * float(np.sum(state.moments.volume * np.einsum("ni,nij,nj->n", ds, arrays.block_compliance, ds)))


class InitialStressTerm(Term):
    """-V_b·σ(t) on the strain unknowns: the stress carried into the step."""

    same_every_solve = True

    def add_to(self, system: BlockSystem, ctx: StepContext) -> None:
        system.rhs[:, ctx.block_type.strain] -= ctx.state.moments.volume[:, None] * ctx.state.stress


class BodyForceTerm(Term):
    """m·g on the translation of every block; gravitational potential energy."""

    same_every_solve = True

    energy_kind = "gravity"

    def add_to(self, system: BlockSystem, ctx: StepContext) -> None:
        system.rhs[:, ctx.block_type.translation] += ctx.arrays.block_mass[:, None] * ctx.arrays.gravity

    def energy(self, arrays: ModelArrays, state: State) -> float:
        return -float(np.sum(arrays.block_mass * (state.moments.centroid @ arrays.gravity)))


class GyroscopicTerm(Term):
    """The rate of change of a 3D block's rotational inertia J: the rotation rows conserve J·ω.

    Shi's inertia ρ∫TᵀT·A takes the mass matrix of the configuration at t as
    constant over the step: on the rotation rows J(t)·(ω(t+Δt) - ω(t))/Δt = τ,
    so a free rigid block keeps ω while its inertia turns with it, angular
    momentum is not conserved and a body spun near its intermediate axis never
    flips. The rows should read (J(t+Δt)·ω(t+Δt) - J(t)·ω(t))/Δt = τ (Euler's
    equations, d(Jω)/dt = Jω̇ + ω × Jω); this term adds the difference,
    -(J(t+Δt) - J(t))·ω(t+Δt)/Δt with J(t+Δt) = R(Δθ) J(t) R(Δθ)ᵀ, iterated with
    the solves until it settles. Free rigid blocks then keep J·ω exactly (with
    Shi's scheme, the paper's at ρ∞ = 1). In 2D J·ω turns with nothing: no term.
    """

    max_iterations = 8

    def __init__(self, tolerance: float = 1e-13) -> None:
        self.tolerance = tolerance  # relative change of the torque between two solves

    def begin(self, ctx: StepContext) -> None:
        mom = ctx.state.moments
        second = mom.second
        trace = np.trace(second, axis1=1, axis2=2)
        density = mass_density(ctx.arrays, mom)
        self.inertia = density[:, None, None] * (trace[:, None, None] * np.eye(second.shape[1]) - second)
        w = ctx.state.velocity[:, ctx.block_type.rotation]
        self.torque = self._torque(ctx, ctx.dt * w, w)

    def _torque(self, ctx: StepContext, rotation_increment: np.ndarray, omega: np.ndarray) -> np.ndarray:
        R = rotation_matrix_3d(rotation_increment)
        turned = R @ self.inertia @ np.swapaxes(R, 1, 2)
        return -np.einsum("nij,nj->ni", turned - self.inertia, omega) / ctx.dt

    def add_to(self, system: BlockSystem, ctx: StepContext) -> None:
        system.rhs[:, ctx.block_type.rotation] += self.torque

    def converged(self, dd: np.ndarray, ctx: StepContext) -> bool:
        c, r = ctx.coeffs, ctx.block_type.rotation
        V, A = ctx.state.velocity, ctx.state.acceleration
        omega = c.v_d * dd[:, r] + c.v_v * V[:, r] + c.v_a * A[:, r]
        torque = self._torque(ctx, ctx.block_type.rotation_increment(dd), omega)
        change = float(np.max(np.abs(torque - self.torque)))
        scale = float(np.max(np.abs(np.einsum("nij,nj->ni", self.inertia, omega)))) / ctx.dt
        self.torque = torque
        return change <= self.tolerance * max(scale, 1e-300)

    def pending(self) -> str:
        return "the gyroscopic torque did not settle"


def block_terms() -> list[Term]:
    """The terms every block has, in assembly order."""
    return [InertiaTerm(), ElasticityTerm(), InitialStressTerm(), BodyForceTerm()]
