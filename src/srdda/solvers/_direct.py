"""The direct backends: LAPACK on the dense matrix, SuperLU, block Cholesky, CHOLMOD and PARDISO (the package doc
compares them).

A system with constraint rows is solved by LU of the augmented matrix with pivoting (every backend here:
Cholesky needs a definite matrix).
"""
from __future__ import annotations

import os
import warnings
from collections import OrderedDict
from collections.abc import Callable
from typing import TYPE_CHECKING, NamedTuple, TypeAlias

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from threadpoolctl import threadpool_limits

from ..assembly.system import BlockSystem
from ._blockcholesky import BlockFactorPattern, factorize_blocks, solve_factored
from ._registry import SolverError, check_finite, register_solver

if TYPE_CHECKING:
    import pypardiso  # optional (srdda[pardiso]), imported where used; it ships no stubs

__all__ = ["DenseSolver", "SuperLUSolver", "BlockCholeskySolver", "CholmodSolver", "PardisoSolver",
           "blas_threads_for_steps"]


Matrix: TypeAlias = sp.csr_matrix  # what _Factorizing.matrix assembles
Factor = Callable[[np.ndarray], np.ndarray]


def _same(a: Matrix, b: Matrix) -> bool:
    """True if two assembled matrices are equal entry for entry (same sparsity and values)."""
    if isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
        return isinstance(a, np.ndarray) and isinstance(b, np.ndarray) and np.array_equal(a, b)
    return (a.shape == b.shape and np.array_equal(a.indptr, b.indptr) and np.array_equal(a.indices, b.indices)
            and np.array_equal(a.data, b.data))


class _Exact:
    """A backend that solves every system to rounding (``tolerance`` is ignored)."""

    def inexact(self, system: BlockSystem) -> bool:
        return False


class _Factorizing(_Exact):
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

    def solve(self, system: BlockSystem, rhs: np.ndarray, tolerance: float | None = None) -> np.ndarray:
        matrix = self.matrix(system)
        if self._last is not None and _same(self._last[0], matrix):
            factor = self._last[1]
        else:
            factor = self.factor(matrix, bool(system.n_constraints))
            self.factorizations += 1
            self._last = (matrix, factor)
        return check_finite(factor(rhs))


def _saddle_superlu(matrix: sp.csr_matrix) -> Factor:
    """Sparse LU (SuperLU, partial pivoting) of the augmented constrained system."""
    try:
        return spla.splu(matrix.tocsc(), permc_spec="COLAMD").solve
    except RuntimeError as exc:
        raise SolverError(f"singular constrained system (redundant or conflicting constraints?): {exc}") from exc


class DenseSolver(_Exact):
    """LAPACK's symmetric solve of the dense matrix (tiny systems: refactorising costs less than comparing)."""

    name = "dense"

    def solve(self, system: BlockSystem, rhs: np.ndarray, tolerance: float | None = None) -> np.ndarray:
        matrix = system.saddle_dense() if system.n_constraints else system.to_dense()
        try:
            with warnings.catch_warnings():
                if system.n_constraints:  # O(1) constraint rows beside stiff penalties: rcond ~1e-23 by scaling
                    warnings.simplefilter("ignore", sla.LinAlgWarning)
                return check_finite(sla.solve(matrix, rhs, assume_a="sym", check_finite=False))
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


def block_keys(columns: np.ndarray, pointers: np.ndarray, n_blocks: int) -> np.ndarray:
    """The keys row·n_blocks + column of a block-sparse matrix's blocks (its BSR ``indices`` and ``indptr``),
    sorted if each row's columns are."""
    return np.repeat(np.arange(n_blocks), np.diff(pointers)) * n_blocks + columns


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
        return block_keys(matrix.indices, matrix.indptr, matrix.shape[0] // matrix.blocksize[0])

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


class _Analysing(_Exact):
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

    def solve(self, system: BlockSystem, rhs: np.ndarray, tolerance: float | None = None) -> np.ndarray:
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
            assert pattern is not None  # positions were found in it
            matrix = pattern.csr(bsr, positions)
        if self._last is not None and np.array_equal(self._last[0].data, matrix.data):
            factor = self._last[1]
        else:
            factor = self.factorize(matrix)
            self.factorizations += 1
            self._last = (matrix, factor)
        return check_finite(factor(rhs))


class _KeptFactor(NamedTuple):
    """The last factorisation: its matrix's block pattern (bytes of its keys), blocks, and substitution."""

    pattern: bytes
    data: np.ndarray
    substitute: Factor


class BlockCholeskySolver(_Exact):
    """Sparse Cholesky whose entries are the system's dense ndof×ndof blocks (``_blockcholesky``).

    The ordering and symbolic factorisation are made for the matrix's own block pattern and kept for the
    last ``KEPT`` patterns met (contacts that open and close make a step's patterns recur); the factor is kept
    while the matrix is unchanged. Unlike the union that CHOLMOD and PARDISO analyse, a pattern's analysis
    does not depend on the matrices solved before it, so a run resumed from a saved state repeats the
    uninterrupted run bit for bit. Constrained systems go to SuperLU's LU with pivoting.
    """

    name = "block-cholesky"
    KEPT = 16  # analyses kept (an ordering and symbolic factorisation: about 0.3 ms at 74 blocks, 1 ms at 273)

    def __init__(self) -> None:
        self.analyses = 0  # symbolic analyses made (benchmarks read them)
        self.factorizations = 0
        self._patterns: OrderedDict[bytes, BlockFactorPattern] = OrderedDict()
        self._last: _KeptFactor | None = None
        self._saddle = SuperLUSolver()

    def _analysis(self, pattern: bytes, keys: np.ndarray, n_blocks: int) -> BlockFactorPattern:
        kept = self._patterns.get(pattern)
        if kept is None:
            kept = self._patterns[pattern] = BlockFactorPattern(keys, n_blocks)
            self.analyses += 1
            if len(self._patterns) > self.KEPT:
                self._patterns.popitem(last=False)
        else:
            self._patterns.move_to_end(pattern)
        return kept

    def solve(self, system: BlockSystem, rhs: np.ndarray, tolerance: float | None = None) -> np.ndarray:
        if system.n_constraints:
            return self._saddle.solve(system, rhs)
        data, columns, pointers = system.block_rows()
        keys = block_keys(columns, pointers, system.n_blocks)
        pattern = keys.tobytes() + system.n_blocks.to_bytes(8, "little")
        last = self._last
        if last is not None and last.pattern == pattern and np.array_equal(last.data, data):
            return check_finite(last.substitute(rhs))
        symbolic = self._analysis(pattern, keys, system.n_blocks)
        factor = symbolic.placed(data)
        failed = factorize_blocks(symbolic.pointers, symbolic.rows, factor)
        if failed >= 0:
            raise SolverError(f"the matrix is not positive definite (block {symbolic.order[failed]})")
        self.factorizations += 1
        ndof = system.ndof

        def substitute(b: np.ndarray) -> np.ndarray:
            blocks = b.reshape(-1, ndof)
            return solve_factored(symbolic.pointers, symbolic.rows, factor, symbolic.order, blocks).ravel()

        self._last = _KeptFactor(pattern, data.copy(), substitute)  # a copy: a caller may change its system in place
        return check_finite(substitute(rhs))


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
    _pardiso: pypardiso.PyPardisoSolver  # set by analyse

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


register_solver("dense", lambda tolerance: DenseSolver())
register_solver("superlu", lambda tolerance: SuperLUSolver())
register_solver("block-cholesky", lambda tolerance: BlockCholeskySolver())
register_solver("cholmod", lambda tolerance: CholmodSolver(), requires="sksparse")
register_solver("pardiso", lambda tolerance: PardisoSolver(), requires="pypardiso")
