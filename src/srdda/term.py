"""The term interface: what every contribution to a time step provides.

A step (:mod:`srdda.step`) is a loop over terms: inertia, elasticity, initial
stress, body force, point loads, springs, hinges and driven points, base
acceleration, contacts and the secant pass. Each term

* ``begin``: looks at the state at t once per step attempt (contacts detect);
* ``add_to``: adds its matrices and forces to the step's system (once per
  step when ``same_every_solve``, else before every solve);
* ``step_length``: after each solve, may damp the step towards the solution
  (a line search: the contacts' Newton iteration, :mod:`srdda.contact.newton`);
* ``converged``: after each solve, says whether its own iteration has settled
  (open-close, the secant pass); a term whose ``cuts_step`` is True has the
  step cut when it has not settled within ``max_iterations`` solves, the others
  are accepted as they are then;
* ``review``: after the update, may cut the step (a vertex moved too far, a
  contact penetrated too deep) or bound the next Δt;
* ``commit``: stores what it carries over to the next step on the new state,
  under its ``name`` in ``State.carried`` (:meth:`srdda.state.State.carrying`);
* ``energy`` / ``work``: its stored energy (one of :data:`ENERGY_KINDS`) and the
  work it did over the step (increments of the :data:`LEDGER`).

This module sits below the step: the terms import it, never the step.
"""
from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from .energy_names import CUT_CAUSES, ENERGY_KINDS, LEDGER

if TYPE_CHECKING:
    from .assembly.system import BlockSystem
    from .integrators.methods import Method
    from .integrators.schemes import SchemeCoefficients
    from .kinematics.blocktype import BlockType
    from .modeldata.arrays import ModelArrays
    from .state import State

__all__ = ["StepContext", "Term", "StepCut", "CUT_CAUSES", "ENERGY_KINDS", "LEDGER"]


@dataclass
class StepContext:
    """What a term needs during one step attempt.

    Stiffnesses a term needs (the run's penalty) are given to it when it is
    made. ``theta`` is the rotation increment per block that the method linearises
    about (None: Shi's T at t; else the secant T_sec, see
    :mod:`srdda.kinematics.update2d`); the secant pass updates it between solves.
    """

    arrays: ModelArrays
    state: State
    method: Method
    coeffs: SchemeCoefficients
    dt: float
    t_load: float
    theta: np.ndarray | None = None

    @property
    def block_type(self) -> BlockType:
        return self.arrays.block_type

    def shape_at(self, blocks: np.ndarray, positions: np.ndarray) -> np.ndarray:
        """Shape functions (n, dim, ndof) of points at ``positions`` (config. at t) of ``blocks``."""
        lever = positions - self.state.moments.centroid[blocks]
        return self.block_type.shape(lever, None if self.theta is None else self.theta[blocks])


@dataclass(frozen=True)
class StepCut:
    """A term's request to repeat the step with Δt × ``factor``, and why (``cause``: one of CUT_CAUSES)."""

    reason: str
    factor: float
    cause: str


class Term:
    """Base class of step terms; every method is a no-op (see the module doc)."""

    name: str = ""  # the key of what the term carries between steps in State.carried ("" carries nothing)
    energy_kind: str | None = None  # which of ENERGY_KINDS ``energy`` reports
    cuts_step: bool = False
    max_iterations: int = 1
    same_every_solve: bool = False  # adds the same to every solve of a step: assembled once per step

    def begin(self, ctx: StepContext) -> None:
        """Prepare the step attempt from the state at t."""

    @property
    def at_points(self) -> bool:
        """True if the term acts at block points (then srdda's secant pass linearises it)."""
        return False

    def add_to(self, system: BlockSystem, ctx: StepContext) -> None:
        """Add matrices and forces to the step's system."""

    @property
    def line_search(self) -> bool:
        """True if the term wants each solve's increments damped by :meth:`step_length` (a Newton iteration)."""
        return False

    def step_length(self, dd_before: np.ndarray, delta: np.ndarray, curvature: Callable[[], float]) -> float:
        """The step α in (0, 1] from the last iterate ``dd_before`` along ``delta`` (the solve's increments
        minus the last iterate); ``curvature()`` gives δᵀAδ of the solved system."""
        return 1.0

    def solve_tolerance(self, tight: float) -> float:
        """The displacement tolerance (m) the next solve of a line-searching term needs from an iterative
        backend: ``tight`` (the run's ``solver_tolerance``) or looser while its iteration is far from settled."""
        return tight

    def converged(self, dd: np.ndarray, ctx: StepContext) -> bool:
        """After a solve with increments ``dd``: has this term's own iteration settled?"""
        return True

    def pending(self) -> str:
        """Why the term has not settled (for the message of a cut step)."""
        return "not converged"

    def review(self, ctx: StepContext, new: State) -> StepCut | float | None:
        """After the update: a cut, the largest Δt allowed for the next step, or None (no opinion)."""
        return None

    def commit(self, new: State) -> State:
        """The accepted state with what this term carries to the next step."""
        return new

    def energy(self, arrays: ModelArrays, state: State) -> float:
        """Energy this term stores at ``state`` (J per m in 2D)."""
        return 0.0

    def work(self, ctx: StepContext, new: State, dd: np.ndarray, multipliers: np.ndarray) -> np.ndarray | None:
        """Increments of the LEDGER over the step, or None when the term does no external work."""
        return None
