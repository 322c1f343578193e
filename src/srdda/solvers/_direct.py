"""The linear-solver seam: one small interface, several backends.

``get_solver(name, tolerance)`` returns an object with ``solve(system, rhs) -> x``
for a :class:`~srdda.assembly.BlockSystem`; one instance serves one run and
keeps what the next solve can reuse (a factor, an analysis, a preconditioner,
the last solution). Backends (measured in docs/performance.md):

* ``dense``: LAPACK (numpy) on the dense matrix; fastest for a handful of blocks.
* ``superlu``: scipy's SuperLU with a symmetric ordering; always available. It
  keeps its factor while the matrix is unchanged; it cannot keep an ordering
  or a symbolic analysis, so every new matrix is ordered and factorised anew.
* ``cholmod``: CHOLMOD via scikit-sparse (``pip install srdda[cholmod]``) and
  ``pardiso``: MKL PARDISO via pypardiso (``pip install srdda[pardiso]``):
  Cholesky of the symmetric positive definite matrix (every unconstrained DDA
  system), with the fill-reducing ordering and the symbolic analysis made once
  per block pattern and reused while the pattern of later matrices lies inside
  it (:class:`_BlockPattern`): contacts that open and close change values, not
  the analysis.
* ``cg-amg``, ``cg-jacobi``: the preconditioned conjugate gradient
  (:mod:`srdda.solvers_iterative`) with smoothed-aggregation multigrid (pyamg)
  or block-Jacobi, warm-started from the previous solution, stopping when every
  unknown of Δd is estimated within ``tolerance`` (m) of the exact solution.
* ``auto``: dense up to ``DENSE_LIMIT`` unknowns, the best installed direct
  backend (pardiso, cholmod, superlu) up to ``ITERATIVE_LIMIT`` blocks,
  ``cg-jacobi`` above (falling back to the direct backend for a solve it
  cannot make).
* ``device="gpu"`` (``cg-jacobi`` and ``auto``): the same conjugate gradient
  with its iterations on a CUDA GPU through CuPy (:mod:`srdda.backends`).

A system with constraint rows (``system.n_constraints > 0``) is the saddle
point [[A, Cᵀ], [C, 0]]·[Δd; μ] = [F; g]; ``rhs`` then has n + nc entries and
the solution holds Δd followed by μ. It is symmetric indefinite, so it is
solved by LU of the augmented matrix with pivoting: LAPACK's Bunch-Kaufman
LDLᵀ (``dense``), SuperLU with partial pivoting and a COLAMD ordering (every
sparse backend: Cholesky and the conjugate gradient need a definite matrix).
See docs/constraints.md.
"""
from __future__ import annotations

import importlib.util
import os
import warnings
from collections.abc import Callable
from dataclasses import replace
from typing import Protocol

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from threadpoolctl import threadpool_limits

from .assembly.system import BlockSystem
from .solvers_iterative import (BlockJacobi, IterativeSolverError, PCGResult, SmoothedAggregation, block_jacobi_pcg,
                                pcg, smallest_eigenvalue_estimate)

__all__ = ["LinearSolver", "SolverError", "get_solver", "available_solvers", "blas_threads_for_steps", "DENSE_LIMIT",
           "ITERATIVE_LIMIT", "DEFAULT_TOLERANCE", "SOLVERS"]

DENSE_LIMIT = 120  # unknowns: LAPACK on the dense matrix up to here (20 blocks in 2D)
ITERATIVE_LIMIT = 500  # blocks: ``auto`` uses a direct factorisation up to here, the conjugate gradient above
# The iterative backends stop when every unknown of the increment is estimated within this of the exact
# solution (m; rad and 1 for rotations and strains, i.e. m per m of block size): 1e-9 m keeps 200 steps
# of the 1,000-block slope within the 1e-6 m of the direct run even if the errors all added up.
DEFAULT_TOLERANCE = 1e-9


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


class _BlockPattern:
    """The block pattern that a symbolic analysis was made for, and the matrices of that pattern.

    Contacts that open drop their coupling blocks from the assembled matrix,
    contacts that close add them back: the pattern of the step's matrix
    changes within the open-close iteration and from step to step while the
    blocks stay where they are. A matrix whose block pattern lies inside the
    analysed one is written into it with explicit zeros, so the ordering and
    symbolic factorisation are reused; a matrix with a new coupling is
    analysed on the union of both patterns. When the union holds more than
    ``GROWTH`` times the blocks of the current matrix, the analysis starts
    from the current pattern again (stale couplings cost fill-in).
    """

    GROWTH = 1.25

    def __init__(self, keys: np.ndarray, n_blocks: int, ndof: int, upper: bool) -> None:
        self.keys = keys  # sorted block keys row·n_blocks + column
        self.n_blocks, self.ndof = n_blocks, ndof
        rows, cols = np.divmod(keys, n_blocks)
        a, c = np.meshgrid(np.arange(ndof), np.arange(ndof), indexing="ij")
        r = (rows[:, None, None] * ndof + a).ravel()
        q = (cols[:, None, None] * ndof + c).ravel()
        keep = np.flatnonzero(q >= r) if upper else np.arange(len(r))
        order = np.lexsort((q[keep], r[keep]))
        self.take = keep[order]  # entry k of the CSR data is entry take[k] of the flattened block data
        self.indices = q[self.take].astype(np.int32)
        self.indptr = np.concatenate([[0], np.cumsum(np.bincount(r[self.take], minlength=n_blocks * ndof))])
        self.indptr = self.indptr.astype(np.int32)

    @staticmethod
    def keys_of(matrix: sp.bsr_matrix) -> np.ndarray:
        n_blocks = matrix.shape[0] // matrix.blocksize[0]
        rows = np.repeat(np.arange(n_blocks), np.diff(matrix.indptr))
        return rows * n_blocks + matrix.indices

    def positions(self, keys: np.ndarray) -> np.ndarray | None:
        """Where the blocks ``keys`` sit in this pattern, or None if some are not in it."""
        pos = np.searchsorted(self.keys, keys)
        inside = pos < len(self.keys)
        if not np.all(inside) or not np.array_equal(self.keys[pos], keys):
            return None
        return pos

    def csr(self, matrix: sp.bsr_matrix, positions: np.ndarray) -> sp.csr_matrix:
        """``matrix`` (BSR) with this pattern's structure (upper triangle only if the pattern is)."""
        data = np.zeros((len(self.keys), self.ndof, self.ndof))
        data[positions] = matrix.data
        n = self.n_blocks * self.ndof
        return sp.csr_matrix((data.reshape(-1)[self.take], self.indices, self.indptr), shape=(n, n))


class _Analysing:
    """A direct backend that orders and analyses the block pattern once, and factorises the values per matrix.

    The factor is kept while the matrix is unchanged (as :class:`_Factorizing`);
    constrained (saddle-point) systems go to SuperLU's LU with pivoting.
    """

    name = "base"
    upper = False  # the backend reads the upper triangle only

    def __init__(self) -> None:
        self.pattern: _BlockPattern | None = None
        self.analyses = 0  # symbolic analyses made (benchmarks read them)
        self.factorizations = 0
        self._last: tuple[sp.csr_matrix, Factor] | None = None
        self._saddle = SuperLUSolver()

    def analyse(self, matrix: sp.csr_matrix) -> None:
        raise NotImplementedError

    def factorize(self, matrix: sp.csr_matrix) -> Factor:
        raise NotImplementedError

    def solve(self, system: BlockSystem, rhs: np.ndarray) -> np.ndarray:
        if system.n_constraints:
            return self._saddle.solve(system, rhs)
        bsr = system.to_bsr()
        keys = _BlockPattern.keys_of(bsr)
        pattern = self.pattern
        positions = None if pattern is None or pattern.n_blocks != system.n_blocks else pattern.positions(keys)
        if positions is None:
            if pattern is not None and pattern.n_blocks == system.n_blocks:
                union = np.union1d(pattern.keys, keys)
                keys_used = union if len(union) <= _BlockPattern.GROWTH * len(keys) else keys
            else:
                keys_used = keys
            pattern = self.pattern = _BlockPattern(keys_used, system.n_blocks, system.ndof, self.upper)
            positions = pattern.positions(keys)
            assert positions is not None
            matrix = pattern.csr(bsr, positions)
            self.analyse(matrix)
            self.analyses += 1
            self._last = None
        else:
            matrix = pattern.csr(bsr, positions)
        if self._last is not None and np.array_equal(self._last[0].data, matrix.data):
            factor = self._last[1]
        else:
            factor = self.factorize(matrix)
            self.factorizations += 1
            self._last = (matrix, factor)
        return _check(factor(rhs))


class CholmodSolver(_Analysing):
    """CHOLMOD's supernodal Cholesky: ``analyze`` once per block pattern, ``cholesky_inplace`` per matrix."""

    name = "cholmod"

    def analyse(self, matrix: sp.csr_matrix) -> None:
        from sksparse.cholmod import analyze

        # a symmetric matrix's CSR arrays are its CSC arrays
        self._factor = analyze(sp.csc_matrix((matrix.data, matrix.indices, matrix.indptr), shape=matrix.shape))

    def factorize(self, matrix: sp.csr_matrix) -> Factor:
        from sksparse.cholmod import CholmodError

        try:
            # the supernodal factorisation is the one BLAS work of a step that threads speed up (a run
            # otherwise holds BLAS to one thread, :func:`blas_threads_for_steps`)
            with threadpool_limits(limits=os.cpu_count(), user_api="blas"):
                self._factor.cholesky_inplace(sp.csc_matrix((matrix.data, matrix.indices, matrix.indptr),
                                                            shape=matrix.shape))
        except CholmodError as exc:
            raise SolverError(f"CHOLMOD failed: {exc}") from exc
        return self._factor


class PardisoSolver(_Analysing):
    """MKL PARDISO for symmetric positive definite matrices (mtype 2, upper triangle).

    Phase 11 (ordering, symbolic factorisation) once per block pattern, phase
    22 (numerical Cholesky) per matrix, phase 33 (substitution) per solve.
    pypardiso exposes the phases through ``set_phase`` and its ``_call_pardiso``.
    """

    name = "pardiso"
    upper = True

    def analyse(self, matrix: sp.csr_matrix) -> None:
        import pypardiso

        if getattr(self, "_pardiso", None) is not None:
            self._pardiso.free_memory(everything=True)  # MKL's memory of the previous analysis
        self._pardiso = pypardiso.PyPardisoSolver(mtype=2)
        self._pardiso.set_iparm(12, 0)  # CSR input
        self._phase(11, matrix, np.zeros(matrix.shape[0]))

    def _phase(self, phase: int, matrix: sp.csr_matrix, rhs: np.ndarray) -> np.ndarray:
        from pypardiso.pardiso_wrapper import PyPardisoError

        self._pardiso.set_phase(phase)
        try:
            return self._pardiso._call_pardiso(matrix, np.asfortranarray(rhs))
        except PyPardisoError as exc:
            raise SolverError(f"PARDISO failed in phase {phase} (-4: the matrix is not positive definite): "
                              f"{exc}") from exc

    def factorize(self, matrix: sp.csr_matrix) -> Factor:
        self._phase(22, matrix, np.zeros(matrix.shape[0]))
        return lambda rhs: self._phase(33, matrix, rhs)


class ConjugateGradientSolver:
    """Preconditioned conjugate gradient to a displacement tolerance (solvers_iterative module doc).

    ``preconditioner`` is ``"amg"`` (pyamg's smoothed aggregation) or
    ``"jacobi"`` (the inverse block diagonal, rebuilt for every matrix: one
    batched ndof×ndof inverse). Each solve starts from the previous solution
    (the open-close iteration changes a few contacts; successive steps move
    alike).

    A multigrid hierarchy is built from one matrix and kept while it serves:
    a solve that has not converged after ``REBUILD_ITERATIONS`` builds a new
    one from its own matrix and goes on from where it stopped (contacts that
    open or close can leave a block held by inertia alone, which the old
    aggregates do not represent; a fresh hierarchy solves these systems from
    zero in 10-25 iterations). The stopping rule's estimate of λ_min(M⁻¹A):
    for a new hierarchy, ``PROBE_ITERATIONS`` Lanczos steps from a random
    vector, halved (they overestimate it by up to 20 % on the walls and slopes
    measured), then the smallest Ritz value of the solves made with it; for
    block-Jacobi, the smallest of all solves (the first one starts from zero).
    Systems with constraint rows (saddle points, not definite) go to the best
    installed direct backend.
    """

    MAX_ITERATIONS = 5000
    REBUILD_ITERATIONS = 40
    PROBE_ITERATIONS = 20

    def __init__(self, preconditioner: str, tolerance: float = DEFAULT_TOLERANCE) -> None:
        if preconditioner not in ("amg", "jacobi"):
            raise ValueError(f"unknown preconditioner {preconditioner!r}; choose 'amg' or 'jacobi'")
        if not tolerance > 0:
            raise ValueError(f"the displacement tolerance must be positive, got {tolerance}")
        self.name = f"cg-{preconditioner}"
        self.preconditioner = preconditioner
        self.tolerance = tolerance
        self.direct = _best_direct()
        self.iterations: list[int] = []  # per solve (benchmarks and tests read them)
        self.setups = 0  # preconditioners built
        self._x: np.ndarray | None = None
        self._amg: SmoothedAggregation | None = None
        self._ritz = np.inf

    def _build_hierarchy(self, matrix: sp.bsr_matrix) -> SmoothedAggregation:
        self._amg = SmoothedAggregation(matrix)
        self.setups += 1
        start = np.random.default_rng(0).standard_normal(matrix.shape[0])  # seeded: runs stay reproducible
        self._ritz = 0.5 * smallest_eigenvalue_estimate(matrix.__matmul__, self._amg, start, self.PROBE_ITERATIONS)
        return self._amg

    def _pcg(self, system: BlockSystem, matrix: sp.bsr_matrix, rhs: np.ndarray, x0: np.ndarray) -> PCGResult:
        if self.preconditioner == "jacobi":
            self.setups += 1
            return block_jacobi_pcg(matrix, BlockJacobi(system.diag), rhs, x0, self.tolerance, self.MAX_ITERATIONS,
                                    self._ritz)
        if self._amg is not None and self._amg.hierarchy.levels[0].A.shape == matrix.shape:
            first = pcg(matrix.__matmul__, self._amg, rhs, x0, self.tolerance, self.REBUILD_ITERATIONS, self._ritz)
            if first.converged:
                return first
            x0 = first.x
        else:
            first = None
        hierarchy = self._build_hierarchy(matrix)  # sets the estimate self._ritz
        second = pcg(matrix.__matmul__, hierarchy, rhs, x0, self.tolerance, self.MAX_ITERATIONS, self._ritz)
        return second if first is None else replace(second, iterations=first.iterations + second.iterations)

    def solve(self, system: BlockSystem, rhs: np.ndarray) -> np.ndarray:
        if system.n_constraints:
            return self.direct.solve(system, rhs)
        matrix = system.to_bsr()
        if self._x is None or len(self._x) != len(rhs):
            if self._x is not None or self.preconditioner == "jacobi":  # another model: forget its estimate
                self._ritz = np.inf
            self._x = np.zeros_like(rhs)
        try:
            result = self._pcg(system, matrix, rhs, self._x)
        except IterativeSolverError as exc:
            self._x = None
            raise SolverError(f"{self.name}: {exc}") from exc
        if not result.converged:
            self._x = None
            raise SolverError(f"{self.name}: the conjugate gradient did not reach the displacement tolerance "
                              f"{self.tolerance:.3g} m in {result.iterations} iterations (estimated error "
                              f"{result.final_residual / result.smallest_ritz:.3g} m)")
        self._ritz = result.smallest_ritz
        self.iterations.append(result.iterations)
        self._x = result.x.copy()
        return _check(result.x)


def blas_threads_for_steps() -> threadpool_limits:
    """A context that holds BLAS (OpenBLAS, MKL) to one thread while a run steps.

    The step's BLAS work is numpy's stacked products of 6×6 and 12×12 blocks,
    which take the same wall time on one thread as on two; the idle BLAS
    threads spin after each call and take the cores from the compiled
    parallel conjugate gradient (the 10,000-brick wall's solves took 2.8
    times longer, docs/performance.md). CHOLMOD's factorisation lifts the
    limit for itself.
    """
    return threadpool_limits(limits=1, user_api="blas")


def _best_direct() -> LinearSolver:
    """The fastest installed direct backend for large systems (measured in docs/performance.md)."""
    return get_solver(next(n for n in ("pardiso", "cholmod", "superlu") if n in available_solvers()))


class AutoSolver:
    """The backend by size: dense LAPACK, then a direct factorisation, then the block-Jacobi conjugate gradient.

    Up to ``DENSE_LIMIT`` unknowns: dense. Up to ``ITERATIVE_LIMIT`` blocks: the
    best installed direct backend (:func:`_best_direct`). Above: ``cg-jacobi``,
    which falls back to the direct backend for a solve it cannot make (a
    matrix found not positive definite, no convergence); ``fallbacks`` counts
    them. Why block-Jacobi and not the multigrid, and the thresholds: measured
    in docs/performance.md (the open-close iteration's warm-started solves
    need a few cheap iterations, where a hierarchy is rebuilt often).
    """

    name = "auto"

    def __init__(self, tolerance: float = DEFAULT_TOLERANCE, iterative: LinearSolver | None = None) -> None:
        self.dense = DenseSolver()
        self.direct = _best_direct()
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

    def solve(self, system: BlockSystem, rhs: np.ndarray) -> np.ndarray:
        chosen = self.choose(system)
        if chosen is not self.iterative:
            return chosen.solve(system, rhs)
        try:
            return chosen.solve(system, rhs)
        except SolverError:
            self.fallbacks += 1
            return self.direct.solve(system, rhs)


_BACKENDS: dict[str, Callable[..., LinearSolver]] = {
    "dense": DenseSolver, "superlu": SuperLUSolver, "cholmod": CholmodSolver, "pardiso": PardisoSolver,
    "cg-amg": lambda tolerance: ConjugateGradientSolver("amg", tolerance),
    "cg-jacobi": lambda tolerance: ConjugateGradientSolver("jacobi", tolerance),
    "auto": AutoSolver}
_ITERATIVE = ("cg-amg", "cg-jacobi", "auto")  # the backends that take a displacement tolerance
_MODULES = {"cholmod": "sksparse", "pardiso": "pypardiso"}
SOLVERS = tuple(_BACKENDS)


def available_solvers() -> list[str]:
    """Names of the backends usable on this machine."""
    return [n for n in _BACKENDS if n not in _MODULES or importlib.util.find_spec(_MODULES[n]) is not None]


def get_solver(name: str = "auto", tolerance: float = DEFAULT_TOLERANCE, device: str = "cpu") -> LinearSolver:
    """The backend called ``name`` (see module doc); ``tolerance`` (m) is the iterative backends' stopping rule.

    ``device="gpu"``: ``cg-jacobi``, or ``auto`` with its conjugate gradient, on a CUDA GPU through CuPy
    (:func:`srdda.backends.conjugate_gradient.gpu_solver`; ``RunSettings.resolved_device`` chooses).
    """
    if name not in _BACKENDS:
        raise ValueError(f"unknown solver {name!r}; choose one of {sorted(_BACKENDS)}")
    if device == "gpu":
        from .backends.conjugate_gradient import gpu_solver

        return gpu_solver(name, tolerance)
    if device != "cpu":
        raise ValueError(f"unknown device {device!r} for a solver; choose 'cpu' or 'gpu'")
    if name not in available_solvers():
        raise ValueError(f"solver {name!r} is not installed (pip install srdda[{name}])")
    return _BACKENDS[name](tolerance) if name in _ITERATIVE else _BACKENDS[name]()
