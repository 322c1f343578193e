"""Equilibrium: the unbalanced-force ratio of a step, the measure of a model brought to rest under its loads.

What "unbalanced force" means for a DDA block. A step solves the block's
equilibrium with its inertial force: M·a + (elastic, contact, constraint
forces) = applied forces, where a is the acceleration in the step's equation
(:mod:`srdda.integrators.schemes`): a = c_m·Δd - m_v·V - m_a·A from the
increments Δd and the velocity and acceleration at t (Shi's scheme: the
step's constant acceleration a = 2Δd/Δt² - 2V/Δt; the generalized-α schemes:
A(t + Δt - α_m)). The inertial force m·a of the block's translation is what
the other forces leave unbalanced: the block's **unbalanced force** (N; N/m
in 2D). Its Δd of translation is the step's displacement of the block's
centroid (the displacement field is affine about the centroid, so this is
exact). At rest in equilibrium it is 0; a block falling freely under gravity
has m·g. Rotations and strains are left out, as 3DEC's ratio takes forces only.

The **unbalanced-force ratio** is 3DEC's: the largest unbalanced force of the
moving blocks over the mean applied force of the moving blocks, the applied
force of a block being its weight m·g plus its point loads at t + Δt. A block
resting on a fixed base has a ratio that falls to 0 as its contacts settle; a
free block in gravity has a ratio of exactly 1. Fixed and removed blocks take
no part. A model with no applied force has the ratio inf while anything is
unbalanced (0 otherwise).

:class:`UnbalancedForceTerm` computes it at every step and carries it in
``State.carried["equilibrium"]`` (so a checkpoint keeps it); :func:`srdda.simulation.settle`
runs a model in damped dynamic steps (Shi's velocity ratio: the velocity at
the end of each step is multiplied by :data:`SETTLE_VELOCITY_RATIO` = 0.8
before the next) until the ratio falls below a tolerance (default 1e-5) or a
number of steps is spent. Measured on a column of ten blocks (docs/stages.md)
it reaches 1e-5 in 10 times fewer steps than Shi's static mode (ratio 0, the
velocities zeroed every step) at Δt = 1 ms; the best ratio depends on Δt
against the model's periods (0.5-0.7 at 10 ms, 0.9 at 1 ms) and 0.8 stays
within 1.8 times the best step count of those measured.
"""
from __future__ import annotations

from dataclasses import dataclass, replace
from typing import TYPE_CHECKING

import numpy as np

from .constraints.loads import point_load_forces
from .modeldata.arrays import ModelArrays
from .state import State
from .term import StepContext, Term

if TYPE_CHECKING:
    from .integrators.schemes import SchemeCoefficients

__all__ = ["RATIO_TOLERANCE", "UnbalancedForce", "UnbalancedForceTerm", "unbalanced_forces",
           "applied_forces", "unbalanced_force_ratio", "unbalanced_force", "SETTLE_VELOCITY_RATIO"]

RATIO_TOLERANCE = 1e-5  # 3DEC's default for `model solve`
SETTLE_VELOCITY_RATIO = 0.8  # damping of the settle steps (module doc: measured)
CARRIED = "equilibrium"  # the term's key in State.carried


@dataclass(frozen=True)
class UnbalancedForce:
    """The unbalanced-force ratio of one step and its parts (module doc)."""

    ratio: float  # largest / mean_applied
    largest: float  # the largest unbalanced force of a moving block, N (N/m in 2D)
    mean_applied: float  # the mean applied force of the moving blocks, N (N/m in 2D)
    block: int  # the block with the largest unbalanced force (-1: no moving block)


def _moving(arrays: ModelArrays) -> np.ndarray:
    """The blocks that take part: neither fixed nor removed by a stage."""
    return ~arrays.block_fixed if arrays.block_removed is None else ~(arrays.block_fixed | arrays.block_removed)


def unbalanced_forces(arrays: ModelArrays, before: State, after: State, coeffs: SchemeCoefficients) -> np.ndarray:
    """|m·a| (nb,) of every block over the step ``before`` -> ``after`` (module doc)."""
    tr = arrays.block_type.translation
    shift = after.moments.centroid - before.moments.centroid
    acceleration = coeffs.c_m * shift - coeffs.m_v * before.velocity[:, tr] - coeffs.m_a * before.acceleration[:, tr]
    return arrays.block_mass * np.linalg.norm(acceleration, axis=1)


def applied_forces(arrays: ModelArrays, t: float) -> np.ndarray:
    """|weight + point loads| (nb,) of every block at time t."""
    force = arrays.block_mass[:, None] * arrays.gravity[None, :]
    if len(arrays.attached.load_force):
        np.add.at(force, arrays.attached.point_block[arrays.attached.load_rows], point_load_forces(arrays, t))
    return np.linalg.norm(force, axis=1)


def unbalanced_force_ratio(arrays: ModelArrays, before: State, after: State,
                           coeffs: SchemeCoefficients) -> UnbalancedForce:
    """The unbalanced-force ratio of the step ``before`` -> ``after`` with the scheme's ``coeffs`` (module doc)."""
    moving = _moving(arrays)
    if not np.any(moving):
        return UnbalancedForce(0.0, 0.0, 0.0, -1)
    unbalanced = np.where(moving, unbalanced_forces(arrays, before, after, coeffs), 0.0)
    block = int(np.argmax(unbalanced))
    largest = float(unbalanced[block])
    mean = float(np.mean(applied_forces(arrays, after.time)[moving]))
    ratio = largest / mean if mean > 0 else (np.inf if largest > 0 else 0.0)
    return UnbalancedForce(float(ratio), largest, mean, block)


def unbalanced_force(state: State) -> UnbalancedForce | None:
    """The unbalanced force of the step that led to ``state`` (None: not computed in this stage)."""
    return state.carried.get(CARRIED)


class UnbalancedForceTerm(Term):
    """Computes the step's unbalanced-force ratio and carries it (adds nothing to the step's system)."""

    name = CARRIED

    def __init__(self) -> None:
        self._ctx: StepContext | None = None

    def begin(self, ctx: StepContext) -> None:
        self._ctx = ctx

    def commit(self, new: State) -> State:
        ctx = self._ctx
        assert ctx is not None
        return new.carrying(self.name, unbalanced_force_ratio(ctx.arrays, ctx.state, new, ctx.coeffs))


def without_ratio(state: State) -> State:
    """``state`` without a carried ratio (a new stage computes its own)."""
    return replace(state, carried={k: v for k, v in state.carried.items() if k != CARRIED})


def reached(state: State, tolerance: float) -> bool:
    """True once the ratio of the step that led to ``state`` is below ``tolerance``."""
    carried = unbalanced_force(state)
    return carried is not None and carried.ratio < tolerance
