"""Sparse Cholesky in the blocks' own units: every entry of the factor is a dense ndof×ndof block.

A DDA step's matrix is block-sparse with dense 6×6 (2D) or 12×12 (3D) blocks,
coupled only where contacts and springs join two blocks. Factorising it entry by
entry (SuperLU, QDLDL) spends most of its time on index work and on orderings
that it cannot keep; here the ordering and the symbolic factorisation are made
on the graph of the blocks, once per block pattern (``BlockCholeskySolver`` keeps
the last ones), and the numerical factorisation is a left-looking Cholesky whose
every operation is a small dense product, in one compiled pass, compiled once
per block size. Measured against SuperLU in docs/performance.md, *Direct solves
in blocks*.

The fill-reducing ordering is SuperLU's multiple minimum degree on the block
graph (a matrix of one entry per block), so no ordering is written here.
"""
from __future__ import annotations

from collections.abc import Callable

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from numba import njit

__all__ = ["BlockFactorPattern", "minimum_degree_order", "factorize_blocks", "solve_factored"]


def minimum_degree_order(keys: np.ndarray, n_blocks: int) -> np.ndarray:
    """A fill-reducing order of the blocks (new position → block) for the symmetric block pattern ``keys``
    (sorted keys row·n_blocks + column, the diagonal included).

    SuperLU's multiple minimum degree on AᵀA + A, read from the column permutation of a factorisation of a
    diagonally dominant matrix with the pattern (one entry per block; its CSR arrays are its CSC arrays).
    """
    rows, cols = np.divmod(keys, n_blocks)
    off = rows != cols
    degree = np.bincount(rows[off], minlength=n_blocks)
    graph = sp.csc_matrix((np.where(off, -1.0, (degree + 1.0)[rows]), cols.astype(np.int32),
                           np.searchsorted(rows, np.arange(n_blocks + 1)).astype(np.int32)),
                          shape=(n_blocks, n_blocks))
    lu = spla.splu(graph, permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0, options={"SymmetricMode": True})
    return np.argsort(lu.perm_c)  # perm_c holds each block's new position (read as the order: 2.7-4.2 × the fill)


class BlockFactorPattern:
    """The symbolic factorisation of a block pattern: the order, and the factor's block columns.

    ``keys`` are the sorted block keys row·n_blocks + column of the full (symmetric) pattern. Column j of the
    factor (in the new order) holds the blocks ``rows[pointers[j]:pointers[j + 1]]``, the diagonal first, the
    others ascending. :meth:`placed` puts a matrix of the pattern into the factor's blocks.
    """

    def __init__(self, keys: np.ndarray, n_blocks: int) -> None:
        rows, cols = np.divmod(keys, n_blocks)
        self.order = minimum_degree_order(keys, n_blocks)  # new position → block
        position = np.empty(n_blocks, dtype=np.int64)  # block → new position
        position[self.order] = np.arange(n_blocks)
        new_row, new_col = position[rows], position[cols]
        lower = new_row > new_col
        by_column = np.argsort(new_col[lower], kind="stable")
        below = new_row[lower][by_column]
        starts = np.concatenate([[0], np.cumsum(np.bincount(new_col[lower], minlength=n_blocks))])
        self.pointers, self.rows = _symbolic(n_blocks, starts, below)
        destination = _destinations(new_row, new_col, self.pointers, self.rows)
        self._read = np.flatnonzero(destination >= 0)  # the matrix's blocks on or below the new diagonal
        self._written = destination[self._read]  # and where they go in the factor

    @property
    def n_factor_blocks(self) -> int:
        return len(self.rows)

    def placed(self, data: np.ndarray) -> np.ndarray:
        """The factor's blocks before the factorisation: the blocks ``data`` (n_keys, d, d) of a matrix with
        this pattern (its keys' order) at their places, zeros at the fill-in."""
        factor = np.zeros((self.n_factor_blocks, *data.shape[1:]))
        factor[self._written] = data[self._read]
        return factor


@njit(cache=True)
def _append_unmarked(source: np.ndarray, lo: int, hi: int, mark: np.ndarray, column: int, rows: np.ndarray,
                     end: int) -> int:
    """Append the rows source[lo:hi] not yet marked for ``column`` at rows[end:], marking them; the new end."""
    for p in range(lo, hi):
        i = source[p]
        if mark[i] != column:
            mark[i] = column
            rows[end] = i
            end += 1
    return end


@njit(cache=True)
def _symbolic(n_blocks: int, starts: np.ndarray, below: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The factor's block columns from the lower pattern (column j's rows ``below[starts[j]:starts[j + 1]]``):
    column j is j, its own rows and its elimination-tree children's rows below it (fill-in)."""
    pointers = np.zeros(n_blocks + 1, dtype=np.int64)
    capacity = max(16, 2 * (len(below) + n_blocks))
    rows = np.empty(capacity, dtype=np.int64)
    mark = np.full(n_blocks, -1, dtype=np.int64)
    child_head = np.full(n_blocks, -1, dtype=np.int64)
    child_next = np.full(n_blocks, -1, dtype=np.int64)
    for j in range(n_blocks):
        start = pointers[j]
        if start + n_blocks - j > capacity:  # at most n_blocks − j rows in column j
            capacity = max(2 * capacity, start + n_blocks - j)
            grown = np.empty(capacity, dtype=np.int64)
            grown[:start] = rows[:start]
            rows = grown
        rows[start] = j
        mark[j] = j
        end = _append_unmarked(below, starts[j], starts[j + 1], mark, j, rows, start + 1)
        child = child_head[j]
        while child != -1:
            end = _append_unmarked(rows, pointers[child] + 1, pointers[child + 1], mark, j, rows, end)
            child = child_next[child]
        rows[start + 1:end] = np.sort(rows[start + 1:end])
        pointers[j + 1] = end
        if end - start > 1:
            parent = rows[start + 1]
            child_next[j] = child_head[parent]
            child_head[parent] = j
    return pointers, rows[:pointers[n_blocks]].copy()


@njit(cache=True)
def _destinations(new_row: np.ndarray, new_col: np.ndarray, pointers: np.ndarray, rows: np.ndarray) -> np.ndarray:
    """Where each matrix block (new_row, new_col) sits in the factor's columns (−1 above the diagonal)."""
    out = np.full(len(new_row), -1, dtype=np.int64)
    for k in range(len(new_row)):
        i, j = new_row[k], new_col[k]
        if i < j:
            continue
        lo, hi = pointers[j], pointers[j + 1]
        while lo < hi:  # the column's rows ascend
            mid = (lo + hi) // 2
            if rows[mid] < i:
                lo = mid + 1
            else:
                hi = mid
        out[k] = lo
    return out


def _factorization(size: int) -> Callable[[np.ndarray, np.ndarray, np.ndarray], int]:
    """The left-looking block Cholesky of :func:`factorize_blocks` compiled for blocks of ``size`` × ``size``
    (a constant of the compiled code: the loops over a block have known lengths and vectorise), or, for
    ``size`` 0, for blocks of any size read from the factor. The same operations in the same order: the
    same bits."""

    @njit(cache=True)
    def factorize(pointers: np.ndarray, rows: np.ndarray, factor: np.ndarray) -> int:
        d = size if size > 0 else factor.shape[1]
        n_blocks = len(pointers) - 1
        where = np.empty(n_blocks, dtype=np.int64)  # position of row i in the current column
        following = np.empty(n_blocks, dtype=np.int64)  # per done column k: the position of its next row to apply
        head = np.full(n_blocks, -1, dtype=np.int64)  # columns whose next row is j: a linked list through ``link``
        link = np.full(n_blocks, -1, dtype=np.int64)
        jk_t = np.empty((d, d))  # L_jkᵀ
        for j in range(n_blocks):
            for p in range(pointers[j], pointers[j + 1]):
                where[rows[p]] = p
            k = head[j]
            while k != -1:
                after = link[k]
                p = following[k]  # rows[p] == j: L_jk
                for b in range(d):
                    for c in range(d):
                        jk_t[c, b] = factor[p, b, c]
                for q in range(p, pointers[k + 1]):  # L_ij −= L_ik·L_jkᵀ for every row i ≥ j of column k
                    t = where[rows[q]]
                    for a in range(d):
                        for c in range(d):  # as rows of axpys, which vectorise (a dot product would not, in order)
                            x = factor[q, a, c]
                            for b in range(d):
                                factor[t, a, b] -= x * jk_t[c, b]
                if p + 1 < pointers[k + 1]:
                    following[k] = p + 1
                    r = rows[p + 1]
                    link[k] = head[r]
                    head[r] = k
                k = after
            diag = factor[pointers[j]]
            for a in range(d):  # the diagonal block's own Cholesky (lower), its upper part zeroed
                for b in range(a + 1):
                    s = diag[a, b]
                    for c in range(b):
                        s -= diag[a, c] * diag[b, c]
                    if a == b:
                        if not s > 0.0:  # also NaN
                            return j
                        diag[a, a] = np.sqrt(s)
                    else:
                        diag[a, b] = s / diag[b, b]
                for b in range(a + 1, d):
                    diag[a, b] = 0.0
            for q in range(pointers[j] + 1, pointers[j + 1]):  # L_ij = A'_ij·L_jj⁻ᵀ, row by row
                block = factor[q]
                for a in range(d):
                    for b in range(d):
                        s = block[a, b]
                        for c in range(b):
                            s -= block[a, c] * diag[b, c]
                        block[a, b] = s / diag[b, b]
            if pointers[j] + 1 < pointers[j + 1]:
                following[j] = pointers[j] + 1
                r = rows[pointers[j] + 1]
                link[j] = head[r]
                head[r] = j
        return -1

    return factorize


# blocks of up to this many unknowns a side are factorised by code compiled for their size (6 × 6: 0.98 → 0.61 ms
# on slope_b's matrices); larger ones by code that reads it (12 × 12 ran 11 % slower compiled for its size)
SIZED_FACTORIZATION = 8
_FACTORIZATIONS: dict[int, Callable[[np.ndarray, np.ndarray, np.ndarray], int]] = {}  # by block size, 0: any


def factorize_blocks(pointers: np.ndarray, rows: np.ndarray, factor: np.ndarray) -> int:
    """Left-looking block Cholesky in place: ``factor`` (n_factor_blocks, d, d) holds the matrix's lower blocks
    at their places (zeros elsewhere) and ends as L with A = L·Lᵀ (each diagonal block lower triangular).

    Returns −1, or the first block column whose diagonal block is not positive definite.
    """
    size = factor.shape[1] if factor.shape[1] <= SIZED_FACTORIZATION else 0
    if size not in _FACTORIZATIONS:
        _FACTORIZATIONS[size] = _factorization(size)
    return _FACTORIZATIONS[size](pointers, rows, factor)


def _substitution(d: int) -> Callable[[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray], np.ndarray]:
    """The substitutions of :func:`solve_factored` compiled for blocks of d × d (as :func:`_factorization`; its
    block product an inner function, not another compiled closure, whose on-disk cache would miss in every
    process)."""

    @njit(cache=True)
    def solve(pointers: np.ndarray, rows: np.ndarray, factor: np.ndarray, order: np.ndarray,
              rhs: np.ndarray) -> np.ndarray:

        def subtract_product(block: np.ndarray, x: np.ndarray, out: np.ndarray, transposed: bool) -> None:
            """out −= block·x, or blockᵀ·x if ``transposed`` (an inner function: compiled into ``solve``)."""
            for a in range(d):
                s = 0.0
                for c in range(d):
                    s += (block[c, a] if transposed else block[a, c]) * x[c]
                out[a] -= s

        n_blocks = len(pointers) - 1
        y = np.empty((n_blocks, d))
        for k in range(n_blocks):
            y[k] = rhs[order[k]]
        for j in range(n_blocks):  # L·z = y
            diag = factor[pointers[j]]
            for a in range(d):
                s = y[j, a]
                for c in range(a):
                    s -= diag[a, c] * y[j, c]
                y[j, a] = s / diag[a, a]
            for q in range(pointers[j] + 1, pointers[j + 1]):  # y_i −= L_ij·z_j below the diagonal
                subtract_product(factor[q], y[j], y[rows[q]], False)
        for j in range(n_blocks - 1, -1, -1):  # Lᵀ·x = z
            for q in range(pointers[j] + 1, pointers[j + 1]):  # x_j −= L_ijᵀ·x_i
                subtract_product(factor[q], y[rows[q]], y[j], True)
            diag = factor[pointers[j]]
            for a in range(d - 1, -1, -1):
                s = y[j, a]
                for c in range(a + 1, d):
                    s -= diag[c, a] * y[j, c]
                y[j, a] = s / diag[a, a]
        x = np.empty_like(y)
        for k in range(n_blocks):
            x[order[k]] = y[k]
        return x

    return solve


_SUBSTITUTIONS: dict[int, Callable[[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray], np.ndarray]] = {}


def solve_factored(pointers: np.ndarray, rows: np.ndarray, factor: np.ndarray, order: np.ndarray,
                   rhs: np.ndarray) -> np.ndarray:
    """x with L·Lᵀ·x' = b' in the factor's order (b' = rhs's blocks in ``order``), returned in the blocks' order."""
    d = factor.shape[1]
    if d not in _SUBSTITUTIONS:
        _SUBSTITUTIONS[d] = _substitution(d)
    return _SUBSTITUTIONS[d](pointers, rows, factor, order, rhs)
