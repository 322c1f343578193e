"""Probe: how many contacts act across a third block (a "phantom" contact)?

Not a benchmark (``make bench`` skips it) and not a test: a probe for developers.
Shi's vertex-vertex rule pairs a vertex v with a vertex q within d0 of it, and
vertex-edge pairs v with an edge within d0, whatever lies between them. This
probe runs a model and, at every recorded step, draws the segment from each
contact vertex to its contacted point (q for vertex-vertex, the projection on
the edge for vertex-edge) and asks whether it passes through the interior of a
third block (the block shrunk by ``DEPTH`` so that touching blocks do not
count). It prints the contacts per step, the phantom ones split into short
segments (< 1 cm: joint junctions, where three blocks meet) and long ones,
and how many phantom contacts were closed (carrying a force).
Usage: python benchmarks/probe_phantom_contacts.py MODEL.toml [STEPS] [METHOD]
Findings on 2026-11-22 are in docs/contacts.md (limitations).
"""
from __future__ import annotations

import dataclasses
import sys
import warnings

import numpy as np
import shapely

import srdda
from srdda.contact.openclose import OPEN
from srdda.io.modelfile import load_model

DEPTH = 1e-5  # m: a segment must pass this far inside a third block
LONG = 0.01  # m


class PhantomCounter:
    """A srdda Recorder that classifies the contacts of every recorded state."""

    def __init__(self) -> None:
        self.counts = dict(steps=0, contacts=0, short_phantom=0, long=0, long_phantom=0, closed_phantom=0)

    def record(self, arrays, state, solves, energy) -> None:
        c = state.contacts
        self.counts["steps"] += 1
        if c is None or len(c.vertex) == 0:
            return
        x = state.vertices
        p, q0, q1 = x[c.vertex], x[c.edge], x[arrays.vertex_next[c.edge]]
        d = q1 - q0
        t = np.einsum("ij,ij->i", p - q0, d) / np.einsum("ij,ij->i", d, d)
        nearest_end = np.where((np.hypot(*(p - q0).T) < np.hypot(*(p - q1).T))[:, None], q0, q1)
        target = np.where((c.kind == 1)[:, None], nearest_end, q0 + t[:, None] * d)
        length = np.hypot(*(p - target).T)
        segments = shapely.linestrings(np.stack([p, target], axis=1))
        blocks = [shapely.Polygon(x[arrays.block_ptr[b]:arrays.block_ptr[b + 1]]).buffer(-DEPTH)
                  for b in range(len(arrays.block_ptr) - 1)]
        seg, blk = shapely.STRtree(blocks).query(segments, predicate="intersects")
        third = (blk != arrays.vertex_block[c.vertex[seg]]) & (blk != arrays.vertex_block[c.edge[seg]])
        phantom = np.zeros(len(c.vertex), dtype=bool)
        phantom[seg[third]] = True
        phantom &= length > 0.0
        self.counts["contacts"] += len(c.vertex)
        self.counts["short_phantom"] += int(np.sum(phantom & (length <= LONG)))
        self.counts["long"] += int(np.sum(length > LONG))
        self.counts["long_phantom"] += int(np.sum(phantom & (length > LONG)))
        self.counts["closed_phantom"] += int(np.sum(phantom & (c.state != OPEN)))

    def finish(self, status, state) -> None:
        self.counts["status"] = status


def main() -> None:
    path = sys.argv[1]
    model, settings = load_model(path)
    settings = dataclasses.replace(settings, n_steps=int(sys.argv[2]) if len(sys.argv) > 2 else 300,
                                   method=sys.argv[3] if len(sys.argv) > 3 else settings.method)
    counter = PhantomCounter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        srdda.run(model, settings, recorders=[counter])
    print(path, settings.method, settings.n_steps, counter.counts)


if __name__ == "__main__":
    main()
