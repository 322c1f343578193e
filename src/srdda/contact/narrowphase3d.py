"""Narrow phase in 3D: vertex-face and edge-edge contacts of candidate polyhedron pairs.

Every contact between two polyhedra is reduced to the two basic types of
Shi's 3D contact theory (G.-H. Shi, "Three dimensional discontinuous
deformation analyses", 38th US Rock Mechanics Symposium, 2001; the reduction
as in S.A.M. Beyabanaki, A. Jafari, S.O. Biabanaki & G.R. Yeung, "A coupling
model of 3-D discontinuous deformation analysis (3-D DDA) and finite element
method", AJSE 34(2B), 2009, and Y.J. Ning, J. Yang, G.W. Ma & P.W. Chen,
"Contact algorithm for 3D DDA and its verification", 2011):

* **vertex-face** (V-F): vertex v of block a against face f of block b. A
  face-face contact is the V-F contacts of the corners of the contact
  polygon (the vertices of each face that lie over the other face), an
  edge-face contact those of the edge's end points over the face plus E-E
  contacts where it crosses the face's rim;
* **edge-edge** (E-E): two crossing edges, the contact point the closest
  points of the two segments, the normal their cross product. Parallel
  edges make no E-E contact (their end points make V-F contacts);
* vertex-edge and vertex-vertex are V-F contacts with the *entrance face*:
  of the faces near v that v's cone fits, the one with the largest signed
  distance to v (the face v would enter through; the 3D counterpart of
  Shi's entrance line, as in the 2D narrow phase).

Criteria (d0 the contact distance, all on the configuration at t):

* distance: the signed distance (positive outside) is below d0, and a
  negative one (penetration) is no deeper than the allowed penetration;
* angle criterion (Shi): v is a convex vertex (all its edges convex) and
  every edge at v points to the outer side of the face's plane, to within
  the angle tolerance: v's cone can touch the face without overlapping it
  first. Reflex vertices and reflex edges (of concave blocks) never make a
  contact: the other block's vertices and edges touch their faces instead;
* V-F *interior*: v projects into the face polygon (its boundary included);
  a V-F *band* contact (v projects outside the polygon by less than d0) is
  the entrance face of v, kept only when v has no interior contact with b;
* E-E: both edges convex, not parallel (sin of their angle above the angle
  tolerance), the closest points inside both segments and farther than d0
  from their ends (nearer, the end vertex's V-F band contact carries the
  contact: an edge whose end juts out past a rim by rounding or by elastic
  strain would otherwise be supported twice at one point); the normal n, turned
  outward from b, lies in b's normal cone at its edge (between the normals
  of its two faces, to within the angle tolerance) and -n in a's;
* plausibility of a penetrating V-F contact: no other face of b that v's
  cone fits is nearer to v than the contacted face's plane (the contacted
  face is v's shortest way out; a vertex beyond a thin block, or beside an
  acute edge, is not a contact with the far face);
* a contact penetrating a convex block deeper than ``_OUTSIDE`` × d0 must be
  inside it: a vertex (or an E-E contact's closest point on either edge) in
  front of any face plane of that block by more than ``_OUTSIDE`` × d0 is
  beside the block, not in it, whatever its depth below the contacted face
  (in a freshly cut 3D slope, vertices beside a block's rim were taken for
  12 cm penetrations of its far face, docs/contacts-3d.md). Shallower
  contacts (rounding at coplanar faces) keep the band rule above.

Output rows [kind, feature of a, feature of b, block a, block b]: kind 0 V-F
(vertex, face), kind 1 E-E (edge of a, edge of b), edges numbered as in
:class:`srdda.contact.detect3d.PolyhedronTopology`.
"""
from __future__ import annotations

import numpy as np
from numba import njit

from .candidates import both_ways, push_row

__all__ = ["VERTEX_FACE", "EDGE_EDGE", "FOUND_FIELDS", "narrow_phase_3d"]

VERTEX_FACE = 0
EDGE_EDGE = 1
FOUND_FIELDS = 5  # [kind, feature a, feature b, block a, block b]
_INSIDE = 1e-9  # a projection this close to a face's boundary (× d0) counts as inside
_OUTSIDE = 1e-3  # a point this far in front of a convex block's face plane (× d0) is outside the block


@njit(cache=True)
def _sub(X, i, j):
    return X[i, 0] - X[j, 0], X[i, 1] - X[j, 1], X[i, 2] - X[j, 2]


@njit(cache=True)
def _cone_fits(X, v, neighbour_ptr, neighbour, vertex_convex, nx, ny, nz, sin_tol):
    """Angle criterion: v convex and each of its edges on the outer side of the plane of normal n."""
    if not vertex_convex[v]:
        return False
    for k in range(neighbour_ptr[v], neighbour_ptr[v + 1]):
        ex, ey, ez = _sub(X, neighbour[k], v)
        length = np.sqrt(ex * ex + ey * ey + ez * ez)
        if nx * ex + ny * ey + nz * ez < -sin_tol * length:
            return False
    return True


@njit(cache=True)
def _outside_distance(X, face_ptr, face_vertex, f, nx, ny, nz, qx, qy, qz):
    """In-plane distance from q (on f's plane) to the polygon f: 0 inside (crossing number in a face frame)."""
    p0 = face_vertex[face_ptr[f]]
    p1 = face_vertex[face_ptr[f] + 1]
    ux, uy, uz = _sub(X, p1, p0)
    lu = np.sqrt(ux * ux + uy * uy + uz * uz)
    ux, uy, uz = ux / lu, uy / lu, uz / lu
    wx, wy, wz = ny * uz - nz * uy, nz * ux - nx * uz, nx * uy - ny * ux  # n × u
    qu = (qx - X[p0, 0]) * ux + (qy - X[p0, 1]) * uy + (qz - X[p0, 2]) * uz
    qw = (qx - X[p0, 0]) * wx + (qy - X[p0, 1]) * wy + (qz - X[p0, 2]) * wz
    inside = False
    best = np.inf
    start, stop = face_ptr[f], face_ptr[f + 1]
    for k in range(start, stop):
        i = face_vertex[k]
        j = face_vertex[k + 1] if k + 1 < stop else face_vertex[start]
        ax = (X[i, 0] - X[p0, 0]) * ux + (X[i, 1] - X[p0, 1]) * uy + (X[i, 2] - X[p0, 2]) * uz
        ay = (X[i, 0] - X[p0, 0]) * wx + (X[i, 1] - X[p0, 1]) * wy + (X[i, 2] - X[p0, 2]) * wz
        bx = (X[j, 0] - X[p0, 0]) * ux + (X[j, 1] - X[p0, 1]) * uy + (X[j, 2] - X[p0, 2]) * uz
        by = (X[j, 0] - X[p0, 0]) * wx + (X[j, 1] - X[p0, 1]) * wy + (X[j, 2] - X[p0, 2]) * wz
        if (ay > qw) != (by > qw) and qu < ax + (qw - ay) * (bx - ax) / (by - ay):
            inside = not inside
        dx, dy = bx - ax, by - ay
        t = min(1.0, max(0.0, ((qu - ax) * dx + (qw - ay) * dy) / (dx * dx + dy * dy)))
        best = min(best, np.hypot(qu - ax - t * dx, qw - ay - t * dy))
    return 0.0 if inside else best


@njit(cache=True)
def _face_distance(X, face_ptr, face_vertex, face_normal, face_point, g, v):
    """Distance from vertex v to the polygon g (plane distance and in-plane distance combined)."""
    nx, ny, nz = face_normal[g, 0], face_normal[g, 1], face_normal[g, 2]
    d = nx * (X[v, 0] - face_point[g, 0]) + ny * (X[v, 1] - face_point[g, 1]) + nz * (X[v, 2] - face_point[g, 2])
    out = _outside_distance(X, face_ptr, face_vertex, g, nx, ny, nz, X[v, 0] - d * nx, X[v, 1] - d * ny,
                            X[v, 2] - d * nz)
    return np.sqrt(d * d + out * out)


@njit(cache=True)
def _height_over(block_face_ptr, face_normal, face_point, b, x, y, z):
    """Largest signed distance of the point (x, y, z) to b's face planes: > 0 outside a convex b."""
    worst = -np.inf
    for g in range(block_face_ptr[b], block_face_ptr[b + 1]):
        h = face_normal[g, 0] * (x - face_point[g, 0]) + face_normal[g, 1] * (y - face_point[g, 1]) \
            + face_normal[g, 2] * (z - face_point[g, 2])
        worst = max(worst, h)
    return worst


@njit(cache=True)
def _in_normal_cone(mx, my, mz, e, edge_v0, edge_v1, edge_faces, face_normal, X, sin_tol):
    """Does the unit vector m lie between the outward normals of edge e's two faces (to the tolerance)?"""
    ex, ey, ez = _sub(X, edge_v1[e], edge_v0[e])
    le = np.sqrt(ex * ex + ey * ey + ez * ez)
    ex, ey, ez = ex / le, ey / le, ez / le
    f, g = edge_faces[e, 0], edge_faces[e, 1]
    ax, ay, az = face_normal[f, 0], face_normal[f, 1], face_normal[f, 2]
    bx, by, bz = face_normal[g, 0], face_normal[g, 1], face_normal[g, 2]
    if mx * (ax + bx) + my * (ay + by) + mz * (az + bz) <= 0.0:
        return False
    # in the plane normal to e: m between a and b when (a × m)·e and (m × b)·e share the sign of (a × b)·e
    s = 1.0 if ((ay * bz - az * by) * ex + (az * bx - ax * bz) * ey + (ax * by - ay * bx) * ez) >= 0.0 else -1.0
    am = (ay * mz - az * my) * ex + (az * mx - ax * mz) * ey + (ax * my - ay * mx) * ez
    mb = (my * bz - mz * by) * ex + (mz * bx - mx * bz) * ey + (mx * by - my * bx) * ez
    return s * am >= -sin_tol and s * mb >= -sin_tol


@njit(cache=True)
def _vertex_face(X, a, b, block_ptr, block_face_ptr, face_ptr, face_vertex, face_normal, face_point,
                 neighbour_ptr, neighbour, vertex_convex, block_convex, boxes, d0, sin_tol, max_depth, buf, n):
    """V-F contacts of a's vertices with b's faces (interior ones, else the entrance face of a band)."""
    inside_tol = _INSIDE * d0
    for v in range(block_ptr[a], block_ptr[a + 1]):
        if not vertex_convex[v]:
            continue
        x, y, z = X[v, 0], X[v, 1], X[v, 2]
        if (x < boxes[b, 0] - d0 or x > boxes[b, 3] + d0 or y < boxes[b, 1] - d0 or y > boxes[b, 4] + d0
                or z < boxes[b, 2] - d0 or z > boxes[b, 5] + d0):
            continue
        interior = 0
        band = -1
        band_distance = -np.inf
        for f in range(block_face_ptr[b], block_face_ptr[b + 1]):
            nx, ny, nz = face_normal[f, 0], face_normal[f, 1], face_normal[f, 2]
            d = nx * (x - face_point[f, 0]) + ny * (y - face_point[f, 1]) + nz * (z - face_point[f, 2])
            if d >= d0 or d < -max_depth:
                continue
            if not _cone_fits(X, v, neighbour_ptr, neighbour, vertex_convex, nx, ny, nz, sin_tol):
                continue
            out = _outside_distance(X, face_ptr, face_vertex, f, nx, ny, nz, x - d * nx, y - d * ny, z - d * nz)
            if out >= d0:
                continue
            if d < -_OUTSIDE * d0 and block_convex[b] and _height_over(block_face_ptr, face_normal, face_point, b,
                                                                       x, y, z) > _OUTSIDE * d0:
                continue  # v is beside b, not in it
            if d < 0.0:  # plausibility: the contacted face is v's shortest way out of b
                slack = 1e-9 * d0
                plausible = True
                for g in range(block_face_ptr[b], block_face_ptr[b + 1]):
                    if g == f or not _cone_fits(X, v, neighbour_ptr, neighbour, vertex_convex, face_normal[g, 0],
                                                face_normal[g, 1], face_normal[g, 2], sin_tol):
                        continue
                    if _face_distance(X, face_ptr, face_vertex, face_normal, face_point, g, v) < -d - slack:
                        plausible = False
                        break
                if not plausible:
                    continue
            if out <= inside_tol:
                buf = push_row(buf, n, (VERTEX_FACE, v, f, a, b))
                n += 1
                interior += 1
            elif d > band_distance:
                band_distance = d
                band = f
        if interior == 0 and band >= 0:
            buf = push_row(buf, n, (VERTEX_FACE, v, band, a, b))
            n += 1
    return buf, n


@njit(cache=True)
def _edge_edge(X, a, b, block_edge_ptr, edge_v0, edge_v1, edge_faces, edge_convex, block_face_ptr, face_normal,
               face_point, block_convex, boxes, d0, sin_tol, max_depth, buf, n):
    """E-E contacts of the crossing convex edges of a and b (closest points inside both, normal in both cones)."""
    for ea in range(block_edge_ptr[a], block_edge_ptr[a + 1]):
        if not edge_convex[ea]:
            continue
        p, p1 = edge_v0[ea], edge_v1[ea]
        lo0 = min(X[p, 0], X[p1, 0]) - d0
        hi0 = max(X[p, 0], X[p1, 0]) + d0
        lo1 = min(X[p, 1], X[p1, 1]) - d0
        hi1 = max(X[p, 1], X[p1, 1]) + d0
        lo2 = min(X[p, 2], X[p1, 2]) - d0
        hi2 = max(X[p, 2], X[p1, 2]) + d0
        if (hi0 < boxes[b, 0] or lo0 > boxes[b, 3] or hi1 < boxes[b, 1] or lo1 > boxes[b, 4] or hi2 < boxes[b, 2]
                or lo2 > boxes[b, 5]):
            continue
        ux, uy, uz = _sub(X, p1, p)
        for eb in range(block_edge_ptr[b], block_edge_ptr[b + 1]):
            if not edge_convex[eb]:
                continue
            q, q1 = edge_v0[eb], edge_v1[eb]
            wx, wy, wz = _sub(X, q1, q)
            cx, cy, cz = uy * wz - uz * wy, uz * wx - ux * wz, ux * wy - uy * wx
            uu = ux * ux + uy * uy + uz * uz
            ww = wx * wx + wy * wy + wz * wz
            cc = cx * cx + cy * cy + cz * cz
            if cc <= sin_tol * sin_tol * uu * ww:
                continue  # parallel edges: their end points make V-F contacts
            rx, ry, rz = _sub(X, p, q)
            uw = ux * wx + uy * wy + uz * wz
            ur = ux * rx + uy * ry + uz * rz
            wr = wx * rx + wy * ry + wz * rz
            s = (uw * wr - ww * ur) / cc
            t = (uu * wr - uw * ur) / cc
            # closest points within d0 of an edge's end belong to that end vertex (its V-F band contact)
            lu, lw = np.sqrt(uu), np.sqrt(ww)
            if not (d0 < s * lu < lu - d0 and d0 < t * lw < lw - d0):
                continue
            norm = np.sqrt(cc)
            mx, my, mz = cx / norm, cy / norm, cz / norm
            fl, fr = edge_faces[eb, 0], edge_faces[eb, 1]
            if mx * (face_normal[fl, 0] + face_normal[fr, 0]) + my * (face_normal[fl, 1] + face_normal[fr, 1]) \
                    + mz * (face_normal[fl, 2] + face_normal[fr, 2]) < 0.0:
                mx, my, mz = -mx, -my, -mz
            d = mx * (rx + s * ux - t * wx) + my * (ry + s * uy - t * wy) + mz * (rz + s * uz - t * wz)
            if d >= d0 or d < -max_depth:
                continue
            if d < -_OUTSIDE * d0:  # a penetrating crossing lies inside both blocks (the convex ones checked)
                if block_convex[b] and _height_over(block_face_ptr, face_normal, face_point, b, X[p, 0] + s * ux,
                                                    X[p, 1] + s * uy, X[p, 2] + s * uz) > _OUTSIDE * d0:
                    continue
                if block_convex[a] and _height_over(block_face_ptr, face_normal, face_point, a, X[q, 0] + t * wx,
                                                    X[q, 1] + t * wy, X[q, 2] + t * wz) > _OUTSIDE * d0:
                    continue
            if not (_in_normal_cone(mx, my, mz, eb, edge_v0, edge_v1, edge_faces, face_normal, X, sin_tol)
                    and _in_normal_cone(-mx, -my, -mz, ea, edge_v0, edge_v1, edge_faces, face_normal, X, sin_tol)):
                continue
            buf = push_row(buf, n, (EDGE_EDGE, ea, eb, a, b))
            n += 1
    return buf, n


@njit(cache=True)
def narrow_phase_3d(X, pairs, boxes, block_ptr, block_face_ptr, face_ptr, face_vertex, face_normal,
                              face_point, neighbour_ptr, neighbour, vertex_convex, block_edge_ptr, edge_v0, edge_v1,
                              edge_faces, edge_convex, d0, sin_tol, max_depth):
    """Contacts (k, 5) [kind, feature a, feature b, block a, block b] of the candidate ``pairs`` (k, 2).

    V-F both ways round, E-E once per pair (module doc).
    """
    block_convex = np.ones(len(block_ptr) - 1, dtype=np.bool_)
    for b in range(len(block_convex)):
        for e in range(block_edge_ptr[b], block_edge_ptr[b + 1]):
            if not edge_convex[e]:
                block_convex[b] = False
                break
    buf = np.empty((max(16, 8 * len(pairs)), 5), dtype=np.int64)
    n = 0
    ordered = both_ways(pairs)
    for m in range(len(ordered)):
        a, b = ordered[m, 0], ordered[m, 1]
        buf, n = _vertex_face(X, a, b, block_ptr, block_face_ptr, face_ptr, face_vertex, face_normal,
                              face_point, neighbour_ptr, neighbour, vertex_convex, block_convex, boxes, d0,
                              sin_tol, max_depth, buf, n)
        if m % 2 == 1:  # after both ways round, the pair's crossing edges once
            buf, n = _edge_edge(X, b, a, block_edge_ptr, edge_v0, edge_v1, edge_faces, edge_convex,
                                block_face_ptr, face_normal, face_point, block_convex, boxes, d0, sin_tol, max_depth,
                                buf, n)
    return buf[:n].copy()
