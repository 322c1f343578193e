"""The normal springs of contacts whose joint has a restitution e_n, in one step attempt (2D and 3D).

Their normal force is :func:`~srdda.contact.law.impact_force` of the gaps at
the step's start and end: nonlinear where a contact closes or opens inside the
step, so each solve takes it linearised at the last solve's end gap (Newton's
method on a monotone force: the open-close iteration solves again until the
force at the new gap is the linear one's), and the dashpot is calibrated to
e_n from the frequency of the block pair's impact (:meth:`ImpactSprings.viscosity`).
docs/contacts.md, "Impacts and restitution".
"""
from __future__ import annotations

import warnings

import numpy as np

from ..assembly.blocks import mass_matrices
from ..assembly.system import BlockSystem, PenaltyPairs, add_penalty_pairs
from ..term import StepContext
from .candidates import pair_keys
from .law import impact_damping_ratio, impact_force, impact_potential

__all__ = ["ImpactSprings", "ImpactWarning", "SETTLED", "RESOLVED"]

SETTLED = 1e-9  # the linearised force is taken as the force once they differ by this × k_n·|gap|
# ωΔt up to which the rebound was measured within 2 % of e_n (1.26; at 1.79 e_n = 0.2 rebounds 7.5 % slow): an
# impact of at least π/1.3 ≈ 2.4 steps (docs/contacts.md, "Impacts and restitution")
RESOLVED = 1.3


class ImpactWarning(UserWarning):
    """An impact on a joint with a restitution too short for the step: its rebound is not held to e_n."""


class ImpactSprings:
    """The normal springs of contacts ``index`` (those with a restitution) of a step: gaps ``gap0`` at its start,
    stiffness k_n and restitution e_n each."""

    def __init__(self, index: np.ndarray, block_a: np.ndarray, block_b: np.ndarray, gap0: np.ndarray,
                 stiffness: np.ndarray, restitution: np.ndarray) -> None:
        self.index = index
        self.block_a, self.block_b = block_a, block_b
        self.gap0, self.stiffness, self.restitution = gap0, stiffness, restitution
        self.at = gap0.copy()  # the end gap the next solve linearises the force at (the last solve's)
        self.solved_at = gap0.copy()  # the one the last solve's force was linearised at
        self.force = np.zeros(len(index))  # N at ``at`` (compression positive)
        self.slope = np.zeros(len(index))  # −∂N/∂g there (N/m)
        self.dashpot = np.zeros(len(index))  # c/Δt of the last solve (N/m)
        self._masses: np.ndarray | None = None  # the blocks' rigid-motion mass matrices at the step's start
        self._warned = False  # ImpactWarning given in this step attempt

    def add_to(self, system: BlockSystem, rows_a: np.ndarray, rows_b: np.ndarray, ctx: StepContext) -> None:
        """The linearised forces N(g1) ≈ N(at) − slope·(g1 − at) on rows n·T_a, n·T_b (n, ndof) of the contacts."""
        self.dashpot = self.viscosity(rows_a, rows_b, ctx)
        self.solved_at = self.at
        self.force, self.slope = impact_force(self.gap0, self.at, self.stiffness, self.dashpot)
        on = self.slope > 0.0  # open at both ends of the step: no force, no stiffness
        s = self.slope[on]
        # add_penalty_pairs puts −s·(g̃ + Δg) on the gap: g̃ = (g0 − at) − N(at)/s
        offset = (self.gap0 - self.at)[on] - self.force[on] / s
        add_penalty_pairs(system, PenaltyPairs(self.block_a[on], rows_a[on][:, None], self.block_b[on],
                                               rows_b[on][:, None], offset[:, None], s), 1.0)

    def applied(self, gap1: np.ndarray) -> np.ndarray:
        """The force (n,) the last solve's linear model gives at end gaps ``gap1``."""
        return self.force - self.slope * (gap1 - self.solved_at)

    def law(self, gap1: np.ndarray) -> np.ndarray:
        """The impact law's force (n,) at end gaps ``gap1``, with the last solve's dashpots."""
        return impact_force(self.gap0, gap1, self.stiffness, self.dashpot)[0]

    def potential(self, gap1: np.ndarray, linearised: bool) -> np.ndarray:
        """ψ (n,) with ∂ψ/∂g1 = −N at end gaps ``gap1``: of the law
        (:func:`~srdda.contact.law.impact_potential`), or of the last solve's linear model,
        −N·g1 + ½s(g1 − g_lin)² (up to a constant)."""
        if linearised:
            return -self.force * gap1 + 0.5 * self.slope * (gap1 - self.solved_at) ** 2
        return impact_potential(self.gap0, gap1, self.stiffness, self.dashpot)

    def settled(self, gap1: np.ndarray) -> bool:
        """Whether the last solve's force is the impact law's at its end gaps ``gap1``; moves the linearisation
        there for the next solve."""
        exact = self.law(gap1)
        scale = self.stiffness * np.maximum(np.abs(self.gap0), np.abs(gap1))
        done = bool(np.all(np.abs(exact - self.applied(gap1)) <= SETTLED * scale))
        self.at = gap1.copy()
        return done

    def energy(self, gap: np.ndarray) -> float:
        """½k_n·p² (J, per m in 2D) of the springs at gaps ``gap``, p = min(g, 0)."""
        return 0.5 * float(np.sum(self.stiffness * np.minimum(gap, 0.0) ** 2))

    def work(self, gap1: np.ndarray, law: bool = False) -> float:
        """Work (J, per m in 2D) over the step of the last solve's forces on the blocks (``law``: of the impact
        law's at ``gap1``, what a converged Newton step applied): N·Δg (N pushes the gap open)."""
        return float(np.sum((self.law(gap1) if law else self.applied(gap1)) * (gap1 - self.gap0)))

    def loss(self, gap1: np.ndarray, law: bool = False) -> float:
        """What the springs took out over the step: their negative work (:meth:`work`) minus the change of
        ½k_n·p²."""
        return -self.work(gap1, law) - (self.energy(gap1) - self.energy(self.gap0))

    def viscosity(self, rows_a: np.ndarray, rows_b: np.ndarray, ctx: StepContext) -> np.ndarray:
        """c/Δt (n,) of the dashpots: c = 2ζ·k_n/ω, ζ from e_n and ωΔt (:func:`impact_damping_ratio`).

        ω is that of the impact of the contact's block pair: ω² = K/m* with K
        the k_n sum of the pair's contacts that act in the step (closed at its
        start or at the last solve's end) and m* the effective mass of their
        resultant, the k_n-weighted mean of their rows n·T over the blocks'
        rigid motion (a face's contacts push its block without turning it; a
        corner's alone, with the turn). Per contact c = 2ζ√(k_n m*) for a
        single contact; contacts side by side share the pair's damping.
        """
        acting = (self.gap0 < 0.0) | (self.at < 0.0)
        out = np.zeros(len(self.index))
        if not np.any(acting):
            return out
        bt, arrays = ctx.block_type, ctx.arrays
        rigid = slice(bt.translation.start, bt.rotation.stop)
        a, b, k = self.block_a[acting], self.block_b[acting], self.stiffness[acting]
        # each contact seen from its pair's lower block: Δg = r_lo·Δd_lo − r_hi·Δd_hi (a swapped one: −r_b, −r_a)
        swap = (a > b)[:, None]
        ra, rb = rows_a[acting][:, rigid], rows_b[acting][:, rigid]
        oriented = ((np.minimum(a, b), np.where(swap, -rb, ra)), (np.maximum(a, b), np.where(swap, -ra, rb)))
        _, first, pair = np.unique(pair_keys(np.column_stack([a, b]), arrays.n_blocks), return_index=True,
                                   return_inverse=True)
        total = np.bincount(pair, k)
        compliance = np.zeros(len(first))
        if self._masses is None:  # the state at t: the same for every solve of the step
            self._masses = mass_matrices(arrays, ctx.state)[:, rigid, rigid]
        masses = self._masses
        for blocks, rows in oriented:
            mean = np.zeros((len(first), rows.shape[1]))  # the resultant's row: Σ k·r / K per pair
            np.add.at(mean, pair, k[:, None] * rows)
            mean /= total[:, None]
            block = blocks[first]
            moves = ~arrays.block_fixed[block]  # a fixed block gives way to nothing
            solved = np.linalg.solve(masses[block[moves]], mean[moves][:, :, None])[:, :, 0]
            compliance[moves] += np.einsum("pi,pi->p", mean[moves], solved)
        omega_dt = np.sqrt(total * compliance)[pair] * ctx.dt
        if not self._warned and np.max(omega_dt) > RESOLVED:
            self._warned = True
            warnings.warn(f"an impact on a joint with a restitution lasts under {np.pi / RESOLVED:.1f} steps "
                          f"(ωΔt > {RESOLVED}): its rebound is not held to e_n; give dt ≤ {RESOLVED}/ω, ω = √(k_n/m*) "
                          "of the impact (docs/contacts.md, \"Impacts and restitution\")", ImpactWarning, stacklevel=2)
        zeta = impact_damping_ratio(self.restitution[acting], omega_dt)
        out[acting] = 2.0 * zeta * k / np.where(omega_dt > 0.0, omega_dt, np.inf)
        return out
