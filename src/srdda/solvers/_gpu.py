"""The block-Jacobi conjugate gradient of a step on an array backend: numpy in CI, CuPy on a GPU (issue 34).

The iteration, its stopping rule (every unknown within ``solver_tolerance``, estimated through the
smallest Ritz value), its warm start and its errors are those of the CPU's ``cg-jacobi``
(:class:`srdda.solvers.ConjugateGradientSolver`, :func:`srdda.solvers.pcg`): this class
only puts the matrix, the preconditioner and the vectors on the backend's device.

What moves to the device, per solve:

* the values of the step's matrix, as the CPU assembles them (``BlockSystem.to_bsr``: ndof×ndof
  blocks, duplicates summed), and the inverse diagonal blocks of block-Jacobi (computed on the CPU
  by the same compiled Cholesky as the CPU path, which names a block that is not positive definite);
* the right-hand side and the start (the last solution); the solution comes back.

The block pattern (BSR ``indptr`` and ``indices``) moves only when it changed: contacts that open or
close change it, within a step or from one step to the next. CuPy has no BSR matrix
(cupyx.scipy.sparse has COO, CSR, CSC and DIA), so the product is a CSR product (cuSPARSE's SpMV on
a GPU, scipy's on numpy): for each new pattern the CSR index arrays and the place of every block
entry in the CSR values are computed on the device with array operations (:class:`BlockPatternCSR`),
and each solve scatters the uploaded block values into CSR order there.
"""
from __future__ import annotations

from dataclasses import replace
from functools import partial
from typing import Any

import numpy as np
import scipy.sparse as sp

from ..assembly.system import BlockSystem
from ..backends.arrays import GPU_SOLVERS, ArrayBackend, cupy_backend
from ._auto import AutoSolver
from ._iterative import BlockJacobi, ConjugateGradientSolver, PCGResult, pcg
from ._registry import DEFAULT_TOLERANCE, LinearSolver, register_solver

__all__ = ["ArrayConjugateGradient", "BlockPatternCSR", "block_diagonal_csr", "gpu_solver"]


def _index_dtype(n: int) -> type:
    """int32 (what cuSPARSE's SpMV takes) while every index fits, else int64."""
    return np.int32 if n < 2**31 else np.int64


class BlockPatternCSR:
    """A BSR block pattern of ndof×ndof blocks as a CSR matrix on a backend, and where each block entry goes.

    Block k of block row i holds entries (a, c); in CSR order they sit in scalar row i·ndof + a,
    after that row's entries from the blocks before k. ``destination`` (nnzb, ndof, ndof) gives each
    entry's position in the CSR values, so ``load`` is one scatter of the uploaded values.
    """

    def __init__(self, backend: ArrayBackend, indptr: np.ndarray, indices: np.ndarray, ndof: int) -> None:
        self.indptr, self.indices = indptr.copy(), indices.copy()  # the host pattern, to compare the next one
        xp = backend.xp
        n_blocks, n_stored = len(indptr) - 1, len(indices)
        n, nnz = n_blocks * ndof, n_stored * ndof * ndof
        index = _index_dtype(max(n, nnz) + 1)
        block_ptr = backend.to_device(np.asarray(indptr, dtype=np.int64))
        block_col = backend.to_device(np.asarray(indices, dtype=np.int64))
        width = (block_ptr[1:] - block_ptr[:-1]) * ndof  # entries in each scalar row of block row i
        local = xp.arange(ndof, dtype=xp.int64)
        # CSR row i·ndof + a starts at indptr[i]·ndof² + a·width[i]
        row_start = (block_ptr[:-1, None] * ndof * ndof + local[None, :] * width[:, None]).reshape(-1)
        block = xp.arange(n_stored, dtype=xp.int64)
        row_of = xp.searchsorted(block_ptr, block, side="right") - 1  # the block row of each stored block
        # entry (a, c) of block k: row_start of (row_of[k], a), then (k - indptr[row]) blocks of ndof, then c
        within = (block - block_ptr[row_of]) * ndof
        self.destination = (row_start.reshape(n_blocks, ndof)[row_of][:, :, None] + within[:, None, None]
                            + local[None, None, :]).reshape(-1)
        columns = xp.empty(nnz, dtype=index)
        columns[self.destination] = xp.broadcast_to((block_col * ndof)[:, None, None] + local[None, None, :],
                                                    (n_stored, ndof, ndof)).reshape(-1).astype(index)
        row_ptr = xp.concatenate([row_start, xp.asarray([nnz], dtype=xp.int64)]).astype(index)
        self._values = xp.empty(nnz, dtype=xp.float64)
        self.matrix = backend.sparse.csr_matrix((self._values, columns, row_ptr), shape=(n, n))

    def same(self, matrix: sp.bsr_matrix) -> bool:
        """True if ``matrix`` has this block pattern."""
        return np.array_equal(self.indptr, matrix.indptr) and np.array_equal(self.indices, matrix.indices)

    def load(self, values: Any) -> Any:
        """The CSR matrix holding ``values`` (the device's copy of the BSR data, (nnzb, ndof, ndof))."""
        self._values[self.destination] = values.reshape(-1)
        self.matrix.data = self._values
        return self.matrix


def block_diagonal_csr(backend: ArrayBackend, n_blocks: int, ndof: int) -> Any:
    """A block-diagonal CSR matrix of ``n_blocks`` ndof×ndof blocks whose values are the blocks in C order.

    Row i·ndof + a holds block i's row a: its values are ``blocks.reshape(-1)`` as they lie, so setting
    ``.data`` to a device copy of the blocks makes the matrix (block-Jacobi's M⁻¹).
    """
    xp = backend.xp
    n, nnz = n_blocks * ndof, n_blocks * ndof * ndof
    index = _index_dtype(nnz + 1)
    local = xp.arange(ndof, dtype=index)
    columns = ((xp.arange(n, dtype=index) // ndof * ndof)[:, None] + local[None, :]).reshape(-1)
    return backend.sparse.csr_matrix((xp.zeros(nnz, dtype=xp.float64), columns,
                                      xp.arange(0, nnz + 1, ndof, dtype=index)), shape=(n, n))


class ArrayConjugateGradient(ConjugateGradientSolver):
    """``cg-jacobi`` with the iteration on an array backend's device (module doc).

    The same solver as the CPU's (stopping rule, warm start from the last solution, the Ritz estimate
    kept between solves, constrained systems to the best direct backend, a ``SolverError`` saying what
    failed); only :meth:`_pcg` differs. ``uploaded_bytes`` counts what went to the device,
    ``pattern_builds`` the block patterns built there.
    """

    def __init__(self, backend: ArrayBackend, tolerance: float = DEFAULT_TOLERANCE) -> None:
        super().__init__("jacobi", tolerance)
        self.backend = backend
        self.uploaded_bytes = 0
        self.pattern_builds = 0
        self._pattern: BlockPatternCSR | None = None
        self._jacobi: Any = None  # the block-diagonal CSR matrix of M⁻¹, kept while the system's size stays

    def _upload(self, array: np.ndarray) -> Any:
        self.uploaded_bytes += array.nbytes
        return self.backend.to_device(array)

    def _pcg(self, system: BlockSystem, matrix: sp.bsr_matrix, rhs: np.ndarray, x0: np.ndarray,
             tolerance: float) -> PCGResult:
        self.setups += 1
        inverse = BlockJacobi(system.diag).inverse
        ndof = system.ndof
        if self._pattern is None or not self._pattern.same(matrix):
            self._pattern = BlockPatternCSR(self.backend, matrix.indptr, matrix.indices, ndof)
            self.uploaded_bytes += matrix.indptr.nbytes + matrix.indices.nbytes
            self.pattern_builds += 1
        product = self._pattern.load(self._upload(np.ascontiguousarray(matrix.data)))
        if self._jacobi is None or self._jacobi.shape[0] != system.size:
            self._jacobi = block_diagonal_csr(self.backend, system.n_blocks, ndof)
        self._jacobi.data = self._upload(inverse).reshape(-1)
        result = pcg(product.__matmul__, self._jacobi.__matmul__, self._upload(rhs), self._upload(x0),
                     tolerance, self.MAX_ITERATIONS, self._ritz)
        return replace(result, x=self.backend.to_host(result.x))


def gpu_solver(name: str, tolerance: float = DEFAULT_TOLERANCE, backend: ArrayBackend | None = None) -> LinearSolver:
    """The solver ``name`` with its conjugate gradient on ``backend`` (default: the GPU, CuPy).

    ``cg-jacobi``: every unconstrained system on the device. ``auto``: the CPU's choice by size (dense
    LAPACK, then a direct factorisation up to ``ITERATIVE_LIMIT`` blocks, constrained systems direct)
    with the device's conjugate gradient above, falling back to the direct backend for a solve it
    cannot make. Raises :class:`~srdda.backends.arrays.GpuUnavailable` without a GPU.
    """
    if name not in GPU_SOLVERS:
        raise ValueError(f"solver {name!r} has no GPU backend; with device 'gpu' choose one of "
                         f"{', '.join(GPU_SOLVERS)}")
    iterative = ArrayConjugateGradient(cupy_backend() if backend is None else backend, tolerance)
    return iterative if name == "cg-jacobi" else AutoSolver(tolerance, iterative=iterative)


for _name in GPU_SOLVERS:
    register_solver(_name, partial(gpu_solver, _name), device="gpu")
