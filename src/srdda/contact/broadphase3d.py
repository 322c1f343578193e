"""Broad phase in 3D: candidate block pairs whose boxes, grown by the contact distance, overlap.

A uniform hash grid compiled with numba, plus a sweep for outsized boxes:

* the cell size h is twice the median largest extent of the grown boxes, so a
  box no larger than h covers at most 2 cells per axis (8 cells in all);
  every (cell, box) entry gets an integer key and one ``argsort`` groups the
  cells; the boxes that share a cell are tested against each other, and a
  pair is reported only in the one cell that holds the lower corner of the
  two boxes' intersection, so each pair comes out once;
* boxes larger than h (a fixed base, a slope under small blocks) are tested
  against every box whose x-range overlaps theirs, found by binary search in
  the boxes sorted by their lower x.

Cost O(N log N) for the sort and O(N·k) for the tests (k: boxes per cell)
whatever the arrangement; a sort-and-sweep along one axis degenerates to
O(N^(5/3)) on a cubic stack of blocks, whose columns share one x-range.
No well-kept library answers all overlapping pairs of 10^5 3D boxes in one
call (shapely's STRtree is 2D; rtree and python-fcl answer one query or
one callback per pair from Python); see docs/contacts-3d.md.
"""
from __future__ import annotations

import numpy as np
from numba import njit

from .candidates import grow_boxes, push_row

__all__ = ["candidate_pairs_3d"]


@njit(cache=True)
def _overlap(boxes, i, j):
    for k in range(3):
        if boxes[i, k] > boxes[j, k + 3] or boxes[j, k] > boxes[i, k + 3]:
            return False
    return True


@njit(cache=True)
def _cell_entries(boxes, small, h, origin):
    """(key, box) of every cell that each small box covers; keys number cells in a dense lattice."""
    nb = len(boxes)
    span = np.zeros(3, dtype=np.int64)
    for k in range(3):
        top = 0
        for b in range(nb):
            if small[b]:
                top = max(top, int(np.floor((boxes[b, k + 3] - origin[k]) / h)))
        span[k] = top + 2
    count = 0
    lo = np.zeros((nb, 3), dtype=np.int64)
    hi = np.zeros((nb, 3), dtype=np.int64)
    for b in range(nb):
        if not small[b]:
            continue
        c = 1
        for k in range(3):
            lo[b, k] = int(np.floor((boxes[b, k] - origin[k]) / h))
            hi[b, k] = int(np.floor((boxes[b, k + 3] - origin[k]) / h))
            c *= hi[b, k] - lo[b, k] + 1
        count += c
    keys = np.empty(count, dtype=np.int64)
    owner = np.empty(count, dtype=np.int64)
    n = 0
    for b in range(nb):
        if not small[b]:
            continue
        for x in range(lo[b, 0], hi[b, 0] + 1):
            for y in range(lo[b, 1], hi[b, 1] + 1):
                for z in range(lo[b, 2], hi[b, 2] + 1):
                    keys[n] = (x * span[1] + y) * span[2] + z
                    owner[n] = b
                    n += 1
    return keys, owner, span


@njit(cache=True)
def _grid_pairs(boxes, keys, owner, span, h, origin, movable):
    """Pairs of small boxes that share a cell, each reported in the cell of their intersection's lower corner."""
    buf = np.empty((max(16, 4 * len(keys)), 2), dtype=np.int64)
    n = 0
    start = 0
    m = len(keys)
    while start < m:
        stop = start + 1
        while stop < m and keys[stop] == keys[start]:
            stop += 1
        cell = keys[start]
        for p in range(start, stop):
            i = owner[p]
            for q in range(p + 1, stop):
                j = owner[q]
                if not (movable[i] or movable[j]) or not _overlap(boxes, i, j):
                    continue
                x = int(np.floor((max(boxes[i, 0], boxes[j, 0]) - origin[0]) / h))
                y = int(np.floor((max(boxes[i, 1], boxes[j, 1]) - origin[1]) / h))
                z = int(np.floor((max(boxes[i, 2], boxes[j, 2]) - origin[2]) / h))
                if (x * span[1] + y) * span[2] + z == cell:
                    buf = push_row(buf, n, (min(i, j), max(i, j)))
                    n += 1
        start = stop
    return buf[:n].copy()


@njit(cache=True)
def _large_pairs(boxes, large, order, xmin_sorted, movable):
    """Pairs of each outsized box with every box it overlaps (a pair of two outsized boxes once)."""
    buf = np.empty((16, 2), dtype=np.int64)
    n = 0
    for i in np.flatnonzero(large):
        stop = np.searchsorted(xmin_sorted, boxes[i, 3], side="right")
        for p in range(stop):
            j = order[p]
            if j == i or (large[j] and j < i) or boxes[j, 3] < boxes[i, 0]:
                continue
            if (movable[i] or movable[j]) and _overlap(boxes, i, j):
                buf = push_row(buf, n, (min(i, j), max(i, j)))
                n += 1
    return buf[:n].copy()


def candidate_pairs_3d(boxes: np.ndarray, margin: float, movable: np.ndarray | None = None) -> np.ndarray:
    """Pairs (k, 2) of blocks a < b whose boxes (nb, 6) grown by ``margin`` overlap, sorted.

    Pairs of two blocks that cannot move (``movable`` False for both) are left out.
    """
    nb = len(boxes)
    if nb < 2:
        return np.empty((0, 2), dtype=np.int64)
    grown = grow_boxes(boxes, margin)
    movable = np.ones(nb, dtype=bool) if movable is None else np.asarray(movable, dtype=bool)
    extent = np.max(grown[:, 3:] - grown[:, :3], axis=1)
    h = 2.0 * float(np.median(extent))
    if not h > 0:
        h = 1.0
    large = extent > h
    origin = grown[:, :3].min(axis=0)
    keys, owner, span = _cell_entries(grown, ~large, h, origin)
    order = np.argsort(keys, kind="stable")
    found = [_grid_pairs(grown, keys[order], owner[order], span, h, origin, movable)]
    if np.any(large):
        by_x = np.argsort(grown[:, 0], kind="stable")
        found.append(_large_pairs(grown, large, by_x, grown[by_x, 0], movable))
    pairs = np.concatenate(found)
    return pairs[np.lexsort((pairs[:, 1], pairs[:, 0]))]
