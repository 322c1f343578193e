"""The global block system: ndof×ndof sub-matrices assembled into one sparse matrix.

Sub-matrices are kept as dense stacks until the solve: ``diag`` (nb, ndof, ndof)
for every block and ``pair_blocks`` (np, ndof, ndof) for coupled pairs (row block
``pair_i``, column block ``pair_j``, both orders present). Conversion to CSR is
one ``coo_matrix`` call; to dense (tiny models) one ``np.add.at``.

Exact constraints (hinges, pins, prescribed motion by multipliers, paper
Eqs. 72-75) add rows C (nc, n) with right-hand side g: the system becomes the
saddle point [[A, Cᵀ], [C, 0]]·[Δd; μ] = [F; g] (``saddle_csr``), where the
constraint force on the first point of a constraint is -μ.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp
from numba import njit

__all__ = ["BlockSystem", "PenaltyPairs", "add_penalty_pairs", "scatter_add"]


@njit(cache=True)
def _scatter_rows(target: np.ndarray, index: np.ndarray, values: np.ndarray) -> None:
    for i in range(index.shape[0]):
        row = index[i]
        for j in range(values.shape[1]):
            target[row, j] += values[i, j]


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


@dataclass
class BlockSystem:
    """Global matrix of ``n_blocks`` blocks, ``ndof`` unknowns each, and its right-hand side."""

    diag: np.ndarray  # (nb, ndof, ndof)
    rhs: np.ndarray  # (nb, ndof)
    pair_i: list[np.ndarray] = field(default_factory=list)
    pair_j: list[np.ndarray] = field(default_factory=list)
    pair_blocks: list[np.ndarray] = field(default_factory=list)
    con_rows: list[np.ndarray] = field(default_factory=list)  # constraint triplets (row, col, value)
    con_cols: list[np.ndarray] = field(default_factory=list)
    con_vals: list[np.ndarray] = field(default_factory=list)
    con_rhs: list[np.ndarray] = field(default_factory=list)

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

    def add_off_diagonal(self, bi: np.ndarray, bj: np.ndarray, blocks: np.ndarray) -> None:
        """Add K_ij blocks (and their transposes at (j, i)); bi != bj required."""
        if len(bi) == 0:
            return
        self.pair_i += [bi, bj]
        self.pair_j += [bj, bi]
        self.pair_blocks += [blocks, np.swapaxes(blocks, 1, 2)]

    def fix_blocks(self, fixed: np.ndarray) -> None:
        """Hold the blocks where ``fixed`` is True: identity rows, zero rhs, couplings dropped."""
        if not np.any(fixed):
            return
        self.diag[fixed] = np.eye(self.ndof)
        self.rhs[fixed] = 0.0
        keep_i, keep_j, keep_b = [], [], []
        for bi, bj, blocks in zip(self.pair_i, self.pair_j, self.pair_blocks):
            free = ~(fixed[bi] | fixed[bj])
            keep_i.append(bi[free])
            keep_j.append(bj[free])
            keep_b.append(blocks[free])
        self.pair_i, self.pair_j, self.pair_blocks = keep_i, keep_j, keep_b
        for k, cols in enumerate(self.con_cols):  # a held block's columns drop out of C
            self.con_vals[k] = np.where(fixed[cols // self.ndof], 0.0, self.con_vals[k])

    def triplets(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(rows, cols, values) of every stored entry, duplicates not summed."""
        nb, ndof = self.n_blocks, self.ndof
        r, c = np.meshgrid(np.arange(ndof), np.arange(ndof), indexing="ij")
        base = np.arange(nb) * ndof
        rows = [(base[:, None, None] + r).ravel()]
        cols = [(base[:, None, None] + c).ravel()]
        vals = [self.diag.ravel()]
        if self.pair_i:
            bi = np.concatenate(self.pair_i) * ndof
            bj = np.concatenate(self.pair_j) * ndof
            rows.append((bi[:, None, None] + r).ravel())
            cols.append((bj[:, None, None] + c).ravel())
            vals.append(np.concatenate(self.pair_blocks).ravel())
        return np.concatenate(rows), np.concatenate(cols), np.concatenate(vals)

    def to_bsr(self) -> sp.bsr_matrix:
        """The matrix in block-sparse rows of ndof×ndof blocks, duplicates summed.

        Sorting and summing whole blocks (not their 36 entries) keeps the index
        work 36 times smaller than a COO assembly.
        """
        nb = self.n_blocks
        n = self.size
        if not self.pair_i:
            return sp.bsr_matrix((self.diag, np.arange(nb), np.arange(nb + 1)), shape=(n, n))
        key = np.concatenate([np.arange(nb) * (nb + 1), *(i * nb + j for i, j in zip(self.pair_i, self.pair_j))])
        blocks = np.concatenate([self.diag, *self.pair_blocks])
        order = np.argsort(key, kind="stable")
        key = key[order]
        first = np.flatnonzero(np.r_[True, key[1:] != key[:-1]])
        data = np.add.reduceat(blocks[order], first, axis=0)
        rows, cols = np.divmod(key[first], nb)
        indptr = np.searchsorted(rows, np.arange(nb + 1))
        return sp.bsr_matrix((data, cols, indptr), shape=(n, n))

    def to_csr(self) -> sp.csr_matrix:
        return self.to_bsr().tocsr()

    def to_dense(self) -> np.ndarray:
        n = self.size
        if not self.pair_i:
            out = np.zeros((self.n_blocks, self.ndof, self.n_blocks, self.ndof))
            idx = np.arange(self.n_blocks)
            out[idx, :, idx, :] = self.diag
            return out.reshape(n, n)
        rows, cols, vals = self.triplets()
        return np.bincount(rows * n + cols, weights=vals, minlength=n * n).reshape(n, n)


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


def add_penalty_pairs(system: BlockSystem, pairs: PenaltyPairs, factor: float) -> None:
    """Add penalty springs to ``system``: matrix ``factor·k·TᵀT``, rhs ``-k·Tᵀg``.

    ``factor`` is the scheme's penalty weight c_p (1 for Shi and the paper's
    scheme, 1 - αf for Chung-Hulbert); the pull-back force always enters whole.
    """
    if len(pairs.block_a) == 0:
        return
    k = pairs.stiffness
    ta = pairs.t_a
    kta = k[:, None, None] * ta
    scatter_add(system.diag, pairs.block_a, factor * np.einsum("nki,nkj->nij", kta, ta))
    scatter_add(system.rhs, pairs.block_a, -np.einsum("nki,nk->ni", kta, pairs.gap))
    if pairs.t_b is None:
        return
    linked = pairs.block_b >= 0
    if not np.any(linked):
        return
    a = pairs.block_a[linked]
    b = pairs.block_b[linked]
    tb = pairs.t_b[linked]
    ktb = k[linked, None, None] * tb
    scatter_add(system.diag, b, factor * np.einsum("nki,nkj->nij", ktb, tb))
    scatter_add(system.rhs, b, np.einsum("nki,nk->ni", ktb, pairs.gap[linked]))
    cross = -factor * np.einsum("nki,nkj->nij", kta[linked], tb)
    same = a == b
    if np.any(same):
        scatter_add(system.diag, a[same], cross[same] + np.swapaxes(cross[same], 1, 2))
    system.add_off_diagonal(a[~same], b[~same], cross[~same])
