"""3D block cutting: convex domains split by joint planes and finite discs.

A domain is one convex polyhedron or several (a non-convex domain is given as
convex parts; their common faces stay block boundaries). Every joint, an
infinite plane or a disc (:class:`~srdda.geometry.jointsets3d.JointPlanes`),
splits the convex fragments it crosses into two convex fragments. The split
of one convex polyhedron by a plane is exact and local (a numba kernel, no
Python loop over fragments, faces or vertices):

* signed distances d of the vertices; |d| <= ``snap`` counts as on the plane;
* every edge whose ends lie strictly on opposite sides gets one intersection
  point, computed from its lower-numbered end so both faces share it;
* each face ring is walked once: the vertices with d >= 0 and the crossing
  points form its part on the positive side, those with d <= 0 its part on
  the negative side (a part without a vertex strictly on its side is dropped);
* the section (the on-plane vertices and the crossing points, a convex
  polygon) ordered by angle about its centroid closes both fragments as a
  new face labelled with the joint's type, outward on each side.

Rules (details and reasons in docs/cutting-3d.md):

* a disc splits a fragment only if it crosses it completely (every vertex of
  the section lies within the disc); fragments are re-examined until no disc
  splits any more, so a disc cuts the pieces it crosses completely after
  other joints have cut a larger fragment;
* a cut that would leave a piece thinner than ``min_thickness`` (largest
  distance of its vertices from the joint plane), smaller than
  ``min_volume``, or degenerate (a face or the volume below 10 x the
  tolerances of :func:`~srdda.geometry.polyhedron.normalize_polyhedron`) is not
  made: the fragment stays whole and the skipped cut is reported
  (:class:`SkippedCut`); volume is always conserved;
* every final fragment is validated; one that fails (none is expected) is
  removed and reported with the reason (:class:`RejectedFragment`).

Joints are applied in the order given; without skipped cuts the result does
not depend on that order (a joint that crosses a fragment completely crosses
every piece of it that it meets).
"""
from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numba import njit, types
from numba.typed import List
from scipy.spatial import ConvexHull, QhullError

from .cutting2d import NO_JOINT, CuttingError
from .jointsets3d import JointPlanes
from .polyhedron import (PLANARITY_TOLERANCE, PolyhedronError, PolyhedronMesh, box, normalize_polyhedra,
                         normalize_polyhedron, polyhedron_moments)

__all__ = ["PolyhedralCut", "RejectedFragment", "SKIP_REASONS", "SkippedCut", "convex_hull_polyhedron",
           "cut_polyhedra", "halfspace_polyhedron"]

_SNAP = 1e-12  # vertices this close to a plane (x domain size) lie on it: the rounding level of the cut points
_SAFETY = 10.0  # pieces must clear the validation's tolerances by this factor
SKIP_REASONS = {1: "thinner than min_thickness", 2: "smaller than min_volume",
                3: "degenerate (a face or the volume below the validation tolerance)"}


@dataclass(frozen=True)
class SkippedCut:
    """A joint that crossed a fragment but did not split it, with why and where."""

    joint: int  # index into the joints given
    reason: str
    value: float  # the thickness (m) or volume (m³) of the smaller piece
    point: tuple[float, float, float]  # centroid of the section it would have cut


@dataclass(frozen=True)
class RejectedFragment:
    """A fragment removed from the result because it is not a valid polyhedron."""

    part: int
    reason: str
    centroid: tuple[float, float, float]


@dataclass(frozen=True)
class PolyhedralCut:
    """Convex blocks cut from a domain, as flat arrays.

    Block ``b`` owns ``vertices[block_ptr[b]:block_ptr[b+1]]`` and faces
    ``face_first[b]:face_first[b+1]``; face ``k`` is the ring of block-local
    vertex indices ``face_vertex[face_ptr[k]:face_ptr[k+1]]``, outward
    counter-clockwise, lying on a joint of type ``face_joint[k]``
    (``NO_JOINT`` = -1: a face of the domain). ``block_part`` is the domain
    part each block comes from.
    """

    vertices: np.ndarray
    block_ptr: np.ndarray
    face_first: np.ndarray
    face_ptr: np.ndarray
    face_vertex: np.ndarray
    face_joint: np.ndarray
    block_part: np.ndarray
    skipped: tuple[SkippedCut, ...]
    rejected: tuple[RejectedFragment, ...]

    @property
    def n_blocks(self) -> int:
        return len(self.block_ptr) - 1

    def block(self, b: int) -> tuple[np.ndarray, list[np.ndarray], np.ndarray]:
        """Vertices (n, 3), faces (local indices) and the faces' joint types of block ``b``."""
        v = self.vertices[self.block_ptr[b]:self.block_ptr[b + 1]]
        ks = range(self.face_first[b], self.face_first[b + 1])
        faces = [self.face_vertex[self.face_ptr[k]:self.face_ptr[k + 1]] for k in ks]
        return v, faces, self.face_joint[self.face_first[b]:self.face_first[b + 1]]

    def blocks(self) -> list[tuple[np.ndarray, list[np.ndarray]]]:
        """Every block as (vertices, faces)."""
        return [self.block(b)[:2] for b in range(self.n_blocks)]

    def mesh(self) -> PolyhedronMesh:
        """The blocks laid out flat (validated), for exact volumes and moments."""
        return PolyhedronMesh.from_blocks(self.blocks())

    def volumes(self) -> np.ndarray:
        """Exact volume of every block (m³)."""
        mesh = self.mesh()
        return polyhedron_moments(mesh.vertices, mesh).volume

    def centroids(self) -> np.ndarray:
        """Centroid (nb, 3) of every block."""
        mesh = self.mesh()
        return polyhedron_moments(mesh.vertices, mesh).centroid


# -- the kernels ---------------------------------------------------------------------------------
@njit(cache=True)
def _piece_metrics(v: np.ndarray, corners: np.ndarray, fptr: np.ndarray) -> tuple[float, float, float]:
    """(bounding-box diagonal, volume, smallest face area) of a polyhedron with outward faces."""
    nv = v.shape[0]
    lo = v[0].copy()
    hi = v[0].copy()
    ref = np.zeros(3)
    for i in range(nv):
        for k in range(3):
            lo[k] = min(lo[k], v[i, k])
            hi[k] = max(hi[k], v[i, k])
            ref[k] += v[i, k] / nv
    size = np.sqrt(np.sum((hi - lo) ** 2))
    volume = 0.0
    min_area = np.inf
    for f in range(len(fptr) - 1):
        s, e = fptr[f], fptr[f + 1]
        p0 = v[corners[s]] - ref
        nx = ny = nz = 0.0
        for c in range(s + 1, e - 1):
            a = v[corners[c]] - ref
            b = v[corners[c + 1]] - ref
            ux, uy, uz = a[0] - p0[0], a[1] - p0[1], a[2] - p0[2]
            wx, wy, wz = b[0] - p0[0], b[1] - p0[1], b[2] - p0[2]
            nx += uy * wz - uz * wy
            ny += uz * wx - ux * wz
            nz += ux * wy - uy * wx
            volume += (p0[0] * (a[1] * b[2] - a[2] * b[1]) + p0[1] * (a[2] * b[0] - a[0] * b[2])
                       + p0[2] * (a[0] * b[1] - a[1] * b[0])) / 6.0
        min_area = min(min_area, 0.5 * np.sqrt(nx * nx + ny * ny + nz * nz))
    return size, volume, min_area


@njit(cache=True)
def _split(v: np.ndarray, corners: np.ndarray, fptr: np.ndarray, labels: np.ndarray, normal: np.ndarray,
           offset: float, snap: float, cap_label: int):
    """Split one convex polyhedron by the plane normal·x = offset.

    Returns (crossed, positive piece (v, corners, fptr, labels), negative
    piece, section points (m, 3), largest |d| of the on-plane vertices,
    largest d, largest -d). ``crossed`` is False when no two vertices lie
    strictly on opposite sides (the pieces are then empty).
    """
    nv = v.shape[0]
    d = np.empty(nv)
    side = np.zeros(nv, dtype=np.int64)
    n_pos = n_neg = 0
    snapped = 0.0
    d_max = 0.0
    d_min = 0.0
    for i in range(nv):
        d[i] = v[i, 0] * normal[0] + v[i, 1] * normal[1] + v[i, 2] * normal[2] - offset
        if d[i] > snap:
            side[i] = 1
            n_pos += 1
        elif d[i] < -snap:
            side[i] = -1
            n_neg += 1
        else:
            snapped = max(snapped, abs(d[i]))
        d_max = max(d_max, d[i])
        d_min = min(d_min, d[i])
    empty_v = np.zeros((0, 3))
    empty_i = np.zeros(0, dtype=np.int64)
    if n_pos == 0 or n_neg == 0:
        return (False, empty_v, empty_i, empty_i, empty_i, empty_v, empty_i, empty_i, empty_i, empty_v,
                snapped, d_max, -d_min)
    nf = len(fptr) - 1
    cross = np.full((nv, nv), -1, dtype=np.int64)
    pts = np.empty((len(corners), 3))
    nx = 0
    for f in range(nf):
        s, e = fptr[f], fptr[f + 1]
        for c in range(s, e):
            a, b = corners[c], corners[c + 1 if c + 1 < e else s]
            if side[a] * side[b] == -1:
                lo, hi = min(a, b), max(a, b)
                if cross[lo, hi] < 0:
                    t = d[lo] / (d[lo] - d[hi])
                    pts[nx] = v[lo] + t * (v[hi] - v[lo])
                    cross[lo, hi] = nv + nx
                    nx += 1
    allv = np.empty((nv + nx, 3))
    allv[:nv] = v
    allv[nv:] = pts[:nx]
    all_side = np.zeros(nv + nx, dtype=np.int64)
    all_side[:nv] = side
    cap_size = nx
    for i in range(nv):
        if side[i] == 0:
            cap_size += 1
    cap = np.empty(cap_size, dtype=np.int64)
    k = 0
    for i in range(nv):
        if side[i] == 0:
            cap[k] = i
            k += 1
    for j in range(nx):
        cap[k] = nv + j
        k += 1
    # order the section by angle about its centroid, counter-clockwise about the normal
    centre = np.zeros(3)
    for i in range(cap_size):
        centre += allv[cap[i]] / cap_size
    helper = np.array([1.0, 0.0, 0.0]) if abs(normal[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    e1 = np.cross(normal, helper)
    e1 /= np.sqrt(np.sum(e1 * e1))
    e2 = np.cross(normal, e1)
    angle = np.empty(cap_size)
    for i in range(cap_size):
        r = allv[cap[i]] - centre
        angle[i] = np.arctan2(np.sum(r * e2), np.sum(r * e1))
    cap = cap[np.argsort(angle)]
    section = np.empty((cap_size, 3))
    for i in range(cap_size):
        section[i] = allv[cap[i]]
    out = []
    for sgn in (1, -1):
        vmap = np.full(nv + nx, -1, dtype=np.int64)
        count = 0
        for i in range(nv + nx):
            if all_side[i] * sgn >= 0:
                vmap[i] = count
                count += 1
        pv = np.empty((count, 3))
        for i in range(nv + nx):
            if vmap[i] >= 0:
                pv[vmap[i]] = allv[i]
        pc = np.empty(len(corners) + 2 * nf + cap_size, dtype=np.int64)
        pf = np.empty(nf + 2, dtype=np.int64)
        pl = np.empty(nf + 1, dtype=np.int64)
        pf[0] = 0
        n_faces = 0
        m = 0
        for f in range(nf):
            s, e = fptr[f], fptr[f + 1]
            start = m
            strict = False
            for c in range(s, e):
                a, b = corners[c], corners[c + 1 if c + 1 < e else s]
                if side[a] * sgn >= 0:
                    pc[m] = vmap[a]
                    m += 1
                    if side[a] == sgn:
                        strict = True
                if side[a] * side[b] == -1:
                    pc[m] = vmap[cross[min(a, b), max(a, b)]]
                    m += 1
            if strict and m - start >= 3:
                pl[n_faces] = labels[f]
                n_faces += 1
                pf[n_faces] = m
            else:
                m = start
        # the section closes the piece: counter-clockwise about the outward normal (-sgn·normal)
        for i in range(cap_size):
            pc[m] = vmap[cap[cap_size - 1 - i] if sgn == 1 else cap[i]]
            m += 1
        pl[n_faces] = cap_label
        n_faces += 1
        pf[n_faces] = m
        out.append((pv, pc[:m].copy(), pf[:n_faces + 1].copy(), pl[:n_faces].copy()))
    p, q = out[0], out[1]
    return (True, p[0], p[1], p[2], p[3], q[0], q[1], q[2], q[3], section, snapped, d_max, -d_min)


@njit(cache=True)
def _disc_cuts(v: np.ndarray, corners: np.ndarray, fptr: np.ndarray, normal: np.ndarray, offset: float,
               centre: np.ndarray, radius: float, snap: float) -> bool:
    """True if the plane crosses the polyhedron (vertices strictly on both sides) and, for a disc, the whole
    section lies within it; checked edge by edge without building the pieces."""
    nv = v.shape[0]
    d = np.empty(nv)
    pos = neg = False
    for i in range(nv):
        d[i] = v[i, 0] * normal[0] + v[i, 1] * normal[1] + v[i, 2] * normal[2] - offset
        pos |= d[i] > snap
        neg |= d[i] < -snap
    if not (pos and neg):
        return False
    if not np.isfinite(radius):
        return True
    reach = (radius * (1.0 + 1e-12) + snap) ** 2
    for i in range(nv):
        if abs(d[i]) <= snap and np.sum((v[i] - centre) ** 2) > reach:
            return False
    for f in range(len(fptr) - 1):
        s, e = fptr[f], fptr[f + 1]
        for c in range(s, e):
            a, b = corners[c], corners[c + 1 if c + 1 < e else s]
            if a < b and ((d[a] > snap and d[b] < -snap) or (d[a] < -snap and d[b] > snap)):
                p = v[a] + d[a] / (d[a] - d[b]) * (v[b] - v[a])
                if np.sum((p - centre) ** 2) > reach:
                    return False
    return True


@njit(cache=True)
def _bbox(v: np.ndarray) -> np.ndarray:
    """(lo, hi) of the vertices, as one array of 6."""
    out = np.empty(6)
    for k in range(3):
        out[k] = v[0, k]
        out[3 + k] = v[0, k]
    for i in range(v.shape[0]):
        for k in range(3):
            out[k] = min(out[k], v[i, k])
            out[3 + k] = max(out[3 + k], v[i, k])
    return out


@njit(cache=True)
def _bbox_misses(box6: np.ndarray, normal: np.ndarray, offset: float, centre: np.ndarray, radius: float,
                 snap: float) -> bool:
    """True if the plane (or disc) surely misses the box (lo, hi) = ``box6``."""
    reach = 0.0
    mid = 0.0
    for k in range(3):
        reach += abs(normal[k]) * 0.5 * (box6[3 + k] - box6[k])
        mid += normal[k] * 0.5 * (box6[3 + k] + box6[k])
    if abs(mid - offset) > reach + snap:
        return True
    if np.isfinite(radius):
        for k in range(3):
            extent = radius * np.sqrt(max(0.0, 1.0 - normal[k] * normal[k]))
            if centre[k] + extent < box6[k] - snap or centre[k] - extent > box6[3 + k] + snap:
                return True
    return False


@njit(cache=True)
def _flatten(vs, cs, fs, ls, alive):
    """The live fragments of typed lists as CSR arrays (vertices, block_ptr, face_first, face_ptr, face_vertex,
    labels)."""
    live = np.array([k for k in range(len(vs)) if alive[k]], dtype=np.int64)
    nb = len(live)
    block_ptr = np.zeros(nb + 1, dtype=np.int64)
    face_first = np.zeros(nb + 1, dtype=np.int64)
    n_corner = 0
    for b in range(nb):
        block_ptr[b + 1] = block_ptr[b] + vs[live[b]].shape[0]
        face_first[b + 1] = face_first[b] + len(fs[live[b]]) - 1
        n_corner += len(cs[live[b]])
    vertices = np.empty((block_ptr[nb], 3))
    face_ptr = np.zeros(face_first[nb] + 1, dtype=np.int64)
    face_vertex = np.empty(n_corner, dtype=np.int64)
    labels = np.empty(face_first[nb], dtype=np.int64)
    m = 0
    for b in range(nb):
        k = live[b]
        vertices[block_ptr[b]:block_ptr[b + 1]] = vs[k]
        f0 = face_first[b]
        for f in range(len(fs[k]) - 1):
            face_ptr[f0 + f + 1] = face_ptr[f0 + f] + fs[k][f + 1] - fs[k][f]
            labels[f0 + f] = ls[k][f]
        face_vertex[m:m + len(cs[k])] = cs[k]
        m += len(cs[k])
    return vertices, block_ptr, face_first, face_ptr, face_vertex, labels


@njit(cache=True)
def _cut_all(vertices, block_ptr, face_first, face_ptr, face_vertex, face_label, normals, points, radii, jlabels,
             snap, min_volume, min_thickness, tol):
    """Apply every joint to the convex parts given flat (CSR, as :func:`_flatten` returns them).

    Returns the fragments flat (vertices, block_ptr, face_first, face_ptr,
    face_vertex, labels), each fragment's part, and the skipped cuts (joint,
    reason, value, point (k, 3)). Typed lists live only inside the kernel.
    """
    vs = List()
    cs = List()
    fs = List()
    ls = List()
    parts = List()
    for b in range(len(block_ptr) - 1):
        f0, f1 = face_first[b], face_first[b + 1]
        vs.append(vertices[block_ptr[b]:block_ptr[b + 1]].copy())
        cs.append(face_vertex[face_ptr[f0]:face_ptr[f1]].copy())
        fs.append(face_ptr[f0:f1 + 1] - face_ptr[f0])
        ls.append(face_label[f0:f1].copy())
        parts.append(b)
    n_joints = len(normals)
    cap = 4 * len(vs) + 64
    alive = np.zeros(cap, dtype=np.bool_)
    boxes = np.empty((cap, 6))
    for k in range(len(vs)):
        alive[k] = True
        boxes[k] = _bbox(vs[k])
    start = np.zeros(n_joints, dtype=np.int64)  # fragments before this index were seen by the joint already
    skip_joint = List.empty_list(types.int64)
    skip_reason = List.empty_list(types.int64)
    skip_value = List.empty_list(types.float64)
    skip_point = List.empty_list(types.float64[:])
    first_pass = True
    changed = True
    while changed:
        changed = False
        for j in range(n_joints):
            radius = radii[j]
            if not first_pass and not np.isfinite(radius):
                continue  # an infinite plane cut everything it could in the first pass
            normal = normals[j]
            centre = points[j]
            offset = np.sum(normal * centre)
            n_now = len(vs)
            for i in range(start[j], n_now):
                if not alive[i] or _bbox_misses(boxes[i], normal, offset, centre, radius, snap):
                    continue
                if not _disc_cuts(vs[i], cs[i], fs[i], normal, offset, centre, radius, snap):
                    continue
                res = _split(vs[i], cs[i], fs[i], ls[i], normal, offset, snap, jlabels[j])
                section, snapped, d_pos, d_neg = res[9], res[10], res[11], res[12]
                size_p, vol_p, area_p = _piece_metrics(res[1], res[2], res[3])
                size_n, vol_n, area_n = _piece_metrics(res[5], res[6], res[7])
                reason = 0
                value = 0.0
                if min(d_pos, d_neg) < min_thickness:
                    reason, value = 1, min(d_pos, d_neg)
                elif min(vol_p, vol_n) < min_volume:
                    reason, value = 2, min(vol_p, vol_n)
                elif (area_p <= _SAFETY * tol * size_p * size_p or area_n <= _SAFETY * tol * size_n * size_n
                      or vol_p <= _SAFETY * tol * size_p ** 3 or vol_n <= _SAFETY * tol * size_n ** 3
                      or snapped * _SAFETY > tol * min(size_p, size_n)):
                    reason, value = 3, min(vol_p, vol_n)
                if reason:
                    skip_joint.append(j)
                    skip_reason.append(reason)
                    skip_value.append(value)
                    mid = np.zeros(3)
                    for r in range(section.shape[0]):
                        mid += section[r] / section.shape[0]
                    skip_point.append(mid)
                    continue
                alive[i] = False  # its two pieces follow, so later joints and passes see them as new
                if len(vs) + 2 > cap:
                    cap *= 2
                    grown = np.zeros(cap, dtype=np.bool_)
                    grown[:len(vs)] = alive[:len(vs)]
                    alive = grown
                    grown_boxes = np.empty((cap, 6))
                    grown_boxes[:len(vs)] = boxes[:len(vs)]
                    boxes = grown_boxes
                pieces = ((res[1], res[2], res[3], res[4]), (res[5], res[6], res[7], res[8]))
                for pv, pc, pf, pl in pieces:
                    vs.append(pv)
                    cs.append(pc)
                    fs.append(pf)
                    ls.append(pl)
                    parts.append(parts[i])
                    alive[len(vs) - 1] = True
                    boxes[len(vs) - 1] = _bbox(pv)
                changed = True
            start[j] = len(vs)  # the pieces this joint made lie on one side of it
        first_pass = False
    n_skip = len(skip_joint)
    sj = np.empty(n_skip, dtype=np.int64)
    sr = np.empty(n_skip, dtype=np.int64)
    sv = np.empty(n_skip)
    sp = np.empty((n_skip, 3))
    for k in range(n_skip):
        sj[k], sr[k], sv[k], sp[k] = skip_joint[k], skip_reason[k], skip_value[k], skip_point[k]
    owner = np.array([parts[k] for k in range(len(parts)) if alive[k]], dtype=np.int64)
    return _flatten(vs, cs, fs, ls, alive), owner, sj, sr, sv, sp


# -- the domain ----------------------------------------------------------------------------------
def _ring_arrays(faces: Sequence[np.ndarray], labels: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Faces as (corners, CSR offsets, labels) for the kernel."""
    return np.concatenate(faces).astype(np.int64), _offsets([len(f) for f in faces]), labels.astype(np.int64)


def _convex_part(part: tuple[object, object], label: str, tol: float) -> tuple[np.ndarray, list[np.ndarray]]:
    """A validated convex polyhedron (vertices, outward faces) from (vertices, faces)."""
    try:
        vertices, faces = part
        v, outward = normalize_polyhedron(vertices, faces, label)
    except (TypeError, ValueError) as exc:
        raise CuttingError(f"domain {label}: {exc}" if not isinstance(exc, PolyhedronError) else str(exc)) from None
    size = float(np.linalg.norm(np.ptp(v, axis=0)))
    for k, f in enumerate(outward):
        p = v[f] - v[f].mean(axis=0)
        normal = 0.5 * np.cross(p, np.roll(p, -1, axis=0)).sum(axis=0)
        normal /= np.linalg.norm(normal)
        beyond = (v - v[f].mean(axis=0)) @ normal
        if beyond.max() > tol * size:
            raise CuttingError(f"domain {label}: not convex (vertex {int(beyond.argmax())} lies "
                               f"{beyond.max():.3g} m outside the plane of face {k}); give a non-convex domain "
                               f"as convex parts")
    return v, outward


def convex_hull_polyhedron(points: object, label: str = "domain") -> tuple[np.ndarray, list[np.ndarray]]:
    """The convex hull of ``points`` (m, 3) as a polyhedron (vertices, outward faces), coplanar facets merged.

    Built by clipping the points' bounding box with every hull plane (the
    same kernel as the cutting), so each face is one planar polygon.
    """
    pts = np.asarray(points, dtype=float)
    if pts.ndim != 2 or pts.shape[1] != 3 or len(pts) < 4 or not np.all(np.isfinite(pts)):
        raise CuttingError(f"{label}: a convex hull needs at least 4 finite [x, y, z] points")
    try:
        hull = ConvexHull(pts)
    except QhullError:
        raise CuttingError(f"{label}: the points are flat (coplanar); they span no volume") from None
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    margin = 0.1 * (hi - lo)
    return halfspace_polyhedron(hull.equations[:, :3], -hull.equations[:, 3], lo - margin, hi + margin, label)


def halfspace_polyhedron(normals: object, offsets: object, lo: Sequence[float] | np.ndarray,
                         hi: Sequence[float] | np.ndarray,
                         label: str = "polyhedron") -> tuple[np.ndarray, list[np.ndarray]]:
    """The convex polyhedron {x in [lo, hi] : normals[k]·x <= offsets[k] for every k}: (vertices, outward faces).

    The box [lo, hi] clipped by each half-space with the cutting kernel, so
    coplanar constraints give one face. An empty result is a
    :class:`CuttingError`.
    """
    n = np.asarray(normals, dtype=float).reshape(-1, 3)
    c = np.asarray(offsets, dtype=float).reshape(-1)
    v, faces = box(lo, hi, label)
    size = float(np.linalg.norm(np.asarray(hi, float) - np.asarray(lo, float)))
    corners, fptr, labels = _ring_arrays(faces, np.full(len(faces), NO_JOINT))
    for k in range(len(n)):
        length = float(np.linalg.norm(n[k]))
        if not length > 0:
            raise CuttingError(f"{label}: half-space {k} has a zero normal")
        d = v @ (n[k] / length) - c[k] / length
        if d.min() > -_SNAP * size:
            raise CuttingError(f"{label}: half-space {k} leaves nothing of the polyhedron")
        res = _split(v, corners, fptr, labels, n[k] / length, c[k] / length, _SNAP * size, NO_JOINT)
        if res[0]:
            v, corners, fptr, labels = res[5], res[6], res[7], res[8]
    return v, [corners[fptr[k]:fptr[k + 1]] for k in range(len(fptr) - 1)]


def cut_polyhedra(domain: object, joints: JointPlanes, *, min_volume: float = 0.0, min_thickness: float = 0.0,
                  boundary_type: int = NO_JOINT) -> PolyhedralCut:
    """Cut a convex domain (or a list of convex parts) by joint planes and discs.

    ``domain``: (vertices, faces) of a convex polyhedron, or a list of them
    (a non-convex domain as convex parts); faces in any orientation.
    ``joints``: :class:`~srdda.geometry.jointsets3d.JointPlanes` (planes,
    discs, generated sets: :func:`~srdda.geometry.jointsets3d.joint_planes`).
    ``min_volume`` (m³) and ``min_thickness`` (m): cuts leaving a smaller or
    thinner piece are skipped and reported. Domain faces get ``boundary_type``.
    """
    if isinstance(domain, tuple) and len(domain) == 2 and np.ndim(domain[0]) == 2:
        parts = [domain]
    elif isinstance(domain, Sequence) and len(domain) > 0:
        parts = list(domain)
    else:
        raise CuttingError("domain: give (vertices, faces) of a convex polyhedron or a list of them")
    if not isinstance(joints, JointPlanes):
        raise CuttingError("joints: give a JointPlanes (JointPlanes.of, or joint_planes for joint sets)")
    for name, value in (("min_volume", min_volume), ("min_thickness", min_thickness)):
        if not (np.isfinite(value) and value >= 0):
            raise CuttingError(f"{name} must be a finite number >= 0, got {value}")
    convex = [_convex_part(p, f"part {k}", 10 * PLANARITY_TOLERANCE) for k, p in enumerate(parts)]
    all_v = np.concatenate([v for v, _ in convex])
    size = float(np.linalg.norm(np.ptp(all_v, axis=0)))
    shift = 0.5 * (all_v.min(axis=0) + all_v.max(axis=0))  # cut about the domain's centre: full precision
    rings = [f for _, faces in convex for f in faces]
    flat = (np.ascontiguousarray(np.concatenate([v for v, _ in convex]) - shift),  # the parts as CSR arrays
            _offsets([len(v) for v, _ in convex]), _offsets([len(faces) for _, faces in convex]),
            _offsets([len(f) for f in rings]), np.concatenate(rings).astype(np.int64),
            np.full(len(rings), boundary_type, dtype=np.int64))
    (vertices, block_ptr, face_first, face_ptr, face_vertex, labels), block_part, sj, sr, sv, sp = _cut_all(
        *flat, np.ascontiguousarray(joints.normal).reshape(-1, 3),
        np.ascontiguousarray(joints.point - shift).reshape(-1, 3), np.ascontiguousarray(joints.radius, dtype=float),
        np.ascontiguousarray(joints.joint_type, dtype=np.int64), _SNAP * size, float(min_volume),
        float(min_thickness), PLANARITY_TOLERANCE)
    skipped = tuple(SkippedCut(int(j), SKIP_REASONS[int(r)], float(val), tuple((p + shift).tolist()))
                    for j, r, val, p in zip(sj, sr, sv, sp))
    vertices += shift
    keep, rejected = _validate(vertices, block_ptr, face_first, face_ptr, face_vertex, block_part)
    if rejected:
        vertices, block_ptr, face_first, face_ptr, face_vertex, labels, block_part = _subset(
            keep, vertices, block_ptr, face_first, face_ptr, face_vertex, labels, block_part)
    return PolyhedralCut(vertices, block_ptr, face_first, face_ptr, face_vertex, labels, block_part, skipped,
                         tuple(rejected))


def _offsets(counts: list[int]) -> np.ndarray:
    """CSR offsets (n + 1,) of consecutive groups of the given sizes."""
    return np.concatenate([[0], np.cumsum(counts)]).astype(np.int64)


def _validate(vertices: np.ndarray, block_ptr: np.ndarray, face_first: np.ndarray, face_ptr: np.ndarray,
              face_vertex: np.ndarray, block_part: np.ndarray) -> tuple[np.ndarray, list[RejectedFragment]]:
    """Which fragments pass :func:`normalize_polyhedron` (all at once; one by one only if some fail)."""
    nb = len(block_ptr) - 1
    blocks = [(vertices[block_ptr[b]:block_ptr[b + 1]],
               [face_vertex[face_ptr[k]:face_ptr[k + 1]] for k in range(face_first[b], face_first[b + 1])])
              for b in range(nb)]
    labels = [f"fragment {b}" for b in range(nb)]
    try:
        normalize_polyhedra(blocks, labels)
        return np.ones(nb, dtype=bool), []
    except PolyhedronError:
        pass
    keep = np.ones(nb, dtype=bool)
    rejected = []
    for b, (v, faces) in enumerate(blocks):
        try:
            normalize_polyhedron(v, faces, labels[b])
        except PolyhedronError as exc:
            keep[b] = False
            rejected.append(RejectedFragment(int(block_part[b]), str(exc), tuple(v.mean(axis=0).tolist())))
    return keep, rejected


def _subset(keep: np.ndarray, vertices: np.ndarray, block_ptr: np.ndarray, face_first: np.ndarray,
            face_ptr: np.ndarray, face_vertex: np.ndarray, labels: np.ndarray, block_part: np.ndarray) -> tuple:
    """The CSR arrays of the kept blocks only."""
    nv_b, nf_b = np.diff(block_ptr), np.diff(face_first)
    nc_f = np.diff(face_ptr)
    v_keep = np.repeat(keep, nv_b)
    f_keep = np.repeat(keep, nf_b)
    c_keep = np.repeat(f_keep, nc_f)
    return (vertices[v_keep], np.concatenate([[0], np.cumsum(nv_b[keep])]),
            np.concatenate([[0], np.cumsum(nf_b[keep])]), np.concatenate([[0], np.cumsum(nc_f[f_keep])]),
            face_vertex[c_keep], labels[f_keep], block_part[keep])
