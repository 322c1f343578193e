"""``auto``: the backend chosen by the size of each system (dense, direct, then the conjugate gradient)."""
from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from ._direct import DenseSolver
from ._iterative import ConjugateGradientSolver
from ._registry import (DEFAULT_TOLERANCE, LinearSolver, SolverError, best_direct, register_solver,
                        solves_inexactly, takes_springs)

if TYPE_CHECKING:
    from ..assembly.system import BlockSystem

__all__ = ["AutoSolver", "DENSE_LIMIT", "ITERATIVE_LIMIT"]

DENSE_LIMIT = 120  # unknowns: LAPACK on the dense matrix up to here (20 blocks in 2D)
ITERATIVE_LIMIT = 500  # blocks: ``auto`` uses a direct factorisation up to here, the conjugate gradient above


class AutoSolver:
    """The backend by size: dense LAPACK, then a direct factorisation, then the block-Jacobi conjugate gradient.

    Up to ``DENSE_LIMIT`` unknowns: dense. Up to ``ITERATIVE_LIMIT`` blocks: the
    best installed direct backend (:func:`~srdda.solvers.best_direct`). Above: ``cg-jacobi``,
    which falls back to the direct backend for a solve it cannot make (a
    matrix found not positive definite, no convergence); ``fallbacks`` counts
    them. Why block-Jacobi and not the multigrid, and the thresholds: measured
    in docs/performance.md (the open-close iteration's warm-started solves
    need a few cheap iterations, where a hierarchy is rebuilt often).
    """

    name = "auto"

    def __init__(self, tolerance: float = DEFAULT_TOLERANCE, iterative: LinearSolver | None = None) -> None:
        self.dense = DenseSolver()
        self.direct = best_direct()
        # ``iterative``: the conjugate gradient of large systems (a GPU one, srdda.backends); default the CPU's
        self.iterative = ConjugateGradientSolver("jacobi", tolerance) if iterative is None else iterative
        self.fallbacks = 0

    def choose(self, system: BlockSystem) -> LinearSolver:
        """The backend that solves ``system``."""
        if system.size + system.n_constraints <= DENSE_LIMIT:
            return self.dense
        if system.n_blocks <= ITERATIVE_LIMIT or system.n_constraints:
            return self.direct
        return self.iterative

    def takes_springs(self, n_blocks: int) -> bool:
        """The large systems' solver's answer (a system it does not take sums its springs when asked)."""
        return n_blocks > ITERATIVE_LIMIT and takes_springs(self.iterative, n_blocks)

    def inexact(self, system: BlockSystem) -> bool:
        chosen = self.choose(system)
        return chosen is self.iterative and solves_inexactly(chosen, system)

    def solve(self, system: BlockSystem, rhs: np.ndarray, tolerance: float | None = None) -> np.ndarray:
        chosen = self.choose(system)
        if chosen is not self.iterative:
            return chosen.solve(system, rhs)
        try:
            return chosen.solve(system, rhs, tolerance)
        except SolverError:
            self.fallbacks += 1
            return self.direct.solve(system, rhs)


register_solver("auto", AutoSolver)
