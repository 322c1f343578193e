"""SRDDA's secant pass: linearise point terms at the converged rotation increment.

Points, springs, hinges and contacts enter a step through shape functions.
Under the ``secant`` linearisation they use T_sec at the block's rotation
increment θ (:mod:`srdda.kinematics.update2d`), which is known only after the
solve: the step starts from θ = Δt·ω(t) and is solved again with the solved
θ until |θ|·|θ - θ_prev| is below the tolerance (the mismatch between the
linearised and the exact rotation displacement of a point per metre of
lever arm is about half of it), or ``max_iterations`` solves in which the
contacts did not change have passed. Then the linearised point terms do no
spurious work on the exact update.
"""
from __future__ import annotations

import numpy as np

from ..term import StepContext, Term

__all__ = ["SecantPass"]


class SecantPass(Term):
    """The secant iteration as a term: it adds nothing and settles when θ stops changing."""

    def __init__(self, tolerance: float, max_iterations: int) -> None:
        self.tolerance = tolerance
        self.max_iterations = max_iterations

    def begin(self, ctx: StepContext) -> None:
        ctx.theta = ctx.block_type.rotation_increment(ctx.dt * ctx.state.velocity)

    def converged(self, dd: np.ndarray, ctx: StepContext) -> bool:
        assert ctx.theta is not None
        solved = ctx.block_type.rotation_increment(dd)
        mismatch = ctx.block_type.secant_mismatch(solved, ctx.theta)
        ctx.theta = solved.copy()
        return mismatch <= self.tolerance

    def pending(self) -> str:
        return "the secant pass did not settle"
