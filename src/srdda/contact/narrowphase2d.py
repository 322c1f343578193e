"""Narrow phase in 2D: vertex-to-edge and vertex-to-vertex contacts of candidate block pairs.

For every candidate pair (a, b), both ways round, each vertex v of a is tested
against each edge of b (numba kernel, no Python loop). Blocks are stored
counter-clockwise, so the outward normal of edge p0 -> p1 is (dy, -dx)/l and
the signed distance n·(v - p0) is positive outside.

* **Distance criterion** (Shi 1988): a vertex is a contact candidate when its
  distance to an edge (or to a vertex) is below d0.
* **Angle criterion** (Shi 1988): the vertex must be convex (interior angle at
  most 180° + tolerance) and both of its edges must lie on the outer side of
  the edge line (to within the angle tolerance), i.e. the vertex's wedge can
  touch the edge without overlapping it first.
* **Vertex-to-edge**: v projects into the interior of the edge.
* **Vertex-to-vertex**: v is within d0 of a vertex q of b and in q's vertex
  region (it projects beyond q on both edges at q). The *entrance line* is the
  edge at q, among the two that
  pass the angle criterion, with the largest signed distance to v: the line
  v entered b through, or would enter through (the shortest way out of b).
  Of the two ways to pair (v, q) -- v on an edge of q or q on an edge of v --
  exactly one contact is kept: q's vertex-edge contact where q has one with
  an edge at v that faces the entrance line (strained blocks whose corners
  met), else the
  one from the lower block index when both pass the angle criterion, else the
  one that passes. A projection within ``CORNER`` of an edge's end is at the end.
* **Vertex in a notch**: where q is a reflex corner of b (interior angle above
  180°), v touches both faces of the notch: it gets a contact with each edge
  at q whose angle criterion it passes, measured to that edge's line, whether
  it projects into the edge or beyond q (no entrance line to choose). With one
  spring only, a vertex held in a notch by one face drifted into the other
  unresisted and, found there as a new contact already compressed, brought
  ½k_n g² from nothing (docs/dev/contact-solve.md).

* **Plausibility**: a vertex behind the edge's line (negative gap) counts
  only if it lies inside the other block, no deeper than the allowed
  penetration, and no closer to another edge of that block that its wedge
  could have entered through (a vertex on the far side of a thin block, or
  on one edge beside an acute corner, is not a contact with that edge; the
  other face of a notch at the edge's end does not compete).

Output: contact vertex, contacted edge (index of its start vertex) and kind
(0 vertex-edge, 1 vertex-vertex).
"""
from __future__ import annotations

import numpy as np
from numba import njit, prange

from .candidates import both_ways, push_row

__all__ = ["VERTEX_EDGE", "VERTEX_VERTEX", "FOUND_VERTEX", "FOUND_EDGE", "FOUND_KIND", "FOUND_FIELDS",
           "narrow_phase_2d", "narrow_phase_2d_parallel"]

VERTEX_EDGE = 0
VERTEX_VERTEX = 1


# a vertex projecting within this fraction of an edge's length of its end is at the end (vertex-vertex): the
# rounding of coordinates at coinciding corners (stacked or cut blocks, 1e-17 of 1 m measured), not a position
# along the edge; without it such a corner was paired both ways, vertex-edge and vertex-vertex, one solve the
# one, the next the other, and each contact found already compressed brought ½k_n g² from nothing
CORNER = 1e-9

# columns of a detected-contact row [vertex, edge start, kind]
FOUND_VERTEX, FOUND_EDGE, FOUND_KIND = range(3)
FOUND_FIELDS = 3

# the parallel narrow phase's share of work (directed candidate pairs) and the rows it makes room for per pair
# (a brick's vertices against a neighbour find at most 2; a chunk that finds more is found again on one thread)
CHUNK_PAIRS = 256
CHUNK_ROOM = 4


@njit(cache=True)
def _wedge_fits(X, nxt, prv, v, nx, ny, sin_tol):
    """Shi's angle criterion: convex vertex v whose two edges stay outside the line of normal n."""
    ax = X[prv[v], 0] - X[v, 0]
    ay = X[prv[v], 1] - X[v, 1]
    bx = X[nxt[v], 0] - X[v, 0]
    by = X[nxt[v], 1] - X[v, 1]
    la = np.sqrt(ax * ax + ay * ay)
    lb = np.sqrt(bx * bx + by * by)
    # interior angle <= 180° (+tol): cross(v - prev, next - v) = cross(-a, b) >= -sin_tol·la·lb
    if -(ax * by - ay * bx) < -sin_tol * la * lb:
        return False
    return nx * ax + ny * ay >= -sin_tol * la and nx * bx + ny * by >= -sin_tol * lb


@njit(cache=True)
def _reflex(X, nxt, prv, q, sin_tol):
    """Whether vertex q is a reflex corner of its block (a notch: interior angle above 180° + tol)."""
    ax = X[q, 0] - X[prv[q], 0]
    ay = X[q, 1] - X[prv[q], 1]
    bx = X[nxt[q], 0] - X[q, 0]
    by = X[nxt[q], 1] - X[q, 1]
    return ax * by - ay * bx < -sin_tol * np.sqrt(ax * ax + ay * ay) * np.sqrt(bx * bx + by * by)


@njit(cache=True)
def _edge_frame(X, nxt, e):
    """Start point, direction and length of edge e; outward normal follows from CCW order."""
    x0 = X[e, 0]
    y0 = X[e, 1]
    dx = X[nxt[e], 0] - x0
    dy = X[nxt[e], 1] - y0
    return x0, y0, dx, dy, np.sqrt(dx * dx + dy * dy)


@njit(cache=True)
def _projection(X, nxt, v, e):
    x0, y0, dx, dy, length = _edge_frame(X, nxt, e)
    return ((X[v, 0] - x0) * dx + (X[v, 1] - y0) * dy) / (length * length)


@njit(cache=True)
def _entrance_edge(X, nxt, prv, v, q, sin_tol):
    """The entrance line of vertex v at vertex q (edge start index), or -1.

    -1 when a vertex-edge contact covers v (it projects into the interior of
    an edge at q whose angle criterion it passes) or neither edge passes the
    angle criterion. Projecting into an edge that v's wedge cannot touch does
    not count: two blocks whose corners coincide (cut blocks, stacked blocks)
    must still make a contact there.
    """
    for e in (prv[q], q):
        t = _projection(X, nxt, v, e)
        if CORNER < t < 1.0 - CORNER:
            x0, y0, dx, dy, length = _edge_frame(X, nxt, e)
            if _wedge_fits(X, nxt, prv, v, dy / length, -dx / length, sin_tol):
                return -1
    best = -1
    best_dist = -np.inf
    for e in (prv[q], q):
        x0, y0, dx, dy, length = _edge_frame(X, nxt, e)
        nx = dy / length
        ny = -dx / length
        if not _wedge_fits(X, nxt, prv, v, nx, ny, sin_tol):
            continue
        dist = nx * (X[v, 0] - x0) + ny * (X[v, 1] - y0)
        if dist > best_dist:
            best_dist = dist
            best = e
    return best


@njit(cache=True)
def _inside(X, block_ptr, nxt, b, x, y):
    """Crossing-number test: does (x, y) lie inside block b?"""
    inside = False
    for e in range(block_ptr[b], block_ptr[b + 1]):
        x0 = X[e, 0]
        y0 = X[e, 1]
        x1 = X[nxt[e], 0]
        y1 = X[nxt[e], 1]
        if (y0 > y) != (y1 > y) and x < x0 + (y - y0) * (x1 - x0) / (y1 - y0):
            inside = not inside
    return inside


@njit(cache=True)
def _segment_distance(X, nxt, e, x, y):
    x0, y0, dx, dy, length = _edge_frame(X, nxt, e)
    t = min(1.0, max(0.0, ((x - x0) * dx + (y - y0) * dy) / (length * length)))
    return np.sqrt((x - x0 - t * dx) ** 2 + (y - y0 - t * dy) ** 2)


@njit(cache=True)
def _boundary_distance(X, block_ptr, nxt, b, x, y):
    """Distance from (x, y) to the outline of block b."""
    best = np.inf
    for f in range(block_ptr[b], block_ptr[b + 1]):
        best = min(best, _segment_distance(X, nxt, f, x, y))
    return best


@njit(cache=True)
def _plausible(X, block_ptr, nxt, prv, b, v, e, max_depth, sin_tol):
    """A vertex behind the edge line is a contact only as a real, shallow penetration.

    It must lie inside block b (or on its outline, to 1e-6 of the edge's
    length: a vertex that penetrated by 1e-8 m at a corner of b may be put
    just outside the corner's other edge by rounding, and must still be
    found), no deeper than ``max_depth``, and the edge must
    be its shortest way out: no other edge of b that v's wedge could have
    entered through (angle criterion) may be nearer. A vertex on the far side
    of a thin block is not a contact, nor is a vertex that sits on one edge near
    an acute corner of b and merely lies behind the line of the corner's other
    edge (it would get a spring as deep as its distance to that line, a
    penetration that never happened: the energy of that spring is created from
    nothing). Edges v's wedge cannot touch do not compete: two blocks whose
    corners coincide (cut or stacked blocks) keep their contact although v is
    as near the other block's side edge as to the supporting one.
    """
    x0, y0, dx, dy, length = _edge_frame(X, nxt, e)
    x = X[v, 0]
    y = X[v, 1]
    depth = -(dy * (x - x0) - dx * (y - y0)) / length
    if depth <= 0.0:
        return True
    if depth > max_depth:
        return False
    slack = 1e-9 * length  # rounding of distances near a vertex shared by two edges
    if not _inside(X, block_ptr, nxt, b, x, y) and _boundary_distance(X, block_ptr, nxt, b, x, y) > 1e-6 * length:
        return False
    for f in range(block_ptr[b], block_ptr[b + 1]):
        if f == e or _segment_distance(X, nxt, f, x, y) >= depth - slack:
            continue
        if (f == prv[e] and _reflex(X, nxt, prv, e, sin_tol)) or (f == nxt[e] and _reflex(X, nxt, prv, f, sin_tol)):
            continue  # the notch's other face: v may press on both
        fx0, fy0, fdx, fdy, flength = _edge_frame(X, nxt, f)
        if _wedge_fits(X, nxt, prv, v, fdy / flength, -fdx / flength, sin_tol):
            return False
    return True


@njit(cache=True)
def _vertex_edge(X, block_ptr, nxt, prv, b, v, e, d0, sin_tol, max_depth):
    """Whether vertex v and edge e of block b make a vertex-edge contact: v projects into the interior of e,
    within d0 of its line, passes the angle criterion and is plausible."""
    x0, y0, dx, dy, length = _edge_frame(X, nxt, e)
    x = X[v, 0]
    y = X[v, 1]
    t = ((x - x0) * dx + (y - y0) * dy) / (length * length)
    if t <= CORNER or t >= 1.0 - CORNER:
        return False
    nx = dy / length
    ny = -dx / length
    dist = nx * (x - x0) + ny * (y - y0)
    return abs(dist) < d0 and _wedge_fits(X, nxt, prv, v, nx, ny, sin_tol) \
        and _plausible(X, block_ptr, nxt, prv, b, v, e, max_depth, sin_tol)


@njit(cache=True)
def _duplicate(X, block_ptr, nxt, prv, a, v, q, chosen, d0, sin_tol, max_depth):
    """Whether q has a vertex-edge contact with an edge at v (of block a) facing the entrance line ``chosen``
    (normals opposite within the angle tolerance): the same contact as the vertex-vertex one of (v, q), which
    would add a second spring to the corner pair, found already compressed where strained blocks' corners
    met (½k_n g² from nothing, issue 29)."""
    cx0, cy0, cdx, cdy, clength = _edge_frame(X, nxt, chosen)
    for f in (prv[v], v):
        x0, y0, dx, dy, length = _edge_frame(X, nxt, f)
        facing = (cdy * dy + cdx * dx) / (clength * length) < 0.0 \
            and abs(cdy * dx - cdx * dy) / (clength * length) <= sin_tol
        if facing and _vertex_edge(X, block_ptr, nxt, prv, a, q, f, d0, sin_tol, max_depth):
            return True
    return False


@njit(cache=True)
def _notch_contacts(X, block_ptr, nxt, prv, b, v, q, d0, sin_tol, max_depth, buf, n):
    """(buf, n) with v's contacts with the two faces of the notch at q (a reflex corner of b) appended: each
    edge at q whose angle criterion v passes, within d0 of its line, where v does not project into its
    interior (there the vertex-edge test finds it) and is plausible."""
    for f in (prv[q], q):
        t = _projection(X, nxt, v, f)
        if CORNER < t < 1.0 - CORNER:
            continue
        x0, y0, dx, dy, length = _edge_frame(X, nxt, f)
        nx = dy / length
        ny = -dx / length
        dist = nx * (X[v, 0] - x0) + ny * (X[v, 1] - y0)
        if abs(dist) < d0 and _wedge_fits(X, nxt, prv, v, nx, ny, sin_tol) \
                and _plausible(X, block_ptr, nxt, prv, b, v, f, max_depth, sin_tol):
            buf = push_row(buf, n, (v, f, VERTEX_VERTEX))
            n += 1
    return buf, n


@njit(cache=True)
def _pair_contacts(X, block_ptr, nxt, prv, boxes, d0, sin_tol, max_depth, a, b, buf, n):
    """(buf, n) with the contacts of a's vertices against b's edges appended as rows from n on."""
    d02 = d0 * d0
    for v in range(block_ptr[a], block_ptr[a + 1]):
        x = X[v, 0]
        y = X[v, 1]
        if x < boxes[b, 0] - d0 or x > boxes[b, 2] + d0 or y < boxes[b, 1] - d0 or y > boxes[b, 3] + d0:
            continue
        for e in range(block_ptr[b], block_ptr[b + 1]):
            if (x - X[e, 0]) ** 2 + (y - X[e, 1]) ** 2 < d02:  # v near the vertex q = e
                if _reflex(X, nxt, prv, e, sin_tol):  # in a notch: both faces
                    buf, n = _notch_contacts(X, block_ptr, nxt, prv, b, v, e, d0, sin_tol, max_depth, buf, n)
                else:  # vertex-vertex: one contact, on the entrance line
                    chosen = _entrance_edge(X, nxt, prv, v, e, sin_tol)
                    if chosen >= 0 \
                            and not _duplicate(X, block_ptr, nxt, prv, a, v, e, chosen, d0, sin_tol, max_depth) \
                            and (a < b or _entrance_edge(X, nxt, prv, e, v, sin_tol) < 0) \
                            and _plausible(X, block_ptr, nxt, prv, b, v, chosen, max_depth, sin_tol):
                        buf = push_row(buf, n, (v, chosen, VERTEX_VERTEX))
                        n += 1
            if _vertex_edge(X, block_ptr, nxt, prv, b, v, e, d0, sin_tol, max_depth):
                buf = push_row(buf, n, (v, e, VERTEX_EDGE))
                n += 1
    return buf, n


@njit(cache=True)
def _chunk_contacts(X, block_ptr, nxt, prv, directed, boxes, d0, sin_tol, max_depth, start, stop, buf, n):
    """(buf, n) with the contacts of the directed pairs start..stop appended, in their order."""
    for k in range(start, stop):
        buf, n = _pair_contacts(X, block_ptr, nxt, prv, boxes, d0, sin_tol, max_depth, directed[k, 0],
                                directed[k, 1], buf, n)
    return buf, n


@njit(cache=True)
def narrow_phase_2d(X, block_ptr, vertex_block, nxt, prv, pairs, boxes, d0, sin_tol, max_depth):
    """Contacts (k, 3) [vertex, edge start, kind] of the candidate ``pairs`` (k, 2).

    A vertex behind the edge's line counts only if it lies inside the other
    block no deeper than ``max_depth`` (an accepted step never penetrates
    deeper, so anything else is a vertex on the far side of a thin block).
    """
    directed = both_ways(pairs)
    buf = np.empty((max(16, 4 * len(pairs)), FOUND_FIELDS), dtype=np.int64)
    buf, n = _chunk_contacts(X, block_ptr, nxt, prv, directed, boxes, d0, sin_tol, max_depth, 0, len(directed),
                             buf, 0)
    return buf[:n].copy()


@njit(parallel=True, cache=True)
def narrow_phase_2d_parallel(X, block_ptr, vertex_block, nxt, prv, pairs, boxes, d0, sin_tol, max_depth,
                             room_per_pair=CHUNK_ROOM):
    """:func:`narrow_phase_2d` with chunks of :data:`CHUNK_PAIRS` directed pairs shared among threads: the
    same rows in the same order.

    Each chunk writes into its own slots (room for ``room_per_pair`` rows a pair); a chunk that found more is
    found again on one thread while the chunks' rows are joined in order.
    """
    directed = both_ways(pairs)
    chunks = (len(directed) + CHUNK_PAIRS - 1) // CHUNK_PAIRS
    room = room_per_pair * CHUNK_PAIRS
    slots = np.empty((chunks * room, FOUND_FIELDS), dtype=np.int64)
    counts = np.zeros(chunks, dtype=np.int64)
    for c in prange(chunks):
        start = c * CHUNK_PAIRS
        own = slots[c * room:(c + 1) * room]
        found, n = _chunk_contacts(X, block_ptr, nxt, prv, directed, boxes, d0, sin_tol, max_depth, start,
                                   min(start + CHUNK_PAIRS, len(directed)), own, 0)
        counts[c] = n
        if n > room:  # found in a longer copy: the chunk is found again below
            counts[c] = -1
    out = np.empty((max(16, 4 * len(pairs)), FOUND_FIELDS), dtype=np.int64)
    n = 0
    for c in range(chunks):
        start = c * CHUNK_PAIRS
        if counts[c] < 0:
            out, n = _chunk_contacts(X, block_ptr, nxt, prv, directed, boxes, d0, sin_tol, max_depth, start,
                                     min(start + CHUNK_PAIRS, len(directed)), out, n)
        else:
            for i in range(counts[c]):
                out = push_row(out, n, (slots[c * room + i, 0], slots[c * room + i, 1], slots[c * room + i, 2]))
                n += 1
    return out[:n].copy()
