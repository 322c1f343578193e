"""Contact detection time against the number of blocks (broad + narrow phase).

Blocks are jittered squares on a grid with a gap of 0.2 % of their size, so
every block has contacts with its neighbours (the worst case for the narrow
phase). Prints a table and the fitted growth exponent of the total time.

    PYTHONPATH=src python benchmarks/bench_contact_detection.py [N ...]
"""
from __future__ import annotations

import platform
import sys
import time

import numpy as np

from srdda.contact.broadphase import block_boxes, candidate_pairs
from srdda.contact.narrowphase import detect_contacts
from srdda.geometry.polygon import previous_vertex_index
from srdda.geometry.polygon import next_vertex_index


def block_grid(n_blocks: int, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """Vertices and block pointer of about ``n_blocks`` slightly rotated unit squares on a grid."""
    rng = np.random.default_rng(seed)
    side = int(np.ceil(np.sqrt(n_blocks)))
    ij = np.stack(np.meshgrid(np.arange(side), np.arange(side), indexing="ij"), -1).reshape(-1, 2)[:n_blocks]
    angle = rng.uniform(-0.01, 0.01, n_blocks)
    c, s = np.cos(angle), np.sin(angle)
    square = 0.499 * np.array([[-1, -1], [1, -1], [1, 1], [-1, 1]], dtype=float)
    rotated = np.einsum("nij,kj->nki", np.stack([np.stack([c, -s], -1), np.stack([s, c], -1)], -2), square)
    vertices = (rotated + ij[:, None, :].astype(float)).reshape(-1, 2)
    return vertices, np.arange(0, 4 * n_blocks + 1, 4, dtype=np.int64)


def time_detection(n_blocks: int, d0: float = 0.01, repeats: int = 3) -> tuple[float, float, int]:
    vertices, ptr = block_grid(n_blocks)
    owner = np.repeat(np.arange(n_blocks), 4)
    nxt, prv = next_vertex_index(ptr), previous_vertex_index(ptr)
    movable = np.ones(n_blocks, dtype=bool)
    best_broad = best_narrow = np.inf
    found = np.empty((0, 3))
    for _ in range(repeats):
        t0 = time.perf_counter()
        boxes = block_boxes(vertices, ptr)
        pairs = candidate_pairs(boxes, d0, movable)
        t1 = time.perf_counter()
        found = detect_contacts(vertices, ptr, owner, nxt, prv, pairs, boxes, d0, np.sin(np.radians(3.0)), 0.4 * d0)
        t2 = time.perf_counter()
        best_broad, best_narrow = min(best_broad, t1 - t0), min(best_narrow, t2 - t1)
    return best_broad, best_narrow, len(found)


def main(sizes: list[int]) -> None:
    time_detection(100)  # compile the numba kernels
    print(f"# {platform.processor() or platform.machine()}, Python {platform.python_version()}")
    print(f"{'blocks':>8} {'broad s':>9} {'narrow s':>9} {'total s':>9} {'contacts':>9} {'µs/block':>9}")
    totals = []
    for n in sizes:
        broad, narrow, k = time_detection(n)
        totals.append(broad + narrow)
        print(f"{n:>8} {broad:>9.4f} {narrow:>9.4f} {broad + narrow:>9.4f} {k:>9} {1e6 * (broad + narrow) / n:>9.2f}")
    if len(sizes) > 1:
        slope = np.polyfit(np.log(sizes), np.log(totals), 1)[0]
        print(f"growth exponent of the total time: {slope:.3f} (N log N over this range: about 1.1)")


if __name__ == "__main__":
    main([int(a) for a in sys.argv[1:]] or [1000, 3000, 10000, 30000, 100000])
