"""The global block system: ndof×ndof sub-matrices assembled into one sparse matrix.

Sub-matrices are kept as dense stacks until the solve: ``diag`` (nb, ndof, ndof)
for every block and ``pair_blocks`` (np, ndof, ndof) for coupled pairs (row block
``pair_i``, column block ``pair_j``; the transposed block at (j, i) is implied). The
block-sparse matrix sums them in one compiled pass (``to_bsr``); the dense one of
tiny models by ``np.bincount``.

A solver that applies the matrix without assembling it (the device's conjugate gradient,
``srdda.solvers``) asks for ``keeps_springs``: penalty springs given as :class:`SpringStack` (unit
rows and which act) are then kept beside the stacks, their right-hand side added at once, and the
matrix's own methods sum them in only when one is asked for (:meth:`BlockSystem.sum_springs`).

Exact constraints (hinges, pins, prescribed motion by multipliers, paper
Eqs. 72-75) add rows C (nc, n) with right-hand side g: the system becomes the
saddle point [[A, Cᵀ], [C, 0]]·[Δd; μ] = [F; g] (``saddle_csr``), where the
constraint force on the first point of a constraint is -μ.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp
from numba import njit, prange

__all__ = ["BlockSystem", "PenaltyPairs", "SpringStack", "add_penalty_pairs", "scatter_add", "PARALLEL_BLOCKS"]

PARALLEL_BLOCKS = 500  # systems of more blocks run their compiled loops on all cores (docs/performance.md)


@njit(cache=True)
def _scatter_rows(target: np.ndarray, index: np.ndarray, values: np.ndarray) -> None:
    for i in range(index.shape[0]):
        row = index[i]
        for j in range(values.shape[1]):
            target[row, j] += values[i, j]


@njit(cache=True)
def _stored(diag: np.ndarray, stack: np.ndarray, rest: np.ndarray, row: int) -> np.ndarray:
    """Stored block ``row`` of [diag; stack; rest] (flattened blocks), without joining the three."""
    n = diag.shape[0]
    if row < n:
        return diag[row]
    return stack[row - n] if row < n + stack.shape[0] else rest[row - n - stack.shape[0]]


@njit(cache=True)
def _entry(diag: np.ndarray, stack: np.ndarray, rest: np.ndarray, row: int, j: int) -> float:
    """Entry j of stored block ``row`` of [diag; stack; rest]."""
    return _stored(diag, stack, rest, row)[j]


@njit(cache=True)
def _pairwise_sum(diag: np.ndarray, stack: np.ndarray, rest: np.ndarray, order: np.ndarray, flip: np.ndarray,
                  layouts: np.ndarray, lo: int, n: int, j: int) -> float:
    """numpy's pairwise sum of entry j of the blocks at sorted positions lo..lo+n (its add.reduce order,
    loops_utils.h); ``order``, ``flip`` and ``layouts`` as in :func:`_segment_sums`."""
    if n < 8:
        res = 0.0
        for i in range(n):
            res += _entry(diag, stack, rest, order[lo + i], layouts[flip[lo + i], j])
        return res
    if n <= 128:
        r = np.empty(8)
        for m in range(8):
            r[m] = _entry(diag, stack, rest, order[lo + m], layouts[flip[lo + m], j])
        i = 8
        while i < n - n % 8:
            for m in range(8):
                r[m] += _entry(diag, stack, rest, order[lo + i + m], layouts[flip[lo + i + m], j])
            i += 8
        width = 1  # the tree ((r0 + r1) + (r2 + r3)) + ((r4 + r5) + (r6 + r7))
        while width < 8:
            for m in range(0, 8, width + width):
                r[m] += r[m + width]
            width += width
        res = r[0]
        while i < n:
            res += _entry(diag, stack, rest, order[lo + i], layouts[flip[lo + i], j])
            i += 1
        return res
    half = n // 2
    half -= half % 8
    return (_pairwise_sum(diag, stack, rest, order, flip, layouts, lo, half, j)
            + _pairwise_sum(diag, stack, rest, order, flip, layouts, lo + half, n - half, j))


@njit(cache=True)
def _segment_sums_of(start: int, stop: int, diag: np.ndarray, stack: np.ndarray, rest: np.ndarray,
                     order: np.ndarray, flip: np.ndarray, layouts: np.ndarray, first: np.ndarray,
                     out: np.ndarray) -> None:
    """``out[s]`` for segments start <= s < stop: the sum of the blocks at sorted positions
    first[s]..first[s+1], as np.add.reduceat sums them.

    The block at sorted position p is row ``order[p]`` of [diag; stack; rest] (n, ndof²),
    read through ``layouts[flip[p]]`` (``layouts`` (2, ndof²): the entries in
    order, then the transpose's), so no joined, sorted or transposed copy is made. numpy adds a segment's
    first block to the pairwise sum of the others; short segments (the usual case: a few contacts
    between two blocks) are summed block by block, long ones entry by entry in
    numpy's pairwise order: the same bits as the reduceat it replaced.
    """
    width = diag.shape[1]
    others = np.empty(width)
    for s in range(start, stop):
        lo = first[s]
        hi = first[s + 1] if s + 1 < first.shape[0] else order.shape[0]
        head = order[lo]
        if hi - lo <= 8:
            others[:] = 0.0
            for i in range(lo + 1, hi):
                block = _stored(diag, stack, rest, order[i])
                if flip[i] == 0:
                    for j in range(width):
                        others[j] += block[j]
                else:
                    for j in range(width):
                        others[j] += block[layouts[1, j]]
            block = _stored(diag, stack, rest, head)
            for j in range(width):
                value = block[layouts[flip[lo], j]]
                out[s, j] = value + others[j] if hi - lo > 1 else value
        else:
            for j in range(width):
                rest_sum = _pairwise_sum(diag, stack, rest, order, flip, layouts, lo + 1, hi - lo - 1, j)
                out[s, j] = _entry(diag, stack, rest, head, layouts[flip[lo], j]) + rest_sum


@njit(cache=True)
def _segment_sums(diag: np.ndarray, stack: np.ndarray, rest: np.ndarray, order: np.ndarray, flip: np.ndarray,
                  layouts: np.ndarray, first: np.ndarray, out: np.ndarray) -> None:
    """:func:`_segment_sums_of` every segment, on one thread."""
    _segment_sums_of(0, first.shape[0], diag, stack, rest, order, flip, layouts, first, out)


@njit(parallel=True, cache=True)
def _segment_sums_parallel(diag: np.ndarray, stack: np.ndarray, rest: np.ndarray, order: np.ndarray,
                           flip: np.ndarray, layouts: np.ndarray, first: np.ndarray, out: np.ndarray) -> None:
    """:func:`_segment_sums` with chunks of 256 segments shared among threads (each segment is one
    thread's: the same bits)."""
    n = first.shape[0]
    for chunk in prange((n + 255) // 256):
        _segment_sums_of(256 * chunk, min(256 * chunk + 256, n), diag, stack, rest, order, flip, layouts, first,
                         out)


def scatter_add(target: np.ndarray, index: np.ndarray, values: np.ndarray) -> None:
    """``target[index[i]] += values[i]`` for every i, repeated indices summed in order.

    What ``np.add.at`` does, compiled: the per-contact scatter of the step's
    assembly (``np.add.at`` on (n, 6, 6) blocks was a tenth of a contact
    step's time). The same order of additions gives the same bits.
    """
    if len(index) == 0:
        return
    if not target.flags.c_contiguous:
        np.add.at(target, index, values)
        return
    _scatter_rows(target.reshape(len(target), -1), np.ascontiguousarray(index, dtype=np.int64),
                  np.ascontiguousarray(values, dtype=np.float64).reshape(len(index), -1))


@dataclass(frozen=True)
class SpringStack:
    """Penalty springs kept unsummed: ``factor``·Σ rᵀr over the rows r that act, r = [rows_a at block a, −rows_b
    at block b].

    ``rows_a``, ``rows_b`` (n, m, ndof): the m unit rows of each of n springs, scaled by the square root of
    their stiffness (a contact's normal row and its shear rows); ``active`` (n, m): the rows that act in
    this solve. The rows are the same arrays for every solve of a step, so a device keeps its copy
    while they are.
    """

    block_a: np.ndarray
    rows_a: np.ndarray
    block_b: np.ndarray
    rows_b: np.ndarray
    active: np.ndarray
    factor: float


@dataclass
class BlockSystem:
    """Global matrix of ``n_blocks`` blocks, ``ndof`` unknowns each, and its right-hand side."""

    diag: np.ndarray  # (nb, ndof, ndof)
    rhs: np.ndarray  # (nb, ndof)
    pair_i: list[np.ndarray] = field(default_factory=list)
    pair_j: list[np.ndarray] = field(default_factory=list)
    pair_blocks: list[np.ndarray] = field(default_factory=list)
    pair_which: list[np.ndarray | None] = field(default_factory=list)  # per stack: the blocks used (None: all)
    con_rows: list[np.ndarray] = field(default_factory=list)  # constraint triplets (row, col, value)
    con_cols: list[np.ndarray] = field(default_factory=list)
    con_vals: list[np.ndarray] = field(default_factory=list)
    con_rhs: list[np.ndarray] = field(default_factory=list)
    held: np.ndarray | None = None  # (nb,) blocks held by fix_blocks: their couplings are left out of the matrix
    keeps_springs: bool = False  # springs given as SpringStack stay unsummed (module doc)
    springs: list[SpringStack] = field(default_factory=list)

    @staticmethod
    def empty(n_blocks: int, ndof: int) -> BlockSystem:
        """A zero system of ``n_blocks`` blocks with ``ndof`` unknowns each."""
        return BlockSystem(np.zeros((n_blocks, ndof, ndof)), np.zeros((n_blocks, ndof)))

    @property
    def n_blocks(self) -> int:
        return len(self.diag)

    @property
    def ndof(self) -> int:
        return self.diag.shape[1]

    @property
    def size(self) -> int:
        return self.n_blocks * self.ndof

    @property
    def n_constraints(self) -> int:
        return int(sum(len(g) for g in self.con_rhs))

    def add_point_constraints(self, block_a: np.ndarray, t_a: np.ndarray, block_b: np.ndarray,
                              t_b: np.ndarray | None, rhs: np.ndarray, components: np.ndarray | None = None) -> None:
        """Add rows T_a·Δd_a - T_b·Δd_b = rhs (n, dim), one per component where ``components`` (n, dim) is True.

        ``block_b == -1`` (or ``t_b`` None) ties the point to the ground.
        Rows are numbered in the order of ``components.ravel()`` after the existing ones.
        """
        n = len(block_a)
        if n == 0:
            return
        shape = np.shape(t_a)  # (n, dim, ndof)
        ndof = self.ndof
        mask = np.ones(shape[:-1], dtype=bool) if components is None else np.asarray(components, dtype=bool)
        rows = np.full(shape[:-1], -1)
        rows[mask] = self.n_constraints + np.arange(int(mask.sum()))
        pick = np.broadcast_to(mask[:, :, None], shape)
        cols = np.broadcast_to(block_a[:, None, None] * ndof + np.arange(ndof), shape)
        self.con_rows.append(np.broadcast_to(rows[:, :, None], shape)[pick])
        self.con_cols.append(cols[pick])
        self.con_vals.append(np.asarray(t_a, dtype=float)[pick])
        if t_b is not None:
            linked = np.broadcast_to((block_b >= 0)[:, None, None], shape) & pick
            cols_b = np.broadcast_to(np.maximum(block_b, 0)[:, None, None] * ndof + np.arange(ndof), shape)
            self.con_rows.append(np.broadcast_to(rows[:, :, None], shape)[linked])
            self.con_cols.append(cols_b[linked])
            self.con_vals.append(-np.asarray(t_b, dtype=float)[linked])
        self.con_rhs.append(np.asarray(rhs, dtype=float)[mask])

    def constraint_matrix(self) -> sp.csr_matrix:
        """C (nc, n) of the constraint rows."""
        if not self.con_rows:
            return sp.csr_matrix((0, self.size))
        return sp.coo_matrix((np.concatenate(self.con_vals),
                              (np.concatenate(self.con_rows), np.concatenate(self.con_cols))),
                             shape=(self.n_constraints, self.size)).tocsr()

    def full_rhs(self) -> np.ndarray:
        """[F; g]: the block right-hand side followed by the constraint right-hand side."""
        if not self.con_rhs:
            return self.rhs.ravel()
        return np.concatenate([self.rhs.ravel(), *self.con_rhs])

    def _saddle_triplets(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        rows, cols, vals = self.triplets()
        n = self.size
        cr, cc, cv = (np.concatenate(x) for x in (self.con_rows, self.con_cols, self.con_vals))
        return (np.concatenate([rows, n + cr, cc]), np.concatenate([cols, cc, n + cr]),
                np.concatenate([vals, cv, cv]))

    def saddle_csr(self) -> sp.csr_matrix:
        """The augmented matrix [[A, Cᵀ], [C, 0]] (paper Eq. 73), symmetric indefinite."""
        m = self.size + self.n_constraints
        if not self.con_rows:
            return self.to_csr()
        rows, cols, vals = self._saddle_triplets()
        return sp.coo_matrix((vals, (rows, cols)), shape=(m, m)).tocsr()

    def saddle_dense(self) -> np.ndarray:
        """[[A, Cᵀ], [C, 0]] as a dense array (tiny models)."""
        m = self.size + self.n_constraints
        if not self.con_rows:
            return self.to_dense()
        rows, cols, vals = self._saddle_triplets()
        return np.bincount(rows * m + cols, weights=vals, minlength=m * m).reshape(m, m)

    def add_off_diagonal(self, bi: np.ndarray, bj: np.ndarray, blocks: np.ndarray,
                         which: np.ndarray | None = None) -> None:
        """Add K_ij blocks (and their transposes at (j, i)); bi != bj required.

        ``which``: the indices of the blocks that enter the matrix (None: all);
        the others are kept in the stack, not copied out of it.
        """
        if len(bi) == 0:
            return
        self.pair_i.append(bi)
        self.pair_j.append(bj)
        self.pair_blocks.append(blocks)
        self.pair_which.append(which)

    def fix_blocks(self, fixed: np.ndarray) -> None:
        """Hold the blocks where ``fixed`` is True: identity rows, zero rhs, couplings dropped.

        The couplings stay in the stacks and are left out when the matrix is
        made (``held``): filtering the stacks here copied them at every solve.
        """
        if not np.any(fixed):
            return
        self.diag[fixed] = np.eye(self.ndof)
        self.rhs[fixed] = 0.0
        self.held = fixed
        for k, cols in enumerate(self.con_cols):  # a held block's columns drop out of C
            self.con_vals[k] = np.where(fixed[cols // self.ndof], 0.0, self.con_vals[k])

    def sum_springs(self) -> None:
        """Sum the kept springs into the diagonal blocks and a coupling stack (held blocks stay as
        :meth:`fix_blocks` left them), for a solver that needs the matrix itself."""
        springs, self.springs = self.springs, []
        for stack in springs:
            acting = np.flatnonzero(np.any(stack.active, axis=1))
            if not len(acting):
                continue
            on = stack.active[acting][:, :, None]
            pairs = PenaltyPairs(stack.block_a[acting], on * stack.rows_a[acting], stack.block_b[acting],
                                 on * stack.rows_b[acting], np.zeros(stack.active[acting].shape), np.ones(len(acting)))
            add_penalty_pairs(self, pairs, stack.factor)
        if springs and self.held is not None:
            self.diag[self.held] = np.eye(self.ndof)

    def _couplings(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Every coupling block in both orders: (row block, column block, its row in [diag; stacks], transposed).

        The order is that of the stacks, each stack's blocks then their
        transposes (the order of the sums, so the bits of the matrix).
        """
        rows, cols, source, flip = [], [], [], []
        offset = self.n_blocks
        for bi, bj, which in zip(self.pair_i, self.pair_j, self.pair_which):
            pick = np.arange(len(bi)) if which is None else which
            a, b = bi[pick], bj[pick]
            index = offset + pick
            rows += [a, b]
            cols += [b, a]
            source += [index, index]
            flip += [np.zeros(len(pick), dtype=np.int8), np.ones(len(pick), dtype=np.int8)]
            offset += len(bi)
        return np.concatenate(rows), np.concatenate(cols), np.concatenate(source), np.concatenate(flip)

    def _free_couplings(self, bi: np.ndarray, bj: np.ndarray) -> np.ndarray:
        """Indices of the couplings between two blocks that are not held."""
        if self.held is None:
            return np.arange(len(bi))
        return np.flatnonzero(~(self.held[bi] | self.held[bj]))

    def triplets(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(rows, cols, values) of every stored entry, duplicates not summed."""
        self.sum_springs()
        nb, ndof = self.n_blocks, self.ndof
        r, c = np.meshgrid(np.arange(ndof), np.arange(ndof), indexing="ij")
        base = np.arange(nb) * ndof
        rows = [(base[:, None, None] + r).ravel()]
        cols = [(base[:, None, None] + c).ravel()]
        vals = [self.diag.ravel()]
        if self.pair_i:
            bi, bj, source, flip = self._couplings()
            free = self._free_couplings(bi, bj)
            blocks = np.concatenate([self.diag, *self.pair_blocks])[source[free]]
            turned = flip[free] == 1
            blocks[turned] = np.swapaxes(blocks[turned], 1, 2)
            rows.append((bi[free, None, None] * ndof + r).ravel())
            cols.append((bj[free, None, None] * ndof + c).ravel())
            vals.append(blocks.ravel())
        return np.concatenate(rows), np.concatenate(cols), np.concatenate(vals)

    def to_bsr(self, springs: bool = True) -> sp.bsr_matrix:
        """The matrix in block-sparse rows of ndof×ndof blocks, duplicates summed (:meth:`block_rows`)."""
        n = self.size
        return sp.bsr_matrix(self.block_rows(springs), shape=(n, n))

    def block_rows(self, springs: bool = True) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The BSR arrays (data (nnzb, ndof, ndof), column indices, row pointers) of the matrix, each row's
        blocks by ascending column, duplicates summed; without scipy's checks, for a backend that reads them.
        ``springs=False``: without the kept springs (a solver that applies them itself).

        Sorting and summing whole blocks (not their 36 entries) keeps the index
        work 36 times smaller than a COO assembly.
        """
        if springs:
            self.sum_springs()
        nb = self.n_blocks
        if not self.pair_i:
            return self.diag, np.arange(nb), np.arange(nb + 1)
        bi, bj, source, flip = self._couplings()
        free = self._free_couplings(bi, bj)
        order, first, cols, indptr = _block_order(np.concatenate([np.arange(nb), bi[free]]),
                                                  np.concatenate([np.arange(nb), bj[free]]), nb)
        # the sorted blocks as rows of [diag; stacks], read in place or transposed (the first stack, usually the
        # contacts', and a second not copied; further ones joined to the second)
        width = self.ndof * self.ndof
        others = self.pair_blocks[1:]
        rest = np.empty((0, width)) if not others else others[0] if len(others) == 1 else np.concatenate(others)
        stack = np.ascontiguousarray(self.pair_blocks[0]).reshape(len(self.pair_blocks[0]), width)
        rest = np.ascontiguousarray(rest).reshape(len(rest), width)
        entries = np.arange(width)
        layouts = np.stack([entries, entries.reshape(self.ndof, self.ndof).T.ravel()])
        data = np.empty((len(first), self.ndof, self.ndof))
        sums = _segment_sums_parallel if nb > PARALLEL_BLOCKS else _segment_sums
        sums(np.ascontiguousarray(self.diag).reshape(nb, width), stack, rest,
             np.concatenate([np.arange(nb), source[free]])[order],
             np.concatenate([np.zeros(nb, dtype=np.int8), flip[free]])[order], layouts, first,
             data.reshape(len(first), -1))
        return data, cols, indptr

    def to_csr(self) -> sp.csr_matrix:
        return self.to_bsr().tocsr()

    def quadratic_form(self, x: np.ndarray) -> float:
        """xᵀAx of the block matrix A (held blocks' couplings left out), x (nb, ndof): the curvature a line
        search needs, without assembling A."""
        value = float(np.einsum("ni,nij,nj->", x, self.diag, x))
        held = np.zeros(self.n_blocks, dtype=bool) if self.held is None else self.held
        for stack in self.springs:
            value += stack.factor * _spring_form(x, stack.block_a.astype(np.int64, copy=False),
                                                 stack.block_b.astype(np.int64, copy=False), stack.rows_a,
                                                 stack.rows_b, stack.active, held)
        for bi, bj, blocks, which in zip(self.pair_i, self.pair_j, self.pair_blocks, self.pair_which):
            index = np.arange(len(bi)) if which is None else np.asarray(which, dtype=np.int64)
            value += 2.0 * _coupling_form(x, bi.astype(np.int64, copy=False), bj.astype(np.int64, copy=False),
                                          blocks, index, held)
        return value

    def to_dense(self) -> np.ndarray:
        self.sum_springs()
        n = self.size
        if not self.pair_i:
            out = np.zeros((self.n_blocks, self.ndof, self.n_blocks, self.ndof))
            idx = np.arange(self.n_blocks)
            out[idx, :, idx, :] = self.diag
            return out.reshape(n, n)
        rows, cols, vals = self.triplets()
        return np.bincount(rows * n + cols, weights=vals, minlength=n * n).reshape(n, n)


@njit(cache=True)
def _coupling_form(x: np.ndarray, bi: np.ndarray, bj: np.ndarray, blocks: np.ndarray, index: np.ndarray,
                   held: np.ndarray) -> float:
    """Σ x[a]ᵀ·K·x[b] over the coupling blocks K = blocks[c] (a = bi[c], b = bj[c]) for c in ``index``, those of
    held blocks left out: the stack read in place, where gathering the picked blocks copied it every solve."""
    total = 0.0
    for m in range(index.shape[0]):
        c = index[m]
        a = bi[c]
        b = bj[c]
        if held[a] or held[b]:
            continue
        for i in range(blocks.shape[1]):
            row = 0.0
            for j in range(blocks.shape[2]):
                row += blocks[c, i, j] * x[b, j]
            total += x[a, i] * row
    return total


@njit(cache=True)
def _spring_form(x: np.ndarray, block_a: np.ndarray, block_b: np.ndarray, rows_a: np.ndarray, rows_b: np.ndarray,
                 active: np.ndarray, held: np.ndarray) -> float:
    """Σ (r_a·x_a − r_b·x_b)² over the acting rows of kept springs, a held block's side left out (its columns
    are out of the matrix)."""
    total = 0.0
    n, m, ndof = rows_a.shape
    for c in range(n):
        a = block_a[c]
        b = block_b[c]
        for r in range(m):
            if not active[c, r]:
                continue
            s = 0.0
            for i in range(ndof):
                if not held[a]:
                    s += rows_a[c, r, i] * x[a, i]
                if not held[b]:
                    s -= rows_b[c, r, i] * x[b, i]
            total += s * s
    return total


@njit(cache=True)
def _block_order(rows: np.ndarray, cols: np.ndarray, nb: int) -> tuple[np.ndarray, np.ndarray, np.ndarray,
                                                                        np.ndarray]:
    """The blocks (row, col) sorted by row then column, equal ones in their given order (a stable sort of
    row·nb + col: the order of the sums, so the bits of the matrix); and the sorted positions where each
    distinct (row, col) starts, its column and the rows' pointers (BSR ``indices``, ``indptr``).

    A counting sort by row and an insertion sort of each row's few blocks by column: O(n), where a sort of
    the keys took a third of the assembly of the 10,000-brick wall.
    """
    n = len(rows)
    start = np.zeros(nb + 1, dtype=np.int64)
    for e in range(n):
        start[rows[e] + 1] += 1
    for r in range(nb):
        start[r + 1] += start[r]
    fill = start[:-1].copy()
    order = np.empty(n, dtype=np.int64)
    for e in range(n):
        order[fill[rows[e]]] = e
        fill[rows[e]] += 1
    first = np.empty(n, dtype=np.int64)
    block_cols = np.empty(n, dtype=np.int64)
    indptr = np.zeros(nb + 1, dtype=np.int64)
    groups = 0
    for r in range(nb):
        for k in range(start[r] + 1, start[r + 1]):  # stable: an entry moves only past larger columns
            e = order[k]
            m = k - 1
            while m >= start[r] and cols[order[m]] > cols[e]:
                order[m + 1] = order[m]
                m -= 1
            order[m + 1] = e
        for k in range(start[r], start[r + 1]):
            if k == start[r] or cols[order[k]] != cols[order[k - 1]]:
                first[groups] = k
                block_cols[groups] = cols[order[k]]
                groups += 1
        indptr[r + 1] = groups
    return order, first[:groups], block_cols[:groups], indptr


@dataclass(frozen=True)
class PenaltyPairs:
    """Point-to-point penalty springs: ½ k |T_a Δd_a - T_b Δd_b + g|².

    ``block_b == -1`` ties the point to the ground (a fixed point). ``t_a`` and
    ``t_b`` are (n, k, ndof) shape functions (k directions), ``gap`` (n, k) the current
    separation x_a - x_b, ``stiffness`` (n,) in N/m.
    """

    block_a: np.ndarray
    t_a: np.ndarray
    block_b: np.ndarray
    t_b: np.ndarray | None
    gap: np.ndarray
    stiffness: np.ndarray


@njit(cache=True)
def _scale_rows(out: np.ndarray, k: float, t: np.ndarray) -> None:
    """out = k·t, without a temporary."""
    for r in range(t.shape[0]):
        for i in range(t.shape[1]):
            out[r, i] = k * t[r, i]


@njit(cache=True)
def _add_products(target: np.ndarray, scale: float, kt: np.ndarray, u: np.ndarray, row: np.ndarray) -> None:
    """target[i, j] += scale · Σ_r kt[r, i]·u[r, j], the sum from zero with the rows in turn (einsum's order).

    One row i at a time in ``row``, j innermost (contiguous, vectorised).
    """
    rows, ndof = kt.shape
    for i in range(ndof):
        row[:] = 0.0
        for r in range(rows):
            k = kt[r, i]
            for j in range(ndof):
                row[j] += k * u[r, j]
        for j in range(ndof):
            target[i, j] += scale * row[j]


@njit(cache=True)
def _group_by_block(blocks: np.ndarray, n_blocks: int) -> tuple[np.ndarray, np.ndarray]:
    """(first, members): the positions p with blocks[p] = b are members[first[b]:first[b+1]], in order.

    A counting sort (stable, O(n)); negative entries (the ground) belong to no block.
    """
    first = np.zeros(n_blocks + 1, dtype=np.int64)
    for p in range(blocks.shape[0]):
        if blocks[p] >= 0:
            first[blocks[p] + 1] += 1
    for b in range(n_blocks):
        first[b + 1] += first[b]
    members = np.empty(first[n_blocks], dtype=np.int64)
    fill = first[:-1].copy()
    for p in range(blocks.shape[0]):
        if blocks[p] >= 0:
            members[fill[blocks[p]]] = p
            fill[blocks[p]] += 1
    return first, members


@njit(cache=True)
def _penalty_block(b: int, diag: np.ndarray, rhs: np.ndarray, first: np.ndarray, members: np.ndarray, t_a: np.ndarray,
                   t_b: np.ndarray, gap: np.ndarray, stiffness: np.ndarray, factor: float) -> None:
    """Block b's sums of :func:`add_penalty_pairs`: its springs' k·TᵀT and -k·Tᵀg, in spring order.

    Its springs are members[first[b]:first[b+1]] of the a sides (0..n-1) then
    the b sides (n..2n-1), in order: the order of :func:`_penalty_serial`
    (and of the einsums and scatters they replaced), so the same bits.
    """
    n, rows, ndof = t_a.shape
    kt = np.empty((rows, ndof))
    row = np.empty(ndof)
    for m in range(first[b], first[b + 1]):
        c = members[m] - n if members[m] >= n else members[m]
        t = t_b[c] if members[m] >= n else t_a[c]
        _scale_rows(kt, stiffness[c], t)
        _add_products(diag[b], factor, kt, t, row)
    for m in range(first[b], first[b + 1]):
        side_b = members[m] >= n
        c = members[m] - n if side_b else members[m]
        t = t_b if side_b else t_a
        for i in range(ndof):
            acc = 0.0
            for r in range(rows):
                acc += (stiffness[c] * t[c, r, i]) * gap[c, r]
            rhs[b, i] += acc if side_b else -acc


@njit(cache=True)
def _add_within_blocks(diag: np.ndarray, block_a: np.ndarray, block_b: np.ndarray, cross: np.ndarray) -> None:
    """A spring within one block adds cross + crossᵀ to its diagonal block, after all other sums."""
    for c in range(block_a.shape[0]):
        if block_a[c] == block_b[c]:
            for i in range(cross.shape[1]):
                for j in range(cross.shape[2]):
                    diag[block_a[c], i, j] += cross[c, i, j] + cross[c, j, i]


@njit(cache=True)
def _penalty_serial(diag: np.ndarray, rhs: np.ndarray, block_a: np.ndarray, block_b: np.ndarray, t_a: np.ndarray,
                    t_b: np.ndarray, gap: np.ndarray, stiffness: np.ndarray, factor: float, cross: np.ndarray) -> None:
    """The sums of :func:`add_penalty_pairs` on one thread, spring by spring.

    Each product sum starts from zero and adds the k rows in turn; each
    target block receives its additions in spring order, first all the a
    blocks' then all the b blocks' (the einsums' and scatters' order, so the
    same bits). The loops are written out: the same sums through small
    helper functions taking array views took 20 % longer (measured on 1,500
    springs).
    """
    n, rows, ndof = t_a.shape
    kt = np.empty((rows, ndof))
    row = np.empty(ndof)
    for side in range(2):
        side_b = side == 1
        blocks = block_b if side_b else block_a
        t = t_b if side_b else t_a
        for c in range(n):
            if blocks[c] >= 0:
                _scale_rows(kt, stiffness[c], t[c])
                _add_products(diag[blocks[c]], factor, kt, t[c], row)
        for c in range(n):
            if blocks[c] >= 0:
                for i in range(ndof):
                    acc = 0.0
                    for r in range(rows):
                        acc += (stiffness[c] * t[c, r, i]) * gap[c, r]
                    rhs[blocks[c], i] += acc if side_b else -acc
    for c in range(n):  # the coupling blocks -factor·k·t_aᵀt_b (none for a spring to the ground)
        cross[c] = 0.0
        if block_b[c] >= 0:
            _scale_rows(kt, stiffness[c], t_a[c])
            _add_products(cross[c], -factor, kt, t_b[c], row)


@njit(parallel=True, cache=True)
def _penalty_parallel(diag: np.ndarray, rhs: np.ndarray, block_a: np.ndarray, block_b: np.ndarray, t_a: np.ndarray,
                      t_b: np.ndarray, gap: np.ndarray, stiffness: np.ndarray, factor: float,
                      cross: np.ndarray) -> None:
    """:func:`_penalty_serial` with the blocks and the springs shared among threads: each block gathers its
    springs (found by one counting sort) in the same order, so the same bits."""
    first, members = _group_by_block(np.concatenate((block_a, block_b)), diag.shape[0])
    for b in prange(diag.shape[0]):
        _penalty_block(b, diag, rhs, first, members, t_a, t_b, gap, stiffness, factor)
    n, rows, ndof = t_a.shape
    for chunk in prange((n + 255) // 256):  # scratch rows per chunk of springs, not per spring
        kt = np.empty((rows, ndof))
        row = np.empty(ndof)
        for c in range(256 * chunk, min(256 * chunk + 256, n)):
            cross[c] = 0.0
            if block_b[c] >= 0:
                _scale_rows(kt, stiffness[c], t_a[c])
                _add_products(cross[c], -factor, kt, t_b[c], row)


def add_penalty_pairs(system: BlockSystem, pairs: PenaltyPairs, factor: float) -> None:
    """Add penalty springs to ``system``: matrix ``factor·k·TᵀT``, rhs ``-k·Tᵀg``.

    ``factor`` is the scheme's penalty weight c_p (1 for Shi and the paper's
    scheme, 1 - αf for Chung-Hulbert); the pull-back force always enters whole.
    One compiled pass sums every spring (:func:`_penalty_serial`), on all
    cores for systems of more than ``PARALLEL_BLOCKS`` blocks
    (:func:`_penalty_parallel`, the same bits).
    """
    n = len(pairs.block_a)
    if n == 0:
        return
    f64 = np.float64
    t_a = np.ascontiguousarray(pairs.t_a, dtype=f64)
    grounded = pairs.t_b is None
    block_b = np.full(n, -1, dtype=np.int64) if grounded else np.ascontiguousarray(pairs.block_b, dtype=np.int64)
    cross = np.empty((n, system.ndof, system.ndof))
    block_a = np.ascontiguousarray(pairs.block_a, dtype=np.int64)
    kernel = _penalty_parallel if system.n_blocks > PARALLEL_BLOCKS else _penalty_serial
    kernel(system.diag, system.rhs, block_a, block_b, t_a,
           t_a if grounded else np.ascontiguousarray(pairs.t_b, dtype=f64),
           np.ascontiguousarray(pairs.gap, dtype=f64), np.ascontiguousarray(pairs.stiffness, dtype=f64),
           float(factor), cross)
    _add_within_blocks(system.diag, block_a, block_b, cross)
    coupled = (block_b >= 0) & (pairs.block_a != block_b)
    if np.all(coupled):  # the usual case (contacts): no copy of the cross blocks
        system.add_off_diagonal(pairs.block_a, block_b, cross)
    else:
        system.add_off_diagonal(pairs.block_a[coupled], block_b[coupled], cross[coupled])
