"""The state of a run at one instant, and the state at t = 0.

A :class:`State` is frozen: a step makes a new one. Arrays cover all blocks
(shapes in terms of the block type: ``dim`` coordinates, ``ndof`` unknowns,
``n_strain`` stress components). What a step term carries from one step to
the next (the contacts, the rock bolts' breaks, a user's term's own state)
is in ``carried`` under the term's name: the state knows no term.
"""
from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from .geometry.polygon import BlockMoments
from .geometry.polyhedron import PolyhedronMoments
from .integrators.methods import Method
from .energy_names import CUT_CAUSES, LEDGER
from .modeldata.arrays import ModelArrays

__all__ = ["State", "initial_state", "mass_density"]


@dataclass(frozen=True)
class State:
    """Everything that changes over a run, at one instant."""

    step: int
    time: float
    vertices: np.ndarray  # (nv, dim)
    points: np.ndarray  # (np, dim) block-attached points
    velocity: np.ndarray  # (nb, ndof) generalized velocity
    acceleration: np.ndarray  # (nb, ndof)
    stress: np.ndarray  # (nb, n_strain)
    rotation: np.ndarray  # accumulated rotation, as the block type composes it
    moments: BlockMoments | PolyhedronMoments  # block integrals of ``vertices``, computed once per state
    multipliers: np.ndarray = field(default_factory=lambda: np.zeros(0))  # μ of the last step (constraint rows)
    ledger: np.ndarray = field(default_factory=lambda: np.zeros(len(LEDGER)))  # cumulative work, see LEDGER
    carried: Mapping[str, Any] = field(default_factory=dict)  # by term name: what the step carries over
    dt_next: float | None = None  # the step-size control's Δt for the next step (None: the run's dt)
    # step attempts cut so far, by cause (CUT_CAUSES order): checkpointed, so a resumed run keeps counting
    cuts: np.ndarray = field(default_factory=lambda: np.zeros(len(CUT_CAUSES), dtype=np.int64))

    @property
    def contacts(self) -> Any:
        """The contacts as the step that led here ended them (the contact term's carried state), or None."""
        return self.carried.get("contacts")

    @property
    def cuts_by_cause(self) -> dict[str, int]:
        """``cuts`` by the name of their cause: ``{"iteration": 0, "displacement": 2, "penetration": 0}``."""
        return dict(zip(CUT_CAUSES, map(int, self.cuts)))

    def carrying(self, name: str, value: Any) -> State:
        """This state with ``value`` carried under the term name ``name``."""
        return replace(self, carried={**self.carried, name: value})


def mass_density(arrays: ModelArrays, moments: BlockMoments | PolyhedronMoments) -> np.ndarray:
    """Density (nb,) of the blocks in the configuration of ``moments``: their constant mass / their volume."""
    return arrays.block_mass / moments.volume


def initial_state(arrays: ModelArrays, method: Method) -> State:
    """The state at t = 0; the acceleration solves M·A = F(0) block by block."""
    bt = arrays.block_type
    mom = arrays.moments(arrays.vertex_position)
    density = mass_density(arrays, mom)
    M = density[:, None, None] * bt.mass_matrix(mom.volume, mom.second)
    force = np.zeros((arrays.n_blocks, bt.ndof))
    force[:, bt.translation] = (density * mom.volume)[:, None] * arrays.gravity
    force[:, bt.strain] = -mom.volume[:, None] * arrays.block_stress
    acc = np.zeros_like(force)
    massive = arrays.block_density > 0
    if np.any(massive):
        acc[massive] = np.linalg.solve(M[massive], force[massive][..., None])[..., 0]
    if method.scheme.name == "shi":
        acc[:] = 0.0
    acc[arrays.block_fixed] = 0.0
    velocity = arrays.block_velocity.copy()
    velocity[arrays.block_fixed] = 0.0
    return State(0, 0.0, arrays.vertex_position.copy(), arrays.attached.point_position.copy(), velocity, acc,
                 arrays.block_stress.copy(), bt.initial_rotation(arrays.n_blocks), mom,
                 np.zeros(arrays.links.n_multipliers))
