"""The penalty springs of a step's contacts, 2D and 3D, summed into the step's system.

A closed contact has a normal spring of stiffness k_n on its gap
g_n = g_0 + n·(T_a Δd_a - T_b Δd_b), a locked one also a shear spring of k_s
on each of its shear components (one in 2D, two in 3D; Shi 1988, ch. 4;
docs/contacts.md, docs/contacts-3d.md). :class:`ContactSprings` holds the
springs' unit rows for one step's shapes and adds the springs of the
contacts' current states to a solve's system, either

* afresh in every solve (systems of at most ``INCREMENTAL_BLOCKS`` blocks: the
  sums, so the paper's rows, are the same bits as always), or
* by changes (larger systems): the springs are summed at the step's first
  solve, and later solves put in or take out only the springs of contacts
  whose state changed, a normal spring where one closed or opened, the shear
  springs where one locked or slipped (docs/performance.md, "Only the
  contacts that changed"), or
* unsummed, for a solver that applies them itself (``system.keeps_springs``:
  the device's conjugate gradient): the step's rows once, and which of them
  act in each solve (:class:`~srdda.assembly.system.SpringStack`).
"""
from __future__ import annotations

import numpy as np
from numba import njit, prange

from ..assembly.system import PARALLEL_BLOCKS, BlockSystem, PenaltyPairs, SpringStack, add_penalty_pairs, scatter_add

__all__ = ["ContactSprings", "INCREMENTAL_BLOCKS", "is_large", "directional_rows"]

# Systems of more blocks add a solve's contact springs as changes to the last solve's sums (and take the rows'
# compiled passes); the sums then differ from a fresh sum in their last bits, which the paper's examples (the
# largest, the sine wave, has 40 blocks) must not. Above it the changes are cheaper: slope_a (74 blocks) and
# slope_b (273) solve 10-20 % faster (docs/dev/performance-history.md, *Sums by changes from 41 blocks*).
INCREMENTAL_BLOCKS = 40


def is_large(n_blocks: int) -> bool:
    """Whether a system of ``n_blocks`` takes the large-system paths: sums by changes and the rows' compiled
    passes (:meth:`ContactSprings.increments`), whose sums differ from the small systems' in the last bits."""
    return n_blocks > INCREMENTAL_BLOCKS


def directional_rows(directions: np.ndarray, shapes: np.ndarray) -> np.ndarray:
    """d·T of every contact: the rows (n, ndof) of directions d (n, k) through shape functions T (n, k, ndof),
    or (n, m, ndof) for m directions each (n, m, k).

    One compiled pass; each entry sums from zero over k in turn, as numpy's
    einsum does for these products (the same bits, checked in
    tests/test_contact_assembly.py), without its set-up per call.
    """
    several = directions.ndim == shapes.ndim  # (n, m, k) against (n, k, ndof)
    d = np.ascontiguousarray(directions if several else directions[:, None, :], dtype=np.float64)
    out = np.empty((*d.shape[:-1], shapes.shape[-1]))
    _directional_rows(d, np.ascontiguousarray(shapes, dtype=np.float64), out)
    return out if several else out[:, 0]


class ContactSprings:
    """The normal and shear springs of n contacts between blocks ``block_a`` and ``block_b``.

    ``normal_a``, ``normal_b`` (n, ndof): the rows n·T of the two sides;
    ``shear_a``, ``shear_b`` (n, k, ndof): the k shear rows; ``gap`` (n,) and
    ``shear0`` (n, k): the start-of-step gap and shear spring displacement;
    ``normal_stiffness``, ``shear_stiffness`` (n,): k_n and k_s of each contact.
    """

    def __init__(self, block_a: np.ndarray, block_b: np.ndarray, normal_a: np.ndarray, normal_b: np.ndarray,
                 shear_a: np.ndarray, shear_b: np.ndarray, gap: np.ndarray, shear0: np.ndarray,
                 normal_stiffness: np.ndarray, shear_stiffness: np.ndarray) -> None:
        self.block_a, self.block_b = block_a, block_b
        self.normal_a, self.normal_b, self.shear_a, self.shear_b = normal_a, normal_b, shear_a, shear_b
        self.gap, self.shear0 = gap, shear0
        self.root_normal, self.root_shear = np.sqrt(normal_stiffness), np.sqrt(shear_stiffness)
        # (diag, rhs, coupling block of every contact, the states they sum) of the sums by changes
        self._sums: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray] | None = None
        # the rows [√k_n·n·T; √k_s·e·T] of each side and the gaps [√k_n·g₀; √k_s·s₀] of the kept springs
        self._unit: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None

    def increments(self, dd: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """How the gaps (n,) and shear spring displacements (n, k) move with the solve's ``dd``:
        the rows times Δd_a minus the rows times Δd_b, one compiled pass, on all cores for systems of more than
        ``PARALLEL_BLOCKS`` blocks (its sums differ from the contact terms' einsums in the last bits)."""
        n, k, _ = self.shear_a.shape
        dn, ds = np.empty(n), np.empty((n, k))
        kernel = _row_increments_parallel if len(dd) > PARALLEL_BLOCKS else _row_increments
        kernel(self.block_a, self.block_b, self.normal_a, self.normal_b, self.shear_a, self.shear_b,
                        np.ascontiguousarray(dd), dn, ds)
        return dn, ds

    def springs(self, index: np.ndarray, normal: np.ndarray, shear: np.ndarray) -> PenaltyPairs:
        """The springs of contacts ``index``: the normal one where ``normal``, the shear ones where ``shear``.

        Each row is scaled by the square root of its stiffness, so the pairs'
        own stiffness is 1.
        """
        rn = self.root_normal[index] * normal[index]
        rs = self.root_shear[index] * shear[index]
        (_, k, ndof), n = self.shear_a.shape, len(index)
        rows_a, rows_b, gap = np.empty((n, 1 + k, ndof)), np.empty((n, 1 + k, ndof)), np.empty((n, 1 + k, 1))
        _stacked_rows(index, self.normal_a, self.shear_a, rn, rs, rows_a)
        _stacked_rows(index, self.normal_b, self.shear_b, rn, rs, rows_b)
        _stacked_rows(index, self.gap[:, None], self.shear0[:, :, None], rn, rs, gap)
        return PenaltyPairs(self.block_a[index], rows_a, self.block_b[index], rows_b, gap[:, :, 0],
                            np.ones(len(index)))

    def part(self, index: np.ndarray, shear: bool, stiffness: np.ndarray) -> PenaltyPairs:
        """The normal spring, or the shear springs, of contacts ``index`` times ``stiffness`` (±1: put in
        or taken out)."""
        if shear:
            root, rows_a, rows_b, gap = self.root_shear, self.shear_a, self.shear_b, self.shear0
        else:
            root, rows_a, rows_b, gap = self.root_normal, self.normal_a[:, None], self.normal_b[:, None], \
                self.gap[:, None]
        r = root[index]
        return PenaltyPairs(self.block_a[index], r[:, None, None] * rows_a[index], self.block_b[index],
                            r[:, None, None] * rows_b[index], r[:, None] * gap[index], stiffness)

    def add_to(self, system: BlockSystem, normal: np.ndarray, shear: np.ndarray, c_p: float,
               by_changes: bool) -> None:
        """Add the normal springs where ``normal`` and the shear springs where ``shear`` to ``system`` (matrix
        weight c_p, module doc): by changes to the last call's sums if ``by_changes`` (the open-close solver
        asks so above ``INCREMENTAL_BLOCKS`` blocks, the Newton solver at every size), else afresh; unsummed
        where ``system.keeps_springs`` (module doc)."""
        acting = np.flatnonzero(normal | shear)
        if system.keeps_springs:
            self._keep(system, acting, normal, shear, c_p)
            return
        if not by_changes:
            if len(acting):
                add_penalty_pairs(system, self.springs(acting, normal, shear), c_p)
            return
        if self._sums is None:  # every contact, the idle ones with rows of zero: a coupling block for each
            sums = BlockSystem.empty(system.n_blocks, system.ndof)
            add_penalty_pairs(sums, self.springs(np.arange(len(normal)), normal, shear), c_p)
            cross = sums.pair_blocks[0] if sums.pair_blocks else np.zeros((len(normal), system.ndof, system.ndof))
            self._sums = (sums.diag, sums.rhs, cross, np.stack([normal, shear]))
        diag, rhs, cross, summed = self._sums
        change = BlockSystem(diag, rhs)
        for k, (is_shear, now) in enumerate(((False, normal), (True, shear))):
            flipped = np.flatnonzero(now != summed[k])
            if len(flipped):
                add_penalty_pairs(change, self.part(flipped, is_shear, np.where(now[flipped], 1.0, -1.0)), c_p)
                scatter_add(cross, flipped, change.pair_blocks[-1])  # in place: no gathered copy of the blocks
        summed[0], summed[1] = normal, shear
        system.diag += diag
        system.rhs += rhs
        # only the acting contacts' coupling blocks: an idle contact's zero block costs every solver iteration
        system.add_off_diagonal(self.block_a, self.block_b, cross, which=acting)

    def _keep(self, system: BlockSystem, acting: np.ndarray, normal: np.ndarray, shear: np.ndarray,
              c_p: float) -> None:
        """The springs as a :class:`SpringStack` (their matrix left to the solver) and their pull-back forces
        −k·Tᵀg added to the right-hand side."""
        n, k, ndof = self.shear_a.shape
        if self._unit is None:
            self._unit = (np.empty((n, 1 + k, ndof)), np.empty((n, 1 + k, ndof)), np.empty((n, 1 + k)))
            _unit_rows(self.root_normal, self.root_shear, self.normal_a, self.normal_b, self.shear_a, self.shear_b,
                       self.gap, self.shear0, *self._unit)
        rows_a, rows_b, gap = self._unit
        active = np.empty((len(normal), 1 + k), dtype=bool)
        active[:, 0] = normal
        active[:, 1:] = shear[:, None]
        system.springs.append(SpringStack(self.block_a, rows_a, self.block_b, rows_b, active, c_p))
        if len(acting):
            _pull_back(system.rhs, acting, self.block_a, self.block_b, rows_a, rows_b, gap, active)


@njit(parallel=True, cache=True)
def _unit_rows(root_normal: np.ndarray, root_shear: np.ndarray, normal_a: np.ndarray, normal_b: np.ndarray,
               shear_a: np.ndarray, shear_b: np.ndarray, gap: np.ndarray, shear0: np.ndarray, rows_a: np.ndarray,
               rows_b: np.ndarray, gaps: np.ndarray) -> None:
    """The kept springs' rows [√k_n·n·T; √k_s·e·T] of each side and their gaps [√k_n·g₀; √k_s·s₀], one pass."""
    n, k, ndof = shear_a.shape
    for c in prange(n):
        for i in range(ndof):
            rows_a[c, 0, i] = root_normal[c] * normal_a[c, i]
            rows_b[c, 0, i] = root_normal[c] * normal_b[c, i]
        gaps[c, 0] = root_normal[c] * gap[c]
        for r in range(k):
            for i in range(ndof):
                rows_a[c, 1 + r, i] = root_shear[c] * shear_a[c, r, i]
                rows_b[c, 1 + r, i] = root_shear[c] * shear_b[c, r, i]
            gaps[c, 1 + r] = root_shear[c] * shear0[c, r]


@njit(cache=True)
def _pull_back(rhs: np.ndarray, acting: np.ndarray, block_a: np.ndarray, block_b: np.ndarray, rows_a: np.ndarray,
               rows_b: np.ndarray, gap: np.ndarray, active: np.ndarray) -> None:
    """The kept springs' forces −Σ_r g_r·r on block a and +Σ_r g_r·r on block b (rows and gaps scaled by √k, so
    the products are k·Tᵀg), the acting rows of contacts ``acting`` in turn (one thread: the same bits)."""
    m, ndof = rows_a.shape[1], rows_a.shape[2]
    for c in acting:
        for i in range(ndof):
            acc_a = 0.0
            acc_b = 0.0
            for r in range(m):
                if active[c, r]:
                    acc_a += gap[c, r] * rows_a[c, r, i]
                    acc_b += gap[c, r] * rows_b[c, r, i]
            rhs[block_a[c], i] -= acc_a
            rhs[block_b[c], i] += acc_b


@njit(parallel=True, cache=True)
def _directional_rows(directions: np.ndarray, shapes: np.ndarray, out: np.ndarray) -> None:
    """out[c, m, i] = Σ_k directions[c, m, k]·shapes[c, k, i], summed from zero in k order."""
    n, count, k = directions.shape
    width = out.shape[-1]
    for c in prange(n):
        for m in range(count):
            for i in range(width):
                acc = 0.0
                for r in range(k):
                    acc += directions[c, m, r] * shapes[c, r, i]
                out[c, m, i] = acc


@njit(cache=True)
def _stacked_rows(index: np.ndarray, first: np.ndarray, more: np.ndarray, first_scale: np.ndarray,
                  more_scale: np.ndarray, out: np.ndarray) -> None:
    """out[m] = [first_scale[m]·first[c]; more_scale[m]·more[c]] for c = index[m]: a spring's rows, stacked."""
    _, k, width = more.shape
    for m in range(len(index)):
        c = index[m]
        for i in range(width):
            out[m, 0, i] = first_scale[m] * first[c, i]
        for r in range(k):
            for i in range(width):
                out[m, 1 + r, i] = more_scale[m] * more[c, r, i]


@njit(cache=True)
def _row_increments_of(c: int, block_a: np.ndarray, block_b: np.ndarray, normal_a: np.ndarray, normal_b: np.ndarray,
                       shear_a: np.ndarray, shear_b: np.ndarray, dd: np.ndarray, dn: np.ndarray, ds: np.ndarray) -> None:
    """dn[c] = normal_a[c]·dd[a] - normal_b[c]·dd[b] and ds[c] likewise with the shear rows."""
    _, k, ndof = shear_a.shape
    a, b = block_a[c], block_b[c]
    acc = 0.0
    for i in range(ndof):
        acc += normal_a[c, i] * dd[a, i] - normal_b[c, i] * dd[b, i]
    dn[c] = acc
    for r in range(k):
        acc = 0.0
        for i in range(ndof):
            acc += shear_a[c, r, i] * dd[a, i] - shear_b[c, r, i] * dd[b, i]
        ds[c, r] = acc


@njit(cache=True)
def _row_increments(block_a: np.ndarray, block_b: np.ndarray, normal_a: np.ndarray, normal_b: np.ndarray,
                    shear_a: np.ndarray, shear_b: np.ndarray, dd: np.ndarray, dn: np.ndarray, ds: np.ndarray) -> None:
    """:func:`_row_increments_of` every contact, on one thread (small models: starting the threads cost more)."""
    for c in range(shear_a.shape[0]):
        _row_increments_of(c, block_a, block_b, normal_a, normal_b, shear_a, shear_b, dd, dn, ds)


@njit(parallel=True, cache=True)
def _row_increments_parallel(block_a: np.ndarray, block_b: np.ndarray, normal_a: np.ndarray, normal_b: np.ndarray,
                             shear_a: np.ndarray, shear_b: np.ndarray, dd: np.ndarray, dn: np.ndarray,
                             ds: np.ndarray) -> None:
    """:func:`_row_increments` with the contacts shared among threads (each contact's sums the same bits)."""
    for c in prange(shear_a.shape[0]):
        _row_increments_of(c, block_a, block_b, normal_a, normal_b, shear_a, shear_b, dd, dn, ds)
