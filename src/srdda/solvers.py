"""The linear-solver seam: one small interface, several backends.

``get_solver(name)`` returns an object with ``solve(system, rhs) -> x`` for a
:class:`~srdda.assembly.BlockSystem`. Backends:

* ``dense``: LAPACK (numpy) on the dense matrix; fastest for a handful of blocks.
* ``superlu``: scipy's SuperLU with a symmetric ordering; always available.
* ``cholmod``: CHOLMOD via scikit-sparse (``pip install srdda[cholmod]``);
  needs a symmetric positive definite matrix (every penalty-only DDA system is).
* ``pardiso``: MKL PARDISO via pypardiso (``pip install srdda[pardiso]``).
* ``auto``: dense up to ``DENSE_LIMIT`` unknowns, else pardiso, cholmod or
  superlu, the first that is installed.

A system with constraint rows (``system.n_constraints > 0``) is the saddle
point [[A, Cᵀ], [C, 0]]·[Δd; μ] = [F; g]; ``rhs`` then has n + nc entries and
the solution holds Δd followed by μ. It is symmetric indefinite, so every
backend solves it by LU of the augmented matrix with pivoting: LAPACK's
Bunch-Kaufman LDLᵀ (``dense``), SuperLU with partial pivoting and a COLAMD
ordering (``superlu``, also used by ``cholmod``, whose Cholesky needs a
definite matrix), PARDISO (``pardiso``). See docs/constraints.md.
"""
from __future__ import annotations

import importlib.util
import warnings
from collections.abc import Callable
from typing import Protocol

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from .assembly.system import BlockSystem

__all__ = ["LinearSolver", "SolverError", "get_solver", "available_solvers", "DENSE_LIMIT", "SOLVERS"]

DENSE_LIMIT = 120


class SolverError(RuntimeError):
    """The global system could not be solved (singular or not finite)."""


class LinearSolver(Protocol):
    name: str

    def solve(self, system: BlockSystem, rhs: np.ndarray) -> np.ndarray: ...


def _check(x: np.ndarray) -> np.ndarray:
    if not np.all(np.isfinite(x)):
        raise SolverError("the solution is not finite: the system is singular or ill-posed")
    return x


Matrix = np.ndarray | sp.csr_matrix
Factor = Callable[[np.ndarray], np.ndarray]


def _same(a: Matrix, b: Matrix) -> bool:
    """True if two assembled matrices are equal entry for entry (same sparsity and values)."""
    if isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
        return isinstance(a, np.ndarray) and isinstance(b, np.ndarray) and np.array_equal(a, b)
    return (a.shape == b.shape and np.array_equal(a.indptr, b.indptr) and np.array_equal(a.indices, b.indices)
            and np.array_equal(a.data, b.data))


class _Factorizing:
    """A backend that factorises the assembled matrix, and keeps the factor while the matrix is unchanged.

    Open-close iterations that only change friction forces, and repeated solves
    of a linear step, change the right-hand side only: they reuse the factor.
    One instance serves one run (``run`` calls :func:`get_solver`), so the
    cache is never shared between runs.
    """

    name = "base"

    def __init__(self) -> None:
        self._last: tuple[Matrix, Factor] | None = None
        self.factorizations = 0  # how many factorisations this instance made (benchmarks read it)

    def matrix(self, system: BlockSystem) -> Matrix:
        return system.saddle_csr() if system.n_constraints else system.to_csr()

    def factor(self, matrix: Matrix, constrained: bool) -> Factor:
        raise NotImplementedError

    def solve(self, system: BlockSystem, rhs: np.ndarray) -> np.ndarray:
        matrix = self.matrix(system)
        if self._last is not None and _same(self._last[0], matrix):
            factor = self._last[1]
        else:
            factor = self.factor(matrix, bool(system.n_constraints))
            self.factorizations += 1
            self._last = (matrix, factor)
        return _check(factor(rhs))


def _saddle_superlu(matrix: sp.csr_matrix) -> Factor:
    """Sparse LU (SuperLU, partial pivoting) of the augmented constrained system."""
    try:
        return spla.splu(matrix.tocsc(), permc_spec="COLAMD").solve
    except RuntimeError as exc:
        raise SolverError(f"singular constrained system (redundant or conflicting constraints?): {exc}") from exc


class DenseSolver:
    """LAPACK's symmetric solve of the dense matrix (tiny systems: refactorising costs less than comparing)."""

    name = "dense"

    def solve(self, system: BlockSystem, rhs: np.ndarray) -> np.ndarray:
        matrix = system.saddle_dense() if system.n_constraints else system.to_dense()
        try:
            with warnings.catch_warnings():
                if system.n_constraints:  # O(1) constraint rows beside stiff penalties: rcond ~1e-23 by scaling
                    warnings.simplefilter("ignore", sla.LinAlgWarning)
                return _check(sla.solve(matrix, rhs, assume_a="sym", check_finite=False))
        except (np.linalg.LinAlgError, sla.LinAlgError) as exc:
            raise SolverError(f"singular system: {exc}") from exc


class SuperLUSolver(_Factorizing):
    name = "superlu"

    def factor(self, matrix: Matrix, constrained: bool) -> Factor:
        if constrained:
            return _saddle_superlu(matrix)
        try:
            return spla.splu(matrix.tocsc(), permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0,
                             options={"SymmetricMode": True}).solve
        except RuntimeError as exc:
            raise SolverError(f"singular system: {exc}") from exc


class CholmodSolver(_Factorizing):
    name = "cholmod"

    def factor(self, matrix: Matrix, constrained: bool) -> Factor:
        if constrained:
            return _saddle_superlu(matrix)
        from sksparse.cholmod import CholmodError, cholesky

        try:
            return cholesky(matrix.tocsc())
        except CholmodError as exc:
            raise SolverError(f"CHOLMOD failed: {exc}") from exc


class PardisoSolver(_Factorizing):
    name = "pardiso"

    def factor(self, matrix: Matrix, constrained: bool) -> Factor:
        import pypardiso

        solver = pypardiso.PyPardisoSolver()
        solver.factorize(matrix)
        return lambda rhs: solver.solve(matrix, rhs)


class AutoSolver:
    """Dense for tiny systems, the fastest installed sparse backend otherwise."""

    name = "auto"

    def __init__(self) -> None:
        self.dense = DenseSolver()
        self.sparse = next(get_solver(n) for n in ("pardiso", "cholmod", "superlu") if n in available_solvers())

    def solve(self, system: BlockSystem, rhs: np.ndarray) -> np.ndarray:
        chosen = self.dense if system.size + system.n_constraints <= DENSE_LIMIT else self.sparse
        return chosen.solve(system, rhs)


_BACKENDS = {"dense": DenseSolver, "superlu": SuperLUSolver, "cholmod": CholmodSolver,
             "pardiso": PardisoSolver, "auto": AutoSolver}
_MODULES = {"cholmod": "sksparse", "pardiso": "pypardiso"}
SOLVERS = tuple(_BACKENDS)


def available_solvers() -> list[str]:
    """Names of the backends usable on this machine."""
    return [n for n in _BACKENDS if n not in _MODULES or importlib.util.find_spec(_MODULES[n]) is not None]


def get_solver(name: str = "auto") -> LinearSolver:
    """The backend called ``name`` (see module doc)."""
    if name not in _BACKENDS:
        raise ValueError(f"unknown solver {name!r}; choose one of {sorted(_BACKENDS)}")
    if name not in available_solvers():
        raise ValueError(f"solver {name!r} is not installed (pip install srdda[{name}])")
    return _BACKENDS[name]()
