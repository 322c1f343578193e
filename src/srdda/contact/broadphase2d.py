"""Broad phase in 2D: candidate block pairs whose boxes, grown by the contact distance, overlap.

A shapely 2 ``STRtree`` (a packed R-tree in GEOS) holds the blocks' axis-aligned
bounding boxes; one bulk ``query`` (envelope overlap, which is exact for
boxes) returns every overlapping pair in C. Building the tree is O(N log N), each query O(log N + k),
so the whole phase never tests all pairs (see docs/contacts.md for timings).
"""
from __future__ import annotations

import numpy as np
import shapely

from .candidates import grow_boxes

__all__ = ["candidate_pairs_2d"]


def candidate_pairs_2d(boxes: np.ndarray, margin: float, movable: np.ndarray | None = None) -> np.ndarray:
    """Pairs (k, 2) of blocks a < b whose boxes grown by ``margin`` overlap, sorted.

    Pairs of two blocks that cannot move (``movable`` False for both) are left out:
    no contact between them can ever act.
    """
    if len(boxes) < 2:
        return np.empty((0, 2), dtype=np.int64)
    grown = grow_boxes(boxes, margin)
    geoms = shapely.box(grown[:, 0], grown[:, 1], grown[:, 2], grown[:, 3])
    tree = shapely.STRtree(geoms)
    query, found = tree.query(geoms)  # envelope overlap: exact for axis-aligned boxes
    keep = query < found
    pairs = np.column_stack([query[keep], found[keep]]).astype(np.int64)
    if movable is not None:
        pairs = pairs[movable[pairs[:, 0]] | movable[pairs[:, 1]]]
    return pairs[np.lexsort((pairs[:, 1], pairs[:, 0]))]
