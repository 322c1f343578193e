"""The block-Jacobi conjugate gradient of a step on an array backend: numpy in CI, CuPy on a GPU (issue 34).

The iteration, its stopping rule (every unknown within ``solver_tolerance``, estimated through the
smallest Ritz value), its warm start and its errors are those of the CPU's ``cg-jacobi``
(:class:`srdda.solvers.ConjugateGradientSolver`, :func:`srdda.solvers.pcg`): this class
only puts the matrix, the preconditioner and the vectors on the backend's device.

What moves to the device, per solve:

* the values of the step's matrix, as the CPU assembles them (``BlockSystem.to_bsr``: ndof×ndof
  blocks, duplicates summed), and, for a system without kept springs, the inverse diagonal blocks of
  block-Jacobi (computed on the CPU by the same compiled Cholesky as the CPU path, which names a block
  that is not positive definite);
* the right-hand side and the start (the last solution); the solution comes back.

The contact springs do not go into that matrix (the solver ``takes_springs``, so the step keeps them
as :class:`~srdda.assembly.system.SpringStack`): their rows move to the device once a step, as a
sparse matrix R of one row per spring row (the rows of its two blocks), and each solve sends only
which springs act (weights w). The product is then A·x = B·x + Rᵀ(w ⊙ R·x), B the rest of the matrix
(the blocks' own terms); block-Jacobi's diagonal blocks get the springs' w·rᵀr summed on the device,
and their inverses are computed there. This leaves out the CPU's work of summing the springs into
blocks at every solve and the upload of the summed matrix (wall_100k: 192 MB a solve).

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

from ..assembly.system import BlockSystem, SpringStack
from ..backends.arrays import GPU_SOLVERS, ArrayBackend, cupy_backend
from ._auto import AutoSolver
from ._iterative import BlockJacobi, ConjugateGradientSolver, PCGResult, not_positive_definite_block, pcg
from ._registry import DEFAULT_TOLERANCE, LinearSolver, register_solver

__all__ = ["ArrayConjugateGradient", "BlockPatternCSR", "DeviceSprings", "block_diagonal_csr", "gpu_solver",
           "spd_inverses"]


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


class DeviceSprings:
    """A :class:`SpringStack`'s rows on a backend's device: R (one CSR row per spring row, the 2·ndof entries
    of its two blocks; a held block's entries zero, its columns being out of the matrix) and Rᵀ.

    Made once for the rows of a step; ``source`` holds the host arrays it was made from, so that a solve
    can tell whether its stack still has them.
    """

    def __init__(self, backend: ArrayBackend, stack: SpringStack, held: np.ndarray | None, n_blocks: int) -> None:
        xp = backend.xp
        self.backend = backend
        self.source = (stack.rows_a, held)
        n, m, ndof = stack.rows_a.shape
        free = np.ones(n_blocks, dtype=bool) if held is None else ~held
        block_a, block_b = (backend.to_device(np.asarray(b, dtype=np.int64)) for b in (stack.block_a, stack.block_b))
        self.block_a, self.block_b = block_a, block_b
        self.rows_a = backend.to_device(stack.rows_a * free[stack.block_a][:, None, None])
        self.rows_b = backend.to_device(stack.rows_b * free[stack.block_b][:, None, None])
        self.uploaded = 2 * stack.rows_a.nbytes + 2 * len(stack.block_a) * 8
        index = _index_dtype(max(n * m * (ndof + ndof), n_blocks * ndof) + 1)
        local = xp.arange(ndof, dtype=xp.int64)
        columns = xp.concatenate([block_a[:, None] * ndof + local, block_b[:, None] * ndof + local], axis=1)
        width = columns.shape[1]  # the two blocks' unknowns
        columns = xp.broadcast_to(columns[:, None, :], (n, m, width)).reshape(-1).astype(index)
        values = xp.concatenate([self.rows_a, -self.rows_b], axis=2).reshape(-1)
        pointers = xp.arange(0, n * m * width + 1, width, dtype=index)
        self.matrix = backend.sparse.csr_matrix((values, columns, pointers), shape=(n * m, n_blocks * ndof))
        self.transpose = self.matrix.T.tocsr()

    def weights(self, stack: SpringStack) -> Any:
        """w (n·m,): ``factor`` where a row acts, else 0 (the only thing a solve sends)."""
        active = self.backend.to_device(np.ascontiguousarray(stack.active).reshape(-1))
        return active.astype(self.backend.xp.float64) * stack.factor

    def apply(self, x: Any, weights: Any) -> Any:
        """Rᵀ(w ⊙ R·x): the springs' part of A·x."""
        return self.transpose @ (weights * (self.matrix @ x))

    def add_diagonal(self, diag: Any, weights: Any) -> None:
        """Add each spring's w·rᵀr to the diagonal blocks ``diag`` (n_blocks, ndof, ndof) of its two blocks."""
        xp = self.backend.xp
        n, m, ndof = self.rows_a.shape
        w = weights.reshape(n, m, 1)
        for block, rows in ((self.block_a, self.rows_a), (self.block_b, self.rows_b)):
            self.backend.scatter_add(diag, block, xp.matmul(xp.swapaxes(w * rows, 1, 2), rows))


def spd_inverses(backend: ArrayBackend, diag: Any) -> Any:
    """The inverses of symmetric positive definite blocks ``diag`` (n, ndof, ndof) on the device, by Cholesky
    (D = L·Lᵀ, D⁻¹ = L⁻ᵀ·L⁻¹); the CPU block-Jacobi's error naming the first block that is not positive definite."""
    xp = backend.xp
    try:
        low = backend.cholesky(diag)
        failed = not bool(xp.all(xp.isfinite(low)))
    except np.linalg.LinAlgError:  # for the whole batch: which block, from the eigenvalues
        failed = True
    if failed:
        values = backend.to_host(xp.linalg.eigvalsh(xp.where(xp.isfinite(diag), diag, -1.0)))
        bad = np.flatnonzero(~(values.min(axis=1) > 0))
        raise not_positive_definite_block(int(bad[0]) if len(bad) else 0)
    inverse_low = xp.linalg.inv(low)
    return xp.matmul(xp.swapaxes(inverse_low, 1, 2), inverse_low)


class ArrayConjugateGradient(ConjugateGradientSolver):
    """``cg-jacobi`` with the iteration on an array backend's device (module doc).

    The same solver as the CPU's (stopping rule, warm start from the last solution, the Ritz estimate
    kept between solves, constrained systems to the best direct backend, a ``SolverError`` saying what
    failed); only :meth:`_pcg` differs. ``uploaded_bytes`` counts what went to the device,
    ``pattern_builds`` the block patterns built there. The solver applies a system's springs itself
    (``takes_springs``; module doc).
    """

    def __init__(self, backend: ArrayBackend, tolerance: float = DEFAULT_TOLERANCE) -> None:
        super().__init__("jacobi", tolerance)
        self.backend = backend
        self.uploaded_bytes = 0
        self.pattern_builds = 0
        self._pattern: BlockPatternCSR | None = None
        self._jacobi: Any = None  # the block-diagonal CSR matrix of M⁻¹, kept while the system's size stays
        self._springs: list[DeviceSprings] = []  # the device's copies of the last solve's spring stacks

    def _upload(self, array: np.ndarray) -> Any:
        self.uploaded_bytes += array.nbytes
        return self.backend.to_device(array)

    def takes_springs(self, n_blocks: int) -> bool:
        return True

    def _matrix(self, system: BlockSystem) -> sp.bsr_matrix:
        """The matrix without the kept springs (the device applies them)."""
        return system.to_bsr(springs=False)

    def _device_springs(self, system: BlockSystem) -> list[DeviceSprings]:
        """The device's copies of ``system``'s spring stacks: those of the last solve while their rows are."""
        kept = []
        for k, stack in enumerate(system.springs):
            old = self._springs[k] if k < len(self._springs) else None
            if old is None or old.source[0] is not stack.rows_a or old.source[1] is not system.held:
                old = DeviceSprings(self.backend, stack, system.held, system.n_blocks)
                self.uploaded_bytes += old.uploaded
            kept.append(old)
        self._springs = kept
        return kept

    def _pcg(self, system: BlockSystem, matrix: sp.bsr_matrix, rhs: np.ndarray, x0: np.ndarray,
             tolerance: float) -> PCGResult:
        self.setups += 1
        ndof = system.ndof
        if self._pattern is None or not self._pattern.same(matrix):
            self._pattern = BlockPatternCSR(self.backend, matrix.indptr, matrix.indices, ndof)
            self.uploaded_bytes += matrix.indptr.nbytes + matrix.indices.nbytes
            self.pattern_builds += 1
        data = self._upload(np.ascontiguousarray(matrix.data))
        product = self._pattern.load(data)
        if self._jacobi is None or self._jacobi.shape[0] != system.size:
            self._jacobi = block_diagonal_csr(self.backend, system.n_blocks, ndof)
        matvec = product.__matmul__
        springs = self._device_springs(system)
        if springs:
            weights = [device.weights(stack) for device, stack in zip(springs, system.springs)]
            self.uploaded_bytes += sum(stack.active.size for stack in system.springs)
            only_diagonal = len(matrix.indices) == system.n_blocks  # B is block-diagonal: its data are the blocks
            # a copy: on numpy the upload is the host array itself, which the springs' sums must not change
            diag = (data if only_diagonal else self._upload(np.ascontiguousarray(system.diag))).copy()
            for device, w in zip(springs, weights):
                device.add_diagonal(diag, w)
            self._jacobi.data = spd_inverses(self.backend, diag).reshape(-1)

            def matvec(x: Any) -> Any:
                y = product @ x
                for device, w in zip(springs, weights):
                    y += device.apply(x, w)
                return y
        else:
            self._jacobi.data = self._upload(BlockJacobi(system.diag).inverse).reshape(-1)
        result = pcg(matvec, self._jacobi.__matmul__, self._upload(rhs), self._upload(x0),
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
