"""Rock bolts: an axial spring with pre-tension and a tensile strength, and an optional dowel (shear) spring.

A bolt joins point a of a block to point b of another block or of the ground
(fixed in space). With d = x_a - x_b, ℓ = |d|, n = d/ℓ and ℓ0 the length at
installation:

* axial force (tension positive) N = P0 + k(ℓ - ℓ0) = k(ℓ - ℓr), ℓr = ℓ0 - P0/k,
  in tension and in compression (a grouted bar), energy ½k(ℓ - ℓr)²; linearised
  about the configuration at t like the axial spring of
  :mod:`srdda.constraints.springs`: k·n nᵀ along n plus the geometric stiffness
  (N/ℓ)(I - n nᵀ) while N > 0;
* shear (dowel) force -k_s·P0·(d - d0) on a, P0 = I - n0 n0ᵀ the projection
  across the initial axis n0, d0 the initial separation: energy ½k_s|P0(d - d0)|²
  (a small-displacement dowel: the projection is that of the installed bolt);
* failure: when N at the end of an accepted step exceeds the strength, the bolt
  breaks for good: from the next step it adds nothing. The break and its time
  (the end of that step) are the term's carried state (:class:`BoltState` in
  ``State.carried["bolts"]``), so a checkpoint keeps them and a resumed run
  goes on with the bolt broken. The energy the bolt held goes to
  the ledger's ``dissipated`` at the break, so the balance stays continuous.

Every operation is on whole arrays of bolts (no Python loop per bolt).
Shape functions are ``ctx.shape_at`` (T at t, or srdda's secant T_sec) with the
scheme's penalty weight c_p.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from ..assembly.system import PenaltyPairs, add_penalty_pairs
from ..term import LEDGER, StepContext, Term
from .data import ConstraintArrays

if TYPE_CHECKING:
    from ..assembly.system import BlockSystem
    from ..modeldata.arrays import ModelArrays
    from ..state import State

__all__ = ["BoltTerm", "BoltForces", "BoltState", "bolt_forces", "bolt_state"]

CARRIED = "bolts"  # the bolt term's key in State.carried


@dataclass(frozen=True)
class BoltState:
    """Which bolts have broken, and when (the bolt term's carried state)."""

    broken: np.ndarray  # (n_bolts,) bool
    break_time: np.ndarray  # (n_bolts,) s, nan while intact

    @classmethod
    def intact(cls, n_bolts: int) -> BoltState:
        return cls(np.zeros(n_bolts, dtype=bool), np.full(n_bolts, np.nan))


def bolt_state(links: ConstraintArrays, state: State) -> BoltState:
    """The bolts' breaks at ``state`` (a state that carries none: every bolt intact)."""
    carried = state.carried.get(CARRIED)
    return carried if carried is not None else BoltState.intact(links.n_bolts)


class BoltForces:
    """Geometry and forces of every bolt at one configuration (broken bolts carry none)."""

    def __init__(self, links: ConstraintArrays, points: np.ndarray, broken: np.ndarray) -> None:
        rb = links.bolt_rows_b
        self.end_a = points[links.bolt_rows_a]
        self.end_b = np.where((rb >= 0)[:, None], points[np.maximum(rb, 0)], links.bolt_ground)
        d = self.end_a - self.end_b
        self.length = np.linalg.norm(d, axis=1)
        self.unit = d / np.where(self.length > 0, self.length, 1.0)[:, None]
        k = links.bolt_stiffness
        initial = np.linalg.norm(links.bolt_axis, axis=1)
        self.rest = initial - links.bolt_pretension / k  # ℓr: the length at which the axial force is zero
        self.intact = ~broken if links.bolt_active is None else ~broken & links.bolt_active  # not yet installed: none
        axis0 = links.bolt_axis / np.where(initial > 0, initial, 1.0)[:, None]
        self.across0 = np.eye(d.shape[1]) - np.einsum("ni,nj->nij", axis0, axis0)  # P0
        self.slip = np.einsum("nij,nj->ni", self.across0, d - links.bolt_axis)  # P0 (d - d0)
        self.axial = np.where(self.intact, k * (self.length - self.rest), 0.0)  # N, tension positive
        self.shear = np.where(self.intact, links.bolt_shear_stiffness * np.linalg.norm(self.slip, axis=1), 0.0)

    def energy(self, links: ConstraintArrays) -> np.ndarray:
        """Energy (n,) held by every bolt: ½k(ℓ - ℓr)² + ½k_s|P0(d - d0)|² (0 when broken)."""
        stored = 0.5 * links.bolt_stiffness * (self.length - self.rest) ** 2 \
            + 0.5 * links.bolt_shear_stiffness * np.sum(self.slip**2, axis=1)
        return np.where(self.intact, stored, 0.0)

    def breaking(self, links: ConstraintArrays) -> np.ndarray:
        """Intact bolts whose axial force exceeds their strength."""
        return self.intact & (self.axial > links.bolt_strength)


def bolt_forces(links: ConstraintArrays, state: State) -> BoltForces:
    """The bolts' ends, axial and shear forces at ``state``."""
    return BoltForces(links, state.points, bolt_state(links, state).broken)


class BoltTerm(Term):
    """Every rock bolt of the model (module doc)."""

    name = CARRIED
    energy_kind = "spring"

    def __init__(self, links: ConstraintArrays) -> None:
        self.links = links
        self._at_start = BoltState.intact(links.n_bolts)  # the breaks at t, carried to t + Δt by commit

    def begin(self, ctx: StepContext) -> None:
        """Keep the breaks of the state at t (the updated state gets them at commit)."""
        self._at_start = bolt_state(self.links, ctx.state)

    @property
    def at_points(self) -> bool:
        return True

    def add_to(self, system: BlockSystem, ctx: StepContext) -> None:
        links = self.links
        bolts = bolt_forces(links, ctx.state)
        point_block = ctx.arrays.attached.point_block
        rb = links.bolt_rows_b
        ba = point_block[links.bolt_rows_a]
        bb = np.where(rb >= 0, point_block[np.maximum(rb, 0)], -1)
        ta = ctx.shape_at(ba, bolts.end_a)
        tb = ctx.shape_at(np.maximum(bb, 0), bolts.end_b)  # rows of ground ends are ignored (block -1)
        n = bolts.unit
        along = np.einsum("ni,nj->nij", n, n)
        across = np.eye(n.shape[1]) - along
        intact = bolts.intact
        c_p = ctx.coeffs.c_p
        k = np.where(intact, links.bolt_stiffness, 0.0)
        gap = (bolts.length - bolts.rest)[:, None] * n
        add_penalty_pairs(system, PenaltyPairs(ba, along @ ta, bb, along @ tb, gap, k), c_p)
        geometric = np.where(bolts.axial > 0, bolts.axial / np.where(bolts.length > 0, bolts.length, 1.0), 0.0)
        if np.any(geometric > 0):
            add_penalty_pairs(system, PenaltyPairs(ba, across @ ta, bb, across @ tb, np.zeros_like(gap), geometric),
                              c_p)
        ks = np.where(intact, links.bolt_shear_stiffness, 0.0)
        if np.any(ks > 0):
            p0 = bolts.across0
            add_penalty_pairs(system, PenaltyPairs(ba, p0 @ ta, bb, p0 @ tb, bolts.slip, ks), c_p)

    def energy(self, arrays: ModelArrays, state: State) -> float:
        return float(np.sum(bolt_forces(self.links, state).energy(self.links)))

    def work(self, ctx: StepContext, new: State, dd: np.ndarray, multipliers: np.ndarray) -> np.ndarray | None:
        """The energy of the bolts that break at the end of this step leaves as ``dissipated``."""
        bolts = BoltForces(self.links, new.points, self._at_start.broken)
        breaking = bolts.breaking(self.links)
        if not np.any(breaking):
            return None
        out = np.zeros(len(LEDGER))
        out[LEDGER.index("dissipated")] = float(np.sum(bolts.energy(self.links)[breaking]))
        return out

    def commit(self, new: State) -> State:
        """Bolts whose axial force exceeds their strength at the new state break, at its time."""
        links, start = self.links, self._at_start
        breaking = BoltForces(links, new.points, start.broken).breaking(links)
        return new.carrying(self.name, BoltState(start.broken | breaking,
                                                 np.where(breaking, new.time, start.break_time)))
