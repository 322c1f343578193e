"""Candidate block pairs kept across steps (issue 14): the broad phase run again only after blocks moved.

The broad phase finds the pairs whose boxes, grown by the contact distance
d0, overlap. :class:`KeptCandidates` runs it with d0 + m (m: the margin) and
keeps that list; at every later detection it only filters the kept pairs by
the d0 test on the current boxes, until some vertex has moved more than m/2
along an axis since the list was made, when the broad phase runs again.

Why the filtered list is the broad phase's own: a box side moves no more
than its vertices do along that axis, so two boxes whose d0-grown boxes
overlap now were within d0 + m along every axis when the list was made,
and are in it. Both broad phases return their pairs sorted (a, b), so the
filtered list is the fresh one, in the same order: contacts, assembly and
results are the same bits with or without the kept list
(tests/test_contact_detection.py).
"""
from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING

import numpy as np
from numba import njit

if TYPE_CHECKING:
    from ..modeldata.arrays import ModelArrays

__all__ = ["block_boxes", "grow_boxes", "boxes_within", "KeptCandidates", "PairFinder", "pair_keys", "push_row", "both_ways"]

GROWTH = 2  # a full row buffer is replaced by one this many times as long


def block_boxes(vertices: np.ndarray, block_ptr: np.ndarray) -> np.ndarray:
    """Boxes (nb, 2·dim) [lower corner, upper corner] of every block."""
    starts = block_ptr[:-1]
    return np.hstack([np.minimum.reduceat(vertices, starts, axis=0), np.maximum.reduceat(vertices, starts, axis=0)])


def pair_keys(pairs: np.ndarray, n_blocks: int) -> np.ndarray:
    """One integer per unordered block pair (k, 2): min·n + max."""
    return np.min(pairs, axis=1) * n_blocks + np.max(pairs, axis=1) if len(pairs) else np.zeros(0, np.int64)


def grow_boxes(boxes: np.ndarray, distance: float) -> np.ndarray:
    """Boxes (nb, 2·dim) [lower corner, upper corner] grown by ``distance`` / 2 on every side."""
    dim = boxes.shape[1] // 2
    return boxes + 0.5 * distance * np.repeat([-1.0, 1.0], dim)


def boxes_within(boxes: np.ndarray, pairs: np.ndarray, distance: float) -> np.ndarray:
    """Which ``pairs`` (k, 2) have boxes that overlap (touching counts) once grown by ``distance``."""
    dim = boxes.shape[1] // 2
    grown = grow_boxes(boxes, distance)
    a, b = grown[pairs[:, 0]], grown[pairs[:, 1]]
    return np.all(a[:, :dim] <= b[:, dim:], axis=1) & np.all(b[:, :dim] <= a[:, dim:], axis=1)


class KeptCandidates:
    """The broad phase ``find(boxes, distance)`` with a margin, kept while the vertices stay within it."""

    def __init__(self, find: Callable[[np.ndarray, float], np.ndarray], distance: float, margin: float) -> None:
        self.find = find
        self.distance = distance
        self.margin = margin
        self.searches = 0  # broad-phase runs (tests and benchmarks read it)
        self._pairs: np.ndarray | None = None
        self._reference: np.ndarray | None = None

    def __call__(self, vertices: np.ndarray, boxes: np.ndarray) -> np.ndarray:
        """The candidate pairs (k, 2), sorted, of the configuration ``vertices`` with block ``boxes``."""
        ref, pairs = self._reference, self._pairs
        if ref is None or pairs is None or ref.shape != vertices.shape \
                or float(np.max(np.abs(vertices - ref))) > 0.5 * self.margin:
            pairs = self._pairs = self.find(boxes, self.distance + self.margin)
            self._reference = vertices.copy()
            self.searches += 1
        return pairs[boxes_within(boxes, pairs, self.distance)]


class PairFinder:
    """The broad phase of a model's contacts: kept candidate pairs (above) less the hinged ones.

    Blocks joined by a hinge turn about a shared point: their faces are not
    joints, so their pairs never make contacts; nor do the pairs of a block a
    stage removed (excavated). ``can_touch`` marks the blocks some other block
    may touch (the step control bounds only their vertices).
    ``find(boxes, distance)`` is the dimension's broad phase.
    """

    def __init__(self, arrays: ModelArrays, distance: float,
                 find: Callable[[np.ndarray, float, np.ndarray], np.ndarray]) -> None:
        self.n_blocks, self.block_ptr = arrays.n_blocks, arrays.block_ptr
        self.excluded = np.unique(pair_keys(arrays.links.hinged_block_pairs, arrays.n_blocks))
        first, second = np.divmod(self.excluded, arrays.n_blocks)
        partners_left_out = np.bincount(np.concatenate([first, second]), minlength=arrays.n_blocks)
        self.removed = arrays.block_removed  # excavated by a stage: its pairs make no contacts
        self.can_touch = partners_left_out < arrays.n_blocks - 1
        if self.removed is not None:
            self.can_touch &= ~self.removed
        movable = ~arrays.block_fixed
        # the broad phase with a margin of d0, run again once a vertex has moved d0/2
        self.candidates = KeptCandidates(lambda boxes, d: find(boxes, d, movable), distance, distance)

    def __call__(self, vertices: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The blocks' boxes and the candidate pairs (k, 2) of the configuration ``vertices``."""
        boxes = block_boxes(vertices, self.block_ptr)
        pairs = self.candidates(vertices, boxes)
        if len(self.excluded):
            pairs = pairs[~np.isin(pair_keys(pairs, self.n_blocks), self.excluded)]
        if self.removed is not None:
            pairs = pairs[~np.any(self.removed[pairs], axis=1)]
        return boxes, pairs


@njit(cache=True)
def push_row(buf: np.ndarray, n: int, row: tuple) -> np.ndarray:
    """``buf`` with ``row`` (a tuple of integers) written as its row ``n``, in a copy twice as long when row n
    would not fit (16 rows at least): the rows the compiled broad and narrow phases find, without knowing how many
    they will find."""
    if n >= buf.shape[0]:
        bigger = np.empty((max(GROWTH * buf.shape[0], n + 16), buf.shape[1]), dtype=buf.dtype)
        bigger[:n] = buf[:n]
        buf = bigger
    for j in range(len(row)):
        buf[n, j] = row[j]
    return buf


@njit(cache=True)
def both_ways(pairs: np.ndarray) -> np.ndarray:
    """The candidate pairs (k, 2) each both ways round, (a, b) then (b, a): the order the narrow phases test
    them in (a's vertices against b, then b's against a)."""
    n = pairs.shape[0]
    out = np.empty((n + n, pairs.shape[1]), dtype=pairs.dtype)
    for k in range(n):
        forward, backward = out[k + k], out[k + k + 1]
        forward[0], forward[1] = pairs[k, 0], pairs[k, 1]
        backward[0], backward[1] = pairs[k, 1], pairs[k, 0]
    return out
